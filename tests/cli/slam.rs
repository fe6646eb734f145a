//! `mrslam slam` run as a user would: a CARMEN log of a drifting robot in, a map and a trajectory out that
//! beat the odometry against the truth; bad logs and bad parameters refused, naming the line or the parameter.

use crate::util::{mrslam, text};
use mrslam_core::Pose2;
use mrslam_core::{Xyt, pose::relative};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The first 12 m of the synthetic office loop, Hokuyo scans, odometry drifting 3 % and 0.01 rad/m.
fn office_run() -> SyntheticRun {
    let path: Vec<Pose2> =
        synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1).into_iter().take(240).collect();
    let drift = Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 };
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::hokuyo(), Pose2::identity(), &drift, 11)
}

/// The run as an old-style CARMEN log: PARAM lines for the laser's geometry, one FLASER line per scan.
fn carmen_lines(run: &SyntheticRun) -> Vec<String> {
    carmen_lines_of(run, &Lidar::hokuyo())
}

/// The run as an old-style CARMEN log of `lidar`'s scans.
fn carmen_lines_of(run: &SyntheticRun, lidar: &Lidar) -> Vec<String> {
    let mut lines = vec![
        format!("PARAM laser_front_laser_fov {}", lidar.fov.to_degrees()),
        format!("PARAM robot_front_laser_max {}", lidar.range_max),
    ];
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&o.pose);
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
    // The preview beside it: in colour, with the path drawn in red.
    let preview = image::open(dir.path().join("office.png")).expect("the map's preview beside it").to_rgb8();
    assert!(preview.pixels().filter(|p| p.0 == [220, 30, 30]).count() > 100, "the path is drawn");
    let (free, occupied, _) = grid.state_counts();
    assert!(free > 10 * occupied && occupied > 200, "free {free} occupied {occupied}");
    let rows: Vec<(f64, f64, f64)> = std::fs::read_to_string(&traj)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|f| f.parse().unwrap()).collect();
            assert_eq!(v.len(), 4, "timestamp x y theta: {l}");
            (v[0], v[1], v[2])
        })
        .collect();
    assert_eq!(rows.len(), 240, "one pose per scan");
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
    // GMapping's matcher cannot feed the calibration.
    refused(&good, &["--preset", "gmapping", "--set", "odometry_calibration=20"], &["odometry_calibration needs"]);
    // Line 10 of the file (its 8th scan) stamped 6 s before line 9's: more than a log may step back.
    let mut back = lines.clone();
    let stamp = |l: &str| -> f64 { l.split_whitespace().rev().nth(2).unwrap().parse().unwrap() };
    let (s9, s10) = (stamp(&back[8]), stamp(&back[9]));
    back[9] = back[9].replace(&format!(" {s10:.3} synthetic {s10:.3}"), &format!(" {:.3} synthetic 0.0", s9 - 6.0));
    let backwards = write_log(dir.path(), "backwards.clf", &back);
    refused(&backwards, &[], &["backwards.clf:10: FLASER: ipc_timestamp", "before the stamp", "on line 9"]);
    // ... which a wider bound accepts.
    let o = mrslam(&["log", "info", backwards.to_str().unwrap(), "--max-step-back", "10"]);
    assert!(o.status.success() && text(&o.stdout).contains("1 stamps out of order (max 6.00 s back, line 10)"));
    // Outputs never overwrite inputs; bad relations are refused before the work.
    refused(&good, &["--trajectory", good.to_str().unwrap()], &["--trajectory", "`.clf` is not a format written here"]);
    let rel = good.with_file_name("rel.txt");
    std::fs::write(&rel, "").unwrap();
    let r = rel.to_str().unwrap();
    refused(&good, &["--relations", r, "--trajectory", r], &["refusing to write an output over the input"]);
    let bad_rel = dir.path().join("bad.relations");
    std::fs::write(&bad_rel, "1 2 0 0 0 0 0 0\n1 2 0 0 0 0 0 zz\n").unwrap();
    refused(&good, &["--relations", bad_rel.to_str().unwrap()], &["bad.relations:2: field yaw: `zz`"]);
    let mut broken = lines.clone();
    broken[5] = "FLASER 667 1.0 2.0".into();
    let broken = write_log(dir.path(), "broken.clf", &broken);
    refused(&broken, &[], &["broken.clf:6", "FLASER"]);
    // A kidnapped robot: the odometry of the 20th scan (line 22) jumps 50 m. Mapped, and said.
    let mut kidnapped = lines.clone();
    let fields: Vec<String> = kidnapped[21].split_whitespace().map(str::to_string).collect();
    let n = fields.len();
    let moved: Vec<String> = fields
        .iter()
        .enumerate()
        .map(
            |(i, f)| {
                if i == n - 6 || i == n - 9 { format!("{:.6}", f.parse::<f64>().unwrap() + 50.0) } else { f.clone() }
            },
        )
        .collect();
    kidnapped[21] = moved.join(" ");
    let kidnapped = write_log(dir.path(), "kidnapped.clf", &kidnapped);
    let o = mrslam(&["slam", kidnapped.to_str().unwrap(), "-o", map.to_str().unwrap(), "--quiet"]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        out.contains("warning: the odometry jumps 2 times")
            && out.contains("largest 50.")
            && out.contains("at line 22"),
        "{out}"
    );
    std::fs::remove_file(&map).unwrap();
    std::fs::remove_file(map.with_extension("pgm")).unwrap();
    let empty = write_log(dir.path(), "empty.clf", &lines[..2]);
    refused(&empty, &[], &["empty.clf", "no laser scans"]);
}

