//! `mrslam sim replay LOG --world WORLD.toml`: the simulator's lidar checked against a real log's scans;
//! `mrslam sim log` (in `sim_log`) writes a simulated run as a log.

use super::replay_plot;
use anyhow::{Context, Result, bail};
use clap::Subcommand;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_core::Pose2;
use mrslam_core::relations::{self, pose_at};
use mrslam_log::ScanRecord;
use mrslam_sim::odometry_errors::{OdometryErrors, drive_along, odometry_errors};
use mrslam_sim::odometry_fit::{fit, worst_relative};
use mrslam_sim::replay::{BandStats, OUTLIER_M, ReplayReport, replay};
use mrslam_sim::{LidarModel, World, WorldSpec};
use mrslam_testbed::scenario::Scenario;
use serde_json::json;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Most parameter sets one `--fit-odometry` tries per robot.
const FIT_EVALUATIONS: usize = 150;
/// Drives (seeds `--seed`, `--seed` + 1, ...) whose errors are averaged for each parameter set: one drive's
/// scale error per metre moves by about 0.002 from seed to seed on FR079, half the real value.
const FIT_SEEDS: u64 = 4;

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
        /// With --scenario: fit each scenario robot's encoder calibration and wheel slip to the log's odometry
        /// errors (`mrslam_sim::odometry_fit`) and print them with the errors they give.
        #[arg(long)]
        fit_odometry: bool,
        /// Hide the progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Write a simulated run as benchmark data: per robot a CARMEN log, its true trajectory and the relations
    /// the truth implies (Kümmerle's format), to score any SLAM on the testbed's worlds.
    Log(super::sim_log::LogArgs),
}

