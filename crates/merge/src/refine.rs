//! Refinement of an accepted-looking alignment on the maps themselves: point-to-point ICP between the walls.
//!
//! Features fix the transform to within a few cells; the walls, thousands of cells, fix it to within one.
//! Each iteration pairs every wall cell of b (placed by the current transform) with the nearest wall cell of
//! a within a search radius, and solves the rigid least-squares transform of the pairs (Umeyama/Kabsch).

use crate::estimate::Model;
use crate::estimate::fit;
use mrslam_core::floor_i64;
use mrslam_core::{CellState, OccupancyGrid, Pose2, pose};
use nalgebra::Point2;

/// ICP parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RefineParams {
    /// Run the refinement (false: the estimator's transform as it is, as the paper does).
    pub enabled: bool,
    /// Largest distance of a pair in the first iteration, in cells of map a.
    pub radius_cells: i64,
    /// Iterations (the radius shrinks to one cell over them).
    pub iterations: usize,
    /// Fewest pairs needed to trust an iteration.
    pub min_pairs: usize,
    /// Most of b's wall cells used (an even stride over them); 0 uses all.
    ///
    /// A few thousand pairs pin a rigid transform as well as fifteen thousand, at a quarter of the cost.
    #[serde(default)]
    pub max_points: usize,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams { enabled: true, radius_cells: 4, iterations: 20, min_pairs: 50, max_points: 4000 }
    }
}

/// Occupied cell centres of a grid, in its map frame.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
pub fn wall_points(g: &OccupancyGrid) -> Vec<Point2<f64>> {
    (0..g.height())
        .flat_map(|iy| (0..g.width()).map(move |ix| (ix, iy)))
        .filter(|&(ix, iy)| g.state(ix, iy) == CellState::Occupied)
        .map(|(ix, iy)| g.cell_center(ix as i64, iy as i64))
        .collect()
}

/// Refines `t_a_b` by ICP of b's walls onto a's walls; returns the input unchanged when too few pairs form.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
pub fn refine(a: &OccupancyGrid, walls_b: &[Point2<f64>], t_a_b: &Pose2, p: &RefineParams) -> Pose2 {
    let mut t = *t_a_b;
    if !p.enabled {
        return t;
    }
    let walls = WallBits::of(a, p.radius_cells.max(1));
    let stride = if p.max_points == 0 { 1 } else { walls_b.len().div_ceil(p.max_points).max(1) };
    let (mut pa, mut pb) = (Vec::with_capacity(walls_b.len()), Vec::with_capacity(walls_b.len()));
    let mut k = 0;
    while k < p.iterations {
        let r = radius_at(p, k);
        pa.clear();
        pb.clear();
        for q in walls_b.iter().step_by(stride) {
            let (fx, fy) = a.world_to_cell_f(&(t * q));
            let best = walls.nearest(fx, fy, r);
            if let Some((d, x, y)) = best
                && d <= (r * r) as f64
            {
                pa.push(a.cell_center(x, y));
                pb.push(*q);
            }
        }
        if pa.len() < p.min_pairs {
            return *t_a_b;
        }
        let Some(mat) = fit(Model::Rigid, &pa, &pb) else { return *t_a_b };
        let next = pose(mat[(0, 2)], mat[(1, 2)], mat[(1, 0)].atan2(mat[(0, 0)]));
        let settled = (next.translation.vector - t.translation.vector).norm() < 1e-6
            && (next.rotation.angle() - t.rotation.angle()).abs() < 1e-8;
        t = next;
        k += 1;
        // A fixed point stays one until the radius shrinks: go straight to the next radius.
        if settled {
            while k < p.iterations && radius_at(p, k) == r {
                k += 1;
            }
        }
    }
    t
}

/// A grid's occupied cells as rows of bits, with a margin of `2 r_max` cells on every side (a point up to
/// `r` cells outside the grid, searched `r` cells around, stays on the bitmap): no bounds checks or log-odds
/// in the search.
struct WallBits {
    /// Margin, cells.
    margin: i64,
    /// Grid size, cells.
    width: i64,
    height: i64,
    /// Words per row (one spare: a window read may touch the next word).
    words: usize,
    bits: Vec<u64>,
}

impl WallBits {
    fn of(a: &OccupancyGrid, r_max: i64) -> Self {
        let m = 2 * r_max;
        let (w, h) = (a.width() as i64, a.height() as i64);
        let words = ((w + 2 * m) as usize).div_ceil(64) + 1;
        let mut bits = vec![0u64; words * (h + 2 * m) as usize];
        for iy in 0..a.height() {
            for ix in 0..a.width() {
                if a.state(ix, iy) == CellState::Occupied {
                    let (row, col) = ((iy as i64 + m) as usize, (ix as i64 + m) as usize);
                    bits[row * words + col / 64] |= 1 << (col % 64);
                }
            }
        }
        WallBits { margin: m, width: w, height: h, words, bits }
    }

    /// Bits `col .. col + len` (`len <= 64`) of bitmap row `row`, lowest first.
    #[inline]
    fn window(&self, row: usize, col: usize, len: usize) -> u64 {
        let (i, s) = (row * self.words + col / 64, col % 64);
        let v = if s == 0 { self.bits[i] } else { (self.bits[i] >> s) | (self.bits[i + 1] << (64 - s)) };
        if len >= 64 { v } else { v & ((1u64 << len) - 1) }
    }

