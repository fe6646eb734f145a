//! `mrslam study logs`, as a user would: a small synthetic CARMEN log with its relations, split into two
//! robots, mapped, merged and scored; a resume; and bad input refused with exit code 1.

use crate::util::{mrslam, text};
use mrslam_core::Pose2;
use mrslam_core::Xyt;
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The first 18 m of the synthetic office loop's first corridor, Hokuyo scans, slightly drifting odometry.
pub fn run() -> SyntheticRun {
    let path: Vec<Pose2> =
        synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1).into_iter().take(360).collect();
    let drift = Drift { scale: 0.01, heading_per_m: 0.005, sigma_trans: 0.01, sigma_rot: 0.005 };
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::hokuyo(), Pose2::identity(), &drift, 3)
}

/// The run as an old-style CARMEN log: PARAM lines for the laser, one FLASER line per scan.
pub fn carmen_log(run: &SyntheticRun) -> String {
    let lidar = Lidar::hokuyo();
    let mut s = format!(
        "PARAM laser_front_laser_fov {}\nPARAM robot_front_laser_max {}\n",
        lidar.fov.to_degrees(),
        lidar.range_max
    );
    for (o, scan) in run.odometry.iter().zip(&run.scans) {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&o.pose);
        let _ = write!(s, "FLASER {}", scan.ranges.len());
        for r in &scan.ranges {
            let _ = write!(s, " {r:.3}");
        }
        let _ = writeln!(s, " {x:.6} {y:.6} {t:.6} {x:.6} {y:.6} {t:.6} {:.3} synthetic {:.3}", o.stamp, o.stamp);
    }
    s
}

/// Relations from the truth: scan k to scan k + gap, for scans across the two halves and within them.
fn relations(run: &SyntheticRun) -> String {
    let mut s = String::from("# t1 t2 x y z roll pitch yaw\n");
    for (a, b) in [(100, 250), (150, 200), (120, 300), (20, 60), (260, 300), (170, 190), (330, 140)] {
        let (ta, pa) = run.truth[a];
        let (tb, pb) = run.truth[b];
        let Xyt { x, y, theta: t } = Xyt::from_pose(&pa.inv_mul(&pb));
        let _ = writeln!(s, "{ta:.3} {tb:.3} {x:.6} {y:.6} 0 0 0 {t:.6}");
    }
    s
}

struct Files {
    _dir: tempfile::TempDir,
    root: PathBuf,
    log: PathBuf,
    rels: PathBuf,
}

fn files() -> Files {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let r = run();
    let (log, rels) = (root.join("office.clf"), root.join("office.relations"));
    std::fs::write(&log, carmen_log(&r)).unwrap();
    std::fs::write(&rels, relations(&r)).unwrap();
    Files { _dir: dir, root, log, rels }
}

fn study(log: &Path, rels: &Path, parts: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "study",
        "logs",
        log.to_str().unwrap(),
        "--relations",
        rels.to_str().unwrap(),
        "--parts",
        parts,
        "--out",
        out.to_str().unwrap(),
        "--preset",
        "hokuyo",
        "--slam-set",
        "linear_update=0.1",
        "--slam-set",
        "angular_update=0.1",
        "--algorithms",
        "sift,rmap",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    mrslam(&args)
}

fn csv(path: &Path) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().map(str::to_string);
    let header = lines.next().unwrap();
    (header, lines.collect())
}

