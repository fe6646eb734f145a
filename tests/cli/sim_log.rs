//! `mrslam sim log`: a simulated run written as benchmark data (a CARMEN log per robot, its true trajectory,
//! relations drawn from the truth) that `mrslam eval` and `mrslam slam` read as they read the real benchmark.

use crate::util::{mrslam, p, root, text};
use std::path::{Path, PathBuf};

/// Two robots of the two-rooms world, each driving its room's loop twice.
fn scenario(dir: &Path) -> PathBuf {
    let world = root().join("worlds/two_rooms.toml");
    let experia = "[4.2, 0.9], [4.6, 3.5], [1.9, 3.4], [1.4, 2.6], [2.0, 1.2], [3.0, 1.1]";
    let prawn = "[8.2, 2.9], [8.8, 4.1], [9.4, 2.0], [8.0, 1.3], [6.6, 1.2], [6.1, 1.95]";
    let text = format!(
        r#"name = "two_laps"
world = "{}"
seed = 3
duration = 150.0
[merge]
when = "rendezvous"
host = "experia"
[[robots]]
name = "experia"
model = "experia"
lidar = "hokuyo_urg_04lx"
start = "start_experia"
route = [{experia}, {experia}]
speed = 0.35
[[robots]]
name = "prawn"
model = "prawn"
lidar = "rplidar_a1"
start = "start_prawn"
route = [{prawn}, {prawn}]
speed = 0.3
"#,
        world.display()
    );
    let path = dir.join("two_laps.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_simulated_run_is_written_as_a_log_its_truth_and_relations_and_scores_as_the_benchmark_does() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let out = dir.path().join("logs");
    let o = mrslam(&["sim", "log", p(&scenario), "--out", p(&out), "--loop-min-travel", "8", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let stdout = text(&o.stdout);
    assert!(stdout.contains("experia") && stdout.contains("across loops"), "{stdout}");
    let summary = json(&out.join("log.json"));
    assert_eq!(summary["seed"], 3);
    for (k, name) in ["experia", "prawn"].iter().enumerate() {
        let robot = &summary["robots"][k];
        assert_eq!(robot["name"], *name);
        let scans = robot["scans"].as_u64().unwrap() as usize;
        // Second laps: loops are there and are long.
        assert!(robot["loop_relations"].as_u64().unwrap() >= 3, "{robot}");
        assert!(robot["longest_loop_m"].as_f64().unwrap() >= 8.0, "{robot}");
        let clf = out.join(format!("{name}.clf"));
        let truth = out.join(format!("{name}.truth"));
        let relations = out.join(format!("{name}.relations"));
        let log = std::fs::read_to_string(&clf).unwrap();
        assert_eq!(log.lines().filter(|l| l.starts_with("ROBOTLASER1 ")).count(), scans);
        assert_eq!(log.lines().filter(|l| l.starts_with("ODOM ")).count(), scans);
        // The truth scores zero against its own relations, and the odometry does not.
        let o = mrslam(&["eval", "relations", p(&truth), p(&relations)]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(text(&o.stdout).contains("translation: 0.0000 ± 0.0000 m"), "{}", text(&o.stdout));
        // The log maps with `mrslam slam` and its relations score the SLAM, well under the odometry's error.
        let summary_path = dir.path().join(format!("{name}.json"));
        let o = mrslam(&[
            "slam",
            p(&clf),
            "-o",
            p(&dir.path().join(format!("{name}.yaml"))),
            "--relations",
            p(&relations),
            "--summary",
            p(&summary_path),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let metric = &json(&summary_path)["metric"];
        assert_eq!(metric["missing"], 0, "{metric}");
        let error = metric["translation_mean_m"].as_f64().unwrap();
        let rotation = metric["rotation_mean_deg"].as_f64().unwrap();
        eprintln!("{name}: {error:.4} m, {rotation:.3} deg");
        // The truth is the pose at each scan's stamp, its first beam (not when the scan came in, a scan period
        // later: that pairing cost 1-2.5 deg on FR079's generated logs). The RPLidar's beams span its whole
        // 0.18 s turn and the SLAM does not deskew: its scans are stamped, and paired with truth and odometry, at
        // the middle beam (at the first, turning scans sat half a turn's motion off: 0.020 m / 1.45 deg, seed 3;
        // now 0.018 m / 0.49 deg; the Hokuyo 0.008 m / 0.14 deg).
        let bound = if *name == "prawn" { 0.8 } else { 0.5 };
        assert!(error < 0.03 && rotation < bound, "{name}: SLAM {error} m, {rotation} deg on its own simulated log");
    }
}

#[test]
fn without_odom_lines_the_odometry_is_in_the_scan_lines_only() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let out = dir.path().join("logs");
    let o = mrslam(&["sim", "log", p(&scenario), "--out", p(&out), "--no-odom-lines", "--seed", "5", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let log = std::fs::read_to_string(out.join("prawn.clf")).unwrap();
    assert_eq!(log.lines().filter(|l| l.starts_with("ODOM ")).count(), 0);
    assert!(log.lines().any(|l| l.starts_with("ROBOTLASER1 ")));
    assert_eq!(json(&out.join("log.json"))["seed"], 5);
    let o = mrslam(&["log", "info", p(&out.join("prawn.clf"))]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

#[test]
fn scan_lines_written_with_late_odometry_have_their_lag_found_and_undone_by_slam() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let out = dir.path().join("logs");
    let args = ["--no-odom-lines", "--line-odometry-lag", "0.12", "--quiet"];
    let o = mrslam(&[&["sim", "log", p(&scenario), "--out", p(&out)][..], &args].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(json(&out.join("log.json"))["robots"][0]["line_odometry_lag_s"], 0.12);
    let summary = dir.path().join("experia.json");
    let map = dir.path().join("experia.yaml");
    let relations = out.join("experia.relations");
    let clf = out.join("experia.clf");
    let o =
        mrslam(&["slam", p(&clf), "-o", p(&map), "--relations", p(&relations), "--summary", p(&summary), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s = json(&summary);
    let lag = &s["line_odometry_lag"];
    let found = lag["lag_s"].as_f64().unwrap();
    let error = s["metric"]["translation_mean_m"].as_f64().unwrap();
    eprintln!("lag found {found} s (applied {}), SLAM {error:.4} m", lag["applied"]);
    // The scans' own heading changes give the lag back (the generated ACES loop: 0.110 and 0.115 s of 0.12 s), and
    // the re-timed odometry maps as on-time odometry does (0.006 m here, 0.008 m from its ODOM lines).
    assert!(lag["applied"] == true && (found - 0.12).abs() <= 0.03, "{lag}");
    assert!(error < 0.02, "SLAM {error} m on odometry written 0.12 s late");
}

#[test]
fn bad_settings_and_outputs_on_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let o = mrslam(&["sim", "log", p(&scenario), "--out", p(dir.path()), "--loop-radius", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--loop-radius 0"), "{}", text(&o.stderr));
    let o = mrslam(&["sim", "log", p(&scenario), "--out", p(dir.path()), "--line-odometry-lag", "2"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("--line-odometry-lag 2: must be a number of seconds from 0 to 1"),
        "{}",
        text(&o.stderr)
    );
    // A scenario named like a robot's output in the output folder is not overwritten.
    let clash = dir.path().join("experia.relations");
    std::fs::copy(&scenario, &clash).unwrap();
    let o = mrslam(&["sim", "log", p(&clash), "--out", p(dir.path()), "--quiet"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    assert!(text(&o.stderr).contains("experia.relations"), "{}", text(&o.stderr));
    assert_eq!(std::fs::read(&clash).unwrap(), std::fs::read(&scenario).unwrap());
}