    /// The occupied cell nearest to continuous cell position (`fx`, `fy`) among the `2 r + 1` square cells
    /// around the one it falls in (`r` at most `r_max`), as (squared distance, ix, iy): the first in row-major
    /// order among equals, as a plain scan of the square finds it. None when there is none, or the point is
    /// more than `r` cells off the grid.
    fn nearest(&self, fx: f64, fy: f64, r: i64) -> Option<(f64, i64, i64)> {
        let (cx, cy) = (floor_i64(fx), floor_i64(fy));
        if cx < -r || cy < -r || cx >= self.width + r || cy >= self.height + r {
            return None;
        }
        let m = self.margin;
        let mut best: Option<(f64, i64, i64)> = None;
        let mut consider = |dx: i64, dy: i64| {
            let (ex, ey) = ((cx + dx) as f64 + 0.5 - fx, (cy + dy) as f64 + 0.5 - fy);
            let d = ex * ex + ey * ey;
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, cx + dx, cy + dy));
            }
        };
        for dy in -r..=r {
            let row = (cy + dy + m) as usize;
            if 2 * r < 63 {
                // Within a row, distance grows with the column's distance from the point's column, so only
                // the nearest wall on either side (and the point's own column) can win: offered in column
                // order, so ties go to the left as in a full scan.
                let bits = self.window(row, (cx - r + m) as usize, (2 * r + 1) as usize);
                let ru = r as u32;
                let left = bits & ((1u64 << ru) - 1);
                if left != 0 {
                    consider(63 - left.leading_zeros() as i64 - r, dy);
                }
                if bits >> ru & 1 == 1 {
                    consider(0, dy);
                }
                let right = bits >> (ru + 1);
                if right != 0 {
                    consider(1 + right.trailing_zeros() as i64, dy);
                }
                continue;
            }
            let (mut dx0, mut left) = (-r, (2 * r + 1) as usize);
            while left > 0 {
                let len = left.min(64);
                let mut bits = self.window(row, (cx + dx0 + m) as usize, len);
                while bits != 0 {
                    consider(dx0 + bits.trailing_zeros() as i64, dy);
                    bits &= bits - 1;
                }
                dx0 += len as i64;
                left -= len;
            }
        }
        best
    }
}

/// Search radius (cells) of iteration `k`: from `radius_cells` down to one.
fn radius_at(p: &RefineParams, k: usize) -> i64 {
    (p.radius_cells - (k as i64 * p.radius_cells) / p.iterations.max(1) as i64).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn nearest_wall_is_the_plain_scan_of_the_square() {
        let map = generate(9, &FloorplanParams::default());
        let walls = WallBits::of(&map, 40);
        let occupied = |x: i64, y: i64| {
            x >= 0
                && y >= 0
                && x < map.width() as i64
                && y < map.height() as i64
                && map.state(x as usize, y as usize) == CellState::Occupied
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut rnd = || rng.random::<f64>();
        let mut found = 0;
        for n in 0..4000 {
            let r = [1, 2, 4, 31, 32, 40][n % 6];
            let (fx, fy) = (rnd() * (map.width() + 20) as f64 - 10.0, rnd() * (map.height() + 20) as f64 - 10.0);
            // Ties: points on cell edges and centres.
            let (fx, fy) = if n % 5 == 0 { (fx.round(), (fy * 2.0).round() / 2.0) } else { (fx, fy) };
            let (cx, cy) = (fx.floor() as i64, fy.floor() as i64);
            let mut want: Option<(f64, i64, i64)> = None;
            if !(cx < -r || cy < -r || cx >= map.width() as i64 + r || cy >= map.height() as i64 + r) {
                for y in cy - r..=cy + r {
                    for x in cx - r..=cx + r {
                        if occupied(x, y) {
                            let (ex, ey) = (x as f64 + 0.5 - fx, y as f64 + 0.5 - fy);
                            let d = ex * ex + ey * ey;
                            if want.is_none_or(|b| d < b.0) {
                                want = Some((d, x, y));
                            }
                        }
                    }
                }
            }
            assert_eq!(walls.nearest(fx, fy, r), want, "({fx}, {fy}) r {r}");
            found += usize::from(want.is_some());
        }
        assert!(found > 1000, "{found}");
    }

    #[test]
    fn icp_pulls_a_near_miss_onto_the_walls() {
        let map = generate(9, &FloorplanParams::default());
        let walls = wall_points(&map);
        let off = pose(0.12, -0.08, 0.012); // 2-3 cells and 0.7 degrees off
        let fixed = refine(&map, &walls, &off, &RefineParams::default());
        assert!(fixed.translation.vector.norm() < 0.02, "{fixed:?}");
        assert!(fixed.rotation.angle().abs() < 0.002, "{fixed:?}");
        let same = refine(&map, &walls, &off, &RefineParams { enabled: false, ..Default::default() });
        assert_eq!(same, off);
    }

    #[test]
    fn points_at_and_beyond_the_edges_of_a_are_safe() {
        let map = generate(9, &FloorplanParams::default());
        let walls = wall_points(&map);
        // b's walls laid half off a, on every side: the search must stay inside its bitmap.
        let (w, h) = (map.width() as f64 * map.resolution(), map.height() as f64 * map.resolution());
        for (x, y) in [(-0.5 * w, 0.0), (0.5 * w, 0.0), (0.0, -0.5 * h), (0.0, 0.5 * h), (-w - 0.1, 0.0)] {
            let moved = pose(x, y, 0.3);
            let out = refine(&map, &walls, &moved, &RefineParams::default());
            assert!(out.translation.vector.iter().all(|v| v.is_finite()));
        }
    }
}
