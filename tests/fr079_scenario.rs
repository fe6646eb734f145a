//! The FR079 scenario (two Pioneers with the presets fitted to the real FR079 robot, in the world our SLAM made of
//! the real log) loads with those presets and runs to its rendezvous: both robots drive their routes, map, and
//! their maps merge where the truth says they lie.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_merge::Algorithm;
use mrslam_sim::{LidarModel, RobotModel, odometry_fit};
use mrslam_testbed::runner::{RunOptions, run};
use mrslam_testbed::scenario::{MergeWhen, Scenario};
use std::path::Path;

#[test]
fn the_fr079_scenario_loads_with_the_fitted_presets_runs_and_merges_right() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fr079_two_robots.toml");
    let scenario = Scenario::from_file(&path).expect("the shipped scenario loads");
    let (slip, encoder) = odometry_fit::preset("pioneer_fr079").unwrap();
    assert_eq!(scenario.robots.len(), 2);
    for r in &scenario.robots {
        assert_eq!(r.model, RobotModel::pioneer(), "{}", r.name);
        assert_eq!((r.slip, r.encoder), (slip, encoder), "{}: the fitted odometry", r.name);
        assert_eq!(r.lidar.name, "sick_lms", "{}", r.name);
        assert_eq!(r.lidar.beam_count(), LidarModel::sick_lms().beam_count());
        assert!((r.lidar.mount.translation.x + 0.04).abs() < 1e-12, "{}: the log's laser offset", r.name);
        assert!(r.route.len() > 30, "{}: a route along the real robot's path", r.name);
    }
    assert_eq!(scenario.merge.when, MergeWhen::Rendezvous);
    // The whole run (about 140 simulated seconds) merged by the cascade, `mrslam merge`'s default.
    let opts = RunOptions { algorithms: Some(vec![Algorithm::Cascade]), ..RunOptions::default() };
    let out = run(&scenario, opts).expect("the scenario runs");
    let report = &out.report;
    eprint!("{}", report.summary());
    assert!(report.merge_at_s < 0.6 * scenario.duration, "the rendezvous at {} s", report.merge_at_s);
    for (name, r) in &report.robots {
        assert!(r.finished, "{name} did not finish its route");
        assert!(r.distance_m > 35.0, "{name} drove its route: {} m", r.distance_m);
        // Measured: east brushes a wall for 41 of 13962 steps late on its route, west never.
        assert!(r.contact_steps * 100 < report.steps as usize, "{name} touched walls for {} steps", r.contact_steps);
        // Measured: 0.07 and 0.10 m against odometry's 1.7 and 4.7 m; map acceptance 0.97 and 0.97.
        assert!(r.slam_rmse_m < 0.25, "{name}: SLAM RMSE {} m", r.slam_rmse_m);
        assert!(r.slam_rmse_m < 0.1 * r.odom_rmse_m, "{name}: SLAM {} m, odometry {} m", r.slam_rmse_m, r.odom_rmse_m);
        assert!(r.map_acceptance > 0.93, "{name}: map acceptance {}", r.map_acceptance);
    }
    assert_eq!(report.merges.len(), 1);
    let m = &report.merges[0];
    // Measured: accepted by the correlative stage, 0.16 deg and 0.023 m from the true transform between the two
    // SLAM frames; the bounds are three times that.
    assert!(m.accepted && m.success, "the merge: {m:?}");
    let (rot, trans) = (m.rotation_error_deg.unwrap(), m.translation_error_m.unwrap());
    assert!(rot <= 0.5 && trans <= 0.07, "merge error against the truth: {rot} deg, {trans} m");
    assert!(m.merged_map_acceptance.unwrap() > 0.93, "{m:?}");
}
