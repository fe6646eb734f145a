//! `mrslam log info`: what a laser log (CARMEN, or a ROS 1 / ROS 2 bag) holds, and what the reader repaired.

use anyhow::Result;
use clap::{Args, Subcommand};
use mrslam_log::{BagSummary, MAX_STEP_BACK, OdometrySource, ReadOptions, SensorLog, TopicChoice, read_log};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// How a log is read (shared by `log info` and `slam`).
#[derive(Args, Debug, Clone)]
pub struct ReadArgs {
    /// Each scan's odometry: `interpolated` (ODOM lines interpolated at the scan's stamp where they bracket
    /// it, else the scan line's own fields; the own fields everywhere when the ODOM lines are stamped in bursts)
    /// or `line` (the scan line's own odometry fields, as GMapping).
    #[arg(long, default_value_t = OdometrySource::Interpolated)]
    pub odometry: OdometrySource,
    /// Refuse a log whose sensor stamps step back by more than this many seconds (real logs interleave
    /// sensors by arrival: up to about 1 s).
    #[arg(long, default_value_t = MAX_STEP_BACK)]
    pub max_step_back: f64,
    /// Keep ODOM increments that report reversing (tv < 0) but move forwards as they are (by default they
    /// are turned round: some robots' odometry integrates the speed's magnitude).
    #[arg(long)]
    pub keep_reversing: bool,
    /// Seconds by which each scan was taken before its stamp: odometry is interpolated at the stamp minus
    /// this.
    #[arg(long, default_value_t = 0.0)]
    pub scan_latency: f64,
    /// A bag's sensor_msgs/LaserScan topic (needed only when it has several).
    #[arg(long, value_name = "TOPIC", allow_hyphen_values = true)]
    pub scan: Option<String>,
    /// A bag's nav_msgs/Odometry topic (needed only when it has several; without one, odometry comes from
    /// /tf).
    #[arg(long, value_name = "TOPIC", allow_hyphen_values = true)]
    pub odom: Option<String>,
    /// A bag's robot frame: odometry from /tf is the odometry frame's transform to it, the laser's mount its
    /// /tf_static transform to the scan's frame (by default the frame the laser's /tf_static chain reaches).
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub base_frame: Option<String>,
}

impl ReadArgs {
    /// The bag topic and frame choices, as `, scan /scan, odom /odom, base_frame base_link` (empty when none).
    pub fn topics_text(&self) -> String {
        let named = [("scan", &self.scan), ("odom", &self.odom), ("base_frame", &self.base_frame)];
        named.iter().filter_map(|(k, v)| v.as_ref().map(|v| format!(", {k} {v}"))).collect()
    }

    /// Reads `path` with these options.
    pub fn read(&self, path: &Path) -> Result<SensorLog> {
        if !(self.max_step_back.is_finite() && self.max_step_back >= 0.0) {
            anyhow::bail!("--max-step-back {}: must be a non-negative number of seconds", self.max_step_back);
        }
        if !(self.scan_latency.is_finite() && self.scan_latency.abs() <= 10.0) {
            anyhow::bail!("--scan-latency {}: must be a number of seconds within ±10", self.scan_latency);
        }
        let options = ReadOptions {
            odometry: self.odometry,
            max_step_back: self.max_step_back,
            repair_reversing: !self.keep_reversing,
            scan_latency: self.scan_latency,
            topics: TopicChoice {
                scan: self.scan.clone(),
                odom: self.odom.clone(),
                base_frame: self.base_frame.clone(),
            },
            ..ReadOptions::default()
        };
        Ok(read_log(path, &options)?)
    }
}

/// Log subcommands.
#[derive(Subcommand)]
pub enum LogCommand {
    /// Print a log's scans, laser, odometry, timing, skipped lines and repairs; for a bag, its topics and
    /// which of them it would use.
    Info {
        /// CARMEN log (plain or gzipped), ROS 1 .bag, ROS 2 .mcap or .db3, or a ROS 2 bag folder.
        log: PathBuf,
        /// How to read it.
        #[command(flatten)]
        read: ReadArgs,
    },
}

