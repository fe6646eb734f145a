//! `mrslam slam LOG -o MAP.yaml`: GMapping-style SLAM on a CARMEN log.
//!
//! Leniency: NaN/negative beams are counted and ignored; scans whose odometry did not move enough are
//! skipped (counted). Errors naming the log line: a malformed line (core's reader), time going backwards in
//! file order, non-finite odometry or scan geometry.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_core::map_io::{self, write_file_atomic};
use mrslam_core::pose::pose_xyt;
use mrslam_core::{CarmenLog, Odometry, Pose2};
use mrslam_slam::synthetic::{Drift, inject_drift};
use mrslam_slam::{Rbpf, SlamParams};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// Parameter presets.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Preset {
    /// GMapping's defaults (80 m range, update every 1 m / 0.5 rad).
    Gmapping,
    /// Hokuyo URG-04LX class robot (4 m).
    Hokuyo,
    /// RpLidar A1 class robot (6 m).
    Rplidar,
}

/// Arguments of `mrslam slam`.
#[derive(Args, Debug)]
pub struct SlamArgs {
    /// CARMEN log (.clf/.log, gzipped or not).
    pub log: PathBuf,
    /// Output map YAML (a PGM is written beside it).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output trajectory: one line per processed scan, `timestamp x y theta` (best particle, map frame).
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Parameter preset.
    #[arg(long, value_enum, default_value_t = Preset::Gmapping)]
    pub preset: Preset,
    /// Number of particles.
    #[arg(long)]
    pub particles: Option<usize>,
    /// RNG seed (filter and injected drift).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Override linearUpdate, metres.
    #[arg(long)]
    pub linear_update: Option<f64>,
    /// Override angularUpdate, radians.
    #[arg(long)]
    pub angular_update: Option<f64>,
    /// Override maxUrange (usable range), metres.
    #[arg(long)]
    pub max_urange: Option<f64>,
    /// Set any SLAM parameter by its name, as in scenario files (repeatable; applied after the preset and the
    /// flags above): e.g. `--set odometry_calibration=20 --set srr=0.2`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Drift injection for testing: systematic heading error, degrees per metre travelled.
    #[arg(long, default_value_t = 0.0)]
    pub drift_heading: f64,
    /// Drift injection: relative scale error of travelled distance (0.03 = +3 %).
    #[arg(long, default_value_t = 0.0)]
    pub drift_scale: f64,
    /// Drift injection: random noise per odometry step, relative (std dev per metre / per radian).
    #[arg(long, default_value_t = 0.0)]
    pub drift_sigma: f64,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `mrslam slam`.
pub fn run(args: SlamArgs) -> Result<ExitCode> {
    for p in std::iter::once(&args.output).chain(&args.trajectory) {
        super::check_output(p)?;
    }
    let mut params = match args.preset {
        Preset::Gmapping => SlamParams::default(),
        Preset::Hokuyo => SlamParams::hokuyo(),
        Preset::Rplidar => SlamParams::rplidar(),
    };
    if let Some(n) = args.particles {
        params.particles = n;
    }
    if let Some(v) = args.linear_update {
        params.linear_update = v;
    }
    if let Some(v) = args.angular_update {
        params.angular_update = v;
    }
    if let Some(v) = args.max_urange {
        params.max_urange = v;
    }
    for kv in &args.set {
        let Some((name, value)) = kv.split_once('=') else {
            bail!("--set {kv}: expected NAME=VALUE");
        };
        params.set(name.trim(), value).map_err(|e| anyhow::anyhow!("--set {kv}: {e}"))?;
    }
    params.validate().map_err(|e| anyhow::anyhow!("slam parameters: {e}"))?;
    let log = CarmenLog::read(&args.log)?;
    if log.scans.is_empty() {
        bail!("{}: no laser scans in the log", args.log.display());
    }
    // Time going backwards in file order is an error naming the line (the reader sorts by stamp).
    let mut by_line: Vec<(usize, f64)> = log.scans.iter().map(|r| (r.line, r.scan.stamp)).collect();
    by_line.sort_by_key(|&(l, _)| l);
    for w in by_line.windows(2) {
        if w[1].1 < w[0].1 {
            bail!(
                "{}:{}: time goes backwards: stamp {} after {} on line {}",
                args.log.display(),
                w[1].0,
                w[1].1,
                w[0].1,
                w[0].0
            );
        }
    }
    let mut odo: Vec<Odometry> = log.scans.iter().map(|r| r.odometry).collect();
    let drift = Drift {
        scale: args.drift_scale,
        heading_per_m: args.drift_heading.to_radians(),
        sigma_trans: args.drift_sigma,
        sigma_rot: args.drift_sigma,
    };
    if drift != Drift::none() {
        inject_drift(&mut odo, &drift, args.seed ^ 0x5eed_d21f_7000_0001);
    }

    let offset: Pose2 = log.scans[0].laser_offset;
    let mut filter = Rbpf::new(params, offset, args.seed).context("slam parameters")?;
    let bar = ProgressBar::new(log.scans.len() as u64);
    if args.quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} scans {msg} [{elapsed_precise}<{eta_precise}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let start = std::time::Instant::now();
    for (rec, o) in log.scans.iter().zip(&odo) {
        let out = filter.process(o, &rec.scan).with_context(|| format!("{}:{}", args.log.display(), rec.line))?;
        if let Some(neff) = out.neff() {
            bar.set_message(format!("Neff {neff:.1}"));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let map = filter.map().context("building the map")?;
    map_io::write_ros_map(&map, &args.output).with_context(|| format!("{}", args.output.display()))?;
    if let Some(path) = &args.trajectory {
        let mut text = String::new();
        for (stamp, p) in filter.trajectory() {
            let (x, y, t) = pose_xyt(&p);
            let _ = writeln!(text, "{stamp:.6} {x:.6} {y:.6} {t:.6}");
        }
        write_file_atomic(path, text.as_bytes()).with_context(|| format!("{}", path.display()))?;
    }
    let c = filter.counters();
    let (free, occ, unknown) = map.state_counts();
    println!(
        "slam: {} scans: {} processed, {} skipped (not moved {}, empty {}), {} invalid beams ignored, {} resamples",
        c.readings,
        c.processed,
        c.skipped_not_moved + c.skipped_empty,
        c.skipped_not_moved,
        c.skipped_empty,
        c.invalid_beams,
        c.resamples
    );
    println!(
        "time {secs:.2} s ({:.1} ms per processed scan), final Neff {:.1} of {}",
        secs * 1e3 / c.processed.max(1) as f64,
        filter.neff(),
        filter.params().particles
    );
    if filter.params().odometry_calibration > 0.0 {
        let [scale, heading] = filter.odometry_calibration();
        println!(
            "odometry calibration learnt: distance scale {:+.2} %, heading drift {:+.4} rad/m",
            100.0 * scale,
            heading
        );
    }
    println!(
        "map {} ({}x{} cells at {} m: {free} free, {occ} occupied, {unknown} unknown)",
        args.output.display(),
        map.width(),
        map.height(),
        map.resolution()
    );
    Ok(ExitCode::SUCCESS)
}
