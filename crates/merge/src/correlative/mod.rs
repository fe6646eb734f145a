//! A global correlative merger: the whole of map b's walls matched against a likelihood field of map a's
//! over every rotation and translation, as Cartographer's loop closure searches a whole submap.
//!
//! ```text
//! pool a and b to search cells (search_resolution)     field::BlockStates
//! score field of a: blurred walls, penalised free      field::ScoreField
//! max-pooled pyramid of the field                      pyramid::Pyramid (Hess et al. 2016)
//! b's wall blocks as points about their centroid       scan::WallScan
//! for each rotation, step = cell / radius (rayon):     (Olson 2009; Cartographer's angular step)
//!     branch and bound over all translations           search::branch_and_bound
//! best distinct (rotation, translation) overall        hypotheses, strongest first
//! each: exhaustive window at a's resolution            local::local_search
//! each: wall ICP, then least shared area and acceptance  refine::refine, verify::agreement
//! ```
//!
//! The shared pipeline then refines each answer by wall ICP and puts it through the verification gate.
//!
//! What the pipeline sees ([`Alignment`]): the evidence is b's wall cells (at a's resolution, thinned to
//! [`CorrelativeParams::max_fine_points`]) placed by the transform. `matches` (and `matched_features`) = those
//! landing on a known cell of a, `inliers` = those of them with a wall of a within one cell: the counts of
//! the gate's wall agreement ([`crate::verify::wall_hits`]). m-explore's confidence
//! `inliers / (8 + 0.3 · matches)` is then above 1 when more than 30 % of b's walls over a's known space meet
//! a's walls (plus 8), and it falls with the share of b's walls that contradict a.

pub mod field;
pub mod local;
pub mod pyramid;
pub mod scan;
pub mod search;

use crate::merger::{Alignment, Evidence, Hypothesis, Merger, NoAlignment};
use crate::refine::{RefineParams, refine, wall_points};
use crate::verify::{agreement, wall_hits};
use field::{BlockStates, HIT, ScoreField};
use local::{LocalWindow, ScanPose, local_search};
use mrslam_core::{OccupancyGrid, Pose2, pose};
use nalgebra::{Point2, Rotation2};
use pyramid::Pyramid;
use rayon::prelude::*;
use scan::WallScan;
use search::{Best, Candidate, Window, branch_and_bound};
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::time::Instant;

/// Parameters of the correlative merger.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CorrelativeParams {
    /// Cell size of the global search, metres: both maps are pooled to it (never finer than a map's own).
    pub search_resolution: f64,
    /// Cell size of a first screening of every rotation and translation, metres; its best
    /// [`CorrelativeParams::screen_candidates`] are searched again around themselves at `search_resolution`.
    /// Below 1.5 `search_resolution` (the default, 0), no screening: the whole search runs at
    /// `search_resolution`. Measured at 0.8 m with 64 candidates: 4x faster on the real pairs (both still
    /// found), but 12 instead of 22 of 24 generated pairs merged, so off.
    pub screen_resolution: f64,
    /// Distinct answers of the screening searched again.
    pub screen_candidates: usize,
    /// Blur (Gaussian σ) of a's walls in the global search, search cells.
    pub sigma_cells: f64,
    /// Blur of a's walls in the fine stage, cells of a.
    pub fine_sigma_cells: f64,
    /// Score of a wall point of b on a free cell of a with no wall near, as a share of a hit (≥ 0, subtracted).
    pub free_penalty: f64,
    /// Levels of the max-pooled pyramid: root blocks of the branch and bound are `2^depth` cells a side.
    pub depth: usize,
    /// Angular step as a multiple of Cartographer's `cell / radius of b's walls` (1: a point at the far
    /// end moves one cell per step).
    pub angle_step_scale: f64,
    /// Most wall points of b in the global search (an even stride over its wall blocks; 0 = all).
    pub max_points: usize,
    /// Most wall points of b in the fine stage and the evidence (0 = all).
    pub max_fine_points: usize,
    /// Distinct answers kept per rotation by the branch and bound.
    pub per_rotation: usize,
    /// Lowest global score, as a share of every point of b on a wall of a.
    pub min_score: f64,
    /// Answers scoring below this share of the best one are dropped; rotations searched later prune with it
    /// (0.7 halves the search time against 0.5 with the same answers on the measured pairs; a rival the gate
    /// must see fits about as well as the best, 0.9 of its walls).
    pub keep_ratio: f64,
    /// Hypotheses handed to verification: the best and this many minus one alternatives.
    pub hypotheses: usize,
    /// Two answers are the same when no wall point of b moves more than this between them, metres.
    pub distinct_m: f64,
    /// Fine stage: angles tried either side of a global answer, over one global step.
    pub fine_angles: usize,
    /// Least area known in both maps (cells of a) at a pose for it to be handed to verification, m².
    ///
    /// Trying every pose finds a small patch where walls coincide by chance (a building's corner on
    /// another's); the gate's common-cell floor, set for feature matches, is too low for such a search.
    pub min_overlap_m2: f64,
    /// Lowest acceptance index (Carpin's, [`crate::verify::Agreement::acceptance_index`]) of a pose before
    /// it is handed to verification.
    ///
    /// Stricter than the gate's: the best of every pose is a far stronger coincidence than a feature
    /// consensus, so its maps must contradict each other less for the same trust.
    pub min_acceptance: f64,
    /// Fewest wall points (search blocks) in map b.
    pub min_points: usize,
    /// Search the rotations on rayon's threads.
    pub parallel: bool,
}

