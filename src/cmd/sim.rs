//! `mrslam sim replay LOG --world WORLD.toml`: the simulator's lidar checked against a real log's scans.

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use mrslam_core::Pose2;
use mrslam_core::ScanRecord;
use mrslam_core::relations::{self, pose_at};
use mrslam_sim::odometry_errors::{OdometryErrors, drive_along, odometry_errors};
use mrslam_sim::replay::{BandStats, OUTLIER_M, ReplayReport, replay};
use mrslam_sim::{LidarModel, World, WorldSpec};
use mrslam_testbed::scenario::Scenario;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Simulator subcommands.
#[derive(Subcommand)]
pub enum SimCommand {
    /// Replay a log in a world: simulate each real scan from its pose, noiseless, and compare beam by beam
    /// (residuals by range and by incidence angle, missing and extra returns, outliers), then fit the noise a
    /// lidar model needs and compare its residuals with the real ones (two-sample Kolmogorov-Smirnov).
    Replay {
        /// CARMEN log.
        log: PathBuf,
        /// World file whose frame is the poses' frame (e.g. `mrslam world from-map` of a map of this log).
        #[arg(long)]
        world: PathBuf,
        /// The robot's pose at each scan from this trajectory (`stamp x y theta`, e.g. `mrslam slam
        /// --trajectory` with the map the world was made from); without it, the log's own laser poses (a
        /// corrected log's are scan-matched).
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// A trajectory pose belongs to a scan within this many seconds.
        #[arg(long, default_value_t = 0.001)]
        tolerance: f64,
        /// The lidar model whose noise the real residuals are compared with.
        #[arg(long, default_value = "hokuyo_urg_04lx", value_parser = LidarModel::PRESETS)]
        lidar: String,
        /// Write the report (JSON) here.
        #[arg(long)]
        report: Option<PathBuf>,
        /// How to read the log.
        #[command(flatten)]
        read: super::log::ReadArgs,
        /// With --trajectory: also drive each robot of this scenario along the trajectory in the simulator and
        /// compare its odometry errors (per metre, per radian) with the log's odometry against the trajectory.
        #[arg(long, value_name = "SCENARIO.toml")]
        scenario: Option<PathBuf>,
        /// Odometry errors are measured over segments of this many metres driven (or --segment-rad turned).
        #[arg(long, default_value_t = mrslam_sim::odometry_errors::SEGMENT_M)]
        segment_m: f64,
        /// ... or this many radians turned, whichever comes first.
        #[arg(long, default_value_t = mrslam_sim::odometry_errors::SEGMENT_RAD)]
        segment_rad: f64,
        /// Seed of the model residuals drawn for the comparison, and of the simulated drives.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
}

/// Runs a sim subcommand.
pub fn run(cmd: SimCommand) -> Result<ExitCode> {
    match cmd {
        SimCommand::Replay {
            log,
            world,
            trajectory,
            tolerance,
            lidar,
            report,
            read,
            scenario,
            segment_m,
            segment_rad,
            seed,
        } => {
            if !(segment_m > 0.0 && segment_rad > 0.0 && segment_m.is_finite() && segment_rad.is_finite()) {
                bail!("--segment-m {segment_m} / --segment-rad {segment_rad}: must be positive");
            }
            if scenario.is_some() && trajectory.is_none() {
                bail!("--scenario: needs --trajectory (the true path the simulated robots drive)");
            }
            let inputs: Vec<&Path> =
                [Some(log.as_path()), Some(world.as_path()), trajectory.as_deref(), scenario.as_deref()]
                    .into_iter()
                    .flatten()
                    .collect();
            if let Some(r) = &report {
                super::paths::check_extension(r, "--report", &["json"])?;
                super::paths::check_outputs(&[r.as_path()], &inputs)?;
            }
            if !(tolerance.is_finite() && tolerance >= 0.0) {
                bail!("--tolerance {tolerance}: must be a non-negative number of seconds");
            }
            let setup = scenario.as_deref().map(Scenario::from_file).transpose()?;
            let spec = WorldSpec::from_toml_file(&world)?;
            let w = World::from_spec(&spec).with_context(|| format!("{}", world.display()))?;
            let traj = trajectory.as_deref().map(relations::read_trajectory).transpose()?;
            let parsed = read.read(&log)?;
            if parsed.scans.is_empty() {
                bail!("{}: no laser scans in the log", log.display());
            }
            let mount = parsed.scans[0].laser_offset;
            // The robot's pose at each scan: from the trajectory, or the logged laser pose less the mount.
            let mut unplaced = 0;
            let placed: Vec<(Pose2, &ScanRecord)> = parsed
                .scans
                .iter()
                .filter_map(|r| {
                    let pose = match &traj {
                        Some(t) => pose_at(t, r.scan.stamp, tolerance),
                        None => Some(r.logged_laser_pose * r.laser_offset.inverse()),
                    };
                    if pose.is_none() {
                        unplaced += 1;
                    }
                    pose.map(|p| (p, r))
                })
                .collect();
            let scans: Vec<(Pose2, &mrslam_core::LaserScan)> = placed.iter().map(|(p, r)| (*p, &r.scan)).collect();
            if scans.is_empty() {
                bail!(
                    "{}: no scan has a pose in {} within {tolerance} s",
                    log.display(),
                    trajectory.as_deref().map_or("the log".into(), |p| p.display().to_string())
                );
            }
            let model = LidarModel::preset(&lidar).context("a lidar preset that clap let through")?;
            let r = replay(&w, &mount, scans.iter().copied(), (model.range_noise_const, model.range_noise_prop), seed);
            print!("{}", describe(&r, unplaced, &lidar));
            // Odometry: the log's against the trajectory, and each scenario robot's driven along it.
            let mut odometry = Vec::new();
            if traj.is_some() {
                let truth: Vec<Pose2> = placed.iter().map(|(p, _)| *p).collect();
                let odom: Vec<Pose2> = placed.iter().map(|(_, r)| r.odometry.pose).collect();
                odometry.push(("log".to_string(), odometry_errors(&truth, &odom, segment_m, segment_rad)));
                let stamped: Vec<(f64, Pose2)> = placed.iter().map(|(p, r)| (r.scan.stamp, *p)).collect();
                for robot in setup.iter().flat_map(|s| &s.robots) {
                    let (t, o) = drive_along(robot.model.clone(), robot.slip, robot.encoder, &stamped, seed)
                        .with_context(|| format!("driving {} along the trajectory", robot.name))?;
                    odometry
                        .push((format!("simulated {}", robot.name), odometry_errors(&t, &o, segment_m, segment_rad)));
                }
                print!("{}", describe_odometry(&odometry));
            }
            if let Some(path) = &report {
                let value = json!({
                    "log": log.display().to_string(),
                    "world": world.display().to_string(),
                    "trajectory": trajectory.as_ref().map(|p| p.display().to_string()),
                    "lidar_model": lidar,
                    "model_noise": { "const_m": model.range_noise_const, "prop": model.range_noise_prop },
                    "outlier_m": OUTLIER_M,
                    "odometry_segments": { "metres": segment_m, "radians": segment_rad },
                    "scans_without_pose": unplaced,
                    "replay": r,
                    "odometry": odometry.iter().map(|(n, e)| json!({ "source": n, "errors": e })).collect::<Vec<_>>(),
                });
                super::eval::write_json(path, &value)?;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn describe_odometry(rows: &[(String, OdometryErrors)]) -> String {
    let mut s = format!(
        "{:<22} {:>8} {:>8} {:>26} {:>26} {:>26}\n",
        "odometry",
        "metres",
        "radians",
        "scale /m mean±std (n)",
        "heading rad/m mean±std (n)",
        "heading /rad mean±std (n)"
    );
    for (name, e) in rows {
        let f = |x: &mrslam_sim::odometry_errors::Spread| format!("{:+.4} ± {:.4} ({})", x.mean, x.std, x.segments);
        s += &format!(
            "{name:<22} {:>8.1} {:>8.1} {:>26} {:>26} {:>26}\n",
            e.metres,
            e.radians,
            f(&e.scale_per_m),
            f(&e.heading_per_m),
            f(&e.heading_per_rad)
        );
    }
    s
}

fn describe(r: &ReplayReport, unplaced: usize, lidar: &str) -> String {
    let pct = |n: usize| 100.0 * n as f64 / r.beams.max(1) as f64;
    let mut s = format!(
        "replay: {} scans ({unplaced} without a pose), {} beams: both returned {:.1} %, the real scan missed a \
         surface {:.1} %, the real scan saw one the world lacks {:.1} %, neither {:.1} %\n",
        r.scans,
        r.beams,
        pct(r.both),
        pct(r.real_missing),
        pct(r.real_extra),
        pct(r.neither)
    );
    let ks = |v: Option<f64>| v.map_or("-".to_string(), |d| format!("{d:.3}"));
    let table = |title: &str, unit: &str, bands: &[BandStats]| {
        let mut t = format!(
            "{title:<16} {:>8} {:>8} {:>9} {:>9} {:>8} {:>8}\n",
            "beams", "outliers", "median m", "sigma m", "KS fit", "KS model"
        );
        for b in bands {
            let band =
                if b.to.is_finite() { format!("{}-{} {unit}", b.from, b.to) } else { format!(">= {} {unit}", b.from) };
            t += &format!(
                "{band:<16} {:>8} {:>8} {:>+9.4} {:>9.4} {:>8} {:>8}\n",
                b.beams,
                b.outliers,
                b.median_m,
                b.sigma_m,
                ks(b.ks_fitted),
                ks(b.ks_model)
            );
        }
        t
    };
    s += &table("range", "m", &r.by_range);
    s += &table("incidence", "deg", &r.by_incidence);
    s += &format!(
        "fitted noise: sigma = {:.4} m + {:.4} x range (the {lidar} model: the KS column compares with its noise)\n",
        r.fitted_noise_const_m, r.fitted_noise_prop
    );
    s
}
