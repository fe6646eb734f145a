//! The paper's two experiments, and the second one explored autonomously, end to end in simulation, checked
//! against ground truth.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_testbed::report::RunReport;
use mrslam_testbed::runner::{RunOptions, run, write_outputs};
use mrslam_testbed::scenario::{ControllerKind, MergeWhen, Scenario};
use std::path::Path;

fn run_scenario(name: &str) -> RunReport {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(format!("{name}.toml"));
    let scenario = Scenario::from_file(&path).expect("the shipped scenario loads");
    let last = std::cell::Cell::new((0.0, 0.0));
    let opts = RunOptions { progress: Some(Box::new(|t, end| last.set((t, end)))), ..RunOptions::default() };
    let out = run(&scenario, opts).expect("the scenario runs");
    // The progress runs to the run's real end: at a rendezvous of routed robots, long before the duration.
    let (t, end) = last.get();
    let routed = scenario.robots.iter().all(|r| r.controller == ControllerKind::Waypoints);
    if routed && scenario.merge.when == MergeWhen::Rendezvous {
        let stop = out.report.merge_at_s;
        assert!(stop < 0.9 * scenario.duration, "{name}: the rendezvous at {stop} s comes before the end");
        assert!(
            (end - stop).abs() <= 0.1 * stop,
            "{name}: last progress ({t} s) expected the end at {end} s, not {stop} s"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    write_outputs(&out, dir.path()).unwrap();
    for f in [
        "experia.yaml",
        "experia.pgm",
        "experia.png",
        "prawn.yaml",
        "prawn.png",
        "truth.yaml",
        "truth.png",
        "report.json",
    ] {
        assert!(dir.path().join(f).exists(), "{f} not written");
    }
    // The picture of each accepted merge: the second robot's walls, placed by the estimate, lie on the truth's.
    let base = mrslam_core::map_io::overlay(&out.truth, &[]);
    for m in out.merges.iter().filter(|m| m.report.accepted) {
        let picture = dir.path().join(format!("overlay_{}.png", m.report.algorithm));
        assert!(picture.exists(), "{} not written", picture.display());
        let over = mrslam_testbed::runner::merge_overlay(&out, &m.report.transform.unwrap().to_pose());
        let near_truth_wall = |x: u32, y: u32| {
            (x.saturating_sub(2)..=x + 2).any(|xx| {
                (y.saturating_sub(2)..=y + 2).any(|yy| base.get_pixel_checked(xx, yy).is_some_and(|p| p.0 == [150; 3]))
            })
        };
        let placed: Vec<(u32, u32)> =
            over.enumerate_pixels().filter(|(_, _, p)| p.0 == [235, 120, 20]).map(|(x, y, _)| (x, y)).collect();
        let on = placed.iter().filter(|&&(x, y)| near_truth_wall(x, y)).count();
        let share = on as f64 / placed.len().max(1) as f64;
        eprintln!(
            "{name}: {} of the second map's {} wall pixels within 2 px of a true wall ({share:.2})",
            on,
            placed.len()
        );
        assert!(
            placed.len() > 100 && share > 0.8,
            "{name}: the overlay does not lay the second map on the truth: {share}"
        );
    }
    eprint!("{}", out.report.summary());
    out.report
}

/// What holds today on every paper scenario: the robots drive their routes without touching anything, the
/// run writes its outputs, and a merge is never accepted unless it is right (a rejected merge is an honest
/// answer; a wrong accepted one is the failure this testbed exists to catch).
fn check_common(r: &RunReport) {
    for (name, robot) in &r.robots {
        assert!(robot.finished, "{name} did not finish its route");
        assert_eq!(robot.contact_steps, 0, "{name} touched an obstacle");
        assert!(robot.slam_rmse_m < robot.odom_rmse_m, "{name}: SLAM is no better than odometry");
    }
    for m in &r.merges {
        assert!(!m.accepted || m.success, "{} accepted a wrong merge: {m:?}", m.algorithm);
    }
}

/// The paper's merger succeeds (accepted, within the scenario's 2 deg / 0.3 m of the true relative pose of
/// the start frames).
fn assert_sift_succeeds(r: &RunReport) {
    let m = r.merges.iter().find(|m| m.algorithm == "sift").expect("a sift merge ran");
    assert!(m.accepted && m.success, "sift merge did not succeed: {m:?}");
}

/// The paper's robots end at the common point, where their maps overlap: against the maps' relative pose as
/// the robots' last poses place them, the SIFT merge is within `rot_deg` and `trans_m` (what it has more
/// against the start frames is the two SLAM maps' drift along their routes).
fn assert_sift_tight_at_the_common_point(r: &RunReport, rot_deg: f64, trans_m: f64) {
    let m = r.merges.iter().find(|m| m.algorithm == "sift").expect("a sift merge ran");
    let (rot, trans) = (m.rotation_error_at_end_deg.unwrap(), m.translation_error_at_end_m.unwrap());
    assert!(rot <= rot_deg && trans <= trans_m, "sift merge at the common point: {rot} deg, {trans} m");
}

/// R-map, honestly: our implementation refuses both paper maps, and nothing wrong gets through.
///
/// What we see: the maximal empty rectangles of a SLAM map depend on every stray hit and every unseen cell,
/// so the two robots' R-maps share few rectangles of similar size; the "common triangles" with the lowest
/// cost (equation 1) pair unrelated rectangles and imply a scale between the maps of 0.4-5 where the truth is
/// 1, so the scale loop gives up ("scale ratio ... beyond the allowed 2"). The paper saw R-map fail on the
/// corridor (its figure 10-11, wrong common triangles); on the floor-plan study it needs overlap ~0.45.
fn assert_rmap_refuses(r: &RunReport) {
    let m = r.merges.iter().find(|m| m.algorithm == "rmap").expect("an rmap merge ran");
    assert!(!m.accepted, "rmap accepted: {m:?}");
}

#[test]
fn paper_corridor_maps_well_and_never_merges_wrongly() {
    let r = run_scenario("paper_corridor");
    check_common(&r);
    for (name, robot) in &r.robots {
        assert!(
            robot.slam_rmse_m < 0.1 * robot.odom_rmse_m,
            "{name}: SLAM error {:.3} m is not well below odometry's {:.3} m",
            robot.slam_rmse_m,
            robot.odom_rmse_m
        );
        assert!(robot.map_acceptance > 0.95, "{name}: map acceptance {:.3}", robot.map_acceptance);
    }
    assert_sift_succeeds(&r);
    // Measured: 0.44 deg, 0.154 m against the start frames; 0.08 deg, 0.050 m at the common point.
    assert_sift_tight_at_the_common_point(&r, 0.5, 0.15);
    assert_rmap_refuses(&r);
}

#[test]
fn paper_two_rooms_maps_well_and_merges() {
    let r = run_scenario("paper_two_rooms");
    check_common(&r);
    for (name, robot) in &r.robots {
        // Measured: Experia 0.012 m against odometry's 0.537 m, Prawn 0.028 m against 0.641 m.
        assert!(robot.slam_rmse_m < 0.1 * robot.odom_rmse_m, "{name}: {robot:?}");
        // Measured: 0.973 and 0.948.
        assert!(robot.map_acceptance > 0.9, "{name}: map acceptance {:.3}", robot.map_acceptance);
    }
    // Measured: 1.04 deg, 0.047 m, 20 inliers of 414 matches; 0.13 deg, 0.036 m at the common point.
    assert_sift_succeeds(&r);
    assert_sift_tight_at_the_common_point(&r, 1.0, 0.05);
    assert_rmap_refuses(&r);
}

#[test]
fn exploring_the_two_rooms_maps_them_and_merges() {
    // Both robots drive to frontiers of their own SLAM maps with their own pose estimates; no route, no truth.
    // Over scenario seeds 1-12 the SIFT merge succeeds on 9 and is refused on 3, never wrong (BENCHMARKS.md);
    // the shipped seed is the first.
    let r = run_scenario("explore_two_rooms");
    check_common(&r);
    for (name, robot) in &r.robots {
        // Measured: Experia 0.009 m against odometry's 0.233 m, Prawn 0.060 m against 1.670 m.
        assert!(robot.slam_rmse_m < 0.25 * robot.odom_rmse_m, "{name}: {robot:?}");
        // Measured: 0.972 and 0.944.
        assert!(robot.map_acceptance > 0.9, "{name}: map acceptance {:.3}", robot.map_acceptance);
    }
    // Measured: Prawn drives 6.9 m and maps both rooms; Experia, keeping 0.53 m from walls, has no reachable
    // frontier left after 4.1 m (and one turn on the spot), its 4 m lidar having seen the west room by then.
    // Both stop on their own.
    assert!(r.robots["prawn"].distance_m > 5.0, "{:?}", r.robots["prawn"]);
    assert!(r.robots["experia"].distance_m > 1.0, "{:?}", r.robots["experia"]);
    // Measured: 0.56 deg, 0.036 m, 19 inliers of 462 matches.
    assert_sift_succeeds(&r);
    // R-map, honestly: over seeds 1-12 it succeeded on this one at most (before the explorers turned once on
    // the spot before giving up, and scans were paired with the odometry of their own instant) and is refused
    // on the others, here too now ("scale ratio 2.167"), though the maps overlap far more (0.65 observed)
    // than in the paper's corridor (0.29). What it may never do is merge wrongly.
    let m = r.merges.iter().find(|m| m.algorithm == "rmap").expect("an rmap merge ran");
    assert!(!m.accepted || m.success, "rmap merged wrongly: {m:?}");
}
