//! The correlative merger through the whole pipeline: generated cuts with known transforms are recovered,
//! pairs that share nothing are refused by the verification gate, bad input is refused with a reason.

use mrslam_core::{OccupancyGrid, Pose2, pose};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{CorrelativeMerger, MergeParams, Merger, merge};

/// Rotation (degrees) and translation (metres) errors of an answer against the truth.
fn error(x: f64, y: f64, theta: f64, truth: &Pose2) -> (f64, f64) {
    let d = truth.inverse() * pose(x, y, theta);
    (d.rotation.angle().to_degrees().abs(), d.translation.vector.norm())
}

fn plan() -> FloorplanParams {
    FloorplanParams { width_m: 18.0, height_m: 14.0, ..FloorplanParams::default() }
}

#[test]
fn generated_cuts_are_merged_at_their_true_transform() {
    let merger = CorrelativeMerger::default();
    for (seed, overlap) in [(1, 0.3), (2, 0.5), (3, 0.4), (4, 0.6)] {
        let map = generate(seed, &plan());
        let pair = cut_pair(&map, &PairSpec { overlap, max_shift_m: 4.0, rotate: true }, seed);
        let out = merge(&merger, &pair.a, &pair.b, &MergeParams::default());
        let r = &out.report;
        assert!(r.accepted, "seed {seed} overlap {overlap}: refused: {:?}", r.reason);
        let t = r.transform.expect("an accepted merge has a transform");
        let (deg, m) = error(t.x, t.y, t.theta, &pair.t_a_b);
        assert!(deg < 0.5 && m < 0.1, "seed {seed} overlap {overlap}: off by {deg:.2} deg, {m:.3} m");
        assert!(r.confidence > 1.0, "seed {seed}: confidence {}", r.confidence);
        assert!(out.merged.is_some());
    }
}

/// Seeds 10-15 of 18 m x 14 m plans. Known limit: over seeds 10-69 the gate let through 4 of 60 such gap pairs
/// (seeds 24, 30, 35, 61: 21-43 m² laid wall on wall, acceptance 0.95-0.97) and 1 of 60 at 24 m x 18 m;
/// trying every pose finds such coincidences in self-similar plans, SIFT's features do not (0 of 120).
#[test]
fn pairs_that_share_nothing_are_refused_never_merged() {
    let merger = CorrelativeMerger::default();
    for seed in 10..16 {
        let map = generate(seed, &plan());
        let pair = cut_pair(&map, &PairSpec { overlap: -0.1, max_shift_m: 4.0, rotate: true }, seed);
        let out = merge(&merger, &pair.a, &pair.b, &MergeParams::default());
        assert!(!out.report.accepted, "seed {seed}: a gap pair merged: {:?}", out.report);
        assert!(out.report.reason.is_some());
        assert!(out.merged.is_none());
    }
}

#[test]
fn maps_without_walls_are_refused_with_a_reason() {
    let map = generate(3, &plan());
    let mut blank = OccupancyGrid::new(100, 80, 0.05, pose(0.0, 0.0, 0.0)).expect("a grid");
    let merger = CorrelativeMerger::default();
    let no_b = merger.align(&map, &blank).expect_err("b has no walls");
    assert!(no_b.reason.contains("too few walls in map b"), "{}", no_b.reason);
    for l in blank.cells_mut() {
        *l = -2.0;
    }
    let no_a = merger.align(&blank, &map).expect_err("a has no walls");
    assert!(no_a.reason.contains("map a has no walls"), "{}", no_a.reason);
}

#[test]
fn maps_at_different_resolutions_are_merged() {
    let map = generate(2, &plan());
    let pair = cut_pair(&map, &PairSpec { overlap: 0.5, max_shift_m: 3.0, rotate: true }, 2);
    // b at 0.1 m: the search pools each map by its own factor.
    let coarse_b = mrslam_merge::resample::to_resolution(&pair.b, 0.1);
    let out = merge(&CorrelativeMerger::default(), &pair.a, &coarse_b, &MergeParams::default());
    let t = out.report.transform.expect("a transform");
    let (deg, m) = error(t.x, t.y, t.theta, &pair.t_a_b);
    assert!(deg < 1.0 && m < 0.15, "off by {deg:.2} deg, {m:.3} m; {:?}", out.report.reason);
}

#[test]
fn answers_do_not_depend_on_threads() {
    use mrslam_merge::CorrelativeParams;
    let map = generate(6, &plan());
    let pair = cut_pair(&map, &PairSpec { overlap: 0.3, max_shift_m: 4.0, rotate: true }, 6);
    let parallel = CorrelativeMerger::default();
    let single = CorrelativeMerger::new(CorrelativeParams { parallel: false, ..CorrelativeParams::default() });
    let first = parallel.align(&pair.a, &pair.b).expect("an answer");
    for m in [&parallel, &single] {
        let again = m.align(&pair.a, &pair.b).expect("an answer");
        assert_eq!(again.transform, first.transform);
        let alts = |al: &mrslam_merge::Alignment| al.alternatives.iter().map(|h| h.transform).collect::<Vec<_>>();
        assert_eq!(alts(&again), alts(&first));
        assert_eq!((again.inliers, again.matches), (first.inliers, first.matches));
    }
}

/// Robots in contact: the search keeps near where both robots were. With the true contact the answer is the one
/// found without it; a contact that the true transform breaks (robot b 20 m away from where it was) gets no
/// merge, not another.
#[test]
fn robots_in_contact_are_merged_where_they_can_have_met_and_nowhere_else() {
    use mrslam_merge::Contact;
    use nalgebra::{Point2, Vector2};
    let merger = CorrelativeMerger::default();
    for (seed, overlap) in [(1, 0.3), (2, 0.5), (3, 0.4)] {
        let map = generate(seed, &plan());
        let pair = cut_pair(&map, &PairSpec { overlap, max_shift_m: 4.0, rotate: true }, seed);
        let (w, h, res) = (pair.a.width() as f64, pair.a.height() as f64, pair.a.resolution());
        let free = pair.a.origin() * Point2::new(0.5 * w * res, 0.5 * h * res);
        let contact = |apart: f64, search_within: bool| Contact {
            a: free,
            b: pair.t_a_b.inverse() * (free + Vector2::new(apart, 0.0)),
            within_m: 8.0,
            search_within,
        };
        // Searched within reach, and everywhere with the gate alone holding the bound.
        for search_within in [true, false] {
            let with = |c: Contact| MergeParams { contact: Some(c), ..MergeParams::default() };
            let near = merge(&merger, &pair.a, &pair.b, &with(contact(3.0, search_within)));
            let r = &near.report;
            assert!(r.accepted, "seed {seed} {search_within}: refused: {:?}", r.reason);
            let t = r.transform.expect("an accepted merge has a transform");
            let (deg, m) = error(t.x, t.y, t.theta, &pair.t_a_b);
            assert!(deg < 0.5 && m < 0.1, "seed {seed} {search_within}: off by {deg:.2} deg, {m:.3} m");
            let far = merge(&merger, &pair.a, &pair.b, &with(contact(20.0, search_within)));
            assert!(!far.report.accepted, "seed {seed} {search_within}: merged out of reach: {:?}", far.report);
        }
    }
}