/// Runs a sim subcommand.
pub fn run(cmd: SimCommand) -> Result<ExitCode> {
    match cmd {
        SimCommand::Log(args) => return super::sim_log::run(args),
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
            fit_odometry,
            quiet,
        } => {
            if !(segment_m > 0.0 && segment_rad > 0.0 && segment_m.is_finite() && segment_rad.is_finite()) {
                bail!("--segment-m {segment_m} / --segment-rad {segment_rad}: must be positive");
            }
            if fit_odometry && scenario.is_none() {
                bail!("--fit-odometry: needs --scenario (the robots whose odometry is fitted)");
            }
            if scenario.is_some() && trajectory.is_none() {
                bail!("--scenario: needs --trajectory (the true path the simulated robots drive)");
            }
            let inputs: Vec<&Path> =
                [Some(log.as_path()), Some(world.as_path()), trajectory.as_deref(), scenario.as_deref()]
                    .into_iter()
                    .flatten()
                    .collect();
            // The report and the pictures beside it: R.residuals.png, and R.odometry.png with a trajectory.
            let plots = report.as_deref().map(|r| {
                (
                    replay_plot::plot_path(r, "residuals"),
                    trajectory.as_ref().map(|_| replay_plot::plot_path(r, "odometry")),
                )
            });
            if let (Some(r), Some((res, odo))) = (&report, &plots) {
                super::Outputs::reading(inputs.iter().copied())
                    .file("--report", r, super::kind::JSON)
                    .file("--report (its residuals plot)", res, super::kind::PNG)
                    .maybe("--report (its odometry plot)", odo.as_deref(), super::kind::PNG)
                    .check()?;
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
                        None => r.logged_laser_pose.map(|p| p * r.laser_offset.inverse()),
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
            let bar = ProgressBar::new(scans.len() as u64);
            if quiet || !std::io::stderr().is_terminal() {
                bar.set_draw_target(ProgressDrawTarget::hidden());
            }
            bar.set_style(
                ProgressStyle::with_template("replay [{bar:40}] {pos}/{len} scans, {elapsed} elapsed, ETA {eta}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            let noise = (model.range_noise_const, model.range_noise_prop);
            let r = replay(&w, &mount, scans.iter().copied().inspect(|_| bar.inc(1)), noise, seed);
            bar.finish_and_clear();
            print!("{}", describe(&r, unplaced, &lidar));
            // Odometry: the log's against the trajectory, and each scenario robot's driven along it.
            let mut odometry = Vec::new();
            let mut paths: Vec<(String, Vec<Pose2>)> = Vec::new();
            if traj.is_some() {
                let truth: Vec<Pose2> = placed.iter().map(|(p, _)| *p).collect();
                let odom: Vec<Pose2> = placed.iter().map(|(_, r)| r.odometry.pose).collect();
                odometry.push(("log".to_string(), odometry_errors(&truth, &odom, segment_m, segment_rad)));
                paths.push(("reference (trajectory)".into(), truth.clone()));
                paths.push(("log odometry".into(), replay_plot::placed_at(&truth[0], &odom)));
                let stamped: Vec<(f64, Pose2)> = placed.iter().map(|(p, r)| (r.scan.stamp, *p)).collect();
                for robot in setup.iter().flat_map(|s| &s.robots) {
                    let (t, o) = drive_along(robot.model.clone(), robot.slip, robot.encoder, &stamped, seed)
                        .with_context(|| format!("driving {} along the trajectory", robot.name))?;
                    odometry
                        .push((format!("simulated {}", robot.name), odometry_errors(&t, &o, segment_m, segment_rad)));
                    let on_reference = replay_plot::error_on_reference(&truth, &t, &o);
                    paths.push((
                        format!("simulated {} odometry (its error on the reference)", robot.name),
                        on_reference,
                    ));
                }
                print!("{}", describe_odometry(&odometry));
                if fit_odometry {
                    let real = odometry[0].1;
                    let fit_seeds: Vec<u64> = (0..FIT_SEEDS).map(|k| seed.wrapping_add(k)).collect();
                    let mut done: Vec<(&mrslam_testbed::scenario::RobotSetup, mrslam_sim::odometry_fit::Fitted)> =
                        Vec::new();
                    for robot in setup.iter().flat_map(|s| &s.robots) {
                        // Robots of the same model, slip and encoder share one fit.
                        let same = |r: &&mrslam_testbed::scenario::RobotSetup| {
                            r.model == robot.model && r.slip == robot.slip && r.encoder == robot.encoder
                        };
                        if let Some((_, f)) = done.iter().find(|(r, _)| same(r)) {
                            odometry.push((format!("fitted {} (mean)", robot.name), f.errors));
                            continue;
                        }
                        let f = fit(
                            &robot.model,
                            (robot.slip, robot.encoder),
                            &stamped,
                            &real,
                            (segment_m, segment_rad),
                            &fit_seeds,
                            FIT_EVALUATIONS,
                        )
                        .with_context(|| format!("fitting {}'s odometry", robot.name))?;
                        println!(
                            "fitted {} ({} parameter sets x {FIT_SEEDS} seeds, loss {:.4}, worst relative difference {:.3}): encoder = {{ \
                             left_radius_error = {:.5}, right_radius_error = {:.5}, wheel_base_error = {:.4} }}, \
                             slip = {{ speed_noise = {:.4}, turn_noise = {:.4} }}",
                            robot.name,
                            f.evaluations,
                            f.loss,
                            worst_relative(&f.errors, &real),
                            f.encoder.left_radius_error,
                            f.encoder.right_radius_error,
                            f.encoder.wheel_base_error,
                            f.slip.speed_noise,
                            f.slip.turn_noise
                        );
                        odometry.push((format!("fitted {} (mean)", robot.name), f.errors));
                        done.push((robot, f));
                    }
                    print!("{}", describe_odometry(&odometry));
                }
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
                if let Some((res, odo)) = &plots {
                    replay_plot::residuals(&r, &lidar, res)?;
                    if let Some(odo) = odo {
                        replay_plot::odometry(&paths, odo)?;
                    }
                }
                // The report last: its presence says the pictures beside it are complete.
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
