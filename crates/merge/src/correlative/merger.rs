//! The correlative merger behind the pipeline's [`Merger`] interface: its answers, checked the other way round.

use super::bookkeeping::fail;
use super::fine::Candidates;
use super::params::CorrelativeMerger;
use crate::alignment::{Alignment, Evidence, Hypothesis, NoAlignment};
use crate::contact::Contact;
use crate::merger::Merger;
use crate::timing::ms;
use crate::verify::{VerifyParams, wall_hits};
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::time::Instant;

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
        if let Some(reason) = significance.refusal(p.answer.min_margin) {
            let no = fail(reason, std::mem::take(timings));
            return Err(if significance.best_score > 0 { NoAnswer::Ambiguous(no) } else { NoAnswer::Unsettled(no) });
        }
        let t = Instant::now();
        let (poses, tried) = self.shared(a, b, &refined, min_overlap_m2);
        timings.insert("overlap".into(), ms(t));
        if poses.is_empty() {
            let smaller = a.known_area().min(b.known_area());
            let reason = if smaller < min_overlap_m2 {
                format!(
                    "the correlative stage accepts a pose only where the maps share {min_overlap_m2:.1} m² of known \
                     space, and the smaller map knows {smaller:.1} m² in all: it cannot accept on maps this small"
                )
            } else {
                format!(
                    "no pose shares {min_overlap_m2:.1} m² of known space with an acceptance index of {:.2} or more{}: \
                     the {} tried share {}",
                    p.answer.min_acceptance,
                    if p.answer.min_margin > 0.0 {
                        " (the significance test lets only the best pose be tried)"
                    } else {
                        ""
                    },
                    tried.len(),
                    tried.join(", ")
                )
            };
            return Err(NoAnswer::Unsettled(fail(reason, std::mem::take(timings))));
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
    /// [`crate::AnswerParams::min_wall_agreement`].
    fn gate(&self, verify: &VerifyParams) -> VerifyParams {
        VerifyParams {
            min_wall_agreement: verify.min_wall_agreement.min(self.params.answer.min_wall_agreement),
            ..*verify
        }
    }

    fn align_near(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        contact: Option<&Contact>,
    ) -> Result<Alignment, Box<NoAlignment>> {
        CorrelativeMerger { contact: contact.copied(), ..self.clone() }.align(a, b)
    }

    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        let p = &self.params;
        let mut timings = BTreeMap::new();
        // The search the other way round does not depend on this one's answer: with threads, both at once.
        let back = || {
            let t = Instant::now();
            let other_way = CorrelativeMerger { contact: self.contact.map(|c| c.swapped()), ..self.clone() };
            (other_way.answers(b, a, &mut BTreeMap::new()), ms(t))
        };
        let (forward, back) = match (p.answer.cross_check, p.parallel) {
            (false, _) => (self.answers(a, b, &mut timings), None),
            (true, false) => {
                // One after the other, the check only for an answer to check (a refusal stands without it).
                let forward = self.answers(a, b, &mut timings);
                let back = forward.is_ok().then(back);
                (forward, back)
            }
            (true, true) => {
                let (forward, back) = rayon::join(|| self.answers(a, b, &mut timings), back);
                (forward, Some(back))
            }
        };
        let (poses, points_b) = forward.map_err(NoAnswer::into_inner)?;
        if let Some((back, took)) = back {
            timings.insert("cross_check".into(), took);
            if let Some(reason) = cross_check_refusal(&poses[0], &points_b, back, p.search.distinct_m) {
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
            alternatives_are_rivals: p.answer.min_margin > 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correlative::params::CorrelativeParams;
    use crate::correlative::settle::{score_near, significance};
    use crate::floorplan::{FloorplanParams, generate};
    use crate::pairs::{PairSpec, cut_pair};
    use mrslam_core::pose;
    use mrslam_matching::WallScan;

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
        let mut off = CorrelativeParams::default();
        off.answer.min_margin = 0.0;
        let off = CorrelativeMerger::new(off);
        assert!(off.align(&g, &g).is_ok());
    }

    #[test]
    fn the_answer_is_checked_the_other_way_round() {
        let map = generate(5, &FloorplanParams { width_m: 16.0, height_m: 12.0, ..FloorplanParams::default() });
        let pair = cut_pair(&map, &PairSpec { overlap: 0.4, max_shift_m: 3.0, rotate: true }, 2);
        let mut one_way = CorrelativeParams::default();
        one_way.answer.cross_check = false;
        let one_way = CorrelativeMerger::new(one_way);
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
            |g: &OccupancyGrid| WallScan::of_blocks(g, 8, CorrelativeParams::default().search.max_points).points.len();
        let (na, nb) = (blocks(&pair.a), blocks(&pair.b));
        let (small, large) = if na < nb { (&pair.a, &pair.b) } else { (&pair.b, &pair.a) };
        let mut between = CorrelativeParams::default();
        between.search.min_points = na.min(nb) + 1;
        assert!(between.search.min_points <= na.max(nb), "the cuts have {na} and {nb} wall blocks");
        let mut one_way = between;
        one_way.answer.cross_check = false;
        let one_way = CorrelativeMerger::new(one_way);
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
        assert!(sig.margin() >= merger.params.answer.min_margin, "margin {:.3}", sig.margin());
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
            let mut params = CorrelativeParams::default();
            params.search.dense_free_share = share;
            let merger = CorrelativeMerger::new(params);
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
}
