//! A team of three robots in the two-rooms world: all three drive, map and are evaluated against the truth;
//! the merge pair (the host and the first other robot) is merged.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_merge::Algorithm;
use mrslam_testbed::runner::{RunOptions, run};
use mrslam_testbed::scenario::Scenario;
use std::path::Path;

/// `paper_two_rooms.toml`'s two robots and a third, `scout`, in the east room by the door, for 20 s.
const THREE_ROBOTS: &str = r#"
name = "three_robots_two_rooms"
world = "../worlds/two_rooms.toml"
seed = 11
duration = 20.0

[merge]
when = "end"
host = "prawn"

[[robots]]
name = "experia"
model = "experia"
lidar = "hokuyo_urg_04lx"
start = "start_experia"
route = [[4.2, 0.9], [4.6, 3.5], [1.9, 3.4]]
speed = 0.35
encoder = { left_radius_error = 0.01, right_radius_error = -0.008, wheel_base_error = 0.02 }

[[robots]]
name = "prawn"
model = "prawn"
lidar = "rplidar_a1"
start = "start_prawn"
route = [[8.2, 2.9], [8.8, 4.1], [9.4, 2.0], [8.0, 1.3]]
speed = 0.3
encoder = { left_radius_error = -0.012, right_radius_error = 0.01, wheel_base_error = -0.02 }

[[robots]]
name = "scout"
model = "experia"
lidar = "hokuyo_urg_04lx"
start = [7.0, 3.3, 3.14159265]
route = [[6.8, 2.9], [6.1, 2.7], [6.1, 1.95]]
speed = 0.3
encoder = { left_radius_error = 0.008, right_radius_error = 0.01, wheel_base_error = -0.015 }
"#;

#[test]
fn three_robots_drive_map_and_are_each_evaluated() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/three_robots_two_rooms.toml");
    let scenario = Scenario::parse(THREE_ROBOTS, &path).expect("a scenario of three robots loads");
    assert_eq!(scenario.robots.len(), 3);
    let opts = RunOptions { algorithms: Some(vec![Algorithm::Sift]), ..RunOptions::default() };
    let out = run(&scenario, opts).expect("three robots run");
    let r = &out.report;
    eprint!("{}", r.summary());
    assert!((r.merge_at_s - 20.0).abs() < 0.05, "{}", r.merge_at_s);
    let names: Vec<&str> = r.robots.keys().map(String::as_str).collect();
    assert_eq!(names, ["experia", "prawn", "scout"]);
    for (name, robot) in &r.robots {
        assert_eq!(robot.contact_steps, 0, "{name} touched an obstacle");
        assert!(robot.distance_m > 1.5, "{name} drove {} m", robot.distance_m);
        assert!(robot.processed >= 5, "{name}: {} scans processed", robot.processed);
        // SLAM against the truth: a few centimetres over the first metres of each route.
        assert!(robot.slam_rmse_m < 0.1, "{name}: SLAM RMSE {} m", robot.slam_rmse_m);
        assert!(robot.slam_final_error_m < 0.15, "{name}: final SLAM error {} m", robot.slam_final_error_m);
        assert!(robot.map_acceptance > 0.85, "{name}: map acceptance {}", robot.map_acceptance);
        assert!(out.maps[name].state_counts().0 > 1000, "{name}'s map has free space");
        assert!(out.frames.contains_key(name) && !out.paths[name].is_empty(), "{name}: frame and path");
    }
    // The merge pair: the host and the first other robot in the file's order.
    assert_eq!(r.merge_pair, Some(["prawn".to_string(), "experia".to_string()]));
    assert_eq!(r.merges.len(), 1);
    let m = &r.merges[0];
    assert!(!m.accepted || m.success, "an accepted merge is right: {m:?}");
    assert!(r.summary().contains("merges of prawn's and experia's maps"), "{}", r.summary());
}
