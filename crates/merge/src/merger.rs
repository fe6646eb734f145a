//! The merge pipeline shared by every algorithm: align, verify, fuse, report.

use crate::boundary_walls::{Boundary, BoundaryWalls};
use crate::fuse::{FusionRule, fuse};
use crate::refine::{RefineParams, refine, wall_points};
use crate::report::MergeReport;
use crate::verify::{Agreement, VerifyParams, agreement_within, ambiguity, confidence, rejection_reason};
use mrslam_core::Xyt;
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::time::Instant;

/// What an algorithm found: the transform taking map b's frame into map a's, and its evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    /// Rigid transform `T_a_b` (points of b's frame into a's frame).
    pub transform: Pose2,
    /// Scale of the estimated model (1 for rigid).
    pub scale: f64,
    /// Tentative correspondences (feature matches, or candidate triangle pairs).
    pub matches: usize,
    /// Features of map a with at least one correspondence: `matches` when each has one, fewer with k-NN.
    ///
    /// m-explore's confidence divides by the match count of a ratio-tested matcher; k candidates per feature
    /// would inflate it k-fold for the same evidence, so the confidence uses this count.
    pub matched_features: usize,
    /// Correspondences that support the transform.
    pub inliers: usize,
    /// Per-stage wall time, milliseconds.
    pub timings_ms: BTreeMap<String, f64>,
    /// Feature locations and inlier pairs, for drawing.
    pub evidence: Evidence,
    /// Weaker transforms the algorithm also found, strongest first; verification may pick one of them.
    pub alternatives: Vec<Hypothesis>,
    /// The alternatives only challenge the first transform (the gate's rival check) and are never accepted in
    /// its place: an answer that did not lead every other pose of a global search is not significant.
    pub alternatives_are_rivals: bool,
}

/// One candidate transform with its support.
#[derive(Debug, Clone, PartialEq)]
pub struct Hypothesis {
    /// Rigid transform `T_a_b`.
    pub transform: Pose2,
    /// Scale of the estimated model.
    pub scale: f64,
    /// Supporting correspondences.
    pub inliers: usize,
    /// Inlier pairs as (index in points_a, index in points_b).
    pub inlier_pairs: Vec<(usize, usize)>,
}

/// Where an algorithm's evidence lies, in each map's own frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Evidence {
    /// Feature points of map a (map frame, metres).
    pub points_a: Vec<Point2<f64>>,
    /// Feature points of map b (map frame, metres).
    pub points_b: Vec<Point2<f64>>,
    /// Inlier pairs as (index in points_a, index in points_b).
    pub inlier_pairs: Vec<(usize, usize)>,
}

/// Why an algorithm could not produce a transform, with the stage timings spent finding out.
#[derive(Debug, Clone, PartialEq)]
pub struct NoAlignment {
    /// Human-readable reason.
    pub reason: String,
    /// Correspondences found before giving up.
    pub matches: usize,
    /// Per-stage wall time, milliseconds.
    pub timings_ms: BTreeMap<String, f64>,
    /// Evidence gathered before giving up.
    pub evidence: Evidence,
}

/// A map-merging algorithm: finds the transform between two occupancy grids of unknown relative pose.
pub trait Merger: Send + Sync {
    /// Short name used in reports and on the command line: [`crate::Algorithm::name`] for this crate's mergers.
    fn name(&self) -> &'static str;
    /// Estimates `T_a_b`, or says why it cannot.
    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>>;
    /// Its stages when it is a [`crate::Cascade`] ([`merge`] puts each stage's answer through the gate in turn).
    fn cascade(&self) -> Option<&crate::Cascade> {
        None
    }
    /// Whether it needs both maps to mark their walls ([`crate::boundary_walls::marks_its_walls`]): [`merge`]
    /// refuses, naming the map, a pair where one does not, rather than let the algorithm take a frontier for a
    /// wall.
    fn needs_marked_walls(&self) -> bool {
        false
    }
    /// The gate its answers go through, given the pipeline's: that gate unless the algorithm says otherwise.
    fn gate(&self, verify: &VerifyParams) -> VerifyParams {
        *verify
    }
}

