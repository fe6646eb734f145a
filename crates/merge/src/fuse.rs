//! Fusion: one grid in map a's frame holding both maps (paper Alg. 3, line 8).

use crate::resample::{GridGeometry, covering_geometry, known_corners};
use mrslam_core::floor_i64;
use mrslam_core::{CellState, OccupancyGrid, Pose2};
use nalgebra::Point2;

/// How two aligned cells combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FusionRule {
    /// Sum the log-odds (independent evidence), clamped to ±`clamp`.
    LogOddsSum,
    /// m-explore's composition: occupied beats free beats unknown.
    OccupiedFreeUnknown,
}

impl FusionRule {
    /// Every rule, as the command line lists them.
    pub const ALL: [FusionRule; 2] = [FusionRule::LogOddsSum, FusionRule::OccupiedFreeUnknown];

    /// The name: `log-odds-sum` or `occupied-free-unknown`.
    pub const fn name(self) -> &'static str {
        match self {
            FusionRule::LogOddsSum => "log-odds-sum",
            FusionRule::OccupiedFreeUnknown => "occupied-free-unknown",
        }
    }
}

impl std::str::FromStr for FusionRule {
    type Err = String;
    /// Reads a name of [`FusionRule::ALL`], or the same with underscores (as JSON writes it).
    fn from_str(s: &str) -> Result<Self, String> {
        FusionRule::ALL
            .into_iter()
            .find(|r| r.name() == s || r.name().replace('-', "_") == s)
            .ok_or_else(|| format!("unknown fusion rule `{s}` (expected log-odds-sum or occupied-free-unknown)"))
    }
}

/// Log-odds clamp of fused cells.
pub const FUSION_CLAMP: f32 = 3.5;

/// Fuses `b`, placed by `t_a_b`, into a grid in a's map frame covering both maps' known cells, at a's
/// resolution.
///
/// Each fused cell takes, from each map, the log-odds of the cell under its centre (nearest neighbour;
/// 0 where the map does not reach), and the two combine by `rule`. Map a shares the fused grid's axes
/// and resolution, so its cells are copied row by row; only b's are transformed, and only over the
/// columns of each row that b's grid can reach.
pub fn fuse(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2, rule: FusionRule) -> OccupancyGrid {
    let mut pts = known_corners(a, &Pose2::identity()).to_vec();
    pts.extend_from_slice(&known_corners(b, t_a_b));
    let geo: GridGeometry = covering_geometry(&pts, a.resolution());
    let (w, h) = (geo.width, geo.height);
    let mut cells = vec![0.0f32; w * h];
    // Map a's values; cells a does not reach stay 0 (as "unknown" in the rule).
    for_each_row_span(&geo, a, &Pose2::identity(), |j, i0, map| {
        let row = &mut cells[j * w..(j + 1) * w];
        match map {
            Mapping::Shift { ix0, iy } => {
                let src = &a.cells()[iy * a.width() + ix0..(iy + 1) * a.width()];
                let n = (w - i0).min(src.len());
                row[i0..i0 + n].copy_from_slice(&src[..n]);
            }
            Mapping::Sample { i1, start, step } => {
                for (i, v) in row.iter_mut().enumerate().take(i1).skip(i0) {
                    if let Some(l) = sample(a, start, step, i) {
                        *v = l;
                    }
                }
            }
        }
    });
    // Map b's values combined in; every cell combines (with 0 where b does not reach).
    let combine = |x: f32, y: f32| match rule {
        FusionRule::LogOddsSum => (x + y).clamp(-FUSION_CLAMP, FUSION_CLAMP),
        FusionRule::OccupiedFreeUnknown => {
            // The cell takes the value of whichever map says more (occupied > free > unknown); a wins ties.
            if CellState::from_log_odds(y) > CellState::from_log_odds(x) { y } else { x }
        }
    };
    let alone = |cells: &mut [f32]| {
        for v in cells {
            *v = combine(*v, 0.0);
        }
    };
    // b's rows in bands, each band walked in column tiles: neighbouring target cells read neighbouring
    // cells of b, whatever the rotation, so b's cells come from cache.
    let mut spans: Vec<(usize, usize, Mapping)> = Vec::new();
    for_each_row_span(&geo, b, t_a_b, |j, i0, map| spans.push((j, i0, map)));
    let end = |i0: usize, map: &Mapping| match *map {
        Mapping::Shift { ix0, .. } => i0 + (w - i0).min(b.width() - ix0),
        Mapping::Sample { i1, .. } => i1,
    };
    const BAND: usize = 16;
    const TILE: usize = 64;
    let mut done = 0; // rows combined so far
    for band in spans.chunk_by(|p, q| p.0 / BAND == q.0 / BAND) {
        let (lo, hi) = band.iter().fold((w, 0), |(lo, hi), (_, i0, map)| (lo.min(*i0), hi.max(end(*i0, map))));
        let mut t0 = lo;
        while t0 < hi {
            let t1 = (t0 + TILE).min(hi);
            for &(j, i0, map) in band {
                let (a0, a1) = (i0.max(t0), end(i0, &map).min(t1));
                let row = &mut cells[j * w..(j + 1) * w];
                match map {
                    Mapping::Shift { ix0, iy } => {
                        let src = &b.cells()[iy * b.width()..(iy + 1) * b.width()];
                        for i in a0..a1 {
                            row[i] = combine(row[i], src[ix0 + i - i0]);
                        }
                    }
                    Mapping::Sample { start, step, .. } => {
                        for (i, v) in row.iter_mut().enumerate().take(a1).skip(a0) {
                            *v = combine(*v, sample(b, start, step, i).unwrap_or(0.0));
                        }
                    }
                }
            }
            t0 = t1;
        }
        // The rest of each row (and the rows b does not reach) combine with 0.
        for &(j, i0, map) in band {
            alone(&mut cells[done * w..j * w]);
            let row = &mut cells[j * w..(j + 1) * w];
            let (head, rest) = row.split_at_mut(i0);
            alone(head);
            alone(&mut rest[end(i0, &map) - i0..]);
            done = j + 1;
        }
    }
    alone(&mut cells[done * w..]);
    OccupancyGrid::from_cells(w, h, geo.resolution, geo.origin, cells).expect("fused geometry is valid by construction")
}

