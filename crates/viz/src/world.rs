//! The world: the display frame, the walls and the true map, all static.
//!
//! rerun's 2D views point y down (like images) whatever the data. So that the world reads as a map (y up,
//! angles counter-clockwise), every spatial root (`world`, `robots`, `maps`, `merge`) carries one static flip
//! `(x, y) ↦ (x, −y)` to the viewer's root: data stays in true metres (hovering shows true values), and the
//! views whose origin is `/` show it north-up. Views rooted at a map image (`maps/<name>`) show the map's own
//! pixel frame, which is north-up too because row 0 of a map image is its top row.

use crate::convert::{GridStyle, affine, color, grid_image_transform, grid_rgba};
use crate::paths;
use crate::recorder::Recorder;
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::{Matrix2, Point2, Vector2};
use rerun::components::{DrawOrder, Radius};
use rerun::{Image, LineStrip2D, LineStrips2D};

/// Draw orders, bottom to top.
pub(crate) mod layer {
    /// The true map.
    pub const TRUTH_MAP: f32 = -30.0;
    /// Robots' maps.
    pub const MAP: f32 = -25.0;
    /// A merged map.
    pub const MERGED: f32 = -20.0;
    /// Walls.
    pub const WALLS: f32 = 5.0;
    /// Paths.
    pub const PATHS: f32 = 10.0;
    /// Scans.
    pub const SCAN: f32 = 20.0;
    /// Merge matches.
    pub const MATCHES: f32 = 25.0;
    /// Keypoints and particles.
    pub const POINTS: f32 = 30.0;
    /// Poses.
    pub const POSES: f32 = 40.0;
}

impl Recorder {
    /// Logs the display flip on every spatial root (static; see the module docs).
    pub fn log_display_frame(&mut self) {
        let flip = affine(&Matrix2::new(1.0, 0.0, 0.0, -1.0), &Vector2::zeros());
        for root in paths::SPATIAL_ROOTS {
            self.log_static(&paths::root(root), &flip);
        }
    }

    /// Logs the world's obstacles as closed outlines at `world/walls` (static).
    pub fn log_walls(&mut self, outlines: &[Vec<Point2<f64>>]) {
        let strips: Vec<LineStrip2D> = outlines
            .iter()
            .filter(|o| o.len() >= 2)
            .map(|o| {
                let mut pts: Vec<[f32; 2]> = o.iter().map(crate::convert::xy).collect();
                if o.len() > 2 {
                    pts.push(pts[0]);
                }
                LineStrip2D::from_iter(pts)
            })
            .collect();
        let arch = LineStrips2D::new(strips)
            .with_colors([color([200, 200, 200, 255])])
            .with_radii([Radius::new_ui_points(1.0)])
            .with_draw_order(DrawOrder::from(layer::WALLS));
        self.log_static(&paths::walls(), &arch);
    }

    /// Logs the true map at `world/truth_map` (static); the grid is in the world frame.
    pub fn log_truth_map(&mut self, grid: &OccupancyGrid) {
        self.log_grid(&paths::truth_map(), grid, &Pose2::identity(), &GridStyle::TRUTH, layer::TRUTH_MAP, true);
    }

    /// Logs `grid` as an RGBA image placed in its frame `frame` (the grid frame's pose in the parent entity's
    /// frame), static or at the current time.
    pub fn log_grid(
        &mut self,
        entity: &rerun::EntityPath,
        grid: &OccupancyGrid,
        frame: &Pose2,
        style: &GridStyle,
        draw_order: f32,
        is_static: bool,
    ) {
        // Raw pixels, not PNG: the viewer takes a time series of encoded images for a video stream, which may not
        // change size, and a map grows. The file is LZ4-compressed, which squeezes a map's uniform areas anyway.
        let pixels = grid_rgba(grid, style);
        let (w, h) = pixels.dimensions();
        let image = Image::from_rgba32(pixels.into_raw(), [w, h]).with_draw_order(DrawOrder::from(draw_order));
        let place = grid_image_transform(grid, frame);
        if is_static {
            self.log_static_all(entity, &[&place, &image]);
        } else {
            self.log_all(entity, &[&place, &image]);
        }
    }
}
