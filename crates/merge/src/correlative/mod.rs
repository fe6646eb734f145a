//! A global correlative merger: the whole of map b's walls matched against a likelihood field of map a's
//! over every translation and the rotations the walls' orientations allow, as Cartographer's loop closure searches
//! a whole submap.
//!
//! ```text
//! pool a and b to search cells (search_resolution)     field::BlockStates
//! score field of a: blurred walls, penalised free      field::ScoreField
//! max-pooled pyramid of the field                      pyramid::Pyramid (Hess et al. 2016)
//! b's wall blocks as points about their centroid       scan::WallScan
//! rotations near the peaks of the wall-orientation     orientation (Carpin 2008's Hough-spectrum idea)
//!     correlation of a and b (± 4°, θ and θ + π)
//! for each such rotation, step = cell / radius (rayon): (Olson 2009; Cartographer's angular step)
//!     branch and bound over all translations           search::branch_and_bound
//! best distinct (rotation, translation) overall        hypotheses, strongest first, and rivals
//! each: a window at a's resolution (every offset; rayon)   local::local_search
//! the strongest: wall ICP, scored again, ranked        refine::refine
//! significance: best against the best 2 m or more away Significance (Lowe's ratio test)
//! a second search with a softer penalty, pooled:      fallback_free_penalty (rivals; its own winner
//!     needs fallback_min_overlap_m2)                   fallback_always
//! hypotheses: least shared area and acceptance         verify::agreement
//! the same the other way round (a's walls on b):       cross_check (refused if ambiguous or elsewhere)
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
pub mod orientation;
pub mod pyramid;
pub mod scan;
pub mod search;

use crate::merger::{Alignment, Evidence, Hypothesis, Merger, NoAlignment};
use crate::refine::{RefineParams, refine, wall_points};
use crate::verify::{VerifyParams, agreement, wall_hits};
use field::{BlockStates, HIT, ScoreField};
use local::{LocalScratch, LocalWindow, ScanPose, WindowField, WindowKey, local_search, window_key};
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
    /// Score of a wall point of b on a free cell of a with no wall near, as a share of a hit (≥ 0, subtracted):
    /// the global search's.
    pub free_penalty: f64,
    /// A free cell of a counts as free space (penalised under b's walls) only when at least this share of the
    /// square of one search cell's extent centred on it is free; fewer leave it unknown (0: every free cell,
    /// as before 2026-12-03).
    ///
    /// A real robot's map is crossed by single rays that pass through glass, doors and gaps far beyond the
    /// walls: thin lines of free cells. Counted as free space they put the other map's walls "in a room": on
    /// ACES in 4 parts, 99 of b's 513 wall points fell on a's free space at the true pose of a pair with 13
    /// relations, and the pair was refused; at 0.5, 12 did and it merged 0.11 m off. With the two logs in 4, 5, 6
    /// and 9 parts (and `min_acceptance` 0.97): ACES 19 of 39 pairs merged correctly instead of 16, 3 false
    /// instead of 5; FR079 45 of 46 as before; generated plans and willow cuts as before.
    pub dense_free_share: f64,
    /// [`CorrelativeParams::free_penalty`] of the fine field, which ranks the answers and decides the
    /// significance test (at 1 with the global search at 2, a wrong pose won both ACES pairs that need the fallback).
    pub fine_free_penalty: f64,
    /// [`CorrelativeParams::free_penalty`] of a second global search, run when the first does not settle the
    /// pair (its best is not significant, or no hypothesis shares enough known space), its answers pooled with
    /// the first's and ranked on the same fine field (0: no second search).
    ///
    /// Two robots' maps contradict each other at the right pose: on the ACES log 15-21 % of b's walls over a's
    /// known space lie on a's free space 0.4 m or more from any wall of a (doors, people, furniture), so at
    /// the 0.4 m search cells the true pose scored 0.24 and 0.07 of the best wrong one and was pruned. A
    /// search at 1 finds it; run alone it costs generated floor plans a third of their 10 % overlap merges.
    pub fallback_free_penalty: f64,
    /// Least area known in both maps at a pose when the fallback search was needed, m².
    ///
    /// The tolerant search finds coincidences the strict one does not: on generated 18 m x 14 m and 24 m x
    /// 18 m plans cut apart (nothing shared), 180° flips laid wall on wall over 23-36 m² (acceptance 0.95-0.99)
    /// with a margin of 0.13-0.29; ACES's true poses share 270-280 m².
    pub fallback_min_overlap_m2: f64,
    /// Run the fallback search even when the first settles the pair, its answers pooled as rivals of the first's
    /// winner (which keeps its own [`CorrelativeParams::min_overlap_m2`] unless a fallback answer beats it); false:
    /// only when the first does not settle it (before 2026-12-02).
    ///
    /// Small maps of the ACES log (the log cut in 9 parts) made the strict search's winner a 180° flip: at the
    /// true pose more of b's walls fall on a's free space (48 against 31 points of 397), so the truth scored a
    /// tenth of the flip and was pruned; the tolerant search finds it, and on the fine field it leads the flip
    /// or comes within the significance margin of it, so the pair is refused instead of merged 4-18 m off.
    pub fallback_always: bool,
    /// Search only the rotations near the peaks of the correlation of the maps' wall-orientation histograms
    /// (`correlative::orientation`, after Carpin 2008's Hough spectra); false: every rotation (the search as
    /// Hess et al. describe it).
    pub rotation_prior: bool,
    /// The peaks kept: local maxima scoring at least this share of the highest.
    pub rotation_peak_ratio: f64,
    /// Rotations within this many degrees of a peak (or of it plus a half turn) are searched.
    pub rotation_tolerance_deg: f64,
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
    /// The verification gate's wall agreement asked of this search's answers, when lower than the gate's own
    /// ([`crate::VerifyParams::min_wall_agreement`], 0.6).
    ///
    /// 0.4: the search's answers already passed stricter checks (acceptance index, shared area, significance,
    /// the search the other way round), and two robots' maps have doubled and bent walls. On the logs every answer
    /// this gate refused at 0.6 was right (ACES in 4-6 parts: 5 pairs at 53-59 %, 0.03-0.06 m off), and at 0.5
    /// one more: ACES in 2 parts mapped from the scan lines' own odometry (the log without its ODOM lines), 49 %,
    /// 0.21 m and 0.61° off. Correct answers on the logs score 49-97 %, the false ones 60-70 %: wall agreement
    /// does not tell them apart there. The map-level studies and 400 further generated pairs at overlap 0 and 0.05
    /// gave the same answers at 0.4, 0.5 and 0.6, and 180 29 m plan pairs at 0-0.1 at 0.4 and 0.5
    /// (benchmarks/runs/2026-12-04-merge-real-unsettled-check.md).
    pub min_wall_agreement: f64,
    /// Lowest acceptance index (Carpin's, [`crate::verify::Agreement::acceptance_index`]) of a pose before
    /// it is handed to verification.
    ///
    /// Stricter than the gate's: the best of every pose is a far stronger coincidence than a feature
    /// consensus, so its maps must contradict each other less for the same trust. 0.97 (0.95 before
    /// 2026-12-03): the logs' correct merges scored 0.975-0.988 (FR079 and ACES in 2-9 parts), the two false
    /// ones of 0.95 scored 0.957 and 0.966 (22 and 32 m off); on generated 18 m x 14 m plans it cost one of 120
    /// merges (at 10 % overlap).
    pub min_acceptance: f64,
    /// The significance test: the best answer's fine score (after wall ICP) must exceed that of every answer
    /// more than [`CorrelativeParams::rival_distinct_m`] away by this share of itself (`rival ≤ (1 - min_margin)
    /// · best`, Lowe's ratio test, Olson's ambiguity test); else the pair is refused as ambiguous, naming the
    /// rival. 0 turns the test off.
    ///
    /// 0.15: on 360 generated pairs the three wrong answers the gate let through led by 0.04-0.09, the
    /// correct ones by 0-1 (a few below 0.15 lost); every correct answer on the real logs by 1.
    pub min_margin: f64,
    /// A rival of the significance test is a pose that moves some wall point of b more than this, metres.
    pub rival_distinct_m: f64,
    /// The global search's best answers clearly apart from its winner, refined on the fine field beside the
    /// hypotheses: rivals for the significance test, and second chances when the coarse ranking is wrong.
    ///
    /// 8: at 32 the fine ranking also found a 180° flip of a generated 24x18 plan laid on the other half (35 m²
    /// shared, acceptance 0.95, margin 0.24) that passed the gate.
    pub rivals: usize,
    /// [`CorrelativeParams::rivals`] of the fallback search, whose poses need
    /// [`CorrelativeParams::fallback_min_overlap_m2`]: ACES's true pose ranked between its 8th and 32nd answer.
    pub fallback_rivals: usize,
    /// The strongest refined answers polished by wall ICP and scored again at the pose they settle at: they
    /// rank the hypotheses and decide the significance test.
    pub polished: usize,
    /// Fewest wall points (search blocks) in map b.
    pub min_points: usize,
    /// Merge the maps the other way round too (a's walls on b's field) and refuse when that is ambiguous (the
    /// significance test) or gives another answer (one that, inverted, moves some wall point of b more than
    /// [`CorrelativeParams::distinct_m`]); when nothing settles the other way round, the answer stands (false:
    /// one way only, as before 2026-12-03). A left-right consistency check, as stereo matching makes.
    ///
    /// On the logs it refused the three 180° flips of ACES in 6 and 9 parts (the other way round a pose 180° away
    /// scored 87-89 % of the best) and no correct merge of ACES and FR079 in 2-9 parts, with other SLAM seeds, log
    /// stretches and drifted odometry (135 correct of 156 pairs either way); the map-level studies gave the same
    /// answers. Refusing also when nothing settles the other way round lost 9 of those correct merges: the fine
    /// field's penalty for free space under a wall is one-sided, and a's walls often find no pose scoring above 0
    /// on b's. It doubles the search's time on the pairs it accepts
    /// (benchmarks/runs/2026-12-03-merge-real-robustness.md).
    pub cross_check: bool,
    /// Search the rotations on rayon's threads.
    pub parallel: bool,
}