/// Parameters of the pipeline around an algorithm.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MergeParams {
    /// Thresholds of the verification gate.
    pub verify: VerifyParams,
    /// Apply the gate (false shows the raw algorithm's answer, accepted whatever it is).
    pub verify_enabled: bool,
    /// How aligned cells combine.
    pub fusion: FusionRule,
    /// Wall ICP applied to the algorithm's transform before verification.
    pub refine: RefineParams,
    /// Which maps get walls where their free space meets unknown, for the alignment and the gate
    /// ([`crate::boundary_walls`]): by default those that do not mark their walls (map_server's light-grey walls,
    /// glass); `Off` is the paper's behaviour. The merged map is fused from the maps as given.
    pub boundary_walls: BoundaryWalls,
}

impl Default for MergeParams {
    fn default() -> Self {
        MergeParams {
            verify: VerifyParams::default(),
            verify_enabled: true,
            fusion: FusionRule::LogOddsSum,
            refine: RefineParams::default(),
            boundary_walls: BoundaryWalls::Unmarked,
        }
    }
}

/// Everything a merge produced.
#[derive(Debug, Clone)]
pub struct MergeOutcome {
    /// The report (also the JSON written by `--report`).
    pub report: MergeReport,
    /// The merged grid in a's frame, when accepted.
    pub merged: Option<OccupancyGrid>,
    /// The algorithm's evidence (present whether accepted or not).
    pub evidence: Evidence,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A hypothesis after refinement and the verification gate.
struct Checked {
    hypothesis: Hypothesis,
    agreement: Agreement,
    ambiguity: Option<f64>,
    /// Why the gate rejects it (None: accepted, or the gate is off).
    reason: Option<String>,
}

/// Refines one hypothesis and puts it through the gate; stage times add up over hypotheses.
fn check(
    a: &OccupancyGrid,
    b: &OccupancyGrid,
    walls_b: &[Point2<f64>],
    mut h: Hypothesis,
    matches: usize,
    p: &MergeParams,
    timings: &mut BTreeMap<String, f64>,
) -> Checked {
    let mut add = |stage: &str, t: Instant| *timings.entry(stage.into()).or_insert(0.0) += ms(t);
    if p.refine.enabled {
        let t = Instant::now();
        h.transform = refine(a, walls_b, &h.transform, &p.refine);
        add("refine", t);
    }
    let t = Instant::now();
    let agr = agreement_within(a, b, &h.transform, p.verify.wall_tolerance_cells);
    add("verify", t);
    let mut reason = if p.verify_enabled { rejection_reason(&p.verify, h.inliers, matches, &agr) } else { None };
    let mut ambiguous = None;
    if reason.is_none() && p.verify_enabled {
        let t = Instant::now();
        let amb = ambiguity(a, walls_b, &h.transform, p.verify.ambiguity_shift_m);
        add("ambiguity", t);
        ambiguous = Some(amb);
        if amb >= p.verify.max_ambiguity {
            reason = Some(format!(
                "ambiguous: slid {} m, b still meets {:.0}% of the walls it meets in place (limit {:.0}%); \
                 the maps do not pin the transform down",
                p.verify.ambiguity_shift_m,
                100.0 * amb,
                100.0 * p.verify.max_ambiguity
            ));
        }
    }
    Checked { hypothesis: h, agreement: agr, ambiguity: ambiguous, reason }
}

/// Why an accepted hypothesis is not trusted after all: a distinct later hypothesis that fits the maps as well.
///
/// A rival need only pass the map checks (common cells, wall agreement, acceptance), not the feature-support
/// ones: a self-similar map can be explained by two transforms with quite different inlier counts. Walls are
/// compared within one cell here whatever `wall_tolerance_cells`: a wider tolerance lets a rival's misplaced
/// walls meet a's, and tells the two transforms apart less.
fn rival_reason(
    a: &OccupancyGrid,
    b: &OccupancyGrid,
    walls_b: &[Point2<f64>],
    chosen: &Checked,
    rest: impl Iterator<Item = Hypothesis>,
    p: &MergeParams,
) -> Option<String> {
    let map_checks = VerifyParams { min_inliers: 0, min_confidence: 0.0, wall_tolerance_cells: 1, ..p.verify };
    let own = if p.verify.wall_tolerance_cells == 1 {
        chosen.agreement.wall_agreement()
    } else {
        agreement_within(a, b, &chosen.hypothesis.transform, 1).wall_agreement()
    };
    for mut h in rest {
        if p.refine.enabled {
            h.transform = refine(a, walls_b, &h.transform, &p.refine);
        }
        let apart = max_displacement(walls_b, &chosen.hypothesis.transform, &h.transform);
        if apart <= p.verify.ambiguity_shift_m {
            continue;
        }
        let agr = agreement_within(a, b, &h.transform, 1);
        if rejection_reason(&map_checks, 0, 0, &agr).is_none() && agr.wall_agreement() >= p.verify.max_rival_ratio * own
        {
            let (d_rot, d_xy) = pose_difference(&chosen.hypothesis.transform, &h.transform);
            return Some(format!(
                "two transforms fit: another one, {d_rot:.0} deg and {d_xy:.1} m away, meets {:.0}% of b's walls \
                 against {:.0}% (rival limit {:.0}%)",
                100.0 * agr.wall_agreement(),
                100.0 * own,
                100.0 * p.verify.max_rival_ratio
            ));
        }
    }
    None
}

/// Largest distance between where two transforms put b's wall points, metres.
fn max_displacement(walls_b: &[Point2<f64>], t1: &Pose2, t2: &Pose2) -> f64 {
    walls_b.iter().map(|q| (t1 * q - t2 * q).norm()).fold(0.0, f64::max)
}

/// Rotation (degrees) and translation (metres) between two transforms.
fn pose_difference(t1: &Pose2, t2: &Pose2) -> (f64, f64) {
    let d = t1.inverse() * t2;
    (d.rotation.angle().to_degrees().abs(), d.translation.vector.norm())
}

/// Runs an algorithm, verifies its answer against both maps, and fuses them when it passes (a cascade: each of
/// its stages in turn, until one passes).
pub fn merge(merger: &dyn Merger, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
    match merger.cascade() {
        Some(c) => crate::cascade::merge_cascade(c, a, b, p),
        None => merge_one(merger, a, b, p),
    }
}

/// Why a map that does not mark its walls cannot go to an algorithm that needs them; None when it does.
fn unmarked_walls(boundary: &Boundary, name: &str) -> Option<String> {
    (!boundary.marks_its_walls()).then(|| {
        format!(
            "map {name} does not mark its walls ({} occupied cells): its walls would be its free/unknown boundary, \
             where a frontier looks like a wall, and this search scores the other map's free space against them; \
             the sift merger takes such maps",
            boundary.occupied()
        )
    })
}

/// The outcome of a merge refused before the gate: no transform, no merged map.
pub(crate) fn refused(
    merger: &dyn Merger,
    reason: String,
    matches: usize,
    timings_ms: BTreeMap<String, f64>,
    start: Instant,
) -> MergeOutcome {
    let report = MergeReport {
        accepted: false,
        algorithm: merger.name().to_string(),
        stage: None,
        transform: None,
        scale: None,
        matches,
        inliers: 0,
        confidence: 0.0,
        acceptance_index: None,
        common_cells: 0,
        wall_agreement: None,
        ambiguity: None,
        reason: Some(reason),
        time_ms: ms(start),
        timings_ms,
    };
    MergeOutcome { report, merged: None, evidence: Evidence::default() }
}

/// [`merge`] for one algorithm.
pub(crate) fn merge_one(merger: &dyn Merger, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
    let start = Instant::now();
    let needed = p.boundary_walls != BoundaryWalls::Off || merger.needs_marked_walls();
    let boundaries = needed.then(|| (Boundary::of(a), Boundary::of(b)));
    merge_bounded(merger, (a, b), boundaries.as_ref().map(|(x, y)| (x, y)), p, start)
}

/// [`merge_one`] with the maps' boundaries found already (None: neither the mode nor the algorithm needs them); the
/// merge's time counts from `start`.
pub(crate) fn merge_bounded(
    merger: &dyn Merger,
    (a, b): (&OccupancyGrid, &OccupancyGrid),
    boundaries: Option<(&Boundary, &Boundary)>,
    p: &MergeParams,
    start: Instant,
) -> MergeOutcome {
    if merger.needs_marked_walls()
        && let Some(reason) = boundaries.and_then(|(x, y)| unmarked_walls(x, "a").or_else(|| unmarked_walls(y, "b")))
    {
        return refused(merger, reason, 0, BTreeMap::new(), start);
    }
    let p = &MergeParams { verify: merger.gate(&p.verify), ..*p };
    // Maps that do not mark their walls get them from their free/unknown boundary; the fusion takes the maps as given.
    let (given_a, given_b) = (a, b);
    let (walled_a, walled_b) = match boundaries {
        Some((x, y)) => (x.walls(a, p.boundary_walls), y.walls(b, p.boundary_walls)),
        None => (None, None),
    };
    let (a, b) = (walled_a.as_ref().unwrap_or(a), walled_b.as_ref().unwrap_or(b));
    let alignment = match merger.align(a, b) {
        Ok(al) => al,
        Err(no) => {
            let NoAlignment { reason, matches, timings_ms, evidence } = *no;
            return MergeOutcome { evidence, ..refused(merger, reason, matches, timings_ms, start) };
        }
    };
    let mut timings = alignment.timings_ms.clone();
    // b's walls serve both the refinement and the ambiguity check: collect them once.
    let walls_b = if p.refine.enabled || p.verify_enabled { wall_points(b) } else { Vec::new() };
    let primary = Hypothesis {
        transform: alignment.transform,
        scale: alignment.scale,
        inliers: alignment.inliers,
        inlier_pairs: alignment.evidence.inlier_pairs.clone(),
    };
    // The algorithm's answer first, then its alternatives: the first that passes the gate is taken, unless a
    // distinct later one fits the maps about as well (then neither is trusted).
    let mut hypotheses = std::iter::once(primary).chain(alignment.alternatives.iter().cloned());
    let first = hypotheses.next().expect("the primary hypothesis");
    let mut chosen = check(a, b, &walls_b, first, alignment.matched_features, p, &mut timings);
    if p.verify_enabled {
        while chosen.reason.is_some() && !alignment.alternatives_are_rivals {
            let Some(h) = hypotheses.next() else { break };
            chosen = check(a, b, &walls_b, h, alignment.matched_features, p, &mut timings);
        }
        if chosen.reason.is_none() {
            let t = Instant::now();
            chosen.reason = rival_reason(a, b, &walls_b, &chosen, hypotheses, p);
            *timings.entry("rivals".into()).or_insert(0.0) += ms(t);
        }
    }
    let Checked { hypothesis, agreement: agr, ambiguity: ambiguous, reason } = chosen;
    let conf = confidence(hypothesis.inliers, alignment.matched_features);
    let mut alignment = alignment;
    alignment.evidence.inlier_pairs = hypothesis.inlier_pairs.clone();
    alignment.transform = hypothesis.transform;
    alignment.scale = hypothesis.scale;
    alignment.inliers = hypothesis.inliers;
    let merged = reason.is_none().then(|| {
        let t = Instant::now();
        let g = fuse(given_a, given_b, &alignment.transform, p.fusion);
        timings.insert("fuse".into(), ms(t));
        g
    });
    let report = MergeReport {
        accepted: reason.is_none(),
        algorithm: merger.name().to_string(),
        stage: None,
        transform: Some(Xyt::from_pose(&alignment.transform)),
        scale: Some(alignment.scale),
        matches: alignment.matches,
        inliers: alignment.inliers,
        confidence: conf,
        acceptance_index: Some(agr.acceptance_index()),
        common_cells: agr.common(),
        wall_agreement: Some(agr.wall_agreement()),
        ambiguity: ambiguous,
        reason,
        time_ms: ms(start),
        timings_ms: timings,
    };
    MergeOutcome { report, merged, evidence: alignment.evidence }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use mrslam_core::pose;

    /// An algorithm that answers with fixed hypotheses.
    pub(crate) struct Fixed(pub Vec<Pose2>);

    /// The same, its alternatives rivals only.
    struct FixedRivals(Vec<Pose2>);

    impl Merger for FixedRivals {
        fn name(&self) -> &'static str {
            "fixed"
        }
        fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
            let al = Fixed(self.0.clone()).align(a, b)?;
            Ok(Alignment { alternatives_are_rivals: true, ..al })
        }
    }

    impl Merger for Fixed {
        fn name(&self) -> &'static str {
            "fixed"
        }
        fn align(&self, _: &OccupancyGrid, _: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
            let hyp = |t: &Pose2| Hypothesis { transform: *t, scale: 1.0, inliers: 12, inlier_pairs: Vec::new() };
            Ok(Alignment {
                transform: self.0[0],
                scale: 1.0,
                matches: 12,
                matched_features: 12,
                inliers: 12,
                timings_ms: BTreeMap::new(),
                evidence: Evidence::default(),
                alternatives: self.0[1..].iter().map(hyp).collect(),
                alternatives_are_rivals: false,
            })
        }
    }

    /// A closed 4 m x 3 m room; with `stub`, a 3 m wall juts in from one side and breaks its symmetry.
    pub(crate) fn room(stub: bool) -> OccupancyGrid {
        let (w, h) = (80, 60);
        let mut g = OccupancyGrid::new(w, h, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..h {
            for ix in 0..w {
                let border = ix < 2 || iy < 2 || ix >= w - 2 || iy >= h - 2;
                let jut = stub && (2..60).contains(&ix) && (18..20).contains(&iy);
                g.set(ix, iy, if border || jut { 2.0 } else { -2.0 });
            }
        }
        g
    }

    /// Half a turn about the room's centre: maps the symmetric room onto itself.
    fn half_turn() -> Pose2 {
        pose(4.0, 3.0, std::f64::consts::PI)
    }

    #[test]
    fn a_symmetric_map_with_two_fitting_transforms_is_refused() {
        let g = room(false);
        let out = merge(&Fixed(vec![Pose2::identity(), half_turn()]), &g, &g, &MergeParams::default());
        assert!(!out.report.accepted);
        let reason = out.report.reason.unwrap();
        assert!(reason.starts_with("two transforms fit"), "{reason}");
        assert!(out.merged.is_none());
    }

    #[test]
    fn a_rival_that_contradicts_the_maps_does_not_block_the_merge() {
        let g = room(true);
        let out = merge(&Fixed(vec![Pose2::identity(), half_turn()]), &g, &g, &MergeParams::default());
        assert!(out.report.accepted, "{:?}", out.report.reason);
        let t = out.report.transform.unwrap();
        assert!(t.x.abs() < 0.05 && t.y.abs() < 0.05 && t.theta.abs() < 0.01, "{t:?}");
    }

    #[test]
    fn the_rival_check_can_be_turned_off() {
        let g = room(false);
        let mut p = MergeParams::default();
        p.verify.max_rival_ratio = f64::INFINITY;
        let out = merge(&Fixed(vec![Pose2::identity(), half_turn()]), &g, &g, &p);
        assert!(out.report.accepted, "{:?}", out.report.reason);
    }

    #[test]
    fn a_rival_only_alternative_is_never_accepted_in_the_first_answers_place() {
        let g = room(true);
        // The first answer, 1 m off, fails the gate; the second is right.
        let hyps = vec![pose(1.0, 0.0, 0.0), Pose2::identity()];
        let out = merge(&Fixed(hyps.clone()), &g, &g, &MergeParams::default());
        assert!(out.report.accepted, "{:?}", out.report.reason);
        let out = merge(&FixedRivals(hyps), &g, &g, &MergeParams::default());
        assert!(!out.report.accepted);
    }
}