/// How one row of the target grid meets a source grid.
#[derive(Debug, Clone, Copy)]
enum Mapping {
    /// Same axes and resolution: target columns `i0..` show source row `iy` from column `ix0` on.
    Shift { ix0: usize, iy: usize },
    /// General: target column `i` has its centre at source cell coordinates `start + i * step`; only
    /// columns `i0 .. i1` can fall on the source grid.
    Sample { i1: usize, start: (f64, f64), step: (f64, f64) },
}

/// The source log-odds under target column `i` of a sampled row.
#[inline]
fn sample(src: &OccupancyGrid, start: (f64, f64), step: (f64, f64), i: usize) -> Option<f32> {
    let (x, y) = (start.0 + i as f64 * step.0, start.1 + i as f64 * step.1);
    // For x >= 0, truncation is the floor (and cheaper than a `floor` call without SSE4.1).
    if x >= 0.0 && y >= 0.0 && x < src.width() as f64 && y < src.height() as f64 {
        Some(src.cells()[y as usize * src.width() + x as usize])
    } else {
        None
    }
}

/// Calls `f(row, first_column, mapping)` for every row of `target` that `src` (placed by `t_target_src`)
/// can reach, in row order, with the columns it can reach.
fn for_each_row_span(
    target: &GridGeometry,
    src: &OccupancyGrid,
    t_target_src: &Pose2,
    mut f: impl FnMut(usize, usize, Mapping),
) {
    let t_src_target = t_target_src.inverse();
    let res = target.resolution;
    let src_of = |x: f64, y: f64| {
        let p = target.origin * Point2::new(x * res, y * res);
        src.world_to_cell_f(&(t_src_target * p))
    };
    let a = src_of(0.5, 0.5);
    let b = src_of(1.5, 0.5);
    let c = src_of(0.5, 1.5);
    let u = (b.0 - a.0, b.1 - a.1);
    let v = (c.0 - a.0, c.1 - a.1);
    let (sw, sh) = (src.width() as f64, src.height() as f64);
    let (tw, th) = (target.width, target.height);
    if sw == 0.0 || sh == 0.0 || tw == 0 {
        return;
    }
    let exact = |d: f64, want: f64| (d - want).abs() < 1e-9;
    if exact(u.0, 1.0) && exact(u.1, 0.0) && exact(v.0, 0.0) && exact(v.1, 1.0) {
        // Column i of row j shows source cell (floor(a.0) + i, floor(a.1) + j).
        let (fx, fy) = (floor_i64(a.0), floor_i64(a.1));
        for j in 0..th {
            let iy = fy + j as i64;
            if iy < 0 || iy >= src.height() as i64 {
                continue;
            }
            let i0 = (-fx).max(0);
            let ix0 = fx + i0;
            if i0 >= tw as i64 || ix0 >= src.width() as i64 {
                continue;
            }
            f(j, i0 as usize, Mapping::Shift { ix0: ix0 as usize, iy: iy as usize });
        }
        return;
    }
    for j in 0..th {
        let start = (a.0 + j as f64 * v.0, a.1 + j as f64 * v.1);
        // Columns where 0 <= start + i step < size in both coordinates, widened by a cell (the exact
        // test is made per cell).
        let (mut lo, mut hi) = (0.0f64, tw as f64);
        for (s0, d, size) in [(start.0, u.0, sw), (start.1, u.1, sh)] {
            if d.abs() < 1e-12 {
                if s0 < 0.0 || s0 >= size {
                    hi = lo;
                }
            } else {
                let (p, q) = ((0.0 - s0) / d, (size - s0) / d);
                lo = lo.max(p.min(q) - 1.0);
                hi = hi.min(p.max(q) + 1.0);
            }
        }
        if hi <= lo {
            continue;
        }
        let (i0, i1) = (lo.max(0.0).floor() as usize, (hi.ceil().max(0.0) as usize).min(tw));
        if i0 < i1 {
            f(j, i0, Mapping::Sample { i1, start, step: u });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn fused_grid_covers_both_and_combines() {
        let mut a = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let mut b = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        a.set(5, 5, -2.0);
        b.set(0, 5, 2.0); // lands on a's (5, 5) when b is shifted by 0.5 m
        b.set(9, 9, -2.0);
        let t = pose(0.5, 0.0, 0.0);
        let at = |g: &OccupancyGrid, x: f64, y: f64| {
            let c = g.world_to_cell(&nalgebra::Point2::new(x, y)).expect("on the fused grid");
            g.state(c.0, c.1)
        };
        let sum = fuse(&a, &b, &t, FusionRule::LogOddsSum);
        // the fused grid spans the known cells of both: x 0.5..1.5 m, y 0.5..1.0 m
        assert_eq!((sum.width(), sum.height()), (10, 5));
        assert_eq!(at(&sum, 0.55, 0.55), CellState::Unknown, "-2 + 2 = 0");
        assert_eq!(at(&sum, 1.45, 0.95), CellState::Free);
        let ofu = fuse(&a, &b, &t, FusionRule::OccupiedFreeUnknown);
        assert_eq!(at(&ofu, 0.55, 0.55), CellState::Occupied);
        assert_eq!(at(&ofu, 1.45, 0.95), CellState::Free);
        assert_eq!(at(&ofu, 0.95, 0.75), CellState::Unknown);
    }

    /// The straightforward fusion: both maps sampled over the whole fused grid, then combined.
    fn fuse_reference(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2, rule: FusionRule) -> OccupancyGrid {
        use crate::resample::sample_cells;
        let mut pts = known_corners(a, &Pose2::identity()).to_vec();
        pts.extend_from_slice(&known_corners(b, t_a_b));
        let geo = covering_geometry(&pts, a.resolution());
        let mut la = vec![0.0f32; geo.width * geo.height];
        let mut lb = vec![0.0f32; geo.width * geo.height];
        sample_cells(&geo, a, &Pose2::identity(), |i, l| la[i] = l);
        sample_cells(&geo, b, t_a_b, |i, l| lb[i] = l);
        let cells = la
            .iter()
            .zip(&lb)
            .map(|(&x, &y)| match rule {
                FusionRule::LogOddsSum => (x + y).clamp(-FUSION_CLAMP, FUSION_CLAMP),
                FusionRule::OccupiedFreeUnknown => {
                    if CellState::from_log_odds(y) > CellState::from_log_odds(x) {
                        y
                    } else {
                        x
                    }
                }
            })
            .collect();
        OccupancyGrid::from_cells(geo.width, geo.height, geo.resolution, geo.origin, cells).unwrap()
    }

    #[test]
    fn row_spans_match_the_straightforward_fusion() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut rnd = || rng.random::<f64>();
        for case in 0..24 {
            let (wa, ha, wb, hb) = (30 + case * 3, 25 + case * 2, 41 - case, 33 + case % 5);
            let yaw_a = if case % 5 == 0 { 0.3 } else { 0.0 };
            let mut a = OccupancyGrid::new(wa, ha, 0.1, pose(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, yaw_a)).unwrap();
            let mut b = OccupancyGrid::new(wb, hb, 0.1, pose(0.3, -0.2, 0.0)).unwrap();
            for c in a.cells_mut().iter_mut().chain(b.cells_mut().iter_mut()) {
                let r = rnd();
                *c = if r < 0.3 {
                    0.0
                } else if r < 0.6 {
                    -2.0
                } else if r < 0.7 {
                    2.0
                } else {
                    (r as f32 - 0.85) * 12.0
                };
            }
            // Rotated, axis-aligned (pure shift) and quarter-turn placements.
            let theta = match case % 4 {
                0 => 0.0,
                1 => std::f64::consts::FRAC_PI_2,
                _ => rnd() * 6.0 - 3.0,
            };
            let t = pose(rnd() * 3.0 - 1.5, rnd() * 3.0 - 1.5, theta);
            for rule in [FusionRule::LogOddsSum, FusionRule::OccupiedFreeUnknown] {
                let got = fuse(&a, &b, &t, rule);
                let want = fuse_reference(&a, &b, &t, rule);
                assert_eq!((got.width(), got.height()), (want.width(), want.height()));
                let differ = got.cells().iter().zip(want.cells()).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
                assert_eq!(differ, 0, "case {case} {rule:?}: {differ} cells differ");
            }
        }
    }
}
