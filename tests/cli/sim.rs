//! `mrslam sim replay`: a log the simulator wrote itself, with a noiseless lidar, replays in its own world with
//! no residual; the report says so; bad inputs are refused.

use crate::util::{mrslam, p, text};
use mrslam_core::Xyt;
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, Sim, SimConfig, SlipParams, WorldSpec};
use std::fmt::Write as _;
use std::path::Path;

const ROOM: &str = r#"
name = "replay room"
[[walls]]
points = [[0, 0], [8, 0], [8, 5], [0, 5], [0, 0]]
[[boxes]]
center = [5, 3]
size = [1.0, 0.6]
angle = 0.4
[[circles]]
center = [2, 1.5]
radius = 0.3
"#;

/// Drives a robot with a noiseless Hokuyo round the room and writes its scans as a CARMEN log: the laser's true
/// pose in the FLASER line's laser pose fields, the robot's in its odometry fields, the lidar's geometry in PARAM
/// lines; and the true trajectory (`stamp x y theta`) to `trajectory`.
fn simulated_log(world: &Path, log: &Path, trajectory: &Path) {
    let spec = WorldSpec::from_toml_file(world).unwrap();
    let mut sim = Sim::with_config(&spec, 1, SimConfig::default()).unwrap();
    let mut lidar = LidarModel::hokuyo_urg_04lx().noiseless();
    lidar.skew = false;
    let (mount, fov, max) = (lidar.mount, (lidar.beam_count() - 1) as f64 * lidar.resolution, lidar.range_max);
    let start = mrslam_core::pose(1.0, 3.5, -0.3);
    let id = sim
        .add_robot("r", RobotModel::experia(), lidar, SlipParams::default(), EncoderParams::default(), start)
        .unwrap();
    sim.set_velocity_command(id, 0.3, 0.2).unwrap();
    let mut traj = String::new();
    let mount_x = mount.translation.x;
    assert!(mount.translation.y == 0.0 && mount.rotation.angle() == 0.0, "the log says only the mount's x");
    let mut text = format!(
        "PARAM laser_front_laser_fov {}\nPARAM robot_front_laser_max {max}\nPARAM robot_frontlaser_offset {mount_x}\n",
        fov.to_degrees()
    );
    for step in 0..400 {
        sim.step();
        if step % 40 != 0 {
            continue;
        }
        let scan = sim.scan_now(id).unwrap();
        let robot = sim.true_pose(id).unwrap();
        let Xyt { x, y, theta } = Xyt::from_pose(&(robot * mount));
        let Xyt { x: ox, y: oy, theta: ot } = Xyt::from_pose(&robot);
        let _ = write!(text, "FLASER {}", scan.len());
        for r in &scan.ranges {
            let r = if r.is_finite() { *r as f64 } else { max };
            let _ = write!(text, " {r:.5}");
        }
        let t = sim.time();
        let _ = writeln!(text, " {x:.6} {y:.6} {theta:.6} {ox:.6} {oy:.6} {ot:.6} {t:.3} sim {t:.3}");
        let _ = writeln!(traj, "{t:.3} {ox:.6} {oy:.6} {ot:.6}");
    }
    std::fs::write(log, text).unwrap();
    std::fs::write(trajectory, traj).unwrap();
}

