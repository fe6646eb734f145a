//! Evaluation against ground truth, which only the evaluator knows.

use mrslam_core::{OccupancyGrid, Pose2};
use mrslam_merge::agreement;

/// Root-mean-square position error of `estimate` against `truth`, pairwise, metres (0 for no pairs).
pub fn rmse(estimate: &[Pose2], truth: &[Pose2]) -> f64 {
    let n = estimate.len().min(truth.len());
    if n == 0 {
        return 0.0;
    }
    let s: f64 =
        estimate.iter().zip(truth).map(|(e, t)| (e.translation.vector - t.translation.vector).norm_squared()).sum();
    (s / n as f64).sqrt()
}

/// Rotation error (radians, absolute) and translation error (metres) of an estimated transform.
pub fn transform_error(estimate: &Pose2, truth: &Pose2) -> (f64, f64) {
    let d = estimate.inverse() * truth;
    (d.rotation.angle().abs(), (estimate.translation.vector - truth.translation.vector).norm())
}

/// Carpin's acceptance index of `map` (in its own frame, placed in the world by `t_world_map`) against the
/// true map.
pub fn map_acceptance(truth: &OccupancyGrid, map: &OccupancyGrid, t_world_map: &Pose2) -> f64 {
    agreement(truth, map, t_world_map).acceptance_index()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn rmse_and_transform_error() {
        let a = [pose(0.0, 0.0, 0.0), pose(1.0, 0.0, 0.0)];
        let b = [pose(0.0, 0.3, 0.0), pose(1.0, -0.4, 1.0)];
        assert!((rmse(&a, &b) - (0.125f64).sqrt()).abs() < 1e-12);
        let (r, t) = transform_error(&pose(1.0, 2.0, 0.1), &pose(1.3, 2.4, -0.1));
        assert!((r - 0.2).abs() < 1e-12 && (t - 0.5).abs() < 1e-12);
    }
}