/// The office run as a log a real robot writes: ODOM lines at twice the scan rate, each FLASER line's own
/// odometry fields stale (the last ODOM line before it), and lines written in arrival order: every third
/// ODOM line arrives late, after the scan that follows it, so stamps step back.
fn arrival_order_lines(run: &SyntheticRun) -> Vec<String> {
    let lidar = Lidar::hokuyo();
    let mut timed: Vec<(f64, String)> = vec![
        (-1.0, format!("PARAM laser_front_laser_fov {}", lidar.fov.to_degrees())),
        (-1.0, format!("PARAM robot_front_laser_max {}", lidar.range_max)),
    ];
    let odom_line = |stamp: f64, p: &Pose2| {
        let Xyt { x, y, theta: t } = Xyt::from_pose(p);
        format!("ODOM {x:.6} {y:.6} {t:.6} 0 0 0 {stamp:.3} synthetic {stamp:.3}")
    };
    for (k, (o, s)) in run.odometry.iter().zip(&run.scans).enumerate() {
        // ODOM at the scan's stamp and half-way to the next reading.
        let late = if k % 3 == 0 { 0.07 } else { 0.0 };
        timed.push((o.stamp + late, odom_line(o.stamp, &o.pose)));
        if let Some(n) = run.odometry.get(k + 1) {
            let half = o.pose.lerp_slerp(&n.pose, 0.5);
            timed.push((0.5 * (o.stamp + n.stamp), odom_line(0.5 * (o.stamp + n.stamp), &half)));
        }
        let stale = if k == 0 { o.pose } else { run.odometry[k - 1].pose };
        let Xyt { x, y, theta: t } = Xyt::from_pose(&stale);
        let mut l = format!("FLASER {}", s.ranges.len());
        for r in &s.ranges {
            let _ = write!(l, " {r:.3}");
        }
        let _ = write!(l, " {x:.6} {y:.6} {t:.6} {x:.6} {y:.6} {t:.6} {:.3} synthetic {:.3}", o.stamp, o.stamp);
        timed.push((o.stamp + 0.01, l));
    }
    timed.sort_by(|a, b| a.0.total_cmp(&b.0));
    timed.into_iter().map(|(_, l)| l).collect()
}

/// `mrslam slam LOG --preset hokuyo --relations REL --summary ...` plus `extra`, writing beside the log; returns
/// what it printed and the summary.
fn slam_scored(log: &Path, rel: &Path, extra: &[&str]) -> (String, serde_json::Value) {
    let (map, summary) = (log.with_extension("yaml"), log.with_extension("json"));
    let mut args = vec!["slam", log.to_str().unwrap(), "-o", map.to_str().unwrap(), "--preset", "hokuyo"];
    args.extend(["--relations", rel.to_str().unwrap(), "--summary", summary.to_str().unwrap(), "--quiet"]);
    args.extend_from_slice(extra);
    let o = mrslam(&args);
    assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    let s = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    (text(&o.stdout), s)
}

/// Data lines (not comments) of a trajectory file.
fn poses_of(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path).unwrap().lines().filter(|l| !l.starts_with('#')).map(str::to_string).collect()
}

