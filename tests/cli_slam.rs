//! `mrslam slam` run as a user would: a CARMEN log of a drifting robot in, a map and a trajectory out that
//! beat the odometry against the truth; bad logs and bad parameters refused, naming the line or the parameter.

use mrslam_core::Pose2;
use mrslam_core::pose::{pose_xyt, relative};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mrslam(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrslam")).args(args).output().expect("mrslam runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The first 12 m of the synthetic office loop, Hokuyo scans, odometry drifting 3 % and 0.01 rad/m.
fn office_run() -> SyntheticRun {
    let path: Vec<Pose2> =
        synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1).into_iter().take(240).collect();
    let drift = Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 };
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::hokuyo(), Pose2::identity(), &drift, 11)
}

/// The run as an old-style CARMEN log: PARAM lines for the laser's geometry, one FLASER line per scan.
fn carmen_lines(run: &SyntheticRun) -> Vec<String> {
    let lidar = Lidar::hokuyo();
    let mut lines = vec![
        format!("PARAM laser_front_laser_fov {}", lidar.fov.to_degrees()),
        format!("PARAM robot_front_laser_max {}", lidar.range_max),
    ];
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        let (x, y, t) = pose_xyt(&o.pose);
        let mut l = format!("FLASER {}", s.ranges.len());
        for r in &s.ranges {
            let _ = write!(l, " {r:.3}");
        }
        let _ = write!(l, " {x:.6} {y:.6} {t:.6} {x:.6} {y:.6} {t:.6} {:.3} synthetic {:.3}", o.stamp, o.stamp);
        lines.push(l);
    }
    lines
}

fn write_log(dir: &Path, name: &str, lines: &[String]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    p
}

/// RMS distance of `stamp x y theta` lines from the truth (both from the start pose).
fn rms_from_truth(traj: &[(f64, f64, f64)], run: &SyntheticRun) -> f64 {
    let t0 = run.truth[0].1;
    let sum: f64 = traj
        .iter()
        .map(|&(stamp, x, y)| {
            let k = run.truth.iter().position(|(s, _)| (s - stamp).abs() < 1e-3).expect("a true pose at the stamp");
            let t = relative(&t0, &run.truth[k].1);
            (t.translation.x - x).powi(2) + (t.translation.y - y).powi(2)
        })
        .sum();
    (sum / traj.len() as f64).sqrt()
}

#[test]
fn maps_a_drifting_log_and_beats_its_odometry() {
    let dir = tempfile::tempdir().unwrap();
    let run = office_run();
    let log = write_log(dir.path(), "office.clf", &carmen_lines(&run));
    let (map, traj) = (dir.path().join("office.yaml"), dir.path().join("office.txt"));
    let o = mrslam(&[
        "slam",
        log.to_str().unwrap(),
        "-o",
        map.to_str().unwrap(),
        "--trajectory",
        traj.to_str().unwrap(),
        "--preset",
        "hokuyo",
        "--set",
        "linear_update=0.1",
        "--set",
        "angular_update=0.1",
        "--set",
        "odometry_calibration=20",
        "--quiet",
    ]);
    assert!(o.status.success(), "stderr: {}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("240 scans:") && out.contains("processed"), "{out}");
    // The drift the log was made with: 1/1.03 - 1 = -2.9 % and -0.0097 rad/m (a short run: roughly).
    assert!(out.contains("odometry calibration learnt: distance scale -"), "{out}");
    let grid = mrslam_core::map_io::read_ros_map(&map).expect("the map reads back");
    let (free, occupied, _) = grid.state_counts();
    assert!(free > 10 * occupied && occupied > 200, "free {free} occupied {occupied}");
    let rows: Vec<(f64, f64, f64)> = std::fs::read_to_string(&traj)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|f| f.parse().unwrap()).collect();
            assert_eq!(v.len(), 4, "timestamp x y theta: {l}");
            (v[0], v[1], v[2])
        })
        .collect();
    assert!(rows.len() > 50, "{} trajectory lines", rows.len());
    let slam = rms_from_truth(&rows, &run);
    let odo0 = run.odometry[0].pose;
    let odometry: Vec<(f64, f64, f64)> = run
        .odometry
        .iter()
        .filter(|o| rows.iter().any(|r| (r.0 - o.stamp).abs() < 1e-3))
        .map(|o| {
            let p = relative(&odo0, &o.pose);
            (o.stamp, p.translation.x, p.translation.y)
        })
        .collect();
    let odo = rms_from_truth(&odometry, &run);
    eprintln!("mrslam slam on 12 m of the office loop: RMS {slam:.4} m, odometry {odo:.3} m\n{out}");
    assert!(slam <= 0.05 && slam * 5.0 <= odo, "SLAM RMS {slam} m, odometry {odo} m");
}

#[test]
fn bad_logs_and_parameters_are_refused_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines = carmen_lines(&office_run());
    lines.truncate(30);
    let map = dir.path().join("m.yaml");
    let refused = |log: &Path, extra: &[&str], needles: &[&str]| {
        let mut args = vec!["slam", log.to_str().unwrap(), "-o", map.to_str().unwrap(), "--quiet"];
        args.extend_from_slice(extra);
        let o = mrslam(&args);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        for n in needles {
            assert!(e.contains(n), "{args:?}: `{n}` not in: {e}");
        }
        assert!(!map.exists(), "{args:?} left a map behind");
    };
    let good = write_log(dir.path(), "good.clf", &lines);
    refused(&good, &["--set", "warp=1"], &["--set warp=1", "unknown SLAM parameter 'warp'"]);
    refused(&good, &["--set", "particles"], &["--set particles", "NAME=VALUE"]);
    refused(&good, &["--set", "srr=-1"], &["srr"]);
    // The default preset is GMapping's, whose matcher cannot feed the calibration.
    refused(&good, &["--set", "odometry_calibration=20"], &["odometry_calibration needs"]);
    // Line 10 of the file (its 8th scan) stamped a second before line 9's.
    let mut back = lines.clone();
    let stamp = |l: &str| -> f64 { l.split_whitespace().rev().nth(2).unwrap().parse().unwrap() };
    let (s9, s10) = (stamp(&back[8]), stamp(&back[9]));
    back[9] = back[9].replace(&format!(" {s10:.3} synthetic {s10:.3}"), &format!(" {:.3} synthetic 0.0", s9 - 1.0));
    let backwards = write_log(dir.path(), "backwards.clf", &back);
    refused(&backwards, &[], &["backwards.clf:10", "time goes backwards"]);
    let mut broken = lines.clone();
    broken[5] = "FLASER 667 1.0 2.0".into();
    let broken = write_log(dir.path(), "broken.clf", &broken);
    refused(&broken, &[], &["broken.clf:6", "FLASER"]);
    let empty = write_log(dir.path(), "empty.clf", &lines[..2]);
    refused(&empty, &[], &["empty.clf", "no laser scans"]);
}
