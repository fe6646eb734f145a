//! `mrslam study`, as a user would: a small map-level study, its files, its shards, and bad input.

use crate::util::{mrslam, root};
use std::path::Path;
use std::process::{Command, Output};

const COLUMNS: &str = "trial,overlap_target,overlap,seed,algorithm,accepted,success,false_merge,rotation_error_deg,\
translation_error_m,time_ms,rotation_error_at_end_deg,translation_error_at_end_m,stage";

/// A small study: 3 overlaps x 4 trials x (sift, rmap) on 12 m x 10 m floor plans.
fn small_study(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "study",
        "overlap",
        "--floorplans",
        "2",
        "--floorplan-size",
        "12x10",
        "--overlaps",
        "0.2:0.6:0.2",
        "--trials",
        "4",
        "--algorithms",
        "sift,rmap",
        "--seed",
        "5",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    mrslam(&args)
}

fn ok(o: &Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn csv(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    (header, lines.map(|l| l.split(',').map(str::to_string).collect()).collect())
}

#[test]
fn a_small_study_writes_consistent_results_summary_and_plot_and_shards_agree() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let o = small_study(&whole, &[]);
    ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("trials/s"), "{stdout}");

    let (header, rows) = csv(&whole.join("results.csv"));
    assert_eq!(header, COLUMNS);
    assert_eq!(rows.len(), 3 * 4 * 2);
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), 14);
        assert!(r[11].is_empty() && r[12].is_empty(), "a cut pair has no SLAM drift: {r:?}");
        assert!(r[13].is_empty(), "sift and rmap are not cascades: no stage: {r:?}");
        assert_eq!(r[0], (i / 2).to_string(), "sorted by trial");
        assert_eq!(r[4], if i % 2 == 0 { "sift" } else { "rmap" }, "then by algorithm");
        let (accepted, success, false_merge) = (r[5] == "true", r[6] == "true", r[7] == "true");
        assert_eq!(false_merge, accepted && !success, "{r:?}");
        if success {
            let rot: f64 = r[8].parse().unwrap();
            let tr: f64 = r[9].parse().unwrap();
            assert!(rot <= 2.0 && tr <= 0.1 + 1e-9, "{r:?}");
        }
        let target: f64 = r[1].parse().unwrap();
        let overlap: f64 = r[2].parse().unwrap();
        assert!((target - overlap).abs() < 0.03, "{r:?}");
    }

    // summary.csv agrees with results.csv.
    let (sheader, summary) = csv(&whole.join("summary.csv"));
    assert!(sheader.starts_with("overlap_bin,algorithm,trials,successes,success_rate,success_lo,success_hi"));
    assert_eq!(summary.len(), 3 * 2);
    for s in &summary {
        let sel: Vec<&Vec<String>> = rows.iter().filter(|r| r[1] == s[0] && r[4] == s[1]).collect();
        assert_eq!(s[2], sel.len().to_string(), "{s:?}");
        assert_eq!(s[3], sel.iter().filter(|r| r[6] == "true").count().to_string(), "{s:?}");
        assert_eq!(s[7], sel.iter().filter(|r| r[7] == "true").count().to_string(), "{s:?}");
        let (rate, lo, hi): (f64, f64, f64) = (s[4].parse().unwrap(), s[5].parse().unwrap(), s[6].parse().unwrap());
        assert!(lo <= rate && rate <= hi, "{s:?}");
    }

    let img = image::open(whole.join("plot.png")).expect("plot.png decodes");
    assert_eq!((img.width(), img.height()), (1200, 900));

    // Two shards, collected, are the whole study row for row (time_ms, wall time, aside).
    let (s0, s1, joined) = (dir.path().join("s0"), dir.path().join("s1"), dir.path().join("joined"));
    ok(&small_study(&s0, &["--shard", "0/2"]));
    ok(&small_study(&s1, &["--shard", "1/2"]));
    assert_eq!(csv(&s0.join("results.csv")).1.len(), 12);
    let o =
        mrslam(&["study", "collect", s1.to_str().unwrap(), s0.to_str().unwrap(), "--out", joined.to_str().unwrap()]);
    ok(&o);
    let (jh, jrows) = csv(&joined.join("results.csv"));
    assert_eq!(jh, COLUMNS);
    let strip = |rows: &[Vec<String>]| rows.iter().map(|r| r[..10].to_vec()).collect::<Vec<_>>();
    assert_eq!(strip(&jrows), strip(&rows));
    let img = image::open(joined.join("plot.png")).expect("collected plot.png decodes");
    assert_eq!((img.width(), img.height()), (1200, 900));
    let strip_time = |rows: &[Vec<String>]| rows.iter().map(|r| r[..9].to_vec()).collect::<Vec<_>>();
    assert_eq!(strip_time(&csv(&joined.join("summary.csv")).1), strip_time(&summary));

    // Collecting one shard of two is refused, naming the missing one; --partial collects it, saying so.
    let half = dir.path().join("half");
    let o = mrslam(&["study", "collect", s0.to_str().unwrap(), "--out", half.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("shard 1/2 of the study is missing") && e.contains("--partial"), "{e}");
    assert!(!half.exists(), "nothing written");
    let o = mrslam(&["study", "collect", s0.to_str().unwrap(), "--out", half.to_str().unwrap(), "--partial"]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("missing:   shards 1/2"));
    assert!(!std::fs::read_to_string(half.join("study.json")).unwrap().contains("\"shard\""));

    // Collecting a shard twice is refused.
    let o =
        mrslam(&["study", "collect", s0.to_str().unwrap(), s0.to_str().unwrap(), "--out", joined.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("also in"));
}

fn refused(args: &[&str], needle: &str) {
    let o = mrslam(args);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(e.contains(needle), "{args:?}: stderr lacks `{needle}`: {e}");
}

#[test]
fn bad_input_is_refused_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let base = ["study", "overlap", "--floorplans", "1", "--quiet", "--out", out];
    let with = |extra: &[&'static str]| base.iter().copied().chain(extra.iter().copied()).collect::<Vec<&str>>();
    refused(&with(&["--overlaps", "0.5:0.2:0.1"]), "empty");
    refused(&with(&["--trials", "0"]), "--trials");
    refused(&with(&["--shard", "3/2"]), "shard");
    refused(&with(&["--algorithms", "sift,magic"]), "unknown algorithm `magic`");
    refused(&with(&["--floorplan-size", "12by10"]), "--floorplan-size");

    // A sweep file missing a parameter, and one naming an unknown robot.
    let sweep = dir.path().join("sweep.toml");
    let scenario = root().join("scenarios/paper_corridor.toml");
    let head = format!("scenario = {:?}\nseeds = [1]\n", scenario.display().to_string());
    std::fs::write(&sweep, format!("{head}[[vary]]\nrobot = \"experia\"\nfield = \"route_end_x\"\n")).unwrap();
    refused(&["study", "scenario", sweep.to_str().unwrap(), "--out", out], "values");
    std::fs::write(&sweep, format!("scenario = {:?}\n", scenario.display().to_string())).unwrap();
    refused(&["study", "scenario", sweep.to_str().unwrap(), "--out", out], "seeds");
    std::fs::write(&sweep, format!("{head}[[vary]]\nrobot = \"robbie\"\nfield = \"route_end_x\"\nvalues = [20.0]\n"))
        .unwrap();
    refused(&["study", "scenario", sweep.to_str().unwrap(), "--out", out], "no robot `robbie`");
    std::fs::write(&sweep, format!("{head}[[vary]]\nrobot = \"experia\"\nfield = \"route_end_x\"\nvalues = [99.0]\n"))
        .unwrap();
    refused(&["study", "scenario", sweep.to_str().unwrap(), "--out", out], "outside the world");
}

#[test]
fn the_shipped_sweep_file_is_valid() {
    let sweep = root().join("scenarios/corridor_sweep.toml");
    let o = mrslam(&["study", "scenario", sweep.to_str().unwrap(), "--dry-run", "--out", "/nonexistent/never"]);
    ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("9 trials"), "{stdout}");
    assert!(stdout.contains("experia.route_end_x=34"), "{stdout}");
}

