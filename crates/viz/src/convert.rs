//! Conversions from mrslam's types to rerun's: poses to transforms, grids to images, colours.

use mrslam_core::{CellState, OccupancyGrid, Pose2};
use nalgebra::{Matrix2, Point2, Vector2};
use rerun::datatypes::Mat3x3;
use rerun::{Color, Transform3D};

/// An RGBA colour.
pub type Rgba = [u8; 4];

/// A robot's colour, by its index in the scenario (blue, orange, green, purple, then around again).
pub fn robot_color(index: usize) -> Rgba {
    const PALETTE: [Rgba; 4] = [[66, 135, 245, 255], [245, 145, 30, 255], [60, 180, 90, 255], [170, 90, 220, 255]];
    PALETTE[index % PALETTE.len()]
}

/// `c` with alpha `a`.
pub fn with_alpha(c: Rgba, a: u8) -> Rgba {
    [c[0], c[1], c[2], a]
}

/// `c` mixed with white by `t` in [0, 1].
pub fn lighten(c: Rgba, t: f32) -> Rgba {
    let mix = |v: u8| (v as f32 + (255.0 - v as f32) * t.clamp(0.0, 1.0)).round() as u8;
    [mix(c[0]), mix(c[1]), mix(c[2]), c[3]]
}

/// A rerun colour.
pub fn color(c: Rgba) -> Color {
    Color::from_unmultiplied_rgba(c[0], c[1], c[2], c[3])
}

/// Viridis-like ramp for t in [0, 1] (dark purple → teal → yellow), used for particle weights.
pub fn ramp(t: f64) -> Rgba {
    const STOPS: [[f64; 3]; 5] =
        [[68.0, 1.0, 84.0], [59.0, 82.0, 139.0], [33.0, 145.0, 140.0], [94.0, 201.0, 98.0], [253.0, 231.0, 37.0]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let c = |k: usize| (STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f).round() as u8;
    [c(0), c(1), c(2), 255]
}

/// A point as rerun's `[x, y]`.
pub fn xy(p: &Point2<f64>) -> [f32; 2] {
    [p.x as f32, p.y as f32]
}

/// The position of a pose as rerun's `[x, y]`.
pub fn pose_xy(p: &Pose2) -> [f32; 2] {
    [p.translation.x as f32, p.translation.y as f32]
}

/// A vector of length `len` along a pose's heading.
pub fn heading(p: &Pose2, len: f64) -> [f32; 2] {
    let a = p.rotation.angle();
    [(len * a.cos()) as f32, (len * a.sin()) as f32]
}

/// A 2D affine map `x ↦ m·x + t` as a rerun transform (z untouched).
pub fn affine(m: &Matrix2<f64>, t: &Vector2<f64>) -> Transform3D {
    // Mat3x3 is column-major.
    let mat = Mat3x3([m[(0, 0)] as f32, m[(1, 0)] as f32, 0.0, m[(0, 1)] as f32, m[(1, 1)] as f32, 0.0, 0.0, 0.0, 1.0]);
    Transform3D::from_translation_mat3x3([t.x as f32, t.y as f32, 0.0], mat)
}

/// A rigid 2D pose as a rerun transform (child frame → parent frame).
pub fn pose_transform(p: &Pose2) -> Transform3D {
    affine(p.rotation.to_rotation_matrix().matrix(), &p.translation.vector)
}

/// The transform that places a grid image (pixel (u, v), v down, row 0 = the grid's top row) in the frame
/// `frame` (the pose of the grid's own frame in the parent).
pub fn grid_image_transform(grid: &OccupancyGrid, frame: &Pose2) -> Transform3D {
    let (m, t) = grid_image_affine(grid, frame);
    affine(&m, &t)
}

/// The affine map (matrix, translation) behind [`grid_image_transform`].
pub fn grid_image_affine(grid: &OccupancyGrid, frame: &Pose2) -> (Matrix2<f64>, Vector2<f64>) {
    let pose = frame * grid.origin();
    let r = grid.resolution();
    // pixel → grid-local metres: x = u·r, y = (h − v)·r
    let local = Matrix2::new(r, 0.0, 0.0, -r);
    let m = pose.rotation.to_rotation_matrix().matrix() * local;
    let t = pose * Point2::new(0.0, grid.height() as f64 * r);
    (m, t.coords)
}

/// Colours of a grid's cells when drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GridStyle {
    /// Occupied cells.
    pub occupied: Rgba,
    /// Free cells.
    pub free: Rgba,
    /// Unknown cells.
    pub unknown: Rgba,
}

