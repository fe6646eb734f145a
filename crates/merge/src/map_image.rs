//! Map → image: how occupied, free and unknown cells become grey levels for SIFT (paper Alg. 3, lines 2-3).

use mrslam_core::{CellState, OccupancyGrid};
use mrslam_core::{FREE_LOGODDS, OCCUPIED_LOGODDS};
use nalgebra::Point2;

/// Grey levels (0..255) given to each cell state when a map becomes an image.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MapEncoding {
    /// Grey level of occupied cells.
    pub occupied: f32,
    /// Grey level of free cells.
    pub free: f32,
    /// Grey level of unknown cells.
    pub unknown: f32,
}

impl MapEncoding {
    /// The paper's encoding, map_server's trinary PGM: occupied black, free white, unknown grey.
    pub const PAPER: MapEncoding = MapEncoding { occupied: 0.0, free: 254.0, unknown: 205.0 };
    /// Walls only: free and unknown share one light level, so the border of what a robot happened to see
    /// (which differs between robots) makes no features; only walls and furniture do.
    pub const WALLS: MapEncoding = MapEncoding { occupied: 0.0, free: 255.0, unknown: 255.0 };

    /// Grey level of a state.
    #[inline]
    pub fn level(&self, s: CellState) -> f32 {
        match s {
            CellState::Occupied => self.occupied,
            CellState::Free => self.free,
            CellState::Unknown => self.unknown,
        }
    }
}

/// A named [`MapEncoding`], as scenario files, studies and the command line choose one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// [`MapEncoding::WALLS`].
    #[default]
    Walls,
    /// [`MapEncoding::PAPER`].
    Paper,
}

impl Encoding {
    /// Every encoding, as the command line lists them.
    pub const ALL: [Encoding; 2] = [Encoding::Walls, Encoding::Paper];

    /// The name: `walls` or `paper`.
    pub const fn name(self) -> &'static str {
        match self {
            Encoding::Walls => "walls",
            Encoding::Paper => "paper",
        }
    }

    /// Its grey levels.
    pub const fn levels(self) -> MapEncoding {
        match self {
            Encoding::Walls => MapEncoding::WALLS,
            Encoding::Paper => MapEncoding::PAPER,
        }
    }
}

impl std::fmt::Display for Encoding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Encoding {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Encoding::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| format!("unknown encoding `{s}` (expected walls or paper)"))
    }
}

impl Default for MapEncoding {
    /// [`MapEncoding::WALLS`]: measured better than the paper's on cut pairs (see BENCHMARKS.md, merge).
    fn default() -> Self {
        MapEncoding::WALLS
    }
}

/// A map rendered as a grey image, with the mapping from pixels back to the map frame.
///
/// Pixel (u, v) (OpenCV convention: integer coordinates at pixel centres, v down) shows cell
/// (x0 + u, y0 + h - 1 - v) of the grid it was rendered from.
#[derive(Debug, Clone)]
pub struct MapImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Grey levels, row-major from the top.
    pub pixels: Vec<f32>,
    /// First grid column shown.
    pub x0: usize,
    /// First grid row shown (the image's bottom row).
    pub y0: usize,
}

impl MapImage {
    /// Renders the grid's known part plus `pad` cells of margin (the whole grid when nothing is known).
    pub fn render(grid: &OccupancyGrid, enc: &MapEncoding, pad: usize) -> MapImage {
        Self::render_dilated(grid, enc, pad, 0)
    }

    /// Like [`MapImage::render`], with occupied cells grown by `dilation` cells (a square neighbourhood).
    ///
    /// SLAM maps draw walls one cell thick and broken; grown walls give SIFT steadier corners.
    pub fn render_dilated(grid: &OccupancyGrid, enc: &MapEncoding, pad: usize, dilation: usize) -> MapImage {
        let (x0, y0, x1, y1) = match grid.known_bounds() {
            Some((a, b, c, d)) => (
                a.saturating_sub(pad),
                b.saturating_sub(pad),
                (c + pad).min(grid.width().saturating_sub(1)),
                (d + pad).min(grid.height().saturating_sub(1)),
            ),
            None => (0, 0, grid.width().saturating_sub(1), grid.height().saturating_sub(1)),
        };
        if grid.width() == 0 || grid.height() == 0 {
            return MapImage { width: 0, height: 0, pixels: Vec::new(), x0: 0, y0: 0 };
        }
        let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
        let mut pixels = vec![enc.unknown; w * h];
        let cells = grid.cells();
        for v in 0..h {
            let iy = y0 + h - 1 - v;
            let row = &cells[iy * grid.width() + x0..iy * grid.width() + x0 + w];
            // `CellState::from_log_odds` as selects, so the loop vectorises.
            for (p, &l) in pixels[v * w..(v + 1) * w].iter_mut().zip(row) {
                let known = if l < FREE_LOGODDS { enc.free } else { enc.unknown };
                *p = if l > OCCUPIED_LOGODDS { enc.occupied } else { known };
            }
        }
        if dilation > 0 {
            dilate_level(&mut pixels, w, h, enc.occupied, dilation);
        }
        MapImage { width: w, height: h, pixels, x0, y0 }
    }