impl Default for CorrelativeParams {
    /// Chosen by measurement on generated 29 m floor-plan pairs (overlap 0.1-0.5, random turns) and the two
    /// real half-log pairs (aces, fr079): a sharp field (σ half a 0.4 m cell) and a free-space penalty of
    /// twice a hit keep b's walls out of a's rooms; blurrier or softer fields prefer laying a half building
    /// over the other (the outer walls coincide), a penalty of 4 made one false merge.
    fn default() -> Self {
        CorrelativeParams {
            search_resolution: 0.4,
            screen_resolution: 0.0,
            screen_candidates: 64,
            sigma_cells: 0.5,
            fine_sigma_cells: 1.5,
            free_penalty: 2.0,
            depth: 6,
            angle_step_scale: 1.0,
            max_points: 800,
            max_fine_points: 6000,
            per_rotation: 2,
            min_score: 0.03,
            keep_ratio: 0.7,
            hypotheses: 4,
            distinct_m: 1.0,
            fine_angles: 3,
            min_overlap_m2: 10.0,
            min_acceptance: 0.95,
            min_points: 20,
            parallel: true,
        }
    }
}

/// The global correlative merger.
#[derive(Debug, Clone, Default)]
pub struct CorrelativeMerger {
    /// Its parameters.
    pub params: CorrelativeParams,
}

impl CorrelativeMerger {
    /// A merger with these parameters.
    pub fn new(params: CorrelativeParams) -> Self {
        CorrelativeMerger { params }
    }
}

/// The rounds of the rotation search, as (modulus, remainder) of the rotation index: every 16th first.
const ROUNDS: [(usize, usize); 5] = [(16, 0), (16, 8), (8, 4), (4, 2), (2, 1)];

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A global answer: rotation index and its best offset.
#[derive(Debug, Clone, Copy)]
struct Global {
    rotation: usize,
    candidate: Candidate,
}

/// Angle difference wrapped to [0, π].
fn angle_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

/// `T_a_b` of a scan pose: b's centroid `c` turned by θ lands at `t` in a's grid frame.
fn to_transform(a: &OccupancyGrid, c: &Point2<f64>, p: &ScanPose) -> Pose2 {
    let rc = Rotation2::new(p.theta) * c.coords;
    *a.origin() * pose(p.tx - rc.x, p.ty - rc.y, p.theta)
}

/// The scan pose of `T_a_b` for a scan about centroid `c`: its rotation, and where `c` lands in a's grid frame.
fn to_scan_pose(a: &OccupancyGrid, c: &Point2<f64>, t_a_b: &Pose2) -> ScanPose {
    let t_g_b = a.origin().inverse() * t_a_b;
    let q = t_g_b * c;
    ScanPose { theta: t_g_b.rotation.angle(), tx: q.x, ty: q.y }
}

