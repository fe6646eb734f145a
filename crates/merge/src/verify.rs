//! Verification of a merge before it is trusted: inlier support and map agreement.
//!
//! Two independent checks. Feature support: the inlier count and m-explore's confidence
//! `inliers / (8 + 0.3 · matches)`. Map consistency: Carpin's acceptance index
//! ω = agree / (agree + disagree) over cells known in both aligned maps (Carpin, "Fast and accurate map
//! merging for multi-robot systems", 2008), computed over enough common cells to mean something.

use crate::resample::{GridGeometry, sample_cells};
use mrslam_core::{CellState, OccupancyGrid, Pose2};
use nalgebra::{Point2, Translation2};

/// Thresholds a merge must pass to be accepted.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VerifyParams {
    /// Fewest inlier matches.
    pub min_inliers: usize,
    /// Lowest m-explore confidence `inliers / (8 + 0.3 · matches)` (m-explore's default threshold is 1.0).
    pub min_confidence: f64,
    /// Lowest acceptance index over the common known cells.
    pub min_acceptance: f64,
    /// Fewest cells known in both maps for the acceptance index to count.
    pub min_common_cells: usize,
    /// Lowest share of b's walls meeting a's walls ([`Agreement::wall_agreement`]).
    pub min_wall_agreement: f64,
    /// Reject when b slid by [`VerifyParams::ambiguity_shift_m`] in some direction keeps this share (or more) of
    /// the walls it matched in place: the maps then do not pin the transform down (a corridor's length).
    pub max_ambiguity: f64,
    /// Slide used by the ambiguity check, metres.
    pub ambiguity_shift_m: f64,
    /// Reject when another hypothesis, distinct from the accepted one, also passes the gate with at least this
    /// share of its wall agreement: two different transforms fit, as when a symmetric map's halves can be laid
    /// end to end. Only algorithms returning alternatives are affected; above 1 turns the check off.
    #[serde(default = "default_max_rival_ratio")]
    pub max_rival_ratio: f64,
    /// A wall of b meets a wall of a ([`Agreement::walls_matched`]) when an occupied cell of a lies within this
    /// many cells of it (in x and in y; 1: the 3x3 neighbourhood). Maps that two
    /// robots made have walls a cell or two apart where the two SLAM runs disagree (ACES: 47-59 % of the walls
    /// within one cell at the right transform, 60 % needed); on generated and willow pairs 2 cells changed no
    /// decision (BENCHMARKS.md, Merge). The rival check compares walls within one cell regardless.
    #[serde(default = "default_wall_tolerance_cells")]
    pub wall_tolerance_cells: usize,
}

fn default_max_rival_ratio() -> f64 {
    0.9
}

fn default_wall_tolerance_cells() -> usize {
    2
}

impl Default for VerifyParams {
    /// Chosen by measurement on generated pairs (BENCHMARKS.md, merge): no gap pair passes.
    fn default() -> Self {
        VerifyParams {
            min_inliers: 4,
            min_confidence: 0.2,
            min_acceptance: 0.9,
            min_common_cells: 200,
            min_wall_agreement: 0.6,
            max_ambiguity: 0.85,
            ambiguity_shift_m: 1.0,
            max_rival_ratio: default_max_rival_ratio(),
            wall_tolerance_cells: default_wall_tolerance_cells(),
        }
    }
}

/// Agreement of two aligned maps.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Agreement {
    /// Cells known in both maps with the same state.
    pub agree: usize,
    /// Cells known in both maps with opposite states (free in one, occupied in the other).
    pub disagree: usize,
    /// Occupied cells of b that land on known cells of a.
    pub walls: usize,
    /// Of those, the ones with an occupied cell of a within one cell (8-neighbourhood).
    pub walls_matched: usize,
}

impl Agreement {
    /// Carpin's acceptance index ω = agree / (agree + disagree); 0 when no cell is known in both.
    pub fn acceptance_index(&self) -> f64 {
        let n = self.agree + self.disagree;
        if n == 0 { 0.0 } else { self.agree as f64 / n as f64 }
    }