/// Runs a log subcommand.
pub fn run(cmd: LogCommand) -> Result<ExitCode> {
    match cmd {
        LogCommand::Info { log, read } => {
            let parsed = read.read(&log)?;
            if parsed.scans.is_empty() {
                let mut skipped: Vec<String> =
                    parsed.skipped.iter().take(5).map(|(k, n)| format!("{n} `{k}`")).collect();
                if parsed.skipped.len() > 5 {
                    skipped.push(format!("lines of {} other kinds", parsed.skipped.len() - 5));
                }
                anyhow::bail!(
                    "{}: no laser scans (FLASER, RLASER or ROBOTLASER1 lines): not a CARMEN laser log? ({} ODOM \
                     lines; skipped: {})",
                    log.display(),
                    parsed.odometry.len(),
                    if skipped.is_empty() { "nothing".to_string() } else { skipped.join(", ") }
                );
            }
            println!("log:       {}", log.display());
            if let Some(bag) = &parsed.bag {
                print_bag(bag);
            }
            println!("scans:     {}", parsed.scans.len());
            if let (Some(first), Some(last)) = (parsed.scans.first(), parsed.scans.last()) {
                let s = &first.scan;
                let duration = last.scan.stamp - s.stamp;
                println!("time:      {:.3} s to {:.3} s ({duration:.1} s)", s.stamp, last.scan.stamp);
                if duration > 0.0 {
                    println!("scan rate: {:.2} Hz", (parsed.scans.len() - 1) as f64 / duration);
                }
                let fov = s.angle_increment.abs() * (s.len().max(1) - 1) as f64;
                println!(
                    "laser:     {} beams spanning {:.1} deg from {:.2} deg every {:.3} deg, range {}..{} m",
                    s.len(),
                    fov.to_degrees(),
                    s.angle_min.to_degrees(),
                    s.angle_increment.to_degrees(),
                    s.range_min,
                    s.range_max
                );
                let counts: std::collections::BTreeSet<usize> = parsed.scans.iter().map(|r| r.scan.len()).collect();
                if counts.len() > 1 {
                    println!("           beam counts differ between scans: {counts:?}");
                }
            }
            match &parsed.bag {
                Some(bag) => println!(
                    "odometry:  {} readings from {}, interpolated at {} scans' stamps{}",
                    parsed.odometry.len(),
                    bag.odometry,
                    parsed.repairs.interpolated_odometry,
                    if parsed.repairs.stamped_in_bursts {
                        "; stamped in bursts, so each scan holds the reading before it"
                    } else {
                        ""
                    }
                ),
                None => println!(
                    "odometry:  {} ODOM lines; scans use {}",
                    parsed.odometry.len(),
                    parsed.repairs.describe_odometry()
                ),
            }
            println!("repairs:   {}", parsed.repairs.describe());
            println!("params:    {}", parsed.params.len());
            let skipped: Vec<String> = parsed.skipped.iter().map(|(k, n)| format!("{n} {k}")).collect();
            println!("skipped:   {}", if skipped.is_empty() { "none".to_string() } else { skipped.join(", ") });
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// A bag's format, topics and the ones the read used.
fn print_bag(bag: &BagSummary) {
    println!("format:    {}", bag.format);
    println!("topics:    {}", bag.topics.len());
    let width = bag.topics.iter().map(|t| t.name.len()).max().unwrap_or(0);
    let type_width = bag.topics.iter().map(|t| t.type_name.len()).max().unwrap_or(0);
    for t in &bag.topics {
        let rate = t.rate().map_or_else(|| "-".to_string(), |r| format!("{r:.2} Hz"));
        println!("           {:width$}  {:type_width$}  {:>7} msgs  {rate}", t.name, t.type_name, t.count);
    }
    println!("uses:      scans from {}; odometry from {}", bag.scan_topic, bag.odometry);
    println!("mount:     {}", bag.laser_mount);
}
