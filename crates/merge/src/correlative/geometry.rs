//! Poses of b's scan in a's grid frame and transforms `T_a_b`, and how far apart two of them are.

use mrslam_core::{OccupancyGrid, Pose2, pose};
use mrslam_matching::{ScanPose, WallScan};
use nalgebra::{Point2, Rotation2};
use std::f64::consts::TAU;

/// Largest distance between where two transforms put the scan's points, metres.
pub(super) fn max_displacement(scan: &WallScan, t: &Pose2, u: &Pose2) -> f64 {
    scan.points.iter().map(|v| scan.centroid + v).map(|q| (t * q - u * q).norm()).fold(0.0, f64::max)
}

/// Angle difference wrapped to [0, π].
pub(super) fn angle_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

/// `T_a_b` of a scan pose: b's centroid `c` turned by θ lands at `t` in a's grid frame.
pub(super) fn to_transform(a: &OccupancyGrid, c: &Point2<f64>, p: &ScanPose) -> Pose2 {
    let rc = Rotation2::new(p.theta) * c.coords;
    *a.origin() * pose(p.tx - rc.x, p.ty - rc.y, p.theta)
}

/// The scan pose of `T_a_b` for a scan about centroid `c`: its rotation, and where `c` lands in a's grid frame.
pub(super) fn to_scan_pose(a: &OccupancyGrid, c: &Point2<f64>, t_a_b: &Pose2) -> ScanPose {
    let t_g_b = a.origin().inverse() * t_a_b;
    let q = t_g_b * c;
    ScanPose { theta: t_g_b.rotation.angle(), tx: q.x, ty: q.y }
}
