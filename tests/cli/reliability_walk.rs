//! The hostile inputs of the third reliability walk (issue 41's follow-up): absurd scales, wrong files, outputs
//! that would land where they must not.

use crate::util::{fails_with, p, plan, text};
use std::path::Path;

/// `name`.yaml beside `plan`'s map, naming the same image (or `image`), with its resolution and origin changed.
fn yaml_like(dir: &Path, name: &str, image: &str, resolution: &str, origin: &str) -> std::path::PathBuf {
    let path = dir.join(format!("{name}.yaml"));
    let text = format!("image: {image}\nresolution: {resolution}\norigin: {origin}\nnegate: 0\n");
    std::fs::write(&path, text).unwrap();
    path
}

/// An empty file `x.clf` in `dir`: for checks made before the log is read.
fn empty_log(dir: &Path) -> std::path::PathBuf {
    let log = dir.join("x.clf");
    std::fs::write(&log, "").unwrap();
    log
}

#[test]
fn maps_of_absurd_or_far_apart_resolutions_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = plan(d, "a", 3);
    plan(d, "b", 4);
    for tiny in ["1e-5", "1e-20"] {
        let t = yaml_like(d, "tiny", "b.pgm", tiny, "[0, 0, 0]");
        fails_with(&["merge", p(&a), p(&t)], &["tiny.yaml:2", "resolution", "between 0.0001 and 100"]);
    }
    // Readable, but 2000 times coarser than the first map: two robots' maps of one place are not that far apart.
    let coarse = yaml_like(d, "coarse", "b.pgm", "100", "[0, 0, 0]");
    fails_with(&["merge", p(&a), p(&coarse)], &["a.yaml", "coarse.yaml", "more than 20x apart"]);
    fails_with(&["merge", p(&a), p(&d.join("b.yaml")), p(&coarse)], &["coarse.yaml", "more than 20x apart"]);
}

#[test]
fn a_map_with_its_origin_moved_is_still_the_same_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = plan(d, "a", 3);
    let res = std::fs::read_to_string(&a).unwrap();
    let res = res.lines().find_map(|l| l.strip_prefix("resolution: ")).unwrap().to_string();
    // The same image, the origin 1 m away.
    let moved = yaml_like(d, "moved", "a.pgm", &res, "[1, 0, 0]");
    fails_with(&["merge", p(&a), p(&moved)], &["a.yaml", "moved.yaml", "both name the image", "a.pgm"]);
    // A copy of the image, the origin 1 m away.
    std::fs::copy(d.join("a.pgm"), d.join("c.pgm")).unwrap();
    let copy = yaml_like(d, "c", "c.pgm", &res, "[1, 0, 0]");
    fails_with(&["merge", p(&a), p(&copy)], &["c.yaml holds the same cells as", "a.yaml"]);
}

#[test]
fn slam_refuses_a_map_resolution_no_reader_would_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The parameters are checked before the log is read, so any file does.
    let log = empty_log(d);
    for delta in ["1e300", "150"] {
        let o = fails_with(
            &["slam", p(&log), "-o", p(&d.join("s.yaml")), "--set", &format!("delta={delta}")],
            &["map.delta", "between 0.0001 and 100"],
        );
        assert!(text(&o.stdout).is_empty());
    }
    assert!(!d.join("s.yaml").exists());
}

/// A small map-level study (2 overlaps x `trials` trials, sift) into `out`, with `extra` flags.
fn overlap_study(out: &Path, trials: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["study", "overlap", "--floorplans", "1", "--floorplan-size", "12x10", "--overlaps", "0.3,0.5"];
    args.extend(["--trials", trials, "--algorithms", "sift", "--quiet", "--out", p(out)]);
    args.extend_from_slice(extra);
    crate::util::mrslam(&args)
}

#[test]
fn absurd_trial_counts_and_seed_ranges_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    for trials in ["18446744073709551615", "1000000000"] {
        fails_with(
            &["study", "overlap", "--floorplans", "1", "--trials", trials, "--out", p(&out)],
            &["--trials", "must be from 1 to 100000"],
        );
        assert!(!out.exists(), "nothing written for --trials {trials}");
    }
    fails_with(&["study", "overlap", "--floorplans", "1000000000", "--out", p(&out)], &["--floorplans", "10000"]);
    assert!(!out.exists());
    let team = crate::util::root().join("scenarios/team_two_rooms.toml");
    fails_with(
        &["study", "team", p(&team), "--seeds", "0:18446744073709551615", "--dry-run", "--out", p(&out)],
        &["--seeds", "at most 10000"],
    );
    for (flag, value, needle) in [
        ("--range", "1e300", "--range 1e300: a range must be a number of metres from 0 to 1e6"),
        ("--duration", "1e300", "--duration 1e300: must be a positive number of seconds, at most 1e6"),
    ] {
        let o = fails_with(&["study", "team", p(&team), flag, value, "--dry-run", "--out", p(&out)], &[needle]);
        assert!(text(&o.stderr).len() < 400, "{}", text(&o.stderr));
    }
}

