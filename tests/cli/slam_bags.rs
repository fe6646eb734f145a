//! `mrslam slam` and `mrslam log info` on ROS bags: every format maps as the CARMEN text it was made from
//! (tests/data/bags: the ACES log's first 10 s; dev/scripts/make_bag_test_data.sh), and bad bags are
//! refused naming the file.

use crate::util::{mrslam, p, text};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bags").join(name)
}

/// The poses of a trajectory file: `stamp x y theta` per data line.
fn poses(path: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(path).unwrap();
    let lines = text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    lines
        .map(|l| l.split_whitespace().map(|v| v.parse::<f64>().unwrap()).collect::<Vec<_>>().try_into().unwrap())
        .collect()
}

/// Maps `log` into `dir` and returns its trajectory.
fn slam(log: &Path, dir: &Path, name: &str, extra: &[&str]) -> Vec<[f64; 4]> {
    let (map, trajectory) = (dir.join(format!("{name}.yaml")), dir.join(format!("{name}.txt")));
    let mut args = vec!["slam", p(log), "-o", p(&map), "--trajectory", p(&trajectory), "--quiet"];
    args.extend_from_slice(extra);
    let o = mrslam(&args);
    assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    poses(&trajectory)
}

fn assert_same_trajectory(a: &[[f64; 4]], b: &[[f64; 4]], name: &str) {
    assert_eq!(a.len(), b.len(), "{name}");
    assert!(a.len() > 60, "{name}: {} poses", a.len());
    // Pose for pose as written, not within a tolerance: on the whole ACES log too (BENCHMARKS.md).
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x, y, "{name}");
    }
}

#[test]
fn every_bag_format_maps_as_the_carmen_text_it_was_made_from() {
    let dir = tempfile::tempdir().unwrap();
    let carmen = slam(&data("aces_10s.clf"), dir.path(), "carmen", &[]);
    // The robot barely moves in these 10 s; the scans and odometry themselves are compared bit for bit in
    // crates/log/tests/bags.rs, the whole log's trajectories in the closing note of issue 40.
    for name in [
        "aces_10s.bag",
        "aces_10s_bz2.bag",
        "aces_10s_lz4.bag",
        "aces_10s_zstd.mcap",
        "aces_10s_mcap",
        "aces_10s_sqlite3",
    ] {
        let bag = slam(&data(name), dir.path(), name, &[]);
        assert_same_trajectory(&bag, &carmen, name);
    }
    // Odometry from /tf instead of /odom: the same poses.
    let tf = slam(&data("aces_10s_lz4.bag"), dir.path(), "tf", &["--base-frame", "base_link"]);
    assert_same_trajectory(&tf, &carmen, "/tf");
    // A log without ODOM lines, converted: its bag's /odom holds the scan lines' odometry.
    let carmen = slam(&data("aces_10s_no_odom.clf"), dir.path(), "carmen_no_odom", &[]);
    let bag = slam(&data("aces_10s_no_odom.bag"), dir.path(), "bag_no_odom", &[]);
    assert_same_trajectory(&bag, &carmen, "no ODOM lines");
}

#[test]
fn log_info_lists_a_bags_topics_and_what_it_would_use() {
    let o = mrslam(&["log", "info", p(&data("aces_10s_mcap"))]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.contains("format:    ROS 2 bag folder: MCAP (uncompressed chunks)"), "{out}");
    let scan = out.lines().find(|l| l.contains("/scan ")).unwrap_or_default();
    assert!(scan.contains("sensor_msgs/msg/LaserScan") && scan.contains("68 msgs") && scan.contains("Hz"), "{out}");
    assert!(out.contains("uses:      scans from /scan; odometry from topic /odom (odom -> base_link)"), "{out}");
    assert!(out.contains("mount:     /tf_static: base_link -> laser"), "{out}");
    assert!(out.contains("scans:     68"), "{out}");
}

#[test]
fn bad_bags_and_topics_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let map = dir.path().join("m.yaml");
    let refused = |log: &Path, extra: &[&str], needles: &[&str]| {
        let mut args = vec!["slam", p(log), "-o", p(&map), "--quiet"];
        args.extend_from_slice(extra);
        let o = mrslam(&args);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{e}");
        for n in needles {
            assert!(e.contains(n), "{args:?}: `{n}` not in: {e}");
        }
        assert!(!map.exists(), "{args:?} left a map behind");
    };
    let bytes = std::fs::read(data("aces_10s_lz4.bag")).unwrap();
    let cut = dir.path().join("cut.bag");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    refused(&cut, &[], &[p(&cut), "cut off at byte"]);
    let bag = data("aces_10s_bz2.bag");
    refused(
        &bag,
        &["--scan", "/laser"],
        &[p(&bag), "--scan /laser: no sensor_msgs/LaserScan topic of that name", "/scan"],
    );
    refused(&bag, &["--odom", "/wheels"], &["--odom /wheels", "(the bag's: /odom)"]);
    refused(&bag, &["--base-frame", "robot"], &["no /tf transform to the base frame robot"]);
}
