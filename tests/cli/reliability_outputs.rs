//! Outputs, as a careless user names them: every command checks its outputs against its inputs and each other
//! by one rule before any work; `run --out DIR` replaces or removes only the files it made; an interrupted run
//! leaves its folder as it was and says so; a map merged with itself is refused.

use crate::util::{fails_with, mrslam, p, root, text};
use mrslam_core::map_io::write_ros_map;
use mrslam_merge::floorplan::{FloorplanParams, generate};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The names of the files in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// A scenario in `dir` on the two-rooms world whose robots stand still: a run of a few simulated seconds.
pub fn idle_scenario(dir: &Path, world: &Path, start_a: &str, start_b: &str) -> PathBuf {
    let text = format!(
        "name = \"idle\"\nworld = {:?}\nseed = 1\nduration = 3.0\n\n[merge]\nwhen = 2.0\nalgorithms = [\"sift\"]\n\n\
         [[robots]]\nname = \"a\"\nmodel = \"experia\"\nlidar = \"hokuyo_urg_04lx\"\nstart = \"{start_a}\"\n\
         controller = \"idle\"\n\n[[robots]]\nname = \"b\"\nmodel = \"prawn\"\nlidar = \"rplidar_a1\"\n\
         start = \"{start_b}\"\ncontroller = \"idle\"\n",
        world.display().to_string()
    );
    let path = dir.join("idle.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn slam_checks_its_outputs_against_each_other_and_their_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = d.join("small.clf");
    std::fs::write(&log, "ODOM 0 0 0 0 0 0 1.0 h 1\n").unwrap();
    let out = |n: &str| d.join(n).to_str().unwrap().to_string();
    let (s, s2, t) = (out("s.yaml"), out("s2.yaml"), out("t.txt"));
    for (args, needles) in [
        (vec!["-o", &s, "--trajectory", &s], vec!["--trajectory", "s.yaml: `.yaml` is not a format"]),
        (vec!["-o", &s2, "--trajectory", &out("s2.pgm")], vec!["--trajectory", "`.pgm` is not a format"]),
        (vec!["-o", &s2, "--summary", &out("s2.png")], vec!["--summary", "`.png` is not a format"]),
        (vec!["-o", &s, "--trajectory", &t, "--summary", &t], vec!["--summary", "`.txt` is not a format"]),
        (vec!["-o", &s, "--summary", &out("s.json"), "--rrd", &out("s.png")], vec!["--rrd", "expected .rrd"]),
    ] {
        let mut a = vec!["slam", p(&log)];
        a.extend(args.iter().copied());
        fails_with(&a, &needles);
    }
    assert_eq!(names(d), vec!["small.clf"], "nothing written");
}

#[test]
fn a_run_removes_no_recording_it_did_not_make_and_writes_over_no_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scenario = idle_scenario(d, &root().join("worlds/two_rooms.toml"), "start_experia", "start_prawn");
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("mine.rrd"), "a recording of the user's").unwrap();
    let run = |extra: &[&str]| {
        let mut a = vec!["run", p(&scenario), "--quiet", "--out", p(&out)];
        a.extend(extra);
        let o = mrslam(&a);
        assert!(o.status.success(), "{}", text(&o.stderr));
        text(&o.stdout)
    };
    let first = run(&["--rrd", out.join("run.rrd").to_str().unwrap()]);
    assert!(!first.contains("removed"), "{first}");
    assert!(out.join("mine.rrd").exists() && out.join("run.rrd").exists() && out.join("report.json").exists());
    // The manifest names every file the run wrote, and only those.
    let manifest = std::fs::read_to_string(out.join("run-files.txt")).unwrap();
    let listed: Vec<&str> = manifest.lines().filter(|l| !l.starts_with('#')).collect();
    let mut expected: Vec<String> =
        names(&out).into_iter().filter(|n| n != "mine.rrd" && n != "run-files.txt").collect();
    expected.sort();
    assert_eq!(listed, expected);
    // A second run without a recording: the first run's recording goes (it no longer matches the report), the
    // user's stays.
    let second = run(&[]);
    assert!(second.contains("removed:") && second.contains("run.rrd"), "{second}");
    assert!(!out.join("run.rrd").exists());
    assert_eq!(std::fs::read_to_string(out.join("mine.rrd")).unwrap(), "a recording of the user's");

    // A world made from a map in the output folder: the run refuses to write its truth over that map.
    let here = d.join("here");
    std::fs::create_dir(&here).unwrap();
    write_ros_map(&generate(5, &FloorplanParams::default()), &here.join("truth.yaml")).unwrap();
    let o = mrslam(&["world", "from-map", p(&here.join("truth.yaml")), "-o", p(&here.join("w.toml"))]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let scenario = idle_scenario(&here, &here.join("w.toml"), "start_a", "start_b");
    let before: Vec<(String, Vec<u8>)> =
        names(&here).into_iter().map(|n| (n.clone(), std::fs::read(here.join(&n)).unwrap())).collect();
    fails_with(
        &["run", p(&scenario), "--quiet", "--out", p(&here)],
        &["truth.yaml", "refusing to write an output over"],
    );
    let after: Vec<(String, Vec<u8>)> =
        names(&here).into_iter().map(|n| (n.clone(), std::fs::read(here.join(&n)).unwrap())).collect();
    assert_eq!(before, after, "nothing written, nothing removed");
    // A folder given to --out is made only when its parent exists.
    let deep = d.join("missing/deep/dir");
    fails_with(&["run", p(&scenario), "--quiet", "--out", p(&deep)], &["missing/deep", "does not exist"]);
    assert!(!d.join("missing").exists());
}