/// Fills in a failure.
fn fail(reason: String, timings: BTreeMap<String, f64>) -> Box<NoAlignment> {
    Box::new(NoAlignment { reason, matches: 0, timings_ms: timings, evidence: Evidence::default() })
}

impl CorrelativeMerger {
    /// The global search: the best distinct poses of b's scan in a's grid frame, strongest first.
    fn global(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        resolution: f64,
        keep: usize,
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<(Vec<Pose2>, f64), Box<NoAlignment>> {
        let p = &self.params;
        let t = Instant::now();
        let fa = ((resolution / a.resolution()).round() as usize).max(1);
        let fb = ((resolution / b.resolution()).round() as usize).max(1);
        let cell = fa as f64 * a.resolution();
        let blocks = BlockStates::of(a, fa);
        let scan = WallScan::of_blocks(b, fb, p.max_points);
        timings.insert("pool".into(), ms(t));
        if scan.points.len() < p.min_points {
            return Err(fail(
                format!("too few walls in map b: {} blocks (need {})", scan.points.len(), p.min_points),
                timings.clone(),
            ));
        }
        let t = Instant::now();
        let penalty = (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = ScoreField::build(&blocks, p.sigma_cells, penalty);
        if !field.values.contains(&HIT) {
            return Err(fail("map a has no walls".into(), timings.clone()));
        }
        let pyramid = Pyramid::build(&field, p.depth);
        timings.insert("field".into(), ms(t));
        let t = Instant::now();
        let step = (p.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let n_rot = (TAU / step).ceil() as usize;
        let step = TAU / n_rot as f64;
        let min_floor = (p.min_score * f64::from(HIT) * scan.points.len() as f64).ceil() as i64;
        let separation = ((p.distinct_m / cell).ceil() as i32).max(1);
        let one = |scratch: &mut (Vec<(i32, i32)>, Vec<Candidate>), j: usize, floor: i64| -> Vec<Global> {
            let (points, roots) = scratch;
            scan.discretize(j as f64 * step, cell, points);
            let (mut x0, mut x1, mut y0, mut y1) = (i32::MAX, i32::MIN, i32::MAX, i32::MIN);
            for &(x, y) in points.iter() {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
            let window = Window { x0: -x1, x1: field.width as i32 - 1 - x0, y0: -y1, y1: field.height as i32 - 1 - y0 };
            let mut best = Best::new(p.per_rotation, separation, floor);
            branch_and_bound(&pyramid, points, window, &mut best, roots);
            best.found.iter().map(|&candidate| Global { rotation: j, candidate }).collect()
        };
        // Rotations in rounds of halving stride (every 16th, then the 8th between them, ...): the best score
        // of the rounds so far sets the floor of the next (keep_ratio of it), so later rounds prune harder.
        // The floor of a round depends only on earlier rounds: the answer does not depend on thread timing.
        let mut all: Vec<Global> = Vec::new();
        let mut floor = min_floor;
        for (modulus, rest) in ROUNDS {
            let js: Vec<usize> = (0..n_rot).filter(|j| j % modulus == rest).collect();
            let found: Vec<Vec<Global>> = if p.parallel {
                js.par_iter().map_init(|| (Vec::new(), Vec::new()), |s, &j| one(s, j, floor)).collect()
            } else {
                let mut scratch = (Vec::new(), Vec::new());
                js.iter().map(|&j| one(&mut scratch, j, floor)).collect()
            };
            all.extend(found.into_iter().flatten());
            let top = all.iter().map(|g| g.candidate.score).max().unwrap_or(i64::MIN);
            floor = floor.max((p.keep_ratio * top as f64).ceil() as i64);
        }
        all.retain(|g| g.candidate.score >= floor);
        all.sort_by(|x, y| {
            y.candidate
                .score
                .cmp(&x.candidate.score)
                .then(x.rotation.cmp(&y.rotation))
                .then(x.candidate.oy.cmp(&y.candidate.oy))
                .then(x.candidate.ox.cmp(&y.candidate.ox))
        });
        timings.insert("search".into(), ms(t));
        let as_pose = |g: &Global| ScanPose {
            theta: g.rotation as f64 * step,
            tx: cell * (f64::from(g.candidate.ox) + 0.5),
            ty: cell * (f64::from(g.candidate.oy) + 0.5),
        };
        let mut kept: Vec<ScanPose> = Vec::new();
        for g in &all {
            let q = as_pose(g);
            let distinct = kept
                .iter()
                .all(|k| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta) > p.distinct_m);
            if distinct {
                kept.push(q);
                if kept.len() >= keep.max(1) {
                    break;
                }
            }
        }
        if kept.is_empty() {
            return Err(fail(
                format!("no pose scores above {:.0}% of a perfect fit", 100.0 * p.min_score),
                timings.clone(),
            ));
        }
        Ok((kept.iter().map(|q| to_transform(a, &scan.centroid, q)).collect(), step))
    }

    /// The global answers at [`CorrelativeParams::search_resolution`], strongest first, and the angular step
    /// they were found at; screened first at [`CorrelativeParams::screen_resolution`] when that is coarser.
    fn search(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<(Vec<Pose2>, f64), Box<NoAlignment>> {
        let p = &self.params;
        if p.screen_resolution < 1.5 * p.search_resolution {
            return self.global(a, b, p.search_resolution, p.hypotheses, timings);
        }
        let (coarse, coarse_step) = self.global(a, b, p.screen_resolution, p.screen_candidates, timings)?;
        // Each screened answer searched again around itself at the search resolution.
        let t = Instant::now();
        let fa = ((p.search_resolution / a.resolution()).round() as usize).max(1);
        let fb = ((p.search_resolution / b.resolution()).round() as usize).max(1);
        let cell = fa as f64 * a.resolution();
        let scan = WallScan::of_blocks(b, fb, p.max_points);
        let penalty = (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = Pyramid::build(&ScoreField::build(&BlockStates::of(a, fa), p.sigma_cells, penalty), 0);
        let step = (p.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let window = LocalWindow {
            cells: (p.screen_resolution / cell).ceil() as i32 + 1,
            angles: (coarse_step / step).ceil() as usize,
            angle_step: step,
        };
        let mut buf = Vec::new();
        let mut found: Vec<(usize, ScanPose, i64)> = coarse
            .iter()
            .enumerate()
            .map(|(i, t_a_b)| {
                let start = to_scan_pose(a, &scan.centroid, t_a_b);
                let (q, s) = local_search(&field.levels[0], cell, &scan, start, &window, &mut buf);
                (i, q, s)
            })
            .collect();
        found.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let mut kept: Vec<ScanPose> = Vec::new();
        for (_, q, _) in &found {
            let distinct = kept
                .iter()
                .all(|k| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta) > p.distinct_m);
            if distinct && kept.len() < p.hypotheses.max(1) {
                kept.push(*q);
            }
        }
        timings.insert("search_local".into(), ms(t));
        Ok((kept.iter().map(|q| to_transform(a, &scan.centroid, q)).collect(), step))
    }
}

impl Merger for CorrelativeMerger {
    fn name(&self) -> &'static str {
        crate::Algorithm::Correlative.name()
    }

    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        let p = &self.params;
        let mut timings = BTreeMap::new();
        let (global, step) = self.search(a, b, &mut timings)?;
        // Fine stage at a's resolution.
        let t = Instant::now();
        let fine_points = wall_points(b);
        let scan = WallScan::of_points(&fine_points, p.max_fine_points);
        let fine = ScoreField::build(
            &BlockStates::of(a, 1),
            p.fine_sigma_cells,
            (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16,
        );
        let fine = Pyramid::build(&fine, 0);
        let coarse_cells = ((p.search_resolution / a.resolution()).round() as i32).max(1);
        let window = LocalWindow {
            cells: coarse_cells + 1,
            angles: p.fine_angles,
            angle_step: step / p.fine_angles.max(1) as f64,
        };
        let mut buf = Vec::new();
        let mut refined: Vec<(usize, ScanPose, i64)> = global
            .iter()
            .enumerate()
            .map(|(i, t_a_b)| {
                let start = to_scan_pose(a, &scan.centroid, t_a_b);
                let (q, s) = local_search(&fine.levels[0], a.resolution(), &scan, start, &window, &mut buf);
                (i, q, s)
            })
            .collect();
        refined.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        timings.insert("fine".into(), ms(t));
        // A pose found by trying every pose needs a shared area of some size to count: a small patch where
        // the walls coincide by chance (a building corner on another) is expected somewhere.
        let t = Instant::now();
        // Checked after the wall ICP the pipeline also runs (its second pass then starts converged): a pose a
        // cell off lays thin walls on free space, which the acceptance index would count against it.
        let icp = RefineParams::default();
        let poses: Vec<Pose2> = refined
            .iter()
            .map(|(_, q, _)| refine(a, &fine_points, &to_transform(a, &scan.centroid, q), &icp))
            .collect();
        let cell_m2 = a.resolution() * a.resolution();
        let checks: Vec<(f64, f64)> = poses
            .iter()
            .map(|t| {
                let agr = agreement(a, b, t);
                (agr.common() as f64 * cell_m2, agr.acceptance_index())
            })
            .collect();
        let largest = checks.iter().map(|c| c.0).fold(0.0, f64::max);
        let best_acceptance = checks.iter().map(|c| c.1).fold(0.0, f64::max);
        let poses: Vec<Pose2> = poses
            .into_iter()
            .zip(&checks)
            .filter(|(_, (m2, acc))| *m2 >= p.min_overlap_m2 && *acc >= p.min_acceptance)
            .map(|(t, _)| t)
            .collect();
        timings.insert("overlap".into(), ms(t));
        if poses.is_empty() {
            return Err(fail(
                format!(
                    "no pose both shares {:.1} m² of known space and has an acceptance index of {:.2}: the best \
                     share at most {largest:.1} m², agree at most {best_acceptance:.3}",
                    p.min_overlap_m2, p.min_acceptance
                ),
                timings,
            ));
        }
        let t = Instant::now();
        let points_b: Vec<Point2<f64>> = scan.points.iter().map(|v| scan.centroid + v).collect();
        let hypotheses: Vec<Hypothesis> = poses
            .iter()
            .map(|&transform| {
                let (_, inliers) = wall_hits(a, &points_b, &transform);
                Hypothesis { transform, scale: 1.0, inliers, inlier_pairs: Vec::new() }
            })
            .collect();
        let (on_known, _) = wall_hits(a, &points_b, &hypotheses[0].transform);
        timings.insert("evidence".into(), ms(t));
        let mut hypotheses = hypotheses.into_iter();
        let Some(first) = hypotheses.next() else {
            return Err(fail("no hypothesis".into(), timings));
        };
        Ok(Alignment {
            transform: first.transform,
            scale: 1.0,
            matches: on_known,
            matched_features: on_known,
            inliers: first.inliers,
            timings_ms: timings,
            evidence: Evidence { points_a: Vec::new(), points_b, inlier_pairs: Vec::new() },
            alternatives: hypotheses.collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use crate::pairs::{PairSpec, cut_pair};

    /// Rotation (degrees) and translation (metres) errors of `t` against `truth`.
    fn error(t: &Pose2, truth: &Pose2) -> (f64, f64) {
        let d = truth.inverse() * t;
        (d.rotation.angle().to_degrees().abs(), d.translation.vector.norm())
    }

    #[test]
    fn the_global_search_recovers_generated_transforms_at_any_angle() {
        let map = generate(5, &FloorplanParams { width_m: 16.0, height_m: 12.0, ..FloorplanParams::default() });
        let merger = CorrelativeMerger::default();
        for (seed, theta) in [(1, 0.3), (2, 1.9), (3, -2.8), (4, -1.2)] {
            let mut pair = cut_pair(&map, &PairSpec { overlap: 0.4, max_shift_m: 3.0, rotate: false }, seed);
            // Turn b by `theta` about its grid origin: its content moves, the truth follows.
            let turn = pose(0.0, 0.0, theta);
            pair.b = crate::resample::resample(&pair.b, &turn, pair.b.resolution());
            pair.t_a_b *= turn.inverse();
            let al = merger.align(&pair.a, &pair.b).unwrap();
            let (deg, m) = error(&al.transform, &pair.t_a_b);
            assert!(deg < 1.0 && m < 0.15, "seed {seed} theta {theta}: off by {deg:.2} deg, {m:.3} m");
        }
    }
}