#[test]
fn negative_numbers_in_lists_and_ranges_get_the_values_own_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    let team = crate::util::root().join("scenarios/team_two_rooms.toml");
    let map = dir.path().join("s.yaml");
    let cases: [(&[&str], &str); 5] = [
        (&["study", "team", p(&team), "--out", p(&out), "--dry-run", "--seeds", "-3:2"], "`-3` is not a whole number"),
        (&["study", "team", p(&team), "--out", p(&out), "--dry-run", "--range", "-5:2:1"], "-5 is negative"),
        (&["study", "overlap", "--floorplans", "1", "--out", p(&out), "--overlaps", "-0.1:0.5:0.1"], "--overlaps"),
        (&["study", "overlap", "--floorplans", "1", "--out", p(&out), "--shard", "-1/2"], "--shard"),
        (&["slam", "small.clf", "-o", p(&map), "--scan", "-x"], "small.clf"),
    ];
    for (args, needle) in cases {
        let o = fails_with(args, &[needle]);
        let e = text(&o.stderr);
        assert!(!e.contains("unexpected argument") && !e.contains("tip:"), "{args:?}: {e}");
    }
}

#[test]
fn collect_refuses_an_incomplete_shard_and_an_output_holding_another_study() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (s0, s1, full) = (d.join("s0"), d.join("s1"), d.join("full"));
    for (s, shard) in [(&s0, "0/2"), (&s1, "1/2")] {
        let o = overlap_study(s, "3", &["--shard", shard]);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    }
    // Shard 1 cut short, as an interruption leaves it: its last trial's row lost.
    let results = s1.join("results.csv");
    let csv = std::fs::read_to_string(&results).unwrap();
    let kept: Vec<&str> = csv.lines().collect();
    std::fs::write(&results, kept[..kept.len() - 1].join("\n") + "\n").unwrap();
    fails_with(&["study", "collect", p(&s0), p(&s1), "--out", p(&full)], &["incomplete shard", "s1", "2 of 3 trials"]);
    let deep = d.join("missing/deep/x");
    fails_with(&["study", "collect", p(&s0), p(&s1), "--out", p(&deep), "--partial"], &["--out", "does not exist"]);
    assert!(!d.join("missing").exists(), "no chain of folders made");
    assert!(!full.exists(), "nothing written");
    let o = crate::util::mrslam(&["study", "collect", p(&s0), p(&s1), "--out", p(&full), "--partial"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("2 of 3 trials"), "{}", text(&o.stdout));
    // Another finished study in --out is not overwritten.
    let other = d.join("other");
    let o = overlap_study(&other, "2", &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let before = std::fs::read(other.join("results.csv")).unwrap();
    fails_with(&["study", "collect", p(&s0), p(&s1), "--out", p(&other), "--partial"], &["another study"]);
    assert_eq!(std::fs::read(other.join("results.csv")).unwrap(), before);
}

#[test]
fn study_and_sim_outputs_need_their_parent_folder() {
    let dir = tempfile::tempdir().unwrap();
    let deep = dir.path().join("missing/deep/x");
    let o = overlap_study(&deep, "1", &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("does not exist"), "{}", text(&o.stderr));
    let scenario = crate::util::root().join("scenarios/paper_two_rooms.toml");
    fails_with(&["sim", "log", p(&scenario), "--out", p(&deep)], &["--out", "does not exist"]);
    assert!(!dir.path().join("missing").exists(), "no chain of folders made");
}

#[test]
fn a_run_overwrites_no_file_of_its_names_that_no_run_listed_and_removes_no_hand_listed_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let world = crate::util::root().join("worlds/two_rooms.toml");
    let scenario = crate::reliability_outputs::idle_scenario(d, &world, "start_experia", "start_prawn");
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("a.yaml"), "the user's own map").unwrap();
    std::fs::write(out.join("report.json"), "the user's own report").unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["run", p(&scenario), "--quiet", "--out", p(&out)];
        args.extend_from_slice(extra);
        crate::util::mrslam(&args)
    };
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("run-files.txt") && text(&o.stderr).contains("--force"), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_to_string(out.join("a.yaml")).unwrap(), "the user's own map");
    let o = run(&["--force"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    // A name appended to run-files.txt by hand is not the run's to remove.
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let manifest = std::fs::read_to_string(out.join("run-files.txt")).unwrap();
    std::fs::write(out.join("run-files.txt"), format!("{manifest}notes.txt\n")).unwrap();
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
}

#[test]
fn a_missing_or_extensionless_map_and_an_image_given_as_a_yaml_are_named_plainly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let b = plan(d, "b", 4);
    fails_with(&["map", "info", p(&d.join("noext"))], &["noext: no such file"]);
    std::fs::write(d.join("noext"), "x").unwrap();
    fails_with(&["map", "info", p(&d.join("noext"))], &["noext: no file extension", ".yaml"]);
    fails_with(&["map", "info", "/dev/null"], &["/dev/null: no file extension"]);
    let o = fails_with(&["merge", p(&b), p(&d.join("b.pgm"))], &["b.pgm: an image, where a map YAML", "map convert"]);
    assert!(!text(&o.stderr).contains("UTF-8"), "{}", text(&o.stderr));
    fails_with(&["merge", p(&b), p(&d.join("gone.yaml"))], &["gone.yaml: no such file"]);
}

