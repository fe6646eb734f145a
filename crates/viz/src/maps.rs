//! Robots' maps as they grow, and the merge: keypoints on both maps, inlier matches, the merged map.

use crate::convert::{GridStyle, Rgba, color, grid_grey, grid_image_transform, pose_transform, xy};
use crate::recorder::Recorder;
use crate::world::layer;
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use rerun::components::{DrawOrder, Radius};
use rerun::{EntityPath, Image, LineStrip2D, LineStrips2D, Points2D};

/// Largest distance, metres, between the two ends of a match (placed by the truth, or by the estimate) for it to
/// count as good.
pub const MATCH_GOOD_M: f64 = 0.5;
/// Colour of a match whose two ends agree (in the truth, when known).
pub const MATCH_GOOD: Rgba = [40, 200, 80, 255];
/// Colour of a match whose two ends disagree.
pub const MATCH_BAD: Rgba = [235, 50, 50, 255];

impl Recorder {
    /// Logs a robot's map at the current time: drawn in the robot's colour, placed in `frame` (the map
    /// frame's pose in the parent's frame).
    pub fn log_map(&mut self, entity: &EntityPath, grid: &OccupancyGrid, frame: &Pose2, c: Rgba) {
        self.log_grid(entity, grid, frame, &GridStyle::tinted(c), layer::MAP, false);
    }

    /// Logs a map in map_server's greys (occupied 0, free 254, unknown 205), one byte a cell, placed in `frame`, at
    /// the current time.
    pub fn log_grey_map(&mut self, entity: &EntityPath, grid: &OccupancyGrid, frame: &Pose2) {
        let (w, h) = (grid.width() as u32, grid.height() as u32);
        let image = Image::from_l8(grid_grey(grid), [w, h]).with_draw_order(DrawOrder::from(layer::MAP));
        self.log_all(entity, &[&grid_image_transform(grid, frame), &image]);
    }

    /// Logs a merged map at the current time, in grey, placed in `frame`.
    pub fn log_merged_map(&mut self, entity: &EntityPath, grid: &OccupancyGrid, frame: &Pose2) {
        self.log_grid(entity, grid, frame, &GridStyle::GREY, layer::MERGED, false);
    }

    /// Logs keypoints (in their map's frame, placed at `frame` in the parent's) as dots, at the current time.
    pub fn log_keypoints(&mut self, entity: &EntityPath, points: &[Point2<f64>], frame: &Pose2, c: Rgba) {
        let arch = Points2D::new(points.iter().map(xy))
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(3.0)])
            .with_draw_order(DrawOrder::from(layer::POINTS));
        self.log_all(entity, &[&pose_transform(frame), &arch]);
    }

    /// Logs matches as segments (both ends in the entity's frame), one colour each, at the current time.
    pub fn log_matches(&mut self, entity: &EntityPath, segments: &[(Point2<f64>, Point2<f64>)], colors: &[Rgba]) {
        let arch = LineStrips2D::new(segments.iter().map(|(a, b)| LineStrip2D::from_iter([xy(a), xy(b)])))
            .with_colors(colors.iter().map(|c| color(*c)))
            .with_radii([Radius::new_ui_points(1.2)])
            .with_draw_order(DrawOrder::from(layer::MATCHES));
        self.log(entity, &arch);
    }
}
