//! Hostile and careless input, as a user meets it: devices and bombs refused before they fill memory, absurd and
//! negative numbers refused by their own checks, files of the wrong kind refused, and help that says what the
//! commands do.

use crate::util::{fails_with, mrslam, p, plan, root, text};
use mrslam_core::map_io::write_ros_map;
use mrslam_merge::floorplan::{FloorplanParams, generate};

#[test]
fn devices_are_refused_before_they_fill_memory() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // /dev/zero as a log, by its own name and named as a CARMEN log.
    fails_with(&["log", "info", "/dev/zero"], &["/dev/zero", "not a log format"]);
    let zero = d.join("zero.clf");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    fails_with(&["log", "info", p(&zero)], &["zero.clf:1: line longer than 1048576 bytes"]);
    // A map whose image is /dev/zero: refused by its first bytes.
    let map = d.join("m.yaml");
    std::fs::write(&map, "image: /dev/zero\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    fails_with(&["map", "info", p(&map)], &["m.yaml:1", "/dev/zero: cannot decode image: its first bytes"]);
}

#[test]
fn absurd_and_negative_numbers_get_their_own_checks() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let w = plan(d, "w", 21);
    let (a, b) = (d.join("a.yaml"), d.join("b.yaml"));
    let cut = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["map", "cut", p(&w), p(&a), p(&b)];
        args.extend(extra);
        fails_with(&args, needles);
    };
    cut(&["--max-shift=-5"], &["--max-shift -5", "0..=1000"]);
    cut(&["--max-shift", "-5"], &["--max-shift -5", "0..=1000"]);
    cut(&["--max-shift", "1e9"], &["--max-shift 1000000000", "0..=1000"]);
    cut(&["--seed", "-1"], &["invalid value '-1' for '--seed <SEED>'"]);
    assert!(!a.exists() && !b.exists());
    let e = text(
        &fails_with(
            &["world", "from-map", p(&w), "-o", p(&d.join("w.toml")), "--clearance", "-1"],
            &["--clearance -1", "must be a positive number"],
        )
        .stderr,
    );
    assert!(!e.contains("-- -1"), "{e}");
    fails_with(&["run", "scenarios/paper_two_rooms.toml", "--seed", "-1"], &["invalid value '-1' for '--seed"]);
    // A map of 1e300 m per pixel.
    std::fs::write(d.join("huge.yaml"), "image: w.pgm\nresolution: 1e300\norigin: [0, 0, 0]\n").unwrap();
    fails_with(&["map", "info", p(&d.join("huge.yaml"))], &["huge.yaml:2", "and 100 metres per pixel"]);
}

#[test]
fn files_of_the_wrong_kind_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A text file and a relations file as logs: no scans is no log.
    let notes = d.join("notes.log");
    std::fs::write(&notes, "Meeting notes\nWe drove the robot round the lab.\n").unwrap();
    fails_with(&["log", "info", p(&notes)], &["notes.log: no laser scans", "not a CARMEN laser log?"]);
    let rels = d.join("r.relations.log");
    std::fs::write(&rels, "1.0 2.0 0.5 0 0 0 0 0.1\n2.0 3.0 0.5 0 0 0 0 0.1\n").unwrap();
    fails_with(&["log", "info", p(&rels)], &["no laser scans", "skipped: 1 `1.0`, 1 `2.0`"]);
    // A relations file as the trajectory.
    let r = d.join("r.relations");
    std::fs::copy(&rels, &r).unwrap();
    fails_with(&["eval", "relations", p(&r), p(&r)], &["r.relations:1: expected 4 fields", "a relations file"]);
    // A folder as a map.
    fails_with(&["map", "info", p(d)], &["is a folder; expected a map YAML"]);
}

#[test]
fn the_correlative_stage_says_plainly_when_maps_are_too_small_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let small = FloorplanParams { width_m: 8.0, height_m: 6.0, ..FloorplanParams::default() };
    let (a, b) = (d.join("a.yaml"), d.join("b.yaml"));
    write_ros_map(&generate(1, &small), &a).unwrap();
    write_ros_map(&generate(2, &small), &b).unwrap();
    let o = mrslam(&["merge", p(&a), p(&b), "--algorithm", "correlative"]);
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(2), "{out}{}", text(&o.stderr));
    assert!(out.contains("cannot accept on maps this small"), "{out}");
    assert!(!out.contains("both shares"), "{out}");
}

#[test]
fn help_says_what_the_commands_write() {
    let help = |args: &[&str]| {
        let mut a = args.to_vec();
        a.push("--help");
        let o = mrslam(&a);
        assert!(o.status.success());
        text(&o.stdout)
    };
    for cmd in [&["merge"][..], &["slam"], &["map", "convert"]] {
        let h = help(cmd);
        assert!(h.contains("PNG preview"), "{cmd:?}: {h}");
    }
    for cmd in ["overlap", "scenario"] {
        assert!(help(&["study", cmd]).contains("study.json"), "{cmd}");
    }
    let merge = help(&["merge"]);
    assert!(merge.contains("[default: 0.15]") && !merge.contains("default()"), "{merge}");
    assert!(help(&["sim", "replay"]).contains("--quiet"));
    assert!(help(&["study", "collect"]).contains("--partial"));
    // The script `features --json` names is in the repository.
    let features = help(&["features"]);
    assert!(features.contains("dev/scripts/opencv_sift.py"), "{features}");
    assert!(root().join("dev/scripts/opencv_sift.py").is_file());
}
