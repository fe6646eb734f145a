//! The fine stage: the best of a small window of angles and cell offsets around a global answer, on a score
//! field at map a's own resolution; each angle's offsets by branch and bound over the field's max-pooled pyramid
//! (exact: the best an exhaustive scan finds).

use super::pyramid::Pyramid;
use super::scan::WallScan;
use super::search::{Best, Window, branch_and_bound};

/// A pose of b's scan in map a's grid frame: turn `theta` about the scan's centroid, which lands at `t`
/// (metres from a's cell (0, 0) corner, along a's grid axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanPose {
    /// Rotation, radians.
    pub theta: f64,
    /// Where the centroid lands, x, metres.
    pub tx: f64,
    /// Where the centroid lands, y, metres.
    pub ty: f64,
}

/// What the fine window spans around a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalWindow {
    /// Offsets tried either side, cells of the field.
    pub cells: i32,
    /// Angles tried either side of the pose's.
    pub angles: usize,
    /// Angular step, radians.
    pub angle_step: f64,
}

/// The best pose within `window` of `start` on `field` (cells of `cell` metres), and its score.
///
/// Ties go to the first angle (from the lowest), within an angle to the offset the branch and bound reaches
/// first: deterministic.
pub fn local_search(
    field: &Pyramid,
    cell: f64,
    scan: &WallScan,
    start: ScanPose,
    window: &LocalWindow,
    points: &mut Vec<(i32, i32)>,
) -> (ScanPose, i64) {
    let (cx, cy) = ((start.tx / cell - 0.5).round() as i32, (start.ty / cell - 0.5).round() as i32);
    let offsets = Window { x0: cx - window.cells, x1: cx + window.cells, y0: cy - window.cells, y1: cy + window.cells };
    let mut roots = Vec::new();
    let mut best = (start, i64::MIN);
    let n = window.angles as i64;
    for j in -n..=n {
        let theta = start.theta + j as f64 * window.angle_step;
        scan.discretize(theta, cell, points);
        // Only a strictly better offset replaces the best of the angles before (as a scan in this order would).
        let floor = if best.1 == i64::MIN { i64::MIN } else { best.1 + 1 };
        let mut found = Best::new(1, 1, floor);
        branch_and_bound(field, points, offsets, &mut found, &mut roots);
        if let Some(c) = found.found.first() {
            let pose = ScanPose { theta, tx: cell * (f64::from(c.ox) + 0.5), ty: cell * (f64::from(c.oy) + 0.5) };
            best = (pose, c.score);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::super::field::ScoreField;
    use super::*;
    use nalgebra::Point2;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_pruned_search_finds_the_exhaustive_best() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for trial in 0..10 {
            let (w, h) = (60, 50);
            let values = (0..w * h).map(|_| rng.random_range(-20i16..=100)).collect();
            let field = ScoreField { width: w, height: h, values };
            let all: Vec<Point2<f64>> =
                (0..40).map(|_| Point2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0))).collect();
            let scan = WallScan::of_points(&all, 0);
            let start = ScanPose { theta: 0.3, tx: 1.2, ty: 1.1 };
            let window = LocalWindow { cells: 6, angles: 2, angle_step: 0.05 };
            let mut pts = Vec::new();
            let flat = local_search(&Pyramid::build(&field, 0), 0.05, &scan, start, &window, &mut pts);
            let deep = local_search(&Pyramid::build(&field, 1 + trial % 4), 0.05, &scan, start, &window, &mut pts);
            assert_eq!(flat.1, deep.1, "trial {trial}");
        }
    }
}