    /// Cells known in both maps.
    pub fn common(&self) -> usize {
        self.agree + self.disagree
    }

    /// Share of b's walls over a's known cells that meet a wall of a within one cell; 0 when none.
    ///
    /// Free space dominates indoor maps, so a wrong alignment can still score a high acceptance index by
    /// laying free on free; walls laid on walls are much rarer by chance.
    pub fn wall_agreement(&self) -> f64 {
        if self.walls == 0 { 0.0 } else { self.walls_matched as f64 / self.walls as f64 }
    }
}

/// Compares map `a` with map `b` placed in a's frame by `t_a_b`, over the cells of `a`; a wall of b meets a
/// wall of a within one cell.
pub fn agreement(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2) -> Agreement {
    agreement_within(a, b, t_a_b, 1)
}

/// [`agreement`] with a wall of b meeting a wall of a within `tolerance` cells (in x and in y).
pub fn agreement_within(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2, tolerance: usize) -> Agreement {
    let cells = a.cells();
    let (w, h) = (a.width(), a.height());
    let occupied = |i: usize| CellState::from_log_odds(cells[i]) == CellState::Occupied;
    let mut r = Agreement::default();
    sample_cells(&GridGeometry::of(a), b, t_a_b, |i, lb| {
        let sa = CellState::from_log_odds(cells[i]);
        let sb = CellState::from_log_odds(lb);
        if sa == CellState::Unknown || sb == CellState::Unknown {
            return;
        }
        if sa == sb {
            r.agree += 1;
        } else {
            r.disagree += 1;
        }
        if sb == CellState::Occupied {
            r.walls += 1;
            let (x, y) = (i % w, i / w);
            let near = (y.saturating_sub(tolerance)..=(y + tolerance).min(h - 1))
                .any(|yy| (x.saturating_sub(tolerance)..=(x + tolerance).min(w - 1)).any(|xx| occupied(yy * w + xx)));
            r.walls_matched += near as usize;
        }
    });
    r
}

/// Map a's cells as two bitmaps: known, and "an occupied cell within one cell".
struct WallIndex {
    width: usize,
    height: usize,
    known: Vec<bool>,
    near_wall: Vec<bool>,
}

impl WallIndex {
    fn of(a: &OccupancyGrid) -> Self {
        let (w, h) = (a.width(), a.height());
        let cells = a.cells();
        let known = cells.iter().map(|&l| CellState::from_log_odds(l) != CellState::Unknown).collect();
        let occupied: Vec<bool> = cells.iter().map(|&l| CellState::from_log_odds(l) == CellState::Occupied).collect();
        // Separable 3x3 dilation of the occupied cells: rows, then columns.
        let mut rows = occupied.clone();
        for (o, r) in rows.chunks_exact_mut(w.max(1)).zip(occupied.chunks_exact(w.max(1))) {
            for (o, &left) in o[1..].iter_mut().zip(r) {
                *o |= left;
            }
            for (o, &right) in o.iter_mut().zip(&r[1..]) {
                *o |= right;
            }
        }
        let mut near_wall = rows.clone();
        for y in 0..h {
            for yy in [y.wrapping_sub(1), y + 1] {
                if yy < h {
                    let (o, r) = (&mut near_wall[y * w..(y + 1) * w], &rows[yy * w..(yy + 1) * w]);
                    for (o, &v) in o.iter_mut().zip(r) {
                        *o |= v;
                    }
                }
            }
        }
        WallIndex { width: w, height: h, known, near_wall }
    }