#[test]
fn the_simulators_own_log_replays_in_its_world_with_no_residual() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (world, log, report) = (d.join("room.toml"), d.join("room.clf"), d.join("replay.json"));
    std::fs::write(&world, ROOM).unwrap();
    let truth = d.join("truth.txt");
    simulated_log(&world, &log, &truth);
    let o = mrslam(&["sim", "replay", p(&log), "--world", p(&world), "--report", p(&report)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("replay: 10 scans"), "{}", text(&o.stdout));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let replay = &r["replay"];
    // Only the log's 5-decimal rounding stands between the two.
    assert!(replay["max_abs_residual_m"].as_f64().unwrap() < 1e-4, "{replay}");
    assert_eq!((replay["real_missing"].as_u64(), replay["real_extra"].as_u64()), (Some(0), Some(0)), "{replay}");
    assert!(replay["both"].as_u64().unwrap() > replay["beams"].as_u64().unwrap() / 2, "{replay}");
    assert!(replay["fitted_noise_const_m"].as_f64().unwrap() < 1e-4, "{replay}");
    // The residual histograms beside the report; no odometry picture without a trajectory.
    assert_png(&d.join("replay.residuals.png"), (1500, 900));
    assert!(!d.join("replay.odometry.png").exists());

    // With the true trajectory: the same residuals, the log's odometry (the truth itself) without error, and the
    // scenario's robots driven along it with theirs.
    let scenario = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/paper_two_rooms.toml");
    let o = mrslam(&[
        "sim",
        "replay",
        p(&log),
        "--world",
        p(&world),
        "--trajectory",
        p(&truth),
        "--scenario",
        p(&scenario),
        "--report",
        p(&report),
        "--segment-m",
        "0.25",
        "--segment-rad",
        "0.25",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(r["replay"]["max_abs_residual_m"].as_f64().unwrap() < 1e-4, "{r}");
    let odometry = r["odometry"].as_array().unwrap();
    let sources: Vec<&str> = odometry.iter().map(|o| o["source"].as_str().unwrap()).collect();
    assert_eq!(sources, ["log", "simulated experia", "simulated prawn"]);
    let log_errors = &odometry[0]["errors"];
    assert!(log_errors["metres"].as_f64().unwrap() > 0.5, "{log_errors}");
    assert!(log_errors["translation_per_m"]["segments"].as_u64().unwrap() >= 3, "{log_errors}");
    assert!(log_errors["translation_per_m"]["rms"].as_f64().unwrap() < 1e-4, "{log_errors}");
    assert!(log_errors["scale_per_m"]["rms"].as_f64().unwrap() < 1e-4, "{log_errors}");
    assert_png(&d.join("replay.residuals.png"), (1500, 900));
    assert_png(&d.join("replay.odometry.png"), (1100, 1000));
    // Each band's histogram holds its inliers.
    let band = &r["replay"]["by_range"][1];
    let counted: u64 = band["histogram"]["real"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum();
    assert_eq!(counted, band["beams"].as_u64().unwrap() - band["outliers"].as_u64().unwrap(), "{band}");

    // A trajectory without the log's stamps: refused, saying so.
    let traj = d.join("t.txt");
    std::fs::write(&traj, "1000.0 0 0 0\n").unwrap();
    let o = mrslam(&["sim", "replay", p(&log), "--world", p(&world), "--trajectory", p(&traj)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("no scan has a pose"), "{}", text(&o.stderr));
    // A report that would overwrite the world: refused.
    let o = mrslam(&["sim", "replay", p(&log), "--world", p(&world), "--report", p(&world)]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&world).unwrap(), ROOM);
    // A report whose picture would overwrite an input (here the trajectory): refused, the input untouched.
    let named = d.join("t.residuals.png");
    std::fs::copy(&truth, &named).unwrap();
    let before = std::fs::read(&named).unwrap();
    let o = mrslam(&[
        "sim",
        "replay",
        p(&log),
        "--world",
        p(&world),
        "--trajectory",
        p(&named),
        "--report",
        p(&d.join("t.json")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert_eq!(std::fs::read(&named).unwrap(), before);
    assert!(!d.join("t.json").exists());
    // Fitting odometry needs the scenario's robots.
    let o = mrslam(&["sim", "replay", p(&log), "--world", p(&world), "--trajectory", p(&truth), "--fit-odometry"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--fit-odometry"), "{}", text(&o.stderr));
}

/// `path` is a PNG of `size` pixels with something drawn on it (a plot, not an empty canvas).
fn assert_png(path: &Path, size: (u32, u32)) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{} is not a PNG", path.display());
    assert!(bytes.len() > 10_000, "{}: only {} bytes", path.display(), bytes.len());
    let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), size);
    let drawn = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(drawn > 5_000, "{}: {drawn} pixels drawn", path.display());
}
