//! The verification gate applied to an algorithm's hypotheses: each refined by wall ICP and checked against both
//! maps, and an accepted one challenged by the later ones (rivals).

use crate::alignment::Hypothesis;
use crate::merge_params::MergeParams;
use crate::refine::refine;
use crate::timing::ms;
use crate::verify::{Agreement, VerifyParams, agreement_within, ambiguity, rejection_reason};
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::time::Instant;

/// A hypothesis after refinement and the verification gate.
pub(crate) struct Checked {
    /// The hypothesis, refined.
    pub(crate) hypothesis: Hypothesis,
    /// How the maps agree under it.
    pub(crate) agreement: Agreement,
    /// Its ambiguity under slides, when the gate measured it.
    pub(crate) ambiguity: Option<f64>,
    /// Why the gate rejects it (None: accepted, or the gate is off).
    pub(crate) reason: Option<String>,
}

/// Refines one hypothesis and puts it through the gate; stage times add up over hypotheses.
pub(crate) fn check(
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
    let mut reason = if p.verify_enabled {
        // The maps' own checks first: what they say of an answer reads the same with or without a contact.
        rejection_reason(&p.verify, h.inliers, matches, &agr)
            .or_else(|| p.contact.and_then(|c| c.refusal(&h.transform)))
    } else {
        None
    };
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
pub(crate) fn rival_reason(
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
        // A rival out of the robots' reach still counts: it says the maps are alike elsewhere too, and an answer
        // within reach may then be a coincidence (the FR079 study, 2026-12-07).
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