    /// Walls of b placed by `t_a_b`: (on a's known cells, of those with a wall of a within one cell).
    fn hits(&self, a: &OccupancyGrid, walls_b: &[Point2<f64>], t_a_b: &Pose2) -> (usize, usize) {
        let (mut on_known, mut matched) = (0, 0);
        for p in walls_b {
            let (ix, iy) = a.world_to_cell_i(&(t_a_b * p));
            if ix < 0 || iy < 0 || ix >= self.width as i64 || iy >= self.height as i64 {
                continue;
            }
            let i = iy as usize * self.width + ix as usize;
            if self.known[i] {
                on_known += 1;
                matched += self.near_wall[i] as usize;
            }
        }
        (on_known, matched)
    }
}

/// Walls of `b` (occupied cell centres, b's frame) placed by `t_a_b`: how many land on a's known cells, and
/// how many of those have an occupied cell of `a` within one cell.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
pub fn wall_hits(a: &OccupancyGrid, walls_b: &[Point2<f64>], t_a_b: &Pose2) -> (usize, usize) {
    WallIndex::of(a).hits(a, walls_b, t_a_b)
}

/// How well the maps still agree when b slides `shift` metres (8 directions, in b's frame) away from `t_a_b`:
/// the largest count of b's walls (`walls_b`, see [`crate::refine::wall_points`]) meeting a's walls over the
/// slides, as a share of the count in place.
///
/// Near 1 means the alignment is not pinned down along some direction, as in a featureless corridor.
pub fn ambiguity(a: &OccupancyGrid, walls_b: &[Point2<f64>], t_a_b: &Pose2, shift: f64) -> f64 {
    let index = WallIndex::of(a);
    let (_, here) = index.hits(a, walls_b, t_a_b);
    if here == 0 {
        return 1.0;
    }
    (0..8)
        .map(|k| {
            let ang = k as f64 * std::f64::consts::FRAC_PI_4;
            let slid = t_a_b * Translation2::new(shift * ang.cos(), shift * ang.sin());
            index.hits(a, walls_b, &slid).1 as f64 / here as f64
        })
        .fold(0.0, f64::max)
}

/// m-explore's match confidence.
pub fn confidence(inliers: usize, matches: usize) -> f64 {
    inliers as f64 / (8.0 + 0.3 * matches as f64)
}

