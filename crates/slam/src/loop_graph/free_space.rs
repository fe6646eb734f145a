//! What a submap saw as open floor, to judge a revisit whose loop search found nothing.
//!
//! A search that finds nothing is no evidence of a wrong map by itself: the robot may be in a room the submap
//! only glimpsed, or seeing through a wall what the submap did not. A scan whose surfaces lie on floor the
//! submap saw open, farther from every wall the submap saw than the search window lets the scan move, is
//! evidence: no pose the window allows puts the robot where it is, and the place the graph puts it looks
//! otherwise. A map whose loops were closed into a wrong building is full of such revisits; a good map has
//! almost none (a person walking, a door closed since).

use super::search::SearchWindow;
use crate::scan_matcher::{PreparedScan, ScanMatcher};
use mrslam_core::CellTraversal;
use mrslam_core::Xyt;

/// Beams that must cross a cell, with none ending in it, for the cell to count as open floor.
const OPEN_CROSSINGS: u16 = 2;
/// Cells at most in a free-space grid (a 30 m range at 0.1 m: about 0.36 million).
const MAX_CELLS: usize = 16 << 20;

/// The cells a submap's beams crossed and ended in, on a grid in its anchor's frame, with each cell's distance
/// to the nearest cell a beam ended in.
#[derive(Debug, Clone)]
pub struct FreeSpace {
    /// Cell (0, 0)'s corner, anchor frame, metres.
    origin: (f64, f64),
    /// Cell size, metres.
    cell: f64,
    width: usize,
    height: usize,
    /// Beams that crossed each cell without ending in it (saturating).
    crossed: Vec<u16>,
    /// Beams that ended in each cell (saturating).
    ended: Vec<u16>,
    /// Distance from each cell to the nearest cell a beam ended in, metres (chamfer: 1 and √2 cells).
    wall_distance: Vec<f32>,
}

/// How a scan placed at a pose agrees with a submap's free space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Judgement {
    /// The scan's points that fell on cells the submap saw (crossed or ended in).
    pub seen: usize,
    /// Of those, the points on open floor beyond the window's reach of every wall the submap saw.
    pub contradicting: usize,
}

impl FreeSpace {
    /// Traces the hits of `scans` (each with its robot pose in the anchor's frame) on a grid of `cell` metres.
    /// `None` when nothing was hit or the grid would be too large.
    pub fn build(scans: &[(Xyt, &PreparedScan)], matcher: &ScanMatcher, cell: f64) -> Option<Self> {
        let mut rays: Vec<((f64, f64), (f64, f64))> = Vec::new();
        let (mut x0, mut y0, mut x1, mut y1) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (pose, scan) in scans {
            let lp = matcher.laser_pose(pose);
            let (s, c) = lp.theta.sin_cos();
            for b in &scan.hits {
                let end = (lp.x + b.r * (c * b.c - s * b.s), lp.y + b.r * (s * b.c + c * b.s));
                for (x, y) in [(lp.x, lp.y), end] {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
                rays.push(((lp.x, lp.y), end));
            }
        }
        if rays.is_empty() || !(x1 - x0).is_finite() || !(y1 - y0).is_finite() {
            return None;
        }
        let origin = (x0 - cell, y0 - cell);
        let width = ((x1 - origin.0) / cell).ceil() as usize + 2;
        let height = ((y1 - origin.1) / cell).ceil() as usize + 2;
        if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
            return None;
        }
        let mut crossed = vec![0u16; width * height];
        let mut ended = vec![0u16; width * height];
        for (from, to) in rays {
            let at = |p: (f64, f64)| ((p.0 - origin.0) / cell, (p.1 - origin.1) / cell);
            let ((sx, sy), (ex, ey)) = (at(from), at(to));
            let trav = CellTraversal::new(sx, sy, ex, ey);
            let end = trav.end_cell();
            for (cx, cy) in trav {
                // Every cell lies inside: the grid spans every ray's two ends with a cell to spare.
                let i = cy as usize * width + cx as usize;
                if (cx, cy) == end {
                    ended[i] = ended[i].saturating_add(1);
                } else {
                    crossed[i] = crossed[i].saturating_add(1);
                }
            }
        }
        let wall_distance = chamfer(&ended, width, height, cell as f32);
        Some(FreeSpace { origin, cell, width, height, crossed, ended, wall_distance })
    }

    /// Places `points` (the scan's end points, robot frame) at `pose` (anchor frame) and counts those on cells the
    /// submap saw and those on its open floor farther from its walls than `window` moves them: the window's
    /// translation, plus its heading times the point's range, plus a cell.
    pub fn judge(&self, points: &[(f64, f64)], pose: &Xyt, window: SearchWindow) -> Judgement {
        let (s, c) = pose.theta.sin_cos();
        let mut judgement = Judgement::default();
        for &(x, y) in points {
            let (wx, wy) = (pose.x + c * x - s * y, pose.y + s * x + c * y);
            let (fx, fy) = ((wx - self.origin.0) / self.cell, (wy - self.origin.1) / self.cell);
            if !(fx >= 0.0 && fy >= 0.0 && fx < self.width as f64 && fy < self.height as f64) {
                continue;
            }
            let i = fy as usize * self.width + fx as usize;
            if self.crossed[i] == 0 && self.ended[i] == 0 {
                continue;
            }
            judgement.seen += 1;
            let reach = window.linear + window.angular * x.hypot(y) + self.cell;
            if self.ended[i] == 0 && self.crossed[i] >= OPEN_CROSSINGS && self.wall_distance[i] as f64 > reach {
                judgement.contradicting += 1;
            }
        }
        judgement
    }
}

/// Distance from every cell to the nearest cell with `ended > 0`, in metres of `cell`-sized steps (1 and √2 per
/// step: within 8 % of the Euclidean distance). Infinite where no cell was ended in.
fn chamfer(ended: &[u16], width: usize, height: usize, cell: f32) -> Vec<f32> {
    let (straight, diagonal) = (cell, cell * std::f32::consts::SQRT_2);
    let mut d: Vec<f32> = ended.iter().map(|&e| if e > 0 { 0.0 } else { f32::INFINITY }).collect();
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let mut v = d[i];
            if x > 0 {
                v = v.min(d[i - 1] + straight);
            }
            if y > 0 {
                v = v.min(d[i - width] + straight);
                if x > 0 {
                    v = v.min(d[i - width - 1] + diagonal);
                }
                if x + 1 < width {
                    v = v.min(d[i - width + 1] + diagonal);
                }
            }
            d[i] = v;
        }
    }
    for y in (0..height).rev() {
        for x in (0..width).rev() {
            let i = y * width + x;
            let mut v = d[i];
            if x + 1 < width {
                v = v.min(d[i + 1] + straight);
            }
            if y + 1 < height {
                v = v.min(d[i + width] + straight);
                if x + 1 < width {
                    v = v.min(d[i + width + 1] + diagonal);
                }
                if x > 0 {
                    v = v.min(d[i + width - 1] + diagonal);
                }
            }
            d[i] = v;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chamfer_distance_is_within_eight_percent_of_the_euclidean_one() {
        let (w, h) = (40, 30);
        let mut ended = vec![0u16; w * h];
        ended[12 * w + 7] = 1;
        let d = chamfer(&ended, w, h, 0.1);
        for y in 0..h {
            for x in 0..w {
                let truth = 0.1 * ((x as f32 - 7.0).hypot(y as f32 - 12.0));
                let got = d[y * w + x];
                assert!(got >= truth - 1e-5 && got <= 1.09 * truth + 1e-5, "({x}, {y}): {got} against {truth}");
            }
        }
    }
}
