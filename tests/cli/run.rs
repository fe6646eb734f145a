//! `mrslam run`, as a user would: bad scenarios are refused with the file, line and field named.

use crate::util::{mrslam, root};
use std::path::{Path, PathBuf};

/// The two-rooms scenario with one line replaced, written next to the shipped one's world path.
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenarios/paper_two_rooms.toml")).unwrap();
    assert!(text.contains(from), "the shipped scenario no longer contains `{from}`");
    let world = root().join("worlds/two_rooms.toml");
    let text =
        text.replace(from, to).replace("\"../worlds/two_rooms.toml\"", &format!("{:?}", world.display().to_string()));
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn assert_refused(path: &Path, needles: &[&str]) {
    let o = mrslam(&["run", path.to_str().unwrap(), "--quiet", "--out", path.with_extension("out").to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "stderr lacks `{n}`: {e}");
    }
}

#[test]
fn bad_scenarios_name_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = variant(d, "world.toml", "world = \"../worlds/two_rooms.toml\"", "world = \"nowhere.toml\"");
    assert_refused(&p, &["world.toml:", "world", "nowhere.toml"]);
    let p = variant(d, "lidar.toml", "lidar = \"rplidar_a1\"", "lidar = \"velodyne\"");
    assert_refused(&p, &["lidar.toml:", "robots[1].lidar", "unknown lidar preset `velodyne`"]);
    let p = variant(d, "start.toml", "start = \"start_prawn\"", "start = [5.6, 3.0, 0.0]");
    assert_refused(&p, &["start.toml:", "robots[1].start", "inside an obstacle"]);
    let p = variant(d, "waypoint.toml", "[9.4, 2.0]", "[90.4, 2.0]");
    assert_refused(&p, &["waypoint.toml:", "robots[1].route[2]", "outside the world"]);
    let p = variant(d, "late.toml", "when = \"rendezvous\"", "when = 500.0");
    assert_refused(&p, &["late.toml:", "merge.when", "after the end"]);
    let p = variant(d, "key.toml", "speed = 0.3\n", "speed = 0.3\nturbo = true\n");
    assert_refused(&p, &["key.toml:", "unknown field `turbo`"]);
    let p = variant(d, "model.toml", "model = \"prawn\"", "model = \"roomba\"");
    assert_refused(&p, &["model.toml:", "robots[1].model", "roomba"]);
    let p = variant(d, "cand.toml", "candidates = 6", "candidates = 0");
    assert_refused(&p, &["cand.toml:", "merge.candidates", "must lie in 1..=16, got 0"]);
    let p = variant(d, "slam.toml", "speed = 0.3\n", "speed = 0.3\nslam = { preset = \"rplidar\", warp = 9 }\n");
    assert_refused(&p, &["slam.toml:", "robots[1].slam.warp", "unknown SLAM parameter 'warp'"]);
    let p = variant(d, "slam2.toml", "speed = 0.3\n", "speed = 0.3\nslam = { particles = \"many\" }\n");
    assert_refused(&p, &["slam2.toml:", "robots[1].slam.particles", "many"]);
}

#[test]
fn unknown_algorithm_and_missing_file_are_refused() {
    let o = mrslam(&["run", root().join("scenarios/paper_two_rooms.toml").to_str().unwrap(), "--algorithm", "magic"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--algorithm magic"));
    let o = mrslam(&["run", "no/such/scenario.toml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no/such/scenario.toml"));
}
