//! N maps at once: overlapping cuts of one floor plan, each moved by a known transform, plus a map of another
//! building: every cut lands where it belongs in map 0's frame, the stranger is left out, no false edge.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_core::{OccupancyGrid, Pose2, pose};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::resample::resample;
use mrslam_merge::{MergeParams, SiftMerger, merge_many};

/// The cells of `map` in the window [x0, x1) x [y0, y1) (fractions of its size), as a grid of their own in
/// the same map frame.
fn window(map: &OccupancyGrid, x0: f64, x1: f64, y0: f64, y1: f64) -> OccupancyGrid {
    let (w, h) = (map.width() as f64, map.height() as f64);
    let (i0, i1, j0, j1) = ((x0 * w) as usize, (x1 * w) as usize, (y0 * h) as usize, (y1 * h) as usize);
    let o = map.origin();
    assert_eq!(o.rotation.angle(), 0.0, "floor plans are axis-aligned");
    let r = map.resolution();
    let mut g = OccupancyGrid::new(
        i1 - i0,
        j1 - j0,
        r,
        pose(o.translation.x + i0 as f64 * r, o.translation.y + j0 as f64 * r, 0.0),
    )
    .unwrap();
    for j in j0..j1 {
        for i in i0..i1 {
            g.set(i - i0, j - j0, map.get(i, j));
        }
    }
    g
}

/// Rotation (deg) and translation (m) between two transforms.
fn error(est: &Pose2, truth: &Pose2) -> (f64, f64) {
    let d = est.inverse() * truth;
    (d.rotation.angle().to_degrees().abs(), d.translation.vector.norm())
}

#[test]
fn overlapping_cuts_are_placed_and_a_stranger_is_left_out() {
    let p = FloorplanParams::default();
    let plan = generate(31, &p);
    let other = generate(77, &p);
    // Four overlapping quarters (30 % of the side shared with each neighbour) and a piece of another building.
    let cuts = [
        window(&plan, 0.0, 0.65, 0.0, 0.65),
        window(&plan, 0.35, 1.0, 0.0, 0.65),
        window(&plan, 0.0, 0.65, 0.35, 1.0),
        window(&plan, 0.35, 1.0, 0.35, 1.0),
        window(&other, 0.2, 0.8, 0.2, 0.8),
    ];
    // Each map re-rendered in its own frame: t_k_world takes the building's frame into map k's.
    let moves =
        [pose(0.7, -1.2, 0.4), pose(-2.0, 3.0, -1.9), pose(4.0, 1.0, 2.6), pose(-3.5, -2.5, 0.9), pose(1.0, 1.0, -0.6)];
    let maps: Vec<OccupancyGrid> = cuts.iter().zip(&moves).map(|(c, t)| resample(c, t, p.resolution)).collect();
    let out = merge_many(&SiftMerger::default(), &maps, &MergeParams::default());
    let r = &out.report;
    let truth = |k: usize| moves[0] * moves[k].inverse(); // T_0_k
    let summary = r
        .pairs
        .iter()
        .map(|q| format!("({}, {}) {} {:?}", q.a, q.b, q.report.accepted, q.report.reason))
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(r.pairs.len(), 10, "{summary}");
    // No false edge: the stranger joins nothing; every accepted pair among the cuts is right.
    for q in &r.pairs {
        if q.b == 4 {
            assert!(!q.report.accepted, "the stranger was merged with map {}:\n{summary}", q.a);
            continue;
        }
        if q.report.accepted {
            let t_ab = moves[q.a] * moves[q.b].inverse();
            let (rot, trans) = error(&q.report.transform.unwrap().to_pose(), &t_ab);
            assert!(rot <= 1.0 && trans <= 0.1, "pair ({}, {}) off by {rot} deg, {trans} m", q.a, q.b);
        }
    }
    assert_eq!(r.not_connected, vec![4], "{summary}");
    assert_eq!(r.components, vec![vec![0, 1, 2, 3], vec![4]], "{summary}");
    assert_eq!(r.tree.len(), 3);
    assert!(r.tree.iter().all(|e| e.child != 4 && e.parent != 4));
    for k in 0..4 {
        let (rot, trans) = error(&r.transforms[k].unwrap().to_pose(), &truth(k));
        assert!(rot <= 1.0 && trans <= 0.1, "map {k} off by {rot} deg, {trans} m; tree {:?}", r.tree);
    }
    assert!(r.transforms[4].is_none());
    // The merged map covers the building: about as many known cells as the plan (rotations blur a little).
    let merged = out.merged.unwrap();
    assert_eq!(merged.resolution(), p.resolution);
    let known = |g: &OccupancyGrid| {
        let (f, o, _) = g.state_counts();
        (f + o) as f64
    };
    let ratio = known(&merged) / known(&plan);
    assert!((0.97..1.05).contains(&ratio), "merged map has {ratio} of the plan's known cells");
}