/// Relations between every scan and the one `gap` scans later, from the truth: `t1 t2 x y z roll pitch yaw`.
fn true_relations(run: &SyntheticRun, gap: usize) -> String {
    let mut text = String::new();
    for (a, b) in run.truth.iter().zip(run.truth.iter().skip(gap)) {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&relative(&a.1, &b.1));
        let _ = writeln!(text, "{:.3} {:.3} {x:.6} {y:.6} 0 0 0 {t:.6}", a.0, b.0);
    }
    text
}

#[test]
fn a_log_in_arrival_order_maps_as_its_sorted_twin_with_a_pose_for_every_scan() {
    let dir = tempfile::tempdir().unwrap();
    let run = office_run();
    let lines = arrival_order_lines(&run);
    let mut sorted = lines.clone();
    let stamp = |l: &str| -> f64 {
        if l.starts_with("PARAM") { -1.0 } else { l.split_whitespace().rev().nth(2).unwrap().parse().unwrap() }
    };
    sorted.sort_by(|a, b| stamp(a).total_cmp(&stamp(b)));
    assert_ne!(lines, sorted, "the arrival order must differ from the stamp order");
    let rel = dir.path().join("office.relations");
    std::fs::write(&rel, true_relations(&run, 10)).unwrap();
    let mut trajectories = Vec::new();
    for (name, lines) in [("arrival.clf", &lines), ("sorted.clf", &sorted)] {
        let log = write_log(dir.path(), name, lines);
        let o = mrslam(&["log", "info", log.to_str().unwrap()]);
        let info = text(&o.stdout);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(info.contains("ODOM lines interpolated at every scan's stamp (240 scans)"), "{info}");
        assert!(info.contains("scan rate: 10.00 Hz") && info.contains("667 beams spanning 240.0 deg"), "{info}");
        if name == "arrival.clf" {
            assert!(info.contains("80 stamps out of order (max 0.05 s back"), "{info}");
        } else {
            assert!(info.contains("stamps in order"), "{info}");
        }
        let traj = dir.path().join(format!("{name}.txt"));
        let (out, s) = slam_scored(&log, &rel, &["--trajectory", traj.to_str().unwrap()]);
        assert!(out.contains("relations: 230 used, 0 missing"), "{out}");
        let header = std::fs::read_to_string(&traj).unwrap();
        assert!(header.starts_with("# mrslam slam ") && header.contains("one pose per scan (240 scans)"), "{header}");
        assert_eq!((s["scans"].as_u64(), s["metric"]["used"].as_u64()), (Some(240), Some(230)), "{s}");
        assert!(s["processed"].as_u64().unwrap() < 100, "updates every 0.25 m: {s}");
        assert!(
            s["real_time_factor"].as_f64().unwrap() > 0.0 && s["metric"]["translation_mean_m"].as_f64().unwrap() < 0.05,
            "{s}"
        );
        trajectories.push(poses_of(&traj));
    }
    assert_eq!(trajectories[0].len(), 240);
    assert_eq!(trajectories[0], trajectories[1], "the same log in another line order gave another trajectory");
}

#[test]
fn a_robotlaser1_log_maps_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let run = office_run();
    let lidar = Lidar::hokuyo();
    let inc = lidar.fov / (lidar.beams - 1) as f64;
    let lines: Vec<String> = run
        .odometry
        .iter()
        .zip(&run.scans)
        .map(|(o, s)| {
            let Xyt { x, y, theta: t } = Xyt::from_pose(&o.pose);
            let mut l = format!(
                "ROBOTLASER1 0 {:.6} {:.6} {inc:.8} {} 0.01 0 {}",
                -lidar.fov / 2.0,
                lidar.fov,
                lidar.range_max,
                s.ranges.len()
            );
            for r in &s.ranges {
                let _ = write!(l, " {r:.3}");
            }
            // No remissions; the laser sits on the robot's centre.
            let _ = write!(
                l,
                " 0 {x:.6} {y:.6} {t:.6} {x:.6} {y:.6} {t:.6} 0 0 0.5 0.5 0 {:.3} synthetic {:.3}",
                o.stamp, o.stamp
            );
            l
        })
        .collect();
    let log = write_log(dir.path(), "robot.clf", &lines);
    let rel = dir.path().join("robot.relations");
    std::fs::write(&rel, true_relations(&run, 20)).unwrap();
    let (out, s) = slam_scored(&log, &rel, &[]);
    assert!(out.contains("the scan lines' own odometry fields (240 scans)"), "{out}");
    let m = &s["metric"];
    assert_eq!(m["used"].as_u64(), Some(220), "{s}");
    // Odometry drifts 3 % of 1 m and 0.01 rad per metre on these relations: SLAM must be well under that.
    assert!(m["translation_mean_m"].as_f64().unwrap() < 0.03 && m["rotation_mean_deg"].as_f64().unwrap() < 1.0, "{m}");
}

