//! The FR079 scenario (two Pioneers with the presets fitted to the real FR079 robot, in the world our SLAM made of
//! the real log) loads with those presets and runs: its first 30 simulated seconds, both robots driving their
//! routes without touching a wall and mapping as they go.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_merge::Algorithm;
use mrslam_sim::{LidarModel, RobotModel, odometry_fit};
use mrslam_testbed::runner::{RunOptions, run};
use mrslam_testbed::scenario::{MergeWhen, Scenario};
use std::path::Path;

#[test]
fn the_fr079_scenario_loads_with_the_fitted_presets_and_runs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/fr079_two_robots.toml");
    let mut scenario = Scenario::from_file(&path).expect("the shipped scenario loads");
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
    // The first 30 s, merged at the end with SIFT alone: enough to drive, map and merge, short enough for a test.
    scenario.duration = 30.0;
    scenario.merge.when = MergeWhen::End;
    let opts = RunOptions { algorithms: Some(vec![Algorithm::Sift]), ..RunOptions::default() };
    let out = run(&scenario, opts).expect("the scenario runs");
    let report = &out.report;
    assert!((report.merge_at_s - 30.0).abs() < 0.5, "{}", report.merge_at_s);
    for (name, r) in &report.robots {
        assert!(r.distance_m > 8.0, "{name} drove its route at 0.4 m/s: {} m", r.distance_m);
        assert_eq!(r.contact_steps, 0, "{name} touched a wall");
        assert!(r.processed >= 5, "{name}: {} scans processed", r.processed);
        assert!(r.slam_rmse_m < 0.3, "{name}: SLAM RMSE {} m", r.slam_rmse_m);
        assert!(out.maps[name].state_counts().0 > 1000, "{name}'s map has free space");
    }
    assert_eq!(report.merges.len(), 1);
}
