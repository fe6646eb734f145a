//! `mrslam sim log SCENARIO.toml --out DIR`: a simulated run written as benchmark data: per robot a CARMEN
//! log, its true trajectory and the relations the truth implies (Kümmerle's format), so any SLAM, ours or
//! another, can be scored on the testbed's worlds.

use super::outputs::{Outputs, kind};
use super::run_bag::RunBag;
use anyhow::{Context, Result, bail};
use clap::Args;
use mrslam_core::output::{AtomicFile, write_file_atomic};
use mrslam_core::relations::{StampedPose, format_relations, format_trajectory};
use mrslam_core::truth_relations::{TruthRelations, relations_from_truth};
use mrslam_core::{LaserScan, Odometry};
use mrslam_log::carmen_writer::CarmenWriter;
use mrslam_sim::LidarModel;
use mrslam_testbed::runner::{PoseHistory, RobotStep, RunOptions, pairing_time, run as run_scenario};
use mrslam_testbed::scenario::Scenario;
use serde_json::json;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `mrslam sim log`.
#[derive(Args)]
pub struct LogArgs {
    /// Scenario file (TOML): its robots drive as in `mrslam run` (no merge is made).
    pub scenario: PathBuf,
    /// Output folder: per robot NAME.clf (the log), NAME.truth (`stamp x y theta`, the robot's true pose at
    /// every scan, world frame), NAME.relations (relations drawn from the truth), and log.json (a summary).
    #[arg(long)]
    pub out: PathBuf,
    /// Override the scenario's seed.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Write no ODOM lines: the odometry is only in the scan lines, as in some benchmark logs.
    #[arg(long)]
    pub no_odom_lines: bool,
    /// Write each scan line's odometry fields as the odometry of this many seconds before the scan, as a logger
    /// that writes the last reading it had (0 to 1 s; the ODOM lines stay on time): a log to measure
    /// `slam`'s lag estimate on.
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    pub line_odometry_lag: f64,
    /// Loop relations join poses at most this far apart, metres (local ones every metre of driving).
    #[arg(long, default_value_t = TruthRelations::default().loop_radius)]
    pub loop_radius: f64,
    /// ... with at least this many metres of driving between them.
    #[arg(long, default_value_t = TruthRelations::default().loop_min_travel)]
    pub loop_min_travel: f64,
    /// Also write the run as a ROS 2 bag (one MCAP file, for `ros2 bag play`, Foxglove or another SLAM): per
    /// robot /NAME/scan, /NAME/odom, /NAME/ground_truth and /NAME/map (the robot's SLAM map), /tf, /tf_static
    /// and /truth_map.
    #[arg(long, value_name = "OUT.mcap")]
    pub mcap: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// One robot's log as it is written.
struct RobotLog {
    name: String,
    writer: CarmenWriter<AtomicFile>,
    truth: Vec<StampedPose>,
    beams: usize,
    range_max: f32,
    /// The robot's recent true and odometry poses.
    history: PoseHistory,
    /// The robot's lidar, for the instant each scan is paired with ([`pairing_time`]).
    lidar: LidarModel,
}

/// The files `mrslam sim log` writes for robot `name` in `dir`.
fn robot_files(dir: &Path, name: &str) -> [PathBuf; 3] {
    ["clf", "truth", "relations"].map(|ext| dir.join(format!("{name}.{ext}")))
}

/// Runs `mrslam sim log`.
pub fn run(args: LogArgs) -> Result<ExitCode> {
    let truth_params =
        TruthRelations { loop_radius: args.loop_radius, loop_min_travel: args.loop_min_travel, ..Default::default() };
    if !(truth_params.loop_radius > 0.0 && truth_params.loop_radius.is_finite()) {
        bail!("--loop-radius {}: must be a positive number of metres", args.loop_radius);
    }
    if !(truth_params.loop_min_travel >= 0.0 && truth_params.loop_min_travel.is_finite()) {
        bail!("--loop-min-travel {}: must be a number of metres, 0 or more", args.loop_min_travel);
    }
    if !(0.0..=1.0).contains(&args.line_odometry_lag) {
        bail!("--line-odometry-lag {}: must be a number of seconds from 0 to 1", args.line_odometry_lag);
    }
    let mut scenario = Scenario::from_file(&args.scenario)?;
    if let Some(s) = args.seed {
        scenario.seed = s;
    }
    super::paths::create_out_folder(&args.out)?;
    let summary_path = args.out.join("log.json");
    let mut outputs = vec![summary_path.clone()];
    for r in &scenario.robots {
        outputs.extend(robot_files(&args.out, &r.name));
    }
    let mut inputs = vec![args.scenario.clone(), scenario.world_path.clone()];
    inputs.extend(scenario.world.bitmap.as_ref().map(|b| b.map.clone()));
    outputs
        .iter()
        .fold(Outputs::reading(inputs.iter().map(PathBuf::as_path)), |rule, o| rule.file("sim log --out", o, kind::ANY))
        .maybe("--mcap", args.mcap.as_deref(), kind::MCAP)
        .check()?;
    let mut bag = args.mcap.as_deref().map(|p| RunBag::create(p, &scenario)).transpose()?;
    let mut logs = Vec::new();
    let mut temporary: Vec<PathBuf> = bag.iter().map(|b| b.temporary().to_path_buf()).collect();
    for r in &scenario.robots {
        let [clf, ..] = robot_files(&args.out, &r.name);
        let header = format!(
            "mrslam sim log: robot `{}` of scenario `{}` ({}), seed {}\ntrue trajectory: {}.truth; relations: {}.relations",
            r.name,
            scenario.name,
            args.scenario.display(),
            scenario.seed,
            r.name,
            r.name
        );
        let file = AtomicFile::create(&clf)?;
        temporary.push(file.temporary_path().to_path_buf());
        let writer = CarmenWriter::new(file, &header).with_context(|| clf.display().to_string())?;
        logs.push(RobotLog {
            name: r.name.clone(),
            writer,
            truth: Vec::new(),
            beams: 0,
            range_max: 0.0,
            history: PoseHistory::default(),
            lidar: r.lidar.clone(),
        });
    }
    // Ctrl-C (or SIGTERM, SIGHUP): the logs and the bag being written are hidden temporary files; they go.
    super::interrupt::on_interrupt(
        format!(
            "mrslam sim log: interrupted: the logs (and bag) being written into {} were removed",
            args.out.display()
        ),
        temporary,
    );
    let bar = super::sim_progress::bar(&scenario.name, scenario.duration, args.quiet);
    let mut write_error: Option<anyhow::Error> = None;
    let odom_lines = !args.no_odom_lines;
    let line_lag = args.line_odometry_lag;
    let tap = |s: &RobotStep<'_>| {
        let log = &mut logs[s.robot];
        log.history.push(s.time, *s.true_pose, s.odometry.pose);
        // A scan was taken from its stamp on, up to a scan period before this step's end; a sweeping lidar's is
        // stamped at its middle beam (a log line has no time per beam, and the bag says none), as the testbed's
        // runs pair it: in the log and the bag alike, so both map as the truth is drawn.
        let restamped: Vec<Cow<'_, LaserScan>> = s
            .scans
            .iter()
            .map(|&scan| match pairing_time(&log.lidar, scan) {
                t if t == scan.stamp => Cow::Borrowed(scan),
                t => Cow::Owned(LaserScan { stamp: t, ..scan.clone() }),
            })
            .collect();
        let scans: Vec<&LaserScan> = restamped.iter().map(|scan| scan.as_ref()).collect();
        if let Some(b) = bag.as_mut() {
            b.step(&RobotStep { scans: &scans, ..*s });
        }
        if write_error.is_some() {
            return;
        }
        for &scan in &scans {
            let (true_pose, odometry_pose) = log.history.at(scan.stamp).unwrap_or((*s.true_pose, s.odometry.pose));
            let odometry = Odometry { stamp: scan.stamp, pose: odometry_pose };
            let late = (line_lag > 0.0).then(|| log.history.at(scan.stamp - line_lag)).flatten();
            let line_odometry = late.map_or(odometry, |(_, pose)| Odometry { pose, ..odometry });
            let written = (|| {
                if odom_lines {
                    log.writer.odometry(&odometry)?;
                }
                log.writer.scan(scan, &line_odometry, s.mount)
            })();
            if let Err(e) = written {
                write_error = Some(anyhow::anyhow!("{}.clf: {e}", log.name));
                return;
            }
            log.truth.push(StampedPose { stamp: scan.stamp, pose: true_pose });
            log.beams = scan.len();
            log.range_max = scan.range_max;
        }
    };
    let opts = RunOptions {
        // A log needs no merge.
        algorithms: Some(Vec::new()),
        progress: Some(Box::new(|t: f64, end: f64| super::sim_progress::show(&bar, t, end))),
        viz: None,
        on_step: Some(Box::new(tap)),
    };
    let out = run_scenario(&scenario, opts)?;
    bar.finish_and_clear();
    if let Some(e) = write_error {
        return Err(e);
    }
    let bag = bag.map(|b| b.finish(&out)).transpose()?;
    let mut robots = Vec::new();
    for log in logs {
        let [clf, truth_path, relations_path] = robot_files(&args.out, &log.name);
        let file = log.writer.finish().with_context(|| clf.display().to_string())?;
        file.commit()?;
        let header = format!("true pose of robot `{}` at each scan of {}.clf, world frame", log.name, log.name);
        write_file_atomic(&truth_path, format_trajectory(&header, &log.truth).as_bytes())?;
        let drawn = relations_from_truth(&log.truth, &truth_params);
        let header = format!(
            "relations of {}.clf drawn from its true trajectory: {} local (1 m or 0.5 rad apart), {} across loops \
             (within {} m after at least {} m of driving)",
            log.name,
            drawn.local.len(),
            drawn.loops.len(),
            truth_params.loop_radius,
            truth_params.loop_min_travel
        );
        write_file_atomic(&relations_path, format_relations(&header, &drawn.all()).as_bytes())?;
        let duration = match (log.truth.first(), log.truth.last()) {
            (Some(a), Some(b)) => b.stamp - a.stamp,
            _ => 0.0,
        };
        let distance = out.report.robots.get(&log.name).map_or(0.0, |r| r.distance_m);
        let longest = drawn.loop_lengths.iter().copied().fold(0.0, f64::max);
        println!(
            "{:<10} {} scans ({} beams, {} m range) over {:.0} s, {:.0} m driven; relations: {} local, {} across \
             loops (longest loop {:.0} m)",
            log.name,
            log.truth.len(),
            log.beams,
            log.range_max,
            duration,
            distance,
            drawn.local.len(),
            drawn.loops.len(),
            longest
        );
        robots.push(json!({
            "name": log.name,
            "log": clf.file_name().map(|n| n.to_string_lossy().into_owned()),
            "scans": log.truth.len(),
            "beams": log.beams,
            "range_max_m": log.range_max,
            "duration_s": duration,
            "distance_m": distance,
            "local_relations": drawn.local.len(),
            "loop_relations": drawn.loops.len(),
            "longest_loop_m": longest,
            "odom_lines": odom_lines,
            "line_odometry_lag_s": line_lag,
        }));
    }
    let summary = json!({
        "scenario": scenario.name,
        "scenario_file": args.scenario.display().to_string(),
        "seed": scenario.seed,
        "sim_s": out.report.sim_s,
        "wall_s": out.report.wall_s,
        "robots": robots,
    });
    let text = serde_json::to_string_pretty(&summary).context("log.json")? + "\n";
    write_file_atomic(&summary_path, text.as_bytes())?;
    println!("outputs:  {}", args.out.display());
    if let Some(b) = bag {
        println!("ROS 2 bag: {}", b.commit()?.display());
    }
    Ok(ExitCode::SUCCESS)
}