/// A map-level study of `trials` trials at two overlaps, as a command to spawn.
fn study_command(out: &Path, seed: &str, trials: &str, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mrslam"));
    c.args(["study", "overlap", "--floorplans", "2", "--floorplan-size", "12x10", "--overlaps", "0.2,0.4"])
        .args(["--trials", trials, "--algorithms", "sift,rmap", "--seed", seed, "--quiet", "--out"])
        .arg(out)
        .args(extra);
    c
}

#[test]
fn an_interrupted_study_keeps_its_finished_trials_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let results = out.join("results.csv");
    let mut command = study_command(&out, "5", "60", &[]);
    // A test run started in the background by a shell without job control inherits SIGINT ignored (POSIX), and
    // the study, which installs no handler of its own, would pass it on: it gets the default action back.
    #[cfg(unix)]
    // SAFETY: between fork and exec only the async-signal-safe `signal` is called.
    unsafe {
        std::os::unix::process::CommandExt::pre_exec(&mut command, || {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    // Interrupt as soon as a few trials are written.
    let start = std::time::Instant::now();
    while std::fs::read_to_string(&results).map_or(0, |t| t.lines().count()) < 5 {
        assert!(start.elapsed().as_secs() < 60, "no trial written within a minute");
        assert!(child.try_wait().unwrap().is_none(), "the study ended before it was interrupted");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    assert!(!child.wait().unwrap().success());
    let (header, kept) = csv(&results);
    assert_eq!(header, COLUMNS);
    assert!(kept.len() >= 4 && kept.len() < 240, "{} rows survive the interruption", kept.len());

    // Started afresh in the same folder: refused, nothing lost.
    let o = study_command(&out, "5", "60", &[]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--resume"), "{}", String::from_utf8_lossy(&o.stderr));
    // Resumed with other parameters: refused.
    let o = study_command(&out, "6", "60", &["--resume"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("`seed` is `5` there but `6` here"));
    // Resumed: the missing trials run, each trial once, the kept rows as they were.
    let o = study_command(&out, "5", "60", &["--resume"]).output().unwrap();
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("trials already done"));
    let (_, rows) = csv(&results);
    assert_eq!(rows.len(), 2 * 60 * 2);
    let keys: std::collections::BTreeSet<(String, String)> =
        rows.iter().map(|r| (r[0].clone(), r[4].clone())).collect();
    assert_eq!(keys.len(), rows.len(), "a trial twice");
    for k in kept.iter().filter(|k| kept.iter().filter(|r| r[0] == k[0]).count() == 2) {
        assert!(rows.contains(k), "kept row {k:?} lost");
    }
}

#[test]
fn collect_refuses_shards_of_different_studies() {
    let dir = tempfile::tempdir().unwrap();
    let (s0, s1, joined) = (dir.path().join("s0"), dir.path().join("s1"), dir.path().join("joined"));
    ok(&study_command(&s0, "5", "2", &["--shard", "0/2"]).output().unwrap());
    ok(&study_command(&s1, "6", "2", &["--shard", "1/2"]).output().unwrap());
    let o =
        mrslam(&["study", "collect", s0.to_str().unwrap(), s1.to_str().unwrap(), "--out", joined.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("study.json") && e.contains("`seed` is `6` there but `5` here"), "{e}");
    assert!(!joined.exists(), "nothing written");
    // Collected into one of the shards: refused.
    let o = mrslam(&["study", "collect", s0.to_str().unwrap(), "--out", s0.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn the_map_style_and_encoding_are_recorded_and_change_what_the_merger_sees() {
    let dir = tempfile::tempdir().unwrap();
    let (walls, boundary) = (dir.path().join("walls"), dir.path().join("boundary"));
    ok(&small_study(&walls, &[]));
    ok(&small_study(&boundary, &["--map-style", "boundary", "--encoding", "paper"]));
    let json = std::fs::read_to_string(boundary.join("study.json")).unwrap();
    assert!(json.contains("\"map_style\"") && json.contains("\"boundary\""), "{json}");
    assert!(json.contains("\"encoding\"") && json.contains("\"paper\""), "{json}");
    // Same pairs (the overlaps are measured on the cut), different maps: the merges differ.
    let (_, a) = csv(&walls.join("results.csv"));
    let (_, b) = csv(&boundary.join("results.csv"));
    assert_eq!(a.len(), b.len());
    assert!(a.iter().zip(&b).all(|(x, y)| x[2] == y[2]), "the same pairs in both");
    assert_ne!(a, b, "dropping the walls changed nothing");
    // Resuming with another style is refused: it would mix two studies.
    let o = small_study(&boundary, &["--resume"]);
    assert_eq!(o.status.code(), Some(1));
}