#[test]
fn a_recorded_run_holds_the_filter_as_it_went_and_the_relations_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = office_run();
    let log = write_log(d, "office.clf", &carmen_lines(&run));
    let rel = d.join("office.relations");
    std::fs::write(&rel, true_relations(&run, 10)).unwrap();
    let (map, summary, rrd) = (d.join("office.yaml"), d.join("office.json"), d.join("office.rrd"));
    let p = |p: &Path| p.to_str().unwrap().to_string();
    let o = mrslam(&[
        "slam",
        &p(&log),
        "-o",
        &p(&map),
        "--relations",
        &p(&rel),
        "--summary",
        &p(&summary),
        "--rrd",
        &p(&rrd),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("rerun: file"), "{}", text(&o.stdout));
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    let (processed, resamples) = (s["processed"].as_u64().unwrap() as usize, s["resamples"].as_u64().unwrap() as usize);
    assert!(processed > 10, "{s}");

    let r = mrslam_viz::inspect::summarize(&rrd).unwrap();
    assert_eq!(r.recordings, ["slam-office-matched-seed0"]);
    assert_eq!(r.footer_manifests.len(), 2, "a standard recording, footer and all: {r:?}");
    assert_eq!(r.timelines.iter().map(String::as_str).collect::<Vec<_>>(), ["sim_time", "step"]);
    // Rows logged over time (a series' static style left out).
    let rows = |e: &str| r.rows_at(e) - r.static_rows.get(e).copied().unwrap_or(0);
    // Every processed scan: the best pose, all particles, the scan, Neff and the real-time factor.
    for e in [
        "/robots/office/slam/pose",
        "/robots/office/slam/particles",
        "/robots/office/scan",
        "/metrics/neff/office",
        "/metrics/realtime/office",
    ] {
        assert_eq!(rows(e), processed, "{e}: {:?}", r.rows);
    }
    // Every reading's odometry (the filter has one from the first reading on).
    assert_eq!(rows("/robots/office/odom/pose"), 240, "{:?}", r.rows);
    // Throttled: paths at most every 2 s of the 24 s log, maps every 10 s, each plus the final one.
    let log_s = 23.9;
    for leaf in ["slam/path", "odom/path"] {
        let n = rows(&format!("/robots/office/{leaf}")) as f64;
        assert!(n >= 3.0 && n <= log_s / 2.0 + 2.0, "{leaf}: {n} rows");
    }
    let maps = rows("/maps/office") as f64;
    assert!((3.0..=log_s / 10.0 + 2.0).contains(&maps), "{maps} maps");
    // The relations: one value per relation scored, and their marks on the path.
    assert_eq!(rows("/metrics/relations/office/translation"), 230);
    assert_eq!(rows("/metrics/relations/office/rotation"), 230);
    assert_eq!(rows("/robots/office/relations"), 1);
    // Events: each resampling, each re-anchoring on the loop-closed graph (drawn with the loop edges and the
    // corrected path), and the loop closure's verdict (the matched preset closes loops while it drives).
    let reanchors = s["loop_closure"]["reanchors"].as_u64().unwrap() as usize;
    assert_eq!(rows("/events"), resamples + reanchors + 1, "{:?}", r.rows);
    assert_eq!(rows("/robots/office/slam/loop_edges"), reanchors, "{:?}", r.rows);
    assert!(r.blueprint_entities.contains("/viewport"), "{:?}", r.blueprint_entities);

    // A destination that cannot be written fails before the filter runs, and leaves no map.
    let bad = d.join("missing/run.rrd");
    let map2 = d.join("again.yaml");
    let o = mrslam(&["slam", &p(&log), "-o", &p(&map2), "--rrd", &p(&bad), "--quiet"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains(&p(&bad)) && text(&o.stderr).contains("does not exist"), "{}", text(&o.stderr));
    assert!(!map2.exists(), "the run went ahead");
    let o = mrslam(&["slam", &p(&log), "-o", &p(&map2), "--rrd", &p(&d.join("run.txt")), "--quiet"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("--rrd"), "{}", text(&o.stderr));
}

#[test]
fn a_log_whose_odometry_is_stamped_in_bursts_maps_on_the_scans_own_odometry() {
    let dir = tempfile::tempdir().unwrap();
    let run = office_run();
    // Each scan line carries its odometry; the ODOM lines come four at a time, stamped within a millisecond of the
    // burst's last scan (a logger that stamps on arrival what it buffered).
    let own = carmen_lines(&run);
    let mut lines = own[..2].to_vec();
    for (group, scans) in own[2..].chunks(4).enumerate() {
        let last = &run.odometry[(4 * group + scans.len() - 1).min(run.odometry.len() - 1)];
        for (j, o) in run.odometry[4 * group..4 * group + scans.len()].iter().enumerate() {
            let Xyt { x, y, theta: t } = Xyt::from_pose(&o.pose);
            let stamp = last.stamp + 1e-4 * j as f64;
            lines.push(format!("ODOM {x:.6} {y:.6} {t:.6} 0 0 0 {stamp:.4} synthetic {stamp:.4}"));
        }
        lines.extend_from_slice(scans);
    }
    let log = write_log(dir.path(), "bursts.clf", &lines);
    let info = mrslam(&["log", "info", log.to_str().unwrap()]);
    let info = text(&info.stdout);
    assert!(info.contains("the scan lines' own odometry fields (240 scans)"), "{info}");
    assert!(info.contains("stamped in bursts (180 of its increments faster than 5 m/s"), "{info}");
    let rel = dir.path().join("office.relations");
    std::fs::write(&rel, true_relations(&run, 10)).unwrap();
    let mut trajectories = Vec::new();
    for extra in [&[][..], &["--odometry", "line"][..]] {
        let traj = dir.path().join(format!("bursts{}.txt", extra.len()));
        let mut args = vec!["--trajectory", traj.to_str().unwrap()];
        args.extend_from_slice(extra);
        let (out, s) = slam_scored(&log, &rel, &args);
        assert!(s["metric"]["translation_mean_m"].as_f64().unwrap() < 0.05, "{out}");
        assert_eq!(s["repairs"]["odometry_stamped_in_bursts"].as_bool(), Some(true), "{s}");
        assert_eq!(s["repairs"]["line_odometry"].as_u64(), Some(240), "{s}");
        trajectories.push(poses_of(&traj));
    }
    assert_eq!(trajectories[0], trajectories[1], "read as stamped in bursts, the log maps as on its scan lines");
}

/// The office lap and 8 m more, SICK scans, odometry true but for a turn of `kink` rad, which it reports three
/// quarters round the lap and the robot never made.
fn kinked_lap(kink: f64) -> Vec<String> {
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let mut run =
        synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), Pose2::identity(), &Drift::none(), 5);
    let at = 3 * run.odometry.len() / 4;
    let turn = mrslam_core::pose(0.0, 0.0, kink);
    let from = run.odometry[at].pose;
    for o in &mut run.odometry[at..] {
        // The rest of the path as the odometry saw it, turned about where the kink happened.
        o.pose = from * turn * from.inverse() * o.pose;
    }
    carmen_lines_of(&run, &Lidar::sick())
}