#[test]
fn a_log_split_into_two_robots_is_mapped_merged_scored_and_resumed() {
    let f = files();
    let out = f.root.join("study");
    let o = study(&f.log, &f.rels, "2", &out, &[]);
    let stdout = text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "stdout: {stdout}\nstderr: {}", text(&o.stderr));
    for name in [
        "study.json",
        "results.csv",
        "summary.csv",
        "plot.png",
        "parts.csv",
        "part-0.yaml",
        "part-0.pgm",
        "part-0.png",
        "part-0.trajectory.txt",
        "part-1.yaml",
        "part-1.pgm",
        "part-1.trajectory.txt",
    ] {
        assert!(out.join(name).is_file(), "{name} missing; stdout: {stdout}");
    }
    let (header, rows) = csv(&out.join("results.csv"));
    let columns: Vec<&str> = header.split(',').collect();
    for c in ["part_i", "part_j", "algorithm", "relations", "overlap", "accepted", "success", "false_merge"] {
        assert!(columns.contains(&c), "{c} not in {header}");
    }
    for c in ["error_m", "error_deg", "truth_error_m", "time_ms", "inliers", "reason"] {
        assert!(columns.contains(&c), "{c} not in {header}");
    }
    assert_eq!(rows.len(), 2, "one pair x two algorithms: {rows:?}");
    let col = |row: &str, name: &str| -> String {
        let k = columns.iter().position(|c| *c == name).unwrap();
        row.split(',').nth(k).unwrap().to_string()
    };
    for r in &rows {
        assert_eq!((col(r, "part_i").as_str(), col(r, "part_j").as_str()), ("0", "1"));
        // Relations 1, 2, 3, 6 and 7 cross the halves (the 7th written from part 1 to part 0).
        assert_eq!(col(r, "relations"), "5", "{r}");
        let overlap: f64 = col(r, "overlap").parse().unwrap();
        assert!(overlap > 0.05 && overlap < 1.0, "{r}");
        // The SLAM is good on this clean log: the true transform explains its relations well.
        let floor: f64 = col(r, "truth_error_m").parse().unwrap();
        assert!(floor < 0.2, "{r}");
    }
    let (header, rows) = csv(&out.join("summary.csv"));
    assert_eq!(
        header,
        "algorithm,pairs,accepted,successes,false_merges,median_time_ms,median_error_m,median_error_deg"
    );
    assert_eq!(rows.iter().map(|r| r.split(',').next().unwrap()).collect::<Vec<_>>(), ["sift", "rmap"]);
    let (header, rows) = csv(&out.join("parts.csv"));
    assert!(header.starts_with("part,first_stamp,last_stamp,scans"), "{header}");
    let scans: usize = rows.iter().map(|r| r.split(',').nth(3).unwrap().parse::<usize>().unwrap()).sum();
    assert_eq!(scans, 360);
    let traj = std::fs::read_to_string(out.join("part-1.trajectory.txt")).unwrap();
    assert_eq!(traj.lines().filter(|l| !l.starts_with('#')).count() + 180, 360, "a pose for every scan");
    assert!(stdout.contains("sift") && stdout.contains("rmap") && stdout.contains("pairs"), "{stdout}");

    // Run again into the same folder: refused, the study kept.
    let o = study(&f.log, &f.rels, "2", &out, &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--resume"), "{}", text(&o.stderr));
    // Resumed: the parts are read back, not mapped again; the same rows come out.
    let before = csv(&out.join("results.csv")).1;
    let parts_before = std::fs::read_to_string(out.join("parts.csv")).unwrap();
    std::fs::remove_file(out.join("results.csv")).unwrap();
    let o = study(&f.log, &f.rels, "2", &out, &["--resume"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("read back"), "{}", text(&o.stdout));
    let after = csv(&out.join("results.csv")).1;
    let strip = |rows: &[String]| -> Vec<String> {
        let k = columns.iter().position(|c| *c == "time_ms").unwrap();
        rows.iter().map(|r| r.split(',').enumerate().filter(|(i, _)| *i != k).map(|(_, f)| f).collect()).collect()
    };
    assert_eq!(strip(&before), strip(&after));
    assert_eq!(std::fs::read_to_string(out.join("parts.csv")).unwrap(), parts_before, "the parts' SLAM counts kept");
    // A resume of another study (other seed) is refused.
    let o = study(&f.log, &f.rels, "2", &out, &["--resume", "--seed", "9"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("`seed`"), "{}", text(&o.stderr));
}

#[test]
fn odometry_drift_is_injected_before_the_split_and_recorded() {
    let f = files();
    let (plain, drifted) = (f.root.join("plain"), f.root.join("drifted"));
    let o = study(&f.log, &f.rels, "2", &plain, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let drift = ["--drift-heading", "2", "--drift-scale", "0.05", "--drift-sigma", "0.01"];
    let o = study(&f.log, &f.rels, "2", &drifted, &drift);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let json = std::fs::read_to_string(drifted.join("study.json")).unwrap();
    assert!(json.contains("\"drift\"") && json.contains("heading 2 deg/m"), "{json}");
    assert!(!std::fs::read_to_string(plain.join("study.json")).unwrap().contains("drift"));
    // The drifted odometry reached the SLAM (its path differs), which still beats it: the parts' true transform
    // explains the relations across them as well as without drift.
    let traj = |d: &Path| std::fs::read_to_string(d.join("part-1.trajectory.txt")).unwrap();
    assert_ne!(traj(&plain), traj(&drifted));
    let floor = |d: &Path| -> f64 {
        let (header, rows) = csv(&d.join("results.csv"));
        let k = header.split(',').position(|c| c == "truth_error_m").unwrap();
        rows[0].split(',').nth(k).unwrap().parse().unwrap()
    };
    assert!(floor(&drifted) < 0.2, "plain {}, drifted {}", floor(&plain), floor(&drifted));
    // The drift is part of the study: a resume without it is refused.
    let o = study(&f.log, &f.rels, "2", &drifted, &["--resume"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("`drift`"), "{}", text(&o.stderr));
}

fn refused(o: &Output, needles: &[&str]) {
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "stderr: {e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
}

#[test]
fn bad_input_is_refused_naming_the_file_and_line() {
    let f = files();
    let out = f.root.join("bad");
    let missing = f.root.join("nowhere.relations");
    refused(&study(&f.log, &missing, "2", &out, &[]), &["nowhere.relations"]);
    for n in ["0", "1"] {
        refused(&study(&f.log, &f.rels, n, &out, &[]), &[&format!("--parts {n}"), "at least 2"]);
    }
    let broken = f.root.join("broken.relations");
    let mut lines: Vec<String> = std::fs::read_to_string(&f.rels).unwrap().lines().map(str::to_string).collect();
    lines[2] = "10.0 25.0 1.0 oops 0 0 0 0".into();
    std::fs::write(&broken, lines.join("\n")).unwrap();
    refused(&study(&f.log, &broken, "2", &out, &[]), &["broken.relations:3", "`oops`"]);
    refused(&study(&f.log, &f.rels, "2", &out, &["--slam-set", "warp=1"]), &["--slam-set warp=1"]);
    refused(&study(&f.log, &f.rels, "2", &out, &["--algorithms", "magic"]), &["unknown algorithm `magic`"]);
    refused(&study(&f.log, &f.rels, "2", &out, &["--drift-sigma", "-0.1"]), &["--drift-sigma -0.1", "negative"]);
    refused(&study(&f.log, &f.rels, "2", &out, &["--drift-scale", "-1"]), &["--drift-scale -1"]);
    // More parts than the log's scans can fill.
    let short = f.root.join("short.clf");
    let log = std::fs::read_to_string(&f.log).unwrap();
    std::fs::write(&short, log.lines().take(5).collect::<Vec<_>>().join("\n") + "\n").unwrap();
    refused(&study(&short, &f.rels, "4", &f.root.join("short"), &[]), &["short.clf", "has no scan"]);
    // A start that failed on its log leaves no study.json to block the corrected retry.
    assert!(!f.root.join("short/study.json").exists(), "a failed start wrote study.json");
    let retry = study(&f.log, &f.rels, "2", &f.root.join("short"), &[]);
    assert_eq!(retry.status.code(), Some(0), "{}", text(&retry.stderr));
    // A missing chain of folders is not made.
    refused(&study(&f.log, &f.rels, "2", &f.root.join("missing/deep/x"), &[]), &["--out", "does not exist"]);
    assert!(!f.root.join("missing").exists());
    // The output folder over an input.
    refused(&study(&f.log, &f.rels, "2", &f.log, &[]), &["is a file"]);
}
