//! The fine stage: an exhaustive search of a small window of angles and cell offsets around a global answer,
//! on a score field at map a's own resolution.

use super::pyramid::PooledGrid;
use super::scan::WallScan;

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
/// Ties go to the first angle (from the lowest), then the lowest offset row, then column: deterministic.
pub fn local_search(
    field: &PooledGrid,
    cell: f64,
    scan: &WallScan,
    start: ScanPose,
    window: &LocalWindow,
    points: &mut Vec<(i32, i32)>,
) -> (ScanPose, i64) {
    let (cx, cy) = ((start.tx / cell - 0.5).round() as i32, (start.ty / cell - 0.5).round() as i32);
    let mut best = (start, i64::MIN);
    let n = window.angles as i64;
    for j in -n..=n {
        let theta = start.theta + j as f64 * window.angle_step;
        scan.discretize(theta, cell, points);
        for oy in cy - window.cells..=cy + window.cells {
            for ox in cx - window.cells..=cx + window.cells {
                let s = field.score(points, ox, oy);
                if s > best.1 {
                    let pose = ScanPose { theta, tx: cell * (f64::from(ox) + 0.5), ty: cell * (f64::from(oy) + 0.5) };
                    best = (pose, s);
                }
            }
        }
    }
    best
}
