//! Pictures of maps for a person: a map cropped to its known cells, with a path drawn over it, or maps laid
//! over a base map; written as PNG.

use super::cells::{PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN, grid_to_image};
use super::error::MapIoError;
use super::grey_image::{GreyImage, encode_png};
use crate::grid::{CellState, OccupancyGrid};
use crate::output::write_file_atomic;
use crate::se2::Pose2;
use nalgebra::Point2;
use std::path::{Path, PathBuf};

/// Cells of margin a preview keeps around the map's known cells.
const PREVIEW_MARGIN: usize = 10;

/// Where the preview of the map `yaml_path` goes: beside it, the same name with `.png`.
pub fn preview_path(yaml_path: &Path) -> PathBuf {
    yaml_path.with_extension("png")
}

/// The pixel box (x0, y0, x1, y1, inclusive, top row 0) of a grid's image that its preview keeps: the known cells
/// and a margin of 10 cells; the whole image when no cell is known.
fn preview_box(img: &GreyImage) -> (usize, usize, usize, usize) {
    let (w, h) = (img.width, img.height);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (i, &v) in img.pixels.iter().enumerate() {
        if v != PGM_UNKNOWN {
            let (x, y) = (i % w, i / w);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        return (0, 0, w.saturating_sub(1), h.saturating_sub(1));
    }
    let (x0, y0) = (x0.saturating_sub(PREVIEW_MARGIN), y0.saturating_sub(PREVIEW_MARGIN));
    (x0, y0, (x1 + PREVIEW_MARGIN).min(w - 1), (y1 + PREVIEW_MARGIN).min(h - 1))
}

/// A picture of a grid for a person: its trinary image (occupied black, free white, unknown grey) cropped to the
/// known cells and a margin of 10 cells.
pub fn preview_image(grid: &OccupancyGrid) -> GreyImage {
    let full = grid_to_image(grid);
    if full.pixels.is_empty() {
        return full;
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let w = full.width;
    let pixels = (y0..=y1).flat_map(|y| full.pixels[y * w + x0..=y * w + x1].iter().copied()).collect();
    GreyImage { width: x1 - x0 + 1, height: y1 - y0 + 1, pixels }
}

/// [`preview_image`] in colour with a path drawn over it in red: `path` is a sequence of points in the map frame
/// (metres), joined by straight lines; points off the picture are clipped.
pub fn preview_with_path(grid: &OccupancyGrid, path: &[Point2<f64>]) -> image::RgbImage {
    let full = grid_to_image(grid);
    let mut out = image::RgbImage::new(1, 1);
    if full.pixels.is_empty() {
        return out;
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    out = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let v = full.pixels[(y as usize + y0) * full.width + x as usize + x0];
        image::Rgb([v, v, v])
    });
    // a point's pixel (fractional), top row 0, in the cropped picture
    let pixel = |p: &Point2<f64>| {
        let (cx, cy) = grid.world_to_cell_f(p);
        (cx - x0 as f64, (full.height as f64 - cy) - y0 as f64)
    };
    for pair in path.windows(2) {
        segment(pixel(&pair[0]), pixel(&pair[1]), |x, y| {
            if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
                out.put_pixel(x as u32, y as u32, image::Rgb([220, 30, 30]));
            }
        });
    }
    out
}

/// Visits the points of the straight line from pixel `a` to pixel `b` (fractional), at most one pixel apart.
fn segment(a: (f64, f64), b: (f64, f64), mut visit: impl FnMut(f64, f64)) {
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).clamp(1, 100_000);
    for k in 0..=steps {
        let t = k as f64 / steps as f64;
        visit(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
    }
}

/// One map laid over another in [`overlay`]: its occupied cells and a path, placed in the base map's frame.
#[derive(Debug, Clone, Copy)]
pub struct OverlayLayer<'a> {
    /// The map whose occupied cells are drawn.
    pub map: &'a OccupancyGrid,
    /// Where the map's frame lies in the base map's frame.
    pub placement: Pose2,
    /// A path in the map's frame, drawn as lines.
    pub path: &'a [Pose2],
    /// Colour of the occupied cells; the path is drawn in a darker shade of it.
    pub colour: [u8; 3],
}