/// Why a merge was rejected, or None when it passes every threshold.
pub fn rejection_reason(p: &VerifyParams, inliers: usize, matches: usize, agreement: &Agreement) -> Option<String> {
    let conf = confidence(inliers, matches);
    if inliers < p.min_inliers {
        Some(format!("only {inliers} inlier matches (need {})", p.min_inliers))
    } else if conf < p.min_confidence {
        Some(format!(
            "confidence {conf:.2} below {:.2} ({inliers} inliers, {matches} features matched)",
            p.min_confidence
        ))
    } else if agreement.common() < p.min_common_cells {
        Some(format!("aligned maps share only {} known cells (need {})", agreement.common(), p.min_common_cells))
    } else if agreement.wall_agreement() < p.min_wall_agreement {
        Some(format!(
            "only {:.0}% of b's walls over a's known cells meet a wall of a (need {:.0}%)",
            100.0 * agreement.wall_agreement(),
            100.0 * p.min_wall_agreement
        ))
    } else if agreement.acceptance_index() < p.min_acceptance {
        Some(format!(
            "acceptance index {:.3} below {:.3}: the aligned maps contradict each other",
            agreement.acceptance_index(),
            p.min_acceptance
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn identical_maps_agree_fully_and_shifted_walls_disagree() {
        let mut g = OccupancyGrid::new(20, 20, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..20 {
            for ix in 0..20 {
                g.set(ix, iy, if ix == 10 { 2.0 } else { -2.0 });
            }
        }
        let same = agreement(&g, &g, &Pose2::identity());
        assert_eq!((same.agree, same.disagree), (400, 0));
        assert_eq!(same.acceptance_index(), 1.0);
        assert_eq!(same.wall_agreement(), 1.0);
        let shifted = agreement(&g, &g, &pose(0.3, 0.0, 0.0));
        // the wall column and its image three cells over disagree in 2 columns of 20 cells
        assert_eq!(shifted.disagree, 40);
        assert!(shifted.acceptance_index() < 0.9);
        assert_eq!(shifted.wall_agreement(), 0.0);
        // one cell off still counts as meeting the wall; three cells off only with a tolerance of three
        assert_eq!(agreement(&g, &g, &pose(0.1, 0.0, 0.0)).wall_agreement(), 1.0);
        assert_eq!(agreement_within(&g, &g, &pose(0.3, 0.0, 0.0), 2).wall_agreement(), 0.0);
        assert_eq!(agreement_within(&g, &g, &pose(0.3, 0.0, 0.0), 3).wall_agreement(), 1.0);
    }

    #[test]
    fn a_corridor_slides_ambiguously_a_room_does_not() {
        // A 10 m corridor (two long walls) and a closed 3 m room, both at 0.1 m.
        let mut corridor = OccupancyGrid::new(100, 30, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let mut room = OccupancyGrid::new(30, 30, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        for (g, closed) in [(&mut corridor, false), (&mut room, true)] {
            let (w, h) = (g.width(), g.height());
            for iy in 0..h {
                for ix in 0..w {
                    let wall = iy == 0 || iy == h - 1 || (closed && (ix == 0 || ix == w - 1));
                    g.set(ix, iy, if wall { 2.0 } else { -2.0 });
                }
            }
        }
        let (cw, rw) = (crate::refine::wall_points(&corridor), crate::refine::wall_points(&room));
        assert!(ambiguity(&corridor, &cw, &Pose2::identity(), 1.0) > 0.85);
        assert!(ambiguity(&room, &rw, &Pose2::identity(), 1.0) < 0.6);
    }

    #[test]
    fn wall_hits_match_a_cell_by_cell_count() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut a = OccupancyGrid::new(40, 30, 0.1, pose(-1.0, 0.5, 0.2)).unwrap();
        for l in a.cells_mut() {
            *l = [-2.0, 0.0, 2.0][rng.random_range(0..3)];
        }
        let walls: Vec<Point2<f64>> =
            (0..500).map(|_| Point2::new(rng.random_range(-2.0..3.0), rng.random_range(0.0..4.0))).collect();
        let t = pose(0.1, -0.1, 0.3);
        let state = |ix: i64, iy: i64| a.get_checked(ix, iy).map(CellState::from_log_odds);
        let (mut known, mut matched) = (0, 0);
        for p in &walls {
            let (ix, iy) = a.world_to_cell_i(&(t * p));
            if state(ix, iy).is_some_and(|s| s != CellState::Unknown) {
                known += 1;
                let near = (-1..=1).any(|dy| (-1..=1).any(|dx| state(ix + dx, iy + dy) == Some(CellState::Occupied)));
                matched += near as usize;
            }
        }
        assert!(known > 100 && matched > 50, "{known} {matched}");
        assert_eq!(wall_hits(&a, &walls, &t), (known, matched));
    }

    #[test]
    fn reasons_name_the_failed_check() {
        let p = VerifyParams::default();
        let good = Agreement { agree: 1000, disagree: 10, walls: 100, walls_matched: 90 };
        assert_eq!(rejection_reason(&p, 30, 40, &good), None);
        assert!(rejection_reason(&p, 3, 40, &good).unwrap().contains("inlier"));
        assert!(rejection_reason(&p, 9, 400, &good).unwrap().contains("confidence"));
        let bad = Agreement { agree: 500, disagree: 500, ..good };
        assert!(rejection_reason(&p, 30, 40, &bad).unwrap().contains("acceptance index"));
        let astray = Agreement { walls_matched: 20, ..good };
        assert!(rejection_reason(&p, 30, 40, &astray).unwrap().contains("walls"));
        let tiny = Agreement { agree: 10, disagree: 0, ..good };
        assert!(rejection_reason(&p, 30, 40, &tiny).unwrap().contains("share only"));
    }
}