impl GridStyle {
    /// ROS map_server greys, opaque: occupied black, free white, unknown grey.
    pub const GREY: GridStyle =
        GridStyle { occupied: [0, 0, 0, 255], free: [254, 254, 254, 255], unknown: [205, 205, 205, 255] };

    /// A robot's map: walls in its colour, free space a light wash of it, unknown transparent, so that maps
    /// drawn over each other (and over the world) stay readable.
    pub fn tinted(c: Rgba) -> GridStyle {
        let dark = [(c[0] as f32 * 0.6) as u8, (c[1] as f32 * 0.6) as u8, (c[2] as f32 * 0.6) as u8, 255];
        GridStyle { occupied: dark, free: with_alpha(lighten(c, 0.55), 70), unknown: [0, 0, 0, 0] }
    }

    /// The true map under everything: walls mid grey, free space faint, unknown transparent.
    pub const TRUTH: GridStyle =
        GridStyle { occupied: [150, 150, 150, 255], free: [255, 255, 255, 18], unknown: [0, 0, 0, 0] };
}

/// A grid drawn as map_server's grey levels, one byte a cell (occupied 0, free 254, unknown 205), north-up like
/// [`grid_rgba`]: a quarter of the bytes, for maps logged many times.
pub fn grid_grey(grid: &OccupancyGrid) -> Vec<u8> {
    let (w, h) = (grid.width(), grid.height());
    let mut out = Vec::with_capacity(w * h);
    for v in 0..h {
        out.extend((0..w).map(|u| match grid.state(u, h - 1 - v) {
            CellState::Occupied => 0,
            CellState::Free => 254,
            CellState::Unknown => 205,
        }));
    }
    out
}

/// A grid drawn as RGBA pixels (row 0 = the grid's top row, so that the picture is north-up).
pub fn grid_rgba(grid: &OccupancyGrid, style: &GridStyle) -> image::RgbaImage {
    let (w, h) = (grid.width(), grid.height());
    let mut img = image::RgbaImage::new(w as u32, h as u32);
    for (u, v, px) in img.enumerate_pixels_mut() {
        let c = match grid.state(u as usize, h - 1 - v as usize) {
            CellState::Occupied => style.occupied,
            CellState::Free => style.free,
            CellState::Unknown => style.unknown,
        };
        *px = image::Rgba(c);
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn grid_image_corners_land_on_the_grid() {
        let g = OccupancyGrid::new(4, 2, 0.5, pose(1.0, 2.0, 0.0)).unwrap();
        let frame = pose(10.0, 0.0, std::f64::consts::FRAC_PI_2);
        let (m, t) = grid_image_affine(&g, &frame);
        let px = |u: f64, v: f64| m * Vector2::new(u, v) + t;
        // Pixel (0, 2) is the bottom-left corner of the image: the grid's origin, seen from the parent.
        let bl = px(0.0, 2.0);
        let want = frame * g.cell_f_to_world(0.0, 0.0);
        assert!((bl - want.coords).norm() < 1e-12, "{bl:?} vs {want:?}");
        // Pixel (4, 0) is the top-right corner: cell coordinates (4, 2).
        let tr = px(4.0, 0.0);
        let want = frame * g.cell_f_to_world(4.0, 2.0);
        assert!((tr - want.coords).norm() < 1e-12);
    }

    #[test]
    fn image_is_north_up() {
        let mut g = OccupancyGrid::new(3, 2, 0.1, Pose2::identity()).unwrap();
        g.set(0, 1, 5.0); // top-left cell occupied
        g.set(2, 0, -5.0); // bottom-right free
        let img = grid_rgba(&g, &GridStyle::GREY);
        assert_eq!((img.width(), img.height()), (3, 2));
        assert_eq!(img.get_pixel(0, 0).0, GridStyle::GREY.occupied);
        assert_eq!(img.get_pixel(2, 1).0, GridStyle::GREY.free);
        assert_eq!(img.get_pixel(1, 1).0, GridStyle::GREY.unknown);
        let grey = grid_grey(&g);
        assert_eq!(grey.len(), 6);
        for (i, px) in img.pixels().enumerate() {
            assert_eq!(grey[i], px.0[0], "pixel {i}: the grey picture is the RGBA one's red channel");
        }
    }

    #[test]
    fn ramp_ends() {
        assert_eq!(ramp(0.0), [68, 1, 84, 255]);
        assert_eq!(ramp(1.0), [253, 231, 37, 255]);
        assert_eq!(ramp(f64::NAN), ramp(0.0));
    }
}