#[test]
fn a_map_that_puts_places_on_top_of_each_other_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Neither the scan-matched odometry nor the filter may take the turn back, and no loop edge is kept.
    let hold = ["--set", "scan_odometry=false", "--set", "loop_min_score=1", "--quiet"];
    let run = |name: &str, kink: f64| {
        let log = write_log(d, &format!("{name}.clf"), &kinked_lap(kink));
        let (map, summary) = (d.join(format!("{name}.yaml")), d.join(format!("{name}.json")));
        let mut args = vec!["slam", log.to_str().unwrap(), "-o", map.to_str().unwrap()];
        args.extend(["--summary", summary.to_str().unwrap()]);
        args.extend(hold);
        let o = mrslam(&args);
        assert!(o.status.success(), "stderr: {}", text(&o.stderr));
        let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
        (text(&o.stdout), s["loop_closure"].clone())
    };
    let (out, loops) = run("straight", 0.0);
    assert!(!out.contains("see walls where the map has open floor"), "{out}");
    assert!(loops["judged"].as_u64().unwrap() >= 10 && loops["contradicts_itself"] == false, "{loops}");
    // Turned 0.6 rad, the lap's end comes back beside its start, not onto it: no revisit long enough to count as
    // a loop left open, but the scans there see walls across the start's corridor.
    let (out, loops) = run("kinked", -0.6);
    assert!(out.contains("warning: ") && out.contains("see walls where the map has open floor"), "{out}");
    assert!(loops["contradicts_itself"] == true && loops["open_loops"] == 0, "{loops}");
}
