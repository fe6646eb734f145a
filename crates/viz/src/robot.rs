//! A robot: poses (true, odometry, SLAM), paths, its particles and its current scan.

use crate::convert::{Rgba, color, heading, pose_transform, pose_xy, ramp, xy};
use crate::recorder::Recorder;
use crate::world::layer;
use mrslam_core::Pose2;
use nalgebra::Point2;
use rerun::components::{DrawOrder, Radius};
use rerun::{Arrows2D, EntityPath, LineStrip2D, LineStrips2D, Points2D};

/// Length of a drawn robot pose arrow, metres.
pub const POSE_ARROW_M: f64 = 0.4;
/// Length of a drawn particle arrow, metres.
pub const PARTICLE_ARROW_M: f64 = 0.15;

impl Recorder {
    /// Logs a frame: the pose of `entity`'s frame in its parent's (static or at the current time).
    pub fn log_frame(&mut self, entity: &EntityPath, pose: &Pose2, is_static: bool) {
        let t = pose_transform(pose);
        if is_static { self.log_static(entity, &t) } else { self.log(entity, &t) }
    }

    /// Logs a pose as an arrow of `color` with a label (none when empty), at the current time.
    pub fn log_pose(&mut self, entity: &EntityPath, pose: &Pose2, c: Rgba, label: &str) {
        let mut arch = Arrows2D::from_vectors([heading(pose, POSE_ARROW_M)])
            .with_origins([pose_xy(pose)])
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(2.5)])
            .with_draw_order(DrawOrder::from(layer::POSES));
        if !label.is_empty() {
            arch = arch.with_labels([label]);
        }
        self.log(entity, &arch);
    }

    /// Logs a path as one line strip, at the current time.
    pub fn log_path<'a>(&mut self, entity: &EntityPath, poses: impl IntoIterator<Item = &'a Pose2>, c: Rgba) {
        let strip: Vec<[f32; 2]> = poses.into_iter().map(pose_xy).collect();
        let arch = LineStrips2D::new([LineStrip2D::from_iter(strip)])
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(1.0)])
            .with_draw_order(DrawOrder::from(layer::PATHS));
        self.log(entity, &arch);
    }

    /// Logs a goal as a large dot with a label (none when empty), at the current time.
    pub fn log_goal(&mut self, entity: &EntityPath, goal: &Point2<f64>, c: Rgba, label: &str) {
        let mut arch = Points2D::new([xy(goal)])
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(6.0)])
            .with_draw_order(DrawOrder::from(layer::POSES));
        if !label.is_empty() {
            arch = arch.with_labels([label]);
        }
        self.log(entity, &arch);
    }

    /// Logs a planned path (points in the parent's frame) as one thin line strip, at the current time.
    pub fn log_plan(&mut self, entity: &EntityPath, points: &[Point2<f64>], c: Rgba) {
        let arch = LineStrips2D::new([LineStrip2D::from_iter(points.iter().map(xy))])
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(1.5)])
            .with_draw_order(DrawOrder::from(layer::PATHS));
        self.log(entity, &arch);
    }

    /// Logs scan end points (already in the parent's frame) as small dots, at the current time.
    pub fn log_scan_points(&mut self, entity: &EntityPath, points: &[Point2<f64>], c: Rgba) {
        let arch = Points2D::new(points.iter().map(xy))
            .with_colors([color(c)])
            .with_radii([Radius::new_ui_points(1.5)])
            .with_draw_order(DrawOrder::from(layer::SCAN));
        self.log(entity, &arch);
    }

    /// Logs particles (pose, normalised weight) as short arrows coloured by weight relative to the heaviest
    /// (dark: light, yellow: heavy), with the weight as label, at the current time.
    pub fn log_particles(&mut self, entity: &EntityPath, particles: &[(Pose2, f64)]) {
        let max = particles.iter().map(|p| p.1).fold(0.0_f64, f64::max);
        let rel = |w: f64| if max > 0.0 { w / max } else { 0.0 };
        let arch = Arrows2D::from_vectors(particles.iter().map(|(p, _)| heading(p, PARTICLE_ARROW_M)))
            .with_origins(particles.iter().map(|(p, _)| pose_xy(p)))
            .with_colors(particles.iter().map(|(_, w)| color(ramp(rel(*w)))))
            .with_radii(particles.iter().map(|(_, w)| Radius::new_ui_points(1.0 + 1.5 * rel(*w) as f32)))
            .with_labels(particles.iter().map(|(_, w)| format!("w={w:.3}")))
            .with_show_labels(false)
            .with_draw_order(DrawOrder::from(layer::POINTS));
        self.log(entity, &arch);
    }
}