    /// Map-frame position of an image point (pixel coordinates, OpenCV convention).
    pub fn pixel_to_map(&self, grid: &OccupancyGrid, u: f64, v: f64) -> Point2<f64> {
        let cx = self.x0 as f64 + u + 0.5;
        let cy = self.y0 as f64 + (self.height as f64 - 1.0 - v) + 0.5;
        grid.cell_f_to_world(cx, cy)
    }

    /// Image position (pixel coordinates) of a map-frame point.
    pub fn map_to_pixel(&self, grid: &OccupancyGrid, p: &Point2<f64>) -> (f64, f64) {
        let (cx, cy) = grid.world_to_cell_f(p);
        let u = cx - 0.5 - self.x0 as f64;
        let v = self.height as f64 - 1.0 - (cy - 0.5 - self.y0 as f64);
        (u, v)
    }
}

/// Grows the pixels at grey level `level` by `r` pixels (separable square dilation).
fn dilate_level(pixels: &mut [f32], w: usize, h: usize, level: f32, r: usize) {
    let mask: Vec<u8> = pixels.iter().map(|&p| u8::from(p == level)).collect();
    // Across: OR of the row shifted by -r ..= r (whole-row operations, vectorised).
    let mut across = mask.clone();
    for y in 0..h {
        let (m, a) = (&mask[y * w..(y + 1) * w], &mut across[y * w..(y + 1) * w]);
        for s in 1..=r.min(w.saturating_sub(1)) {
            for (o, &v) in a[s..].iter_mut().zip(&m[..w - s]) {
                *o |= v;
            }
            for (o, &v) in a[..w - s].iter_mut().zip(&m[s..]) {
                *o |= v;
            }
        }
    }
    // Down: OR of the rows y - r ..= y + r.
    let mut grown = vec![0u8; w];
    for y in 0..h {
        grown.fill(0);
        for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
            for (o, &v) in grown.iter_mut().zip(&across[yy * w..(yy + 1) * w]) {
                *o |= v;
            }
        }
        for (p, &g) in pixels[y * w..(y + 1) * w].iter_mut().zip(&grown) {
            if g != 0 {
                *p = level;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn dilation_grows_walls_by_the_radius() {
        let mut g = OccupancyGrid::new(9, 9, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        g.cells_mut().fill(-2.0);
        g.set(4, 4, 2.0);
        let img = MapImage::render_dilated(&g, &MapEncoding::WALLS, 0, 1);
        let dark = img.pixels.iter().filter(|&&p| p == 0.0).count();
        assert_eq!(dark, 9, "a single wall cell grows into a 3x3 block");
        assert_eq!(MapImage::render(&g, &MapEncoding::WALLS, 0).pixels.iter().filter(|&&p| p == 0.0).count(), 1);
    }

    #[test]
    fn pixel_and_map_coordinates_invert() {
        let mut g = OccupancyGrid::new(20, 10, 0.1, pose(1.0, -2.0, 0.0)).unwrap();
        g.set(3, 2, 2.0);
        g.set(12, 7, -2.0);
        let img = MapImage::render(&g, &MapEncoding::PAPER, 1);
        assert_eq!((img.x0, img.y0, img.width, img.height), (2, 1, 12, 8));
        // cell (3, 2) is occupied: it sits at u = 1, v = h - 1 - (2 - 1) = 6
        assert_eq!(img.pixels[6 * img.width + 1], 0.0);
        assert_eq!(img.pixels[(img.height - 1 - 6) * img.width + 10], 254.0);
        let p = img.pixel_to_map(&g, 1.0, 6.0);
        assert!((p - g.cell_center(3, 2)).norm() < 1e-12);
        let (u, v) = img.map_to_pixel(&g, &p);
        assert!((u - 1.0).abs() < 1e-9 && (v - 6.0).abs() < 1e-9);
    }
}