#[test]
fn an_interrupted_run_leaves_the_folder_as_it_was_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text_of = |name: &str| std::fs::read_to_string(root().join(name)).unwrap();
    let world = root().join("worlds/two_rooms.toml");
    // The two-rooms scenario merging at the end of its 180 s: long enough to be interrupted.
    let long = text_of("scenarios/paper_two_rooms.toml")
        .replace("\"../worlds/two_rooms.toml\"", &format!("{:?}", world.display().to_string()))
        .replace("when = \"rendezvous\"", "when = 170.0");
    let scenario = d.join("long.toml");
    std::fs::write(&scenario, long).unwrap();
    let quick = idle_scenario(d, &world, "start_experia", "start_prawn");
    let out = d.join("out");
    let rrd = out.join("run.rrd");
    let o = mrslam(&["run", p(&quick), "--quiet", "--out", p(&out), "--rrd", p(&rrd)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let snapshot = || -> Vec<(String, Vec<u8>)> {
        names(&out).into_iter().map(|n| (n.clone(), std::fs::read(out.join(&n)).unwrap())).collect()
    };
    let before = snapshot();

    let child = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["run", p(&scenario), "--quiet", "--out", p(&out), "--rrd", p(&rrd)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once the run is under way: its recording has started.
    let partial = out.join("run.partial.rrd");
    while !partial.exists() {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("interrupted") && e.contains("as they were before this run"), "{e}");
    assert!(e.contains("run.partial.rrd"), "{e}");
    // Every file of the earlier run is there and unchanged; only the partial recording is new.
    let after: Vec<(String, Vec<u8>)> = snapshot().into_iter().filter(|(n, _)| n != "run.partial.rrd").collect();
    assert_eq!(after, before);
}

#[test]
fn a_map_merged_with_itself_or_its_copy_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = d.join("a.yaml");
    write_ros_map(&generate(3, &FloorplanParams::default()), &a).unwrap();
    let b = d.join("b.yaml");
    write_ros_map(&generate(4, &FloorplanParams::default()), &b).unwrap();
    std::fs::copy(&a, d.join("copy.yaml")).unwrap();
    std::fs::copy(d.join("a.pgm"), d.join("copy.pgm")).unwrap();
    std::fs::write(d.join("copy.yaml"), std::fs::read_to_string(&a).unwrap().replace("a.pgm", "copy.pgm")).unwrap();
    fails_with(&["merge", p(&a), p(&a)], &["a.yaml", "the same map file given twice"]);
    fails_with(&["merge", p(&a), p(&d.join("copy.yaml"))], &["copy.yaml holds the same cells as", "a copy?"]);
    fails_with(&["merge", p(&a), p(&b), p(&a)], &["the same map file given twice"]);
    fails_with(&["merge", p(&a), p(&b), p(&d.join("./b.yaml"))], &["the same map file given twice"]);
}