/// A picture of maps laid over a base map (the truth, say): the base in light greys, each layer's occupied cells
/// in its colour at its placement, each layer's path in a darker shade; cropped as [`preview_image`] crops the
/// base. Where the placements are right, the layers' walls cover the base's.
pub fn overlay(base: &OccupancyGrid, layers: &[OverlayLayer]) -> image::RgbImage {
    let full = grid_to_image(base);
    if full.pixels.is_empty() {
        return image::RgbImage::new(1, 1);
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let mut out = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let v = match full.pixels[(y as usize + y0) * full.width + x as usize + x0] {
            PGM_OCCUPIED => 150,
            PGM_FREE => 245,
            _ => 215,
        };
        image::Rgb([v, v, v])
    });
    let pixel = |p: &Point2<f64>| {
        let (cx, cy) = base.world_to_cell_f(p);
        (cx - x0 as f64, (full.height as f64 - cy) - y0 as f64)
    };
    let mut put = |x: f64, y: f64, c: [u8; 3]| {
        if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
            out.put_pixel(x as u32, y as u32, image::Rgb(c));
        }
    };
    for layer in layers {
        let m = layer.map;
        for iy in 0..m.height() {
            for ix in 0..m.width() {
                if m.state(ix, iy) == CellState::Occupied {
                    let (x, y) = pixel(&(layer.placement * m.cell_center(ix as i64, iy as i64)));
                    put(x, y, layer.colour);
                }
            }
        }
        let dark = layer.colour.map(|c| c / 2);
        for pair in layer.path.windows(2) {
            let a = pixel(&(layer.placement * Point2::from(pair[0].translation.vector)));
            let b = pixel(&(layer.placement * Point2::from(pair[1].translation.vector)));
            segment(a, b, |x, y| put(x, y, dark));
        }
    }
    out
}

/// Writes an RGB picture as a PNG at `png_path` (through a temporary name).
pub fn write_rgb_png(img: &image::RgbImage, png_path: &Path) -> Result<(), MapIoError> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| MapIoError::Image { path: png_path.to_path_buf(), message: e.to_string() })?;
    Ok(write_file_atomic(png_path, &bytes)?)
}

/// Writes [`preview_image`] of `grid` as a PNG at `png_path` (through a temporary name).
pub fn write_map_preview(grid: &OccupancyGrid, png_path: &Path) -> Result<(), MapIoError> {
    Ok(write_file_atomic(png_path, &encode_png(&preview_image(grid), png_path)?)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_io::{read_grey_image, write_ros_map_with_preview};

    #[test]
    fn a_preview_is_the_map_cropped_to_its_known_cells() {
        let mut g = OccupancyGrid::new(100, 80, 0.05, crate::pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 30..40 {
            for ix in 20..50 {
                g.set(ix, iy, if ix == 20 { 2.0 } else { -2.0 });
            }
        }
        let img = preview_image(&g);
        assert_eq!((img.width, img.height), (30 + 20, 10 + 20));
        // the wall column, 10 pixels in from the left, is black; the corner of the margin is unknown grey
        assert_eq!(img.pixels[15 * img.width + 10], PGM_OCCUPIED);
        assert_eq!(img.pixels[15 * img.width + 11], PGM_FREE);
        assert_eq!(img.pixels[0], PGM_UNKNOWN);
        let dir = tempfile::tempdir().unwrap();
        let yaml = dir.path().join("m.yaml");
        write_ros_map_with_preview(&g, &yaml).unwrap();
        let png = read_grey_image(&preview_path(&yaml)).unwrap();
        assert_eq!((png.width, png.height, png.pixels), (img.width, img.height, img.pixels));
        // an empty map's preview is the whole (unknown) image
        let empty = OccupancyGrid::new(7, 5, 0.05, crate::pose(0.0, 0.0, 0.0)).unwrap();
        assert_eq!((preview_image(&empty).width, preview_image(&empty).height), (7, 5));
        // A path along the free strip, from cell (25, 35) to (45, 35): red on that row, 11 px from the top.
        let path = [Point2::new(25.5 * 0.05, 35.5 * 0.05), Point2::new(45.5 * 0.05, 35.5 * 0.05)];
        let rgb = preview_with_path(&g, &path);
        assert_eq!((rgb.width() as usize, rgb.height() as usize), (img.width, img.height));
        let row = (80 - 35 - 1) - (80 - 40 - 10); // the cell row's pixel row in the crop
        assert_eq!(rgb.get_pixel(15, row as u32).0, [220, 30, 30]);
        assert_eq!(rgb.get_pixel(35, row as u32).0, [220, 30, 30]);
        assert_eq!(rgb.get_pixel(15, row as u32 + 2).0, [PGM_FREE; 3]);
        // The map laid over itself, placed right: its wall cells in the layer's colour where the base's are.
        let layer = OverlayLayer { map: &g, placement: Pose2::identity(), path: &[], colour: [0, 0, 255] };
        let over = overlay(&g, &[layer]);
        assert_eq!((over.width() as usize, over.height() as usize), (img.width, img.height));
        assert_eq!(over.get_pixel(10, 15).0, [0, 0, 255]);
        assert_eq!(over.get_pixel(11, 15).0, [245; 3]);
        // Placed one metre (20 cells) to the right: the wall is drawn there instead.
        let moved = OverlayLayer { placement: crate::pose(1.0, 0.0, 0.0), ..layer };
        let over = overlay(&g, &[moved]);
        assert_eq!(over.get_pixel(10, 15).0, [150; 3]);
        assert_eq!(over.get_pixel(30, 15).0, [0, 0, 255]);
    }
}
