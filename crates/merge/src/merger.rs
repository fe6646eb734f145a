//! The merger interface and the pipeline every algorithm's answer goes through: align, refine, verify, fuse, report.

use crate::boundary_walls::{Boundary, BoundaryWalls};
use crate::contact::Contact;
use crate::fuse::fuse;
use crate::gate::{Checked, check, rival_reason};
use crate::refine::wall_points;
use crate::report::{MergeOutcome, MergeReport, refused};
use crate::timing::ms;
use crate::verify::{VerifyParams, confidence};
use mrslam_core::OccupancyGrid;
use mrslam_core::Xyt;
use std::collections::BTreeMap;
use std::time::Instant;

// The correlative search (its own module tree) names these through here.
use crate::alignment::{Alignment, Hypothesis, NoAlignment};
use crate::merge_params::MergeParams;

/// A map-merging algorithm: finds the transform between two occupancy grids of unknown relative pose.
pub trait Merger: Send + Sync {
    /// Short name used in reports and on the command line: [`crate::Algorithm::name`] for this crate's mergers.
    fn name(&self) -> &'static str;
    /// Estimates `T_a_b`, or says why it cannot.
    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>>;
    /// [`Merger::align`] for maps whose robots were in `contact`: an algorithm that searches may keep to the
    /// transforms that put them within reach (the gate refuses the others whatever the algorithm does).
    fn align_near(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        contact: Option<&Contact>,
    ) -> Result<Alignment, Box<NoAlignment>> {
        let _ = contact;
        self.align(a, b)
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
    /// Runs it through the pipeline: its answer refined, put through the gate, fused when accepted. A merger made
    /// of others (the cascade) overrides it to run each of them through the pipeline in turn.
    fn merge(&self, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
        merge_one(self, a, b, p)
    }
}

/// Runs an algorithm, verifies its answer against both maps, and fuses them when it passes: [`Merger::merge`].
pub fn merge(merger: &dyn Merger, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
    merger.merge(a, b, p)
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

/// [`merge`] for one algorithm.
pub(crate) fn merge_one<M: Merger + ?Sized>(
    merger: &M,
    a: &OccupancyGrid,
    b: &OccupancyGrid,
    p: &MergeParams,
) -> MergeOutcome {
    let start = Instant::now();
    let needed = p.boundary_walls != BoundaryWalls::Off || merger.needs_marked_walls();
    let boundaries = needed.then(|| (Boundary::of(a), Boundary::of(b)));
    merge_bounded(merger, (a, b), boundaries.as_ref().map(|(x, y)| (x, y)), p, start)
}

/// [`merge_one`] with the maps' boundaries found already (None: neither the mode nor the algorithm needs them); the
/// merge's time counts from `start`.
pub(crate) fn merge_bounded<M: Merger + ?Sized>(
    merger: &M,
    (a, b): (&OccupancyGrid, &OccupancyGrid),
    boundaries: Option<(&Boundary, &Boundary)>,
    p: &MergeParams,
    start: Instant,
) -> MergeOutcome {
    if merger.needs_marked_walls()
        && let Some(reason) = boundaries.and_then(|(x, y)| unmarked_walls(x, "a").or_else(|| unmarked_walls(y, "b")))
    {
        return refused(merger.name(), reason, 0, BTreeMap::new(), start);
    }
    let p = &MergeParams { verify: merger.gate(&p.verify), ..*p };
    // Maps that do not mark their walls get them from their free/unknown boundary; the fusion takes the maps as given.
    let (given_a, given_b) = (a, b);
    let (walled_a, walled_b) = match boundaries {
        Some((x, y)) => (x.walls(a, p.boundary_walls), y.walls(b, p.boundary_walls)),
        None => (None, None),
    };
    let (a, b) = (walled_a.as_ref().unwrap_or(a), walled_b.as_ref().unwrap_or(b));
    let alignment = match merger.align_near(a, b, p.contact.as_ref()) {
        Ok(al) => al,
        Err(no) => {
            let NoAlignment { reason, matches, timings_ms, evidence } = *no;
            return MergeOutcome { evidence, ..refused(merger.name(), reason, matches, timings_ms, start) };
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
    use crate::alignment::Evidence;
    use mrslam_core::{Pose2, pose};

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
