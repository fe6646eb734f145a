//! The merge pipeline shared by every algorithm: align, verify, fuse, report.

use crate::fuse::{FusionRule, fuse};
use crate::refine::{RefineParams, refine, wall_points};
use crate::report::{MergeReport, TransformXyt};
use crate::verify::{Agreement, VerifyParams, agreement, ambiguity, confidence, rejection_reason};
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
    /// Short name used in reports and on the command line (`sift`, `rmap`).
    fn name(&self) -> &'static str;
    /// Estimates `T_a_b`, or says why it cannot.
    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>>;
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
}

impl Default for MergeParams {
    fn default() -> Self {
        MergeParams {
            verify: VerifyParams::default(),
            verify_enabled: true,
            fusion: FusionRule::LogOddsSum,
            refine: RefineParams::default(),
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
    let agr = agreement(a, b, &h.transform);
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

/// Runs an algorithm, verifies its answer against both maps, and fuses them when it passes.
pub fn merge(merger: &dyn Merger, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
    let start = Instant::now();
    let alignment = match merger.align(a, b) {
        Ok(al) => al,
        Err(no) => {
            let report = MergeReport {
                accepted: false,
                algorithm: merger.name().to_string(),
                transform: None,
                scale: None,
                matches: no.matches,
                inliers: 0,
                confidence: 0.0,
                acceptance_index: None,
                common_cells: 0,
                wall_agreement: None,
                ambiguity: None,
                reason: Some(no.reason),
                time_ms: ms(start),
                timings_ms: no.timings_ms,
            };
            return MergeOutcome { report, merged: None, evidence: no.evidence };
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
    // The algorithm's answer first, then its alternatives: the first that passes the gate is taken.
    let mut chosen = check(a, b, &walls_b, primary, alignment.matched_features, p, &mut timings);
    if chosen.reason.is_some() && p.verify_enabled {
        for h in &alignment.alternatives {
            let c = check(a, b, &walls_b, h.clone(), alignment.matched_features, p, &mut timings);
            if c.reason.is_none() {
                chosen = c;
                break;
            }
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
        let g = fuse(a, b, &alignment.transform, p.fusion);
        timings.insert("fuse".into(), ms(t));
        g
    });
    let report = MergeReport {
        accepted: reason.is_none(),
        algorithm: merger.name().to_string(),
        transform: Some(TransformXyt::from_pose(&alignment.transform)),
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