impl Default for CorrelativeParams {
    /// Chosen by measurement on generated 29 m floor-plan pairs (overlap 0.1-0.5, random turns) and the two
    /// real half-log pairs (aces, fr079): a sharp field (σ half a 0.4 m cell) and a free-space penalty of
    /// twice a hit keep b's walls out of a's rooms; blurrier or softer fields prefer laying a half building
    /// over the other (the outer walls coincide), a penalty of 4 made one false merge. The significance test,
    /// the fallback search and the ranking of every answer on the fine field after wall ICP: 2026-12-02
    /// (benchmarks/runs/2026-12-02-merge-real-significance.md).
    fn default() -> Self {
        CorrelativeParams {
            search_resolution: 0.4,
            screen_resolution: 0.0,
            screen_candidates: 64,
            sigma_cells: 0.5,
            fine_sigma_cells: 1.5,
            free_penalty: 2.0,
            fine_free_penalty: 2.0,
            dense_free_share: 0.5,
            fallback_free_penalty: 1.0,
            fallback_min_overlap_m2: 100.0,
            fallback_always: true,
            rotation_prior: true,
            rotation_peak_ratio: 0.3,
            rotation_tolerance_deg: 4.0,
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
            min_acceptance: 0.97,
            min_wall_agreement: 0.4,
            min_margin: 0.15,
            rival_distinct_m: 2.0,
            rivals: 8,
            fallback_rivals: 32,
            polished: 8,
            min_points: 20,
            cross_check: true,
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

/// What the global search found.
#[derive(Debug, Clone)]
struct Found {
    /// The best distinct poses (`T_a_b`), strongest first.
    poses: Vec<Pose2>,
    /// The best distinct answers more than [`CorrelativeParams::rival_distinct_m`] from the first, at most
    /// [`CorrelativeParams::rivals`], strongest first (none scored below the search's pruning floor).
    rivals: Vec<Pose2>,
    /// Angular step of the search, radians.
    step: f64,
}

/// How far the best answer stands above the best clearly different one, both scored on the fine field (Lowe's
/// ratio test; Olson's ambiguity test for loop closures).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Significance {
    /// The best answer, `T_a_b`.
    pub best: Pose2,
    /// Its fine score.
    pub best_score: i64,
    /// The best answer more than [`CorrelativeParams::rival_distinct_m`] away, among the global search's
    /// answers above its pruning floor; None when there was none.
    pub rival: Option<Pose2>,
    /// Its fine score (0 when there was none).
    pub rival_score: i64,
}

impl Significance {
    /// `(best - rival) / best`: the share by which the winner beats every clearly different pose searched (1 when
    /// none was left above the search's pruning floor, 0 when the best score is not positive).
    pub fn margin(&self) -> f64 {
        if self.best_score <= 0 {
            0.0
        } else if self.rival.is_none() {
            1.0
        } else {
            (self.best_score - self.rival_score.max(0)) as f64 / self.best_score as f64
        }
    }

    /// Why the answer is refused at `min_margin`, naming the rival; None when it stands out enough (or the
    /// test is off, `min_margin` ≤ 0).
    fn refusal(&self, min_margin: f64) -> Option<String> {
        if min_margin <= 0.0 || self.margin() >= min_margin {
            return None;
        }
        let (x, y, deg) = (self.best.translation.x, self.best.translation.y, self.best.rotation.angle().to_degrees());
        if self.best_score <= 0 {
            return Some(format!(
                "no pose scores above 0 (b's walls fall on a's free space more than on its walls): the best (x {x:.2} \
                 m, y {y:.2} m, {deg:.1} deg) scores {}",
                self.best_score
            ));
        }
        // A positive best without a rival leads by 100 %: never refused.
        let r = self.rival.as_ref()?;
        let d = self.best.inverse() * r;
        Some(format!(
            "ambiguous: the best pose (x {x:.2} m, y {y:.2} m, {deg:.1} deg) scores {}, a pose {:.0} deg and {:.1} m \
             away (x {:.2} m, y {:.2} m, {:.1} deg) scores {} ({:.0}% of it); the best must lead by {:.0}%",
            self.best_score,
            d.rotation.angle().to_degrees().abs(),
            d.translation.vector.norm(),
            r.translation.x,
            r.translation.y,
            r.rotation.angle().to_degrees(),
            self.rival_score,
            100.0 * self.rival_score as f64 / self.best_score.max(1) as f64,
            100.0 * min_margin
        ))
    }
}

/// The significance of the correlative merger's answer for a pair (its best answer against its best clearly
/// different one, both on the fine field). Public (through the crate's `dev` module) only for the development
/// probes.
pub fn significance(merger: &CorrelativeMerger, a: &OccupancyGrid, b: &OccupancyGrid) -> Option<Significance> {
    merger.settled(a, b, &mut BTreeMap::new()).ok().map(|c| c.significance)
}

/// Both maps pooled to one search resolution, built once per pair and resolution: a's block states and b's wall
/// blocks as a scan (both searches of a pair share them).
struct Pooled {
    /// The search cell, metres (a whole number of a's cells).
    cell: f64,
    /// a's states on search cells.
    blocks: BlockStates,
    /// b's wall blocks, thinned to [`CorrelativeParams::max_points`].
    scan: WallScan,
}

impl Pooled {
    /// `cells_a`: a's cells as [`dense_free_cells`] gives them.
    fn build(a: &OccupancyGrid, cells_a: &BlockStates, b: &OccupancyGrid, resolution: f64, max_points: usize) -> Self {
        let fa = ((resolution / a.resolution()).round() as usize).max(1);
        let fb = ((resolution / b.resolution()).round() as usize).max(1);
        Pooled {
            cell: fa as f64 * a.resolution(),
            blocks: cells_a.pooled(fa),
            scan: WallScan::of_blocks(b, fb, max_points),
        }
    }
}

/// a's cell states with its free cells kept only where at least [`CorrelativeParams::dense_free_share`] of the
/// search cell's extent (made odd) around them is free: what both the global search and the fine field score.
fn dense_free_cells(a: &OccupancyGrid, p: &CorrelativeParams) -> BlockStates {
    let fa = ((p.search_resolution / a.resolution()).round() as usize).max(1);
    let mut cells = BlockStates::cells(a);
    cells.keep_dense_free(fa | 1, p.dense_free_share);
    cells
}

/// What the fine stage scores on, built once per pair: b's wall points at its own resolution (thinned to
/// [`CorrelativeParams::max_fine_points`] in the scan) and the score field of a at a's resolution.
struct FineField {
    /// Every wall point of b (b's frame), for wall ICP.
    points: Vec<Point2<f64>>,
    /// The same thinned, about their centroid.
    scan: WallScan,
    /// a's fine score field, laid out for the windows.
    field: WindowField,
}

impl FineField {
    /// `cells_a`: a's cells as [`dense_free_cells`] gives them.
    fn build(a: &OccupancyGrid, cells_a: &BlockStates, b: &OccupancyGrid, p: &CorrelativeParams) -> Self {
        let points = wall_points(b);
        let scan = WallScan::of_points(&points, p.max_fine_points);
        let penalty = (p.fine_free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = ScoreField::build(cells_a, p.fine_sigma_cells, penalty);
        FineField { points, scan, field: WindowField::new(&field, fine_window_cells(a, p) as usize) }
    }
}

/// The fine stage's work on one pair kept between its calls, for one window extent: each window's answer, and
/// each start's polish by its index among the starts.
#[derive(Debug, Default)]
struct FineCache {
    window: Option<LocalWindow>,
    windows: BTreeMap<WindowKey, (ScanPose, i64)>,
    polished: BTreeMap<usize, (Pose2, i64)>,
}

/// Offsets the fine windows search either side of a global answer, cells of a: a search cell and one more.
fn fine_window_cells(a: &OccupancyGrid, p: &CorrelativeParams) -> i32 {
    ((p.search_resolution / a.resolution()).round() as i32).max(1) + 1
}

/// `f` over `items` in order, on rayon or on this thread, each worker with its own scratch `S`.
fn map_with_scratch<T: Sync, S: Default, R: Send>(
    parallel: bool,
    items: &[T],
    f: impl Fn(&mut S, &T) -> R + Sync + Send,
) -> Vec<R> {
    if parallel {
        items.par_iter().map_init(S::default, f).collect()
    } else {
        let mut scratch = S::default();
        items.iter().map(|x| f(&mut scratch, x)).collect()
    }
}

/// The global search's answers refined on the fine field, strongest first, and the significance of the first.
struct Candidates {
    /// Polished poses `T_a_b` and their fine scores, strongest first.
    refined: Vec<(Pose2, i64)>,
    significance: Significance,
    /// The fine scan's points (thinned), b's frame.
    scan_points: Vec<Point2<f64>>,
    /// Least shared area a hypothesis needs, m²: more when the fallback search was needed.
    min_overlap_m2: f64,
    /// The best polished answer came from the first of the searches pooled.
    best_from_first: bool,
}

/// The global score of `t_a_b` (the best within two search cells and two angular steps of it), and how many
/// of b's search points land on a wall's blur, on penalised free space and elsewhere there.
/// Public (through the crate's `dev` module) only for the development probes.
pub fn score_near(
    merger: &CorrelativeMerger,
    a: &OccupancyGrid,
    b: &OccupancyGrid,
    t_a_b: &Pose2,
) -> (i64, [usize; 3], Pose2) {
    let p = &merger.params;
    let fa = ((p.search_resolution / a.resolution()).round() as usize).max(1);
    let fb = ((p.search_resolution / b.resolution()).round() as usize).max(1);
    let cell = fa as f64 * a.resolution();
    let scan = WallScan::of_blocks(b, fb, p.max_points);
    let penalty = (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
    let field = ScoreField::build(&dense_free_cells(a, p).pooled(fa), p.sigma_cells, penalty);
    let grid = WindowField::new(&field, 2);
    let step = (p.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
    let window = LocalWindow { cells: 2, angles: 2, angle_step: step };
    let start = to_scan_pose(a, &scan.centroid, t_a_b);
    let mut pts = Vec::new();
    let (q, s) = local_search(&grid, cell, &scan, start, &window, &mut LocalScratch::default());
    scan.discretize(q.theta, cell, &mut pts);
    let (_, cx, cy) = window_key(&q, cell);
    let mut counts = [0usize; 3];
    for &(x, y) in &pts {
        let v = grid.get(x + cx, y + cy);
        counts[if v > 0 {
            0
        } else if v < 0 {
            1
        } else {
            2
        }] += 1;
    }
    (s, counts, to_transform(a, &scan.centroid, &q))
}

/// Largest distance between where two transforms put the scan's points, metres.
fn max_displacement(scan: &WallScan, t: &Pose2, u: &Pose2) -> f64 {
    scan.points.iter().map(|v| scan.centroid + v).map(|q| (t * q - u * q).norm()).fold(0.0, f64::max)
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
        pooled: &Pooled,
        keep: usize,
        peaks: &[f64],
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Found, Box<NoAlignment>> {
        let p = &self.params;
        let Pooled { cell, blocks, scan } = pooled;
        let cell = *cell;
        if scan.points.len() < p.min_points {
            return Err(fail(
                format!("too few walls in map b: {} blocks (need {})", scan.points.len(), p.min_points),
                timings.clone(),
            ));
        }
        let t = Instant::now();
        let penalty = (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = ScoreField::build(blocks, p.sigma_cells, penalty);
        if !field.values.contains(&HIT) {
            return Err(fail("map a has no walls".into(), timings.clone()));
        }
        let pyramid = Pyramid::build(&field, p.depth);
        timings.insert("field".into(), ms(t));
        let t = Instant::now();
        let step = (p.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let n_rot = (TAU / step).ceil() as usize;
        let step = TAU / n_rot as f64;
        let tolerance = p.rotation_tolerance_deg.to_radians().max(step);
        let searched = |j: usize| peaks.is_empty() || orientation::near_a_peak(j as f64 * step, peaks, tolerance);
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
            let js: Vec<usize> = (0..n_rot).filter(|&j| j % modulus == rest && searched(j)).collect();
            let found = map_with_scratch(p.parallel, &js, |s, &j| one(s, j, floor));
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
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut kept: Vec<(ScanPose, i64)> = Vec::new();
        for g in &all {
            let q = as_pose(g);
            if kept.iter().all(|(k, _)| apart(&q, k) > p.distinct_m) {
                kept.push((q, g.candidate.score));
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
        // The best answers clearly apart from the winner: the significance test's rivals.
        let winner = kept[0].0;
        let mut rivals: Vec<ScanPose> = Vec::new();
        for q in all.iter().map(as_pose) {
            if rivals.len() >= p.rivals {
                break;
            }
            if apart(&q, &winner) > p.rival_distinct_m && rivals.iter().all(|k| apart(&q, k) > p.distinct_m) {
                rivals.push(q);
            }
        }
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        Ok(Found {
            poses: kept.iter().map(|(q, _)| transform(q)).collect(),
            rivals: rivals.iter().map(transform).collect(),
            step,
        })
    }

    /// The global answers and the significance test's rivals, each refined by a search of a small window on the
    /// fine field (a's resolution); the refined answers strongest first.
    ///
    /// `cache` keeps each window's answer, and each start's polish by its index among the starts: a second call
    /// whose searches begin with the first call's (the fallback pooled with the strict search) reuses them.
    fn candidates(
        &self,
        a: &OccupancyGrid,
        fine_field: &FineField,
        searches: &[&Found],
        cache: &mut FineCache,
        timings: &mut BTreeMap<String, f64>,
    ) -> Candidates {
        let p = &self.params;
        let t = Instant::now();
        let FineField { points: fine_points, scan, field: fine } = fine_field;
        let window = LocalWindow {
            cells: fine_window_cells(a, p),
            angles: p.fine_angles,
            angle_step: searches.iter().map(|f| f.step).fold(f64::INFINITY, f64::min) / p.fine_angles.max(1) as f64,
        };
        if cache.window != Some(window) {
            *cache = FineCache { window: Some(window), ..FineCache::default() };
        }
        let one = |buf: &mut LocalScratch, &(key, start): &(WindowKey, ScanPose)| {
            (key, local_search(fine, a.resolution(), scan, start, &window, buf))
        };
        // Every global answer and rival refined: the fine field ranks them (the coarse search only screens).
        // Starts of the same window (the strict and tolerant searches often agree) are searched once.
        let starts: Vec<(WindowKey, ScanPose)> = searches
            .iter()
            .flat_map(|f| f.poses.iter().chain(&f.rivals))
            .map(|t_a_b| to_scan_pose(a, &scan.centroid, t_a_b))
            .map(|start| (window_key(&start, a.resolution()), start))
            .collect();
        let mut todo: Vec<(WindowKey, ScanPose)> = Vec::new();
        for s in &starts {
            if !cache.windows.contains_key(&s.0) && todo.iter().all(|t| t.0 != s.0) {
                todo.push(*s);
            }
        }
        cache.windows.extend(map_with_scratch(p.parallel, &todo, one));
        let mut refined: Vec<(usize, ScanPose, i64)> = starts
            .iter()
            .enumerate()
            .map(|(i, (key, _))| {
                let (q, score) = cache.windows[key];
                (i, q, score)
            })
            .collect();
        refined.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut distinct: Vec<(usize, ScanPose, i64)> = Vec::new();
        for r in refined {
            if distinct.iter().all(|k| apart(&r.1, &k.1) > p.distinct_m) {
                distinct.push(r);
            }
        }
        // The strongest polished by wall ICP and scored again where they settle: the fine window's steps (a
        // third of the global angular step) leave a few per cent of the score to chance, as much as a rival's
        // lead can be.
        let icp = RefineParams::default();
        let window0 = LocalWindow { cells: 0, angles: 0, angle_step: 0.0 };
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        let top: Vec<(usize, ScanPose)> = distinct.iter().take(p.polished.max(1)).map(|&(i, q, _)| (i, q)).collect();
        let polish = |buf: &mut LocalScratch, &(i, q): &(usize, ScanPose)| {
            let t = refine(a, fine_points, &transform(&q), &icp);
            let start = to_scan_pose(a, &scan.centroid, &t);
            (i, (t, local_search(fine, a.resolution(), scan, start, &window0, buf).1))
        };
        let todo: Vec<(usize, ScanPose)> =
            top.iter().filter(|(i, _)| !cache.polished.contains_key(i)).copied().collect();
        cache.polished.extend(map_with_scratch(p.parallel, &todo, polish));
        let mut polished: Vec<(usize, Pose2, i64)> = top
            .iter()
            .map(|&(i, _)| {
                let (t, score) = cache.polished[&i];
                (i, t, score)
            })
            .collect();
        polished.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let from_first = searches.first().map_or(0, |f| f.poses.len() + f.rivals.len());
        let best_from_first = polished[0].0 < from_first;
        // The significance test: the best polished answer against every one clearly apart from it.
        let moved = |t: &Pose2, u: &Pose2| max_displacement(scan, t, u);
        let (best, best_score) = (polished[0].1, polished[0].2);
        let rival = polished[1..].iter().find(|r| moved(&r.1, &best) > p.rival_distinct_m);
        let significance =
            Significance { best, best_score, rival: rival.map(|r| r.1), rival_score: rival.map_or(0, |r| r.2) };
        *timings.entry("fine".into()).or_insert(0.0) += ms(t);
        Candidates {
            refined: polished.iter().map(|(_, t, s)| (*t, *s)).collect(),
            significance,
            scan_points: scan.points.iter().map(|v| scan.centroid + v).collect(),
            min_overlap_m2: p.min_overlap_m2,
            best_from_first,
        }
    }

    /// The candidates of the search with [`CorrelativeParams::free_penalty`]; when they do not settle the pair
    /// (the best is not significant, or no hypothesis shares enough known space at the acceptance asked for),
    /// pooled with those of a second search with [`CorrelativeParams::fallback_free_penalty`].
    fn settled(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Candidates, Box<NoAlignment>> {
        let p = &self.params;
        let t = Instant::now();
        let cells_a = dense_free_cells(a, p);
        let pooled = Pooled::build(a, &cells_a, b, p.search_resolution, p.max_points);
        timings.insert("pool".into(), ms(t));
        let t = Instant::now();
        let peaks =
            if p.rotation_prior { orientation::rotation_peaks(a, b, p.rotation_peak_ratio) } else { Vec::new() };
        timings.insert("orientation".into(), ms(t));
        let strict = self.search(a, &cells_a, b, &pooled, &peaks, timings)?;
        let t = Instant::now();
        let fine = FineField::build(a, &cells_a, b, p);
        timings.insert("fine_field".into(), ms(t));
        let mut cache = FineCache::default();
        let first = self.candidates(a, &fine, &[&strict], &mut cache, timings);
        let settles = |c: &Candidates| {
            c.significance.refusal(p.min_margin).is_none()
                && !self.shared(a, b, &c.refined, c.min_overlap_m2).0.is_empty()
        };
        let first_settles = settles(&first);
        if p.fallback_free_penalty <= 0.0
            || p.fallback_free_penalty == p.free_penalty
            || (first_settles && !p.fallback_always)
        {
            return Ok(first);
        }
        let tolerant = CorrelativeMerger::new(CorrelativeParams {
            free_penalty: p.fallback_free_penalty,
            rivals: p.fallback_rivals,
            ..*p
        });
        let mut more = BTreeMap::new();
        let Ok(second) = tolerant.search(a, &cells_a, b, &pooled, &peaks, &mut more) else {
            return Ok(first);
        };
        for (k, v) in more {
            timings.insert(format!("fallback_{k}"), v);
        }
        let mut pooled = self.candidates(a, &fine, &[&strict, &second], &mut cache, timings);
        // A pose only the tolerant search found needs the larger shared area; the first search's settled answer,
        // now tested against the tolerant search's rivals too, keeps its own.
        if !first_settles || !pooled.best_from_first {
            pooled.min_overlap_m2 = p.min_overlap_m2.max(p.fallback_min_overlap_m2);
        }
        Ok(pooled)
    }

    /// The first [`CorrelativeParams::hypotheses`] of `refined` that share `min_m2` of known space at an
    /// acceptance index of [`CorrelativeParams::min_acceptance`] (none unless the first does, with the
    /// significance test on), and what each tried had.
    ///
    /// A pose found by trying every pose needs a shared area of some size to count: a small patch where the walls
    /// coincide by chance (a building corner on another) is expected somewhere. Checked after wall ICP: a pose a
    /// cell off lays thin walls on free space, which the acceptance index would count against it.
    fn shared(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        refined: &[(Pose2, i64)],
        min_m2: f64,
    ) -> (Vec<Pose2>, Vec<String>) {
        let p = &self.params;
        let cell_m2 = a.resolution() * a.resolution();
        let mut tried = Vec::new();
        let mut poses = Vec::new();
        for (t, _) in refined.iter().take(p.hypotheses.max(1)) {
            let agr = agreement(a, b, t);
            let (m2, acc) = (agr.common() as f64 * cell_m2, agr.acceptance_index());
            tried.push(format!("{m2:.1} m² at {acc:.3}"));
            if m2 >= min_m2 && acc >= p.min_acceptance {
                poses.push(*t);
            }
        }
        // With the significance test on, only the best may be accepted: a weaker answer led nothing.
        if p.min_margin > 0.0 && poses.first() != refined.first().map(|r| &r.0) {
            poses.clear();
        }
        (poses, tried)
    }

    /// The global answers at [`CorrelativeParams::search_resolution`], strongest first, and the angular step
    /// they were found at; screened first at [`CorrelativeParams::screen_resolution`] when that is coarser.
    fn search(
        &self,
        a: &OccupancyGrid,
        cells_a: &BlockStates,
        b: &OccupancyGrid,
        pooled: &Pooled,
        peaks: &[f64],
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Found, Box<NoAlignment>> {
        let p = &self.params;
        if p.screen_resolution < 1.5 * p.search_resolution {
            return self.global(a, pooled, p.hypotheses, peaks, timings);
        }
        let t = Instant::now();
        let screen = Pooled::build(a, cells_a, b, p.screen_resolution, p.max_points);
        timings.insert("pool_screen".into(), ms(t));
        let coarse = self.global(a, &screen, p.screen_candidates, peaks, timings)?;
        // Each screened answer searched again around itself at the search resolution.
        let t = Instant::now();
        let Pooled { cell, blocks, scan } = pooled;
        let cell = *cell;
        let penalty = (p.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let step = (p.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let cells = (p.screen_resolution / cell).ceil() as i32 + 1;
        let field = WindowField::new(&ScoreField::build(blocks, p.sigma_cells, penalty), cells as usize);
        let window = LocalWindow { cells, angles: (coarse.step / step).ceil() as usize, angle_step: step };
        let mut buf = LocalScratch::default();
        let mut found: Vec<(usize, ScanPose, i64)> = coarse
            .poses
            .iter()
            .enumerate()
            .map(|(i, t_a_b)| {
                let start = to_scan_pose(a, &scan.centroid, t_a_b);
                let (q, s) = local_search(&field, cell, scan, start, &window, &mut buf);
                (i, q, s)
            })
            .collect();
        found.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut kept: Vec<(ScanPose, i64)> = Vec::new();
        for (_, q, s) in &found {
            if kept.iter().all(|(k, _)| apart(q, k) > p.distinct_m) && kept.len() < p.hypotheses.max(1) {
                kept.push((*q, *s));
            }
        }
        let winner = kept[0].0;
        let rivals: Vec<ScanPose> =
            found.iter().map(|f| f.1).filter(|q| apart(q, &winner) > p.rival_distinct_m).take(p.rivals).collect();
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        timings.insert("search_local".into(), ms(t));
        Ok(Found {
            poses: kept.iter().map(|(q, _)| transform(q)).collect(),
            rivals: rivals.iter().map(transform).collect(),
            step,
        })
    }
}

/// Why [`CorrelativeMerger::answers`] has no answer.
enum NoAnswer {
    /// A clearly different pose scores nearly as well as the best (the significance test).
    Ambiguous(Box<NoAlignment>),
    /// Too few walls, no pose scores above 0, or none shares enough known space.
    Unsettled(Box<NoAlignment>),
}

impl NoAnswer {
    fn into_inner(self) -> Box<NoAlignment> {
        match self {
            NoAnswer::Ambiguous(no) | NoAnswer::Unsettled(no) => no,
        }
    }
}

/// Why the answer `t_a_b` is refused by the answer the other way round (`back`, a pose of a in b's frame first),
/// if it is: that is ambiguous, or it moves some point of `points_b` more than `distinct_m` from `t_a_b`.
fn cross_check_refusal(
    t_a_b: &Pose2,
    points_b: &[Point2<f64>],
    back: Result<(Vec<Pose2>, Vec<Point2<f64>>), NoAnswer>,
    distinct_m: f64,
) -> Option<String> {
    match back {
        Ok((back, _)) => {
            let back = back.first()?.inverse();
            let moved = points_b.iter().map(|q| ((t_a_b * q) - (back * q)).norm()).fold(0.0, f64::max);
            let (x, y, deg) = (back.translation.x, back.translation.y, back.rotation.angle().to_degrees());
            (moved > distinct_m).then(|| {
                format!(
                    "merged the other way round the maps give another answer (x {x:.2} m, y {y:.2} m, {deg:.1} deg), \
                     {moved:.1} m from this one at some wall of b"
                )
            })
        }
        Err(NoAnswer::Ambiguous(no)) => Some(format!("merged the other way round the maps are {}", no.reason)),
        // Nothing scores or shares enough the other way round: nothing to check the answer against.
        Err(NoAnswer::Unsettled(_)) => None,
    }
}

impl CorrelativeMerger {
    /// The poses that pass the significance test and the shared-area check, best first, and b's wall points (b's
    /// frame, thinned) that weigh them; else why none does.
    fn answers(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<(Vec<Pose2>, Vec<Point2<f64>>), NoAnswer> {
        let p = &self.params;
        let Candidates { refined, significance, scan_points, min_overlap_m2, .. } =
            self.settled(a, b, timings).map_err(NoAnswer::Unsettled)?;
        if let Some(reason) = significance.refusal(p.min_margin) {
            let no = fail(reason, std::mem::take(timings));
            return Err(if significance.best_score > 0 { NoAnswer::Ambiguous(no) } else { NoAnswer::Unsettled(no) });
        }
        let t = Instant::now();
        let (poses, tried) = self.shared(a, b, &refined, min_overlap_m2);
        timings.insert("overlap".into(), ms(t));
        if poses.is_empty() {
            return Err(NoAnswer::Unsettled(fail(
                format!(
                    "no pose {}both shares {:.1} m² of known space and has an acceptance index of {:.2}: the {} \
                     best share {}",
                    if p.min_margin > 0.0 { "(the best, as the significance test asks) " } else { "" },
                    min_overlap_m2,
                    p.min_acceptance,
                    tried.len(),
                    tried.join(", ")
                ),
                std::mem::take(timings),
            )));
        }
        Ok((poses, scan_points))
    }
}

impl Merger for CorrelativeMerger {
    fn name(&self) -> &'static str {
        crate::Algorithm::Correlative.name()
    }

    /// A boundary is a wall or a frontier, and the search scores b's walls on a's free space against a pose: with
    /// the boundary as walls, b's frontier lies on a's free space at the true pose. Measured on a generated plan
    /// cut at 20 % overlap with its walls dropped: the truth scored 2088, a 180° flip 12 m off 39767, and the flip
    /// passed the gate (benchmarks/runs/2026-12-02-merge-cascade.md).
    fn needs_marked_walls(&self) -> bool {
        true
    }

    /// The pipeline's gate with the wall agreement asked of its answers at most
    /// [`CorrelativeParams::min_wall_agreement`].
    fn gate(&self, verify: &VerifyParams) -> VerifyParams {
        VerifyParams { min_wall_agreement: verify.min_wall_agreement.min(self.params.min_wall_agreement), ..*verify }
    }

    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        let p = &self.params;
        let mut timings = BTreeMap::new();
        let (poses, points_b) = self.answers(a, b, &mut timings).map_err(NoAnswer::into_inner)?;
        if p.cross_check {
            let t = Instant::now();
            let back = self.answers(b, a, &mut BTreeMap::new());
            timings.insert("cross_check".into(), ms(t));
            if let Some(reason) = cross_check_refusal(&poses[0], &points_b, back, p.distinct_m) {
                return Err(fail(reason, timings));
            }
        }
        let t = Instant::now();
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
            alternatives_are_rivals: p.min_margin > 0.0,
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

    /// An 8 m x 6 m building at 5 cm: outer walls and two inner walls that a half turn about its centre maps
    /// onto each other; with `asymmetric`, a further 4 m wall that the half turn does not.
    fn building(asymmetric: bool) -> OccupancyGrid {
        let (w, h) = (160usize, 120usize);
        let mut g = OccupancyGrid::new(w, h, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..h {
            for ix in 0..w {
                let border = ix < 2 || iy < 2 || ix >= w - 2 || iy >= h - 2;
                let inner = ((39..41).contains(&iy) && ix < 60) || ((79..81).contains(&iy) && ix >= 100);
                let extra = asymmetric && (129..131).contains(&ix) && iy < 80;
                g.set(ix, iy, if border || inner || extra { 2.0 } else { -2.0 });
            }
        }
        g
    }

    #[test]
    fn a_map_a_half_turn_maps_onto_itself_is_refused_as_ambiguous() {
        let g = building(false);
        let merger = CorrelativeMerger::default();
        let sig = significance(&merger, &g, &g).unwrap();
        assert!(sig.margin() < 0.05, "margin {:.3}", sig.margin());
        let no = merger.align(&g, &g).unwrap_err();
        assert!(no.reason.starts_with("ambiguous"), "{}", no.reason);
        // The rival is named: the other of identity and the half turn, about 180 degrees away.
        let rival = (sig.best.inverse() * sig.rival.unwrap()).rotation.angle().abs().to_degrees();
        assert!(rival > 178.0, "rival {rival:.1} deg away");
        assert!(no.reason.contains(&format!("a pose {rival:.0} deg")), "{}", no.reason);
        // With the test off the old behaviour returns: an answer (one of the two) for the gate to judge.
        let off = CorrelativeMerger::new(CorrelativeParams { min_margin: 0.0, ..CorrelativeParams::default() });
        assert!(off.align(&g, &g).is_ok());
    }

    #[test]
    fn the_answer_is_checked_the_other_way_round() {
        let map = generate(5, &FloorplanParams { width_m: 16.0, height_m: 12.0, ..FloorplanParams::default() });
        let pair = cut_pair(&map, &PairSpec { overlap: 0.4, max_shift_m: 3.0, rotate: true }, 2);
        let one_way = CorrelativeMerger::new(CorrelativeParams { cross_check: false, ..Default::default() });
        let forward = one_way.align(&pair.a, &pair.b).unwrap();
        let checked = CorrelativeMerger::default().align(&pair.a, &pair.b).unwrap();
        assert_eq!(checked.transform, forward.transform, "the check only accepts or refuses");
        assert!(checked.timings_ms.contains_key("cross_check"));
        let back = one_way.align(&pair.b, &pair.a).unwrap();
        let (deg, m) = error(&back.transform.inverse(), &forward.transform);
        assert!(deg < 0.5 && m < 0.1, "the other way round: {deg:.2} deg, {m:.3} m apart");
        // A map a with fewer wall blocks than b: asking for a count between the two, a into b is not searched;
        // nothing to check against, the answer stands.
        let blocks =
            |g: &OccupancyGrid| WallScan::of_blocks(g, 8, CorrelativeParams::default().max_points).points.len();
        let (na, nb) = (blocks(&pair.a), blocks(&pair.b));
        let (small, large) = if na < nb { (&pair.a, &pair.b) } else { (&pair.b, &pair.a) };
        let between = CorrelativeParams { min_points: na.min(nb) + 1, ..Default::default() };
        assert!(between.min_points <= na.max(nb), "the cuts have {na} and {nb} wall blocks");
        let one_way = CorrelativeMerger::new(CorrelativeParams { cross_check: false, ..between });
        let checked = CorrelativeMerger::new(between);
        assert_eq!(checked.align(small, large).unwrap().transform, one_way.align(small, large).unwrap().transform);
    }

    #[test]
    fn the_other_way_round_refuses_when_ambiguous_or_elsewhere_not_when_unsettled() {
        let no = |reason: &str| fail(reason.to_string(), BTreeMap::new());
        let points: Vec<Point2<f64>> = vec![Point2::new(0.0, 0.0), Point2::new(10.0, 0.0)];
        let t = pose(1.0, 2.0, 0.3);
        // b's points 10 m from the origin move 10 · 0.08 = 0.8 m under a turn of 0.08 rad: the same answer at 1 m.
        let near = Ok((vec![(t * pose(0.0, 0.0, 0.08)).inverse()], Vec::new()));
        assert_eq!(cross_check_refusal(&t, &points, near, 1.0), None);
        let far = Ok((vec![(t * pose(0.0, 0.0, 0.12)).inverse()], Vec::new()));
        let why = cross_check_refusal(&t, &points, far, 1.0).unwrap();
        assert!(why.contains("another answer") && why.contains("1.2 m"), "{why}");
        let why = cross_check_refusal(&t, &points, Err(NoAnswer::Ambiguous(no("ambiguous: a half turn"))), 1.0);
        assert_eq!(why.as_deref(), Some("merged the other way round the maps are ambiguous: a half turn"));
        assert_eq!(cross_check_refusal(&t, &points, Err(NoAnswer::Unsettled(no("too few walls"))), 1.0), None);
    }

    #[test]
    fn a_map_a_half_turn_does_not_map_onto_itself_is_accepted() {
        let g = building(true);
        let merger = CorrelativeMerger::default();
        let sig = significance(&merger, &g, &g).unwrap();
        assert!(sig.margin() >= merger.params.min_margin, "margin {:.3}", sig.margin());
        let al = merger.align(&g, &g).unwrap();
        let (deg, m) = error(&al.transform, &Pose2::identity());
        assert!(deg < 0.5 && m < 0.05, "off by {deg:.2} deg, {m:.3} m");
    }

    #[test]
    fn single_rays_into_unknown_space_do_not_count_against_the_true_pose() {
        // a: the building's left 100 columns (the rest unknown); b: the whole building; the truth: identity.
        let b = building(true);
        let mut a = b.clone();
        for iy in 0..120 {
            for ix in 100..160 {
                a.set(ix, iy, 0.0);
            }
        }
        // The same a crossed by a fan of single rays from (50, 60) out over its unknown part, as a real lidar
        // sees through glass: lines of free cells where b's walls are.
        let mut rays = a.clone();
        for k in 0..24 {
            let th = -0.6 + 1.2 * f64::from(k) / 23.0;
            for s in 50..200 {
                let (ix, iy) = ((50.0 + f64::from(s) * th.cos()) as usize, (60.0 + f64::from(s) * th.sin()) as usize);
                if (100..160).contains(&ix) && (2..118).contains(&iy) {
                    rays.set(ix, iy, -2.0);
                }
            }
        }
        let score = |share: f64, a: &OccupancyGrid| {
            let merger = CorrelativeMerger::new(CorrelativeParams { dense_free_share: share, ..Default::default() });
            let (s, counts, _) = score_near(&merger, a, &b, &Pose2::identity());
            (s, counts[1])
        };
        let (dense, dense_rays) = (score(0.5, &a), score(0.5, &rays));
        let (every, every_rays) = (score(0.0, &a), score(0.0, &rays));
        // Without the rays the two agree; counting every free cell, b's walls under the rays (28 of its points)
        // sink the true pose below zero; counting dense free space only, the rays change nothing.
        assert_eq!(dense, every);
        assert!(every_rays.1 >= every.1 + 20 && every_rays.0 < 0, "{every:?} -> {every_rays:?}");
        assert_eq!(dense_rays, dense);
    }

    #[test]
    fn its_gate_asks_less_wall_agreement_and_nothing_else_changes() {
        let merger = CorrelativeMerger::default();
        let gate = VerifyParams::default();
        assert_eq!(merger.gate(&gate), VerifyParams { min_wall_agreement: 0.4, ..gate });
        // A gate that already asks less keeps its own.
        let lax = VerifyParams { min_wall_agreement: 0.3, ..gate };
        assert_eq!(merger.gate(&lax), lax);
    }

    #[test]
    fn the_margin_is_the_winners_lead_over_its_rival() {
        let s = |best, rival: Option<i64>| Significance {
            best: Pose2::identity(),
            best_score: best,
            rival: rival.map(|_| pose(1.0, 2.0, PI)),
            rival_score: rival.unwrap_or(0),
        };
        assert!((s(1000, Some(900)).margin() - 0.1).abs() < 1e-12);
        assert_eq!(s(1000, Some(-50)).margin(), 1.0);
        assert_eq!(s(1000, None).margin(), 1.0);
        assert_eq!(s(-10, None).margin(), 0.0);
        assert!(s(1000, Some(900)).refusal(0.0).is_none());
        assert!(s(1000, Some(900)).refusal(0.05).is_none());
        let why = s(1000, Some(900)).refusal(0.15).unwrap();
        assert!(why.contains("180 deg") && why.contains("90% of it") && why.contains("lead by 15%"), "{why}");
    }
}