#[test]
fn help_texts_name_every_file_written() {
    let help = |args: &[&str]| text(&crate::util::mrslam(args).stdout);
    let cut = help(&["map", "cut", "--help"]);
    assert!(cut.contains("PNG preview"), "{cut}");
    let logs = help(&["study", "logs", "--help"]);
    assert!(logs.contains("part-K.png"), "{logs}");
}

#[cfg(unix)]
#[test]
fn an_output_name_that_is_not_utf8_is_refused_before_any_work() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = empty_log(d);
    let out = d.join(std::ffi::OsStr::from_bytes(b"y\xff.yaml"));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .arg("slam")
        .arg(&log)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("not UTF-8"), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_dir(d).unwrap().count(), 1, "nothing written");
}

/// Sends `signal` (`-INT`, `-TERM`) to `child` once `ready` exists (and a moment more), and returns its output.
#[cfg(unix)]
fn interrupt(child: std::process::Child, ready: &Path, signal: &str) -> std::process::Output {
    let start = std::time::Instant::now();
    while !ready.exists() && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    let kill = std::process::Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    child.wait_with_output().unwrap()
}

/// The names in `dir` that start with a dot (hidden temporary files).
fn hidden(dir: &Path) -> Vec<String> {
    let names = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned());
    names.filter(|n| n.starts_with('.')).collect()
}

#[cfg(unix)]
#[test]
fn sigterm_ends_a_run_as_ctrl_c_does_and_leaves_no_temporary_bag() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let world = crate::util::root().join("worlds/two_rooms.toml");
    let long = std::fs::read_to_string(crate::util::root().join("scenarios/paper_two_rooms.toml"))
        .unwrap()
        .replace("\"../worlds/two_rooms.toml\"", &format!("{:?}", world.display().to_string()))
        .replace("when = \"rendezvous\"", "when = 170.0");
    let scenario = d.join("long.toml");
    std::fs::write(&scenario, long).unwrap();
    let (out, bag) = (d.join("out"), d.join("run.mcap"));
    let child = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["run", p(&scenario), "--quiet", "--out", p(&out), "--mcap", p(&bag)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let temporary = d.join(format!(".run.mcap.tmp{}", child.id()));
    let o = interrupt(child, &temporary, "-TERM");
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{e}");
    assert!(e.contains("interrupted") && e.contains("as they were before this run"), "{e}");
    assert_eq!(hidden(d), Vec::<String>::new(), "temporary files left");
    assert!(!bag.exists());
}

#[cfg(unix)]
#[test]
fn an_interrupted_slam_says_what_it_left() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = d.join("office.clf");
    std::fs::write(&log, crate::study_logs::carmen_log(&crate::study_logs::run())).unwrap();
    let (map, rrd) = (d.join("m.yaml"), d.join("s.rrd"));
    let child = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["slam", p(&log), "-o", p(&map), "--rrd", p(&rrd), "--set", "linear_update=0.01"])
        .args(["--set", "particles=200"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = interrupt(child, &mrslam_viz::partial_path(&rrd), "-INT");
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("mrslam slam: interrupted: nothing written to") && e.contains("s.partial.rrd"), "{e}");
    assert!(!map.exists());
}

#[test]
fn a_device_given_as_relations_or_a_trajectory_is_refused_at_its_first_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let rels = dir.path().join("r.relations");
    std::fs::write(&rels, "0 1 0 0 0 0 0 0\n").unwrap();
    fails_with(&["eval", "relations", "/dev/zero", p(&rels)], &["/dev/zero", "byte 1 is NUL"]);
    let traj = dir.path().join("t.txt");
    std::fs::write(&traj, "0 0 0 0\n1 1 0 0\n").unwrap();
    fails_with(&["eval", "relations", p(&traj), "/dev/zero"], &["/dev/zero", "byte 1 is NUL"]);
}
