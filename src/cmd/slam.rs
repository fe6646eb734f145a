//! `mrslam slam LOG -o MAP.yaml`: GMapping-style SLAM on a laser log (CARMEN, or a ROS 1 / ROS 2 bag).
//!
//! Leniency: NaN/negative beams are counted and ignored; scans whose odometry did not move enough are
//! skipped (counted); sensor lines out of stamp order are reordered and repeated scans dropped (mrslam-log's
//! repairs, counted and reported). Errors naming the log line: a malformed line, stamps stepping back by more than
//! `--max-step-back`, non-finite odometry or scan geometry.

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_core::relations::{self, StampedPose};
use mrslam_core::{LaserScan, Odometry, Pose2};
use mrslam_log::{MAX_SPEED, MAX_TURN_RATE, faster_than_a_robot};
use mrslam_slam::synthetic::{Drift, inject_drift};
use mrslam_slam::{LogRun, LogRunError, Preset, Rbpf, map_log, odometry_lag};
use mrslam_viz::{Level, ProcessedScan, RelationMark, SlamLogRecorder};
use nalgebra::Point2;
use serde_json::json;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam slam`.
#[derive(Args, Debug)]
pub struct SlamArgs {
    /// Laser log: CARMEN (.clf/.log, gzipped or not), ROS 1 .bag, ROS 2 .mcap or .db3, or a ROS 2 bag folder.
    pub log: PathBuf,
    /// Output map YAML (the PGM and a PNG preview are written beside it).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output trajectory: one pose per scan of the log, in stamp order, `stamp x y theta` (best particle,
    /// map frame; scans the filter did not process are placed by odometry, see the file's header).
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Score the trajectory against these benchmark relations (Kümmerle et al. 2009) at the end.
    #[arg(long)]
    pub relations: Option<PathBuf>,
    /// Relation stamps match a scan's stamp within this many seconds.
    #[arg(long, default_value_t = super::eval::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    /// Write a JSON summary of the run here: scans, processed, time, real-time factor, peak memory,
    /// resamples, repairs and (with --relations) the metric.
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// How to read the log.
    #[command(flatten)]
    pub read: super::log::ReadArgs,
    /// Parameter preset: matched (GMapping's filter on scan-matched odometry), gmapping (the reference),
    /// hokuyo or rplidar (the simulated robots').
    #[arg(long, default_value_t = Preset::Matched)]
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
    /// flags above): a dotted name (`matcher.sigma`, `filter.particles`) or GMapping's flat one (`sigma`,
    /// `particles`, `srr`): e.g. `--set odometry_calibration=20 --set motion.srr=0.2`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Odometry errors added to the log's (testing).
    #[command(flatten)]
    pub drift: DriftArgs,
    /// Hide the progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Where to watch the run (rerun): the map as it grows, the best particle's path and the odometry's, the
    /// particles, the scan, Neff, the real-time factor, resampling and loop closure, the relations' errors.
    #[command(flatten)]
    pub viz: super::viz::VizArgs,
}

/// Odometry errors injected into a log's odometry before the SLAM (`mrslam slam`, `mrslam study logs`): to test
/// the filter, and the merges of its maps, on worse odometry than the robot had.
#[derive(Args, Debug, Clone, Copy, PartialEq)]
pub struct DriftArgs {
    /// Drift injection for testing: systematic heading error, degrees per metre travelled.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub drift_heading: f64,
    /// Drift injection: relative scale error of travelled distance (0.03 = +3 %).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub drift_scale: f64,
    /// Drift injection: random noise per odometry step, relative (std dev per metre / per radian).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub drift_sigma: f64,
}

impl DriftArgs {
    /// The drift these flags ask for.
    pub fn drift(&self) -> Drift {
        Drift {
            scale: self.drift_scale,
            heading_per_m: self.drift_heading.to_radians(),
            sigma_trans: self.drift_sigma,
            sigma_rot: self.drift_sigma,
        }
    }

    /// Refuses values that are not numbers, a negative noise and a distance scale of -100 % or less.
    pub fn validate(&self) -> Result<()> {
        let DriftArgs { drift_heading: h, drift_scale: k, drift_sigma: s } = *self;
        if !(h.is_finite() && k.is_finite() && s.is_finite()) {
            bail!("--drift-heading {h}, --drift-scale {k}, --drift-sigma {s}: must be numbers");
        }
        if s < 0.0 {
            bail!("--drift-sigma {s}: must not be negative");
        }
        if k <= -1.0 {
            bail!("--drift-scale {k}: must be above -1 (a distance cannot shrink by 100 % or more)");
        }
        Ok(())
    }

    /// No drift asked for.
    pub fn is_none(&self) -> bool {
        self.drift() == Drift::none()
    }

    /// Re-integrates `odometry` with the drift applied (nothing when none is asked), its noise seeded from `seed`.
    pub fn inject(&self, odometry: &mut [Odometry], seed: u64) {
        if !self.is_none() {
            inject_drift(odometry, &self.drift(), seed ^ 0x5eed_d21f_7000_0001);
        }
    }

    /// The flags as a study records them.
    pub fn describe(&self) -> String {
        format!("heading {} deg/m, scale {}, sigma {}", self.drift_heading, self.drift_scale, self.drift_sigma)
    }
}

/// Refuses a map resolution (`map.delta`, set through `flag`) the map reader would refuse, so that no run ends
/// in a map no command can read.
pub fn check_map_resolution(flag: &str, params: &mrslam_slam::SlamParams) -> Result<()> {
    let delta = params.map.delta;
    if !(map_io::MIN_RESOLUTION..=map_io::MAX_RESOLUTION).contains(&delta) {
        bail!(
            "{flag} map.delta={delta}: the map's resolution must be between {} and {} metres per pixel (the map \
             reader's bounds)",
            map_io::MIN_RESOLUTION,
            map_io::MAX_RESOLUTION
        );
    }
    Ok(())
}

/// Runs `mrslam slam`.
pub fn run(args: SlamArgs) -> Result<ExitCode> {
    super::Outputs::reading(std::iter::once(args.log.as_path()).chain(args.relations.as_deref()))
        .file("--output", &args.output, super::kind::MAP)
        .maybe("--trajectory", args.trajectory.as_deref(), super::kind::TRAJECTORY)
        .maybe("--summary", args.summary.as_deref(), super::kind::JSON)
        .maybe("--rrd", args.viz.rrd.as_deref(), super::kind::RRD)
        .check()?;
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        bail!("--tolerance {}: must be a non-negative number of seconds", args.tolerance);
    }
    args.drift.validate()?;
    let mut params = args.preset.params();
    if let Some(n) = args.particles {
        params.filter.particles = n;
    }
    if let Some(v) = args.linear_update {
        params.filter.linear_update = v;
    }
    if let Some(v) = args.angular_update {
        params.filter.angular_update = v;
    }
    if let Some(v) = args.max_urange {
        params.map.max_urange = v;
    }
    super::args::set_each("--set", &args.set, |name, value| params.set(name, value))?;
    params.validate().map_err(|e| anyhow::anyhow!("slam parameters: {e}"))?;
    check_map_resolution("--set", &params)?;
    // Read the relations before the long work, so that a bad file costs nothing.
    let rels = match &args.relations {
        Some(p) => Some(relations::read_relations(p)?),
        None => None,
    };
    let log = args.read.read(&args.log)?;
    if log.scans.is_empty() {
        bail!("{}: no laser scans in the log", args.log.display());
    }
    let mut odo: Vec<Odometry> = log.scans.iter().map(|r| r.odometry).collect();
    args.drift.inject(&mut odo, args.seed);
    // Jumps as the log's lines have them, before the re-timing below blends each scan's with the next's.
    let jumps = odometry_jumps(&odo, &log.scans);
    let lag = if log.odometry.is_empty() {
        let scans: Vec<&LaserScan> = log.scans.iter().map(|r| &r.scan).collect();
        odometry_lag::retime_line_odometry(&mut odo, &scans, &params, log.scans[0].laser_offset)
    } else {
        None
    };

    let gate = super::slam_eta::Gate {
        linear: params.filter.linear_update,
        angular: params.filter.angular_update,
        temporal: params.filter.temporal_update,
    };
    let offset: Pose2 = log.scans[0].laser_offset;
    let mut filter = Rbpf::new(params, offset, args.seed).context("slam parameters")?;
    // The recording's destinations are opened before the long work, so that a bad one fails at once.
    let name = mrslam_log::log_name(&args.log);
    let mut viz = args
        .viz
        .open(&format!("slam-{name}-{}-seed{}", args.preset, args.seed), &format!("slam {name}"))?
        .map(|rec| SlamLogRecorder::new(rec, &name));
    // Ctrl-C (or SIGTERM, SIGHUP): nothing is written before the end, but the recording so far.
    super::interrupt::on_interrupt(interrupted_message(&args), Vec::new());
    let stamp0 = log.scans[0].scan.stamp;
    let bar = ProgressBar::new(log.scans.len() as u64);
    if args.quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} scans {msg} [{elapsed_precise}<{work_eta}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .with_key("work_eta", super::slam_eta::eta_key(super::slam_eta::processed_so_far(&odo, gate))),
    );
    let start = std::time::Instant::now();
    let mut index = 0;
    let mut first_slam = None;
    let mut reanchors = 0;
    let run = map_log(&mut filter, odo.iter().zip(log.scans.iter().map(|r| &r.scan)), |out, filter| {
        if let Some(neff) = out.neff() {
            bar.set_message(match filter.loop_report() {
                Some(l) => format!(
                    "Neff {neff:.1}, loops: {} searched, {} kept, {} open",
                    l.candidates, l.closures, l.open_loops
                ),
                None => format!("Neff {neff:.1}"),
            });
        }
        bar.inc(1);
        if let Some(v) = viz.as_mut() {
            let scan = &log.scans[index].scan;
            let elapsed = start.elapsed().as_secs_f64();
            v.set_time(index as u64, scan.stamp - stamp0);
            if out.is_processed() {
                let best = filter.best_pose();
                first_slam.get_or_insert(best);
                let points: Vec<Point2<f64>> = scan.endpoints(&(best * offset)).map(|(_, p)| p).collect();
                v.processed(ProcessedScan {
                    best: &best,
                    points: &points,
                    particles: filter.particles(),
                    neff: filter.neff(),
                    resampled: out.resampled(),
                    realtime_factor: (elapsed > 0.0).then(|| (scan.stamp - stamp0) / elapsed),
                });
            }
            if filter.counters().reanchors > reanchors {
                reanchors = filter.counters().reanchors;
                let path: Vec<Pose2> = filter.trajectory().into_iter().map(|(_, p)| p).collect();
                let edges: Vec<(Pose2, Pose2)> =
                    filter.loop_edges().into_iter().map(|(a, b)| (path[a], path[b])).collect();
                let l = filter.loop_report().unwrap_or_default();
                let text = format!(
                    "loop closed: {} loop edges kept; the trajectory moved by up to {:.2} m",
                    l.closures, l.max_correction
                );
                v.loops_closed(&path, &edges, &text);
            }
            if let Some(odom) = filter.odometry_pose() {
                v.odometry(&odom, first_slam.as_ref());
            }
            if v.map_due()
                && let Some(map) = filter.live_map()
            {
                v.map(&map);
            }
        }
        index += 1;
    })
    .map_err(|e| match e {
        LogRunError::Reading { index, error } => {
            anyhow::anyhow!("{}: {error}", log.scans[index].source.in_file(&args.log))
        }
        LogRunError::NothingProcessed => anyhow::anyhow!("the filter processed no scan: no trajectory"),
    })?;
    bar.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    let map = filter.map().context("building the map")?;
    map_io::write_ros_map(&map, &args.output).with_context(|| format!("{}", args.output.display()))?;
    // A pose for every scan: the filter's at the processed ones, odometry in between.
    let trajectory: Vec<StampedPose> =
        log.scans.iter().zip(&run.poses).map(|(r, &pose)| StampedPose { stamp: r.scan.stamp, pose }).collect();
    let score = rels.as_ref().map(|r| relations::score(&trajectory, r, args.tolerance));
    if let Some(mut v) = viz.take() {
        record_the_end(&mut v, &filter, &map, &run, &log.scans, score.as_ref())?;
        let stats = v.finish()?;
        println!("rerun: {} ({} rows in {} chunks)", args.viz.describe(), stats.rows, stats.chunks);
    }

    let (poses, processed, loops) = (run.poses, run.processed, run.loop_closure);
    let stamps: Vec<f64> = log.scans.iter().map(|r| r.scan.stamp).collect();
    // The preview beside the map: the map with the best particle's path (a pose per scan) in red.
    let path: Vec<nalgebra::Point2<f64>> = poses.iter().map(|p| p.translation.vector.into()).collect();
    let preview = map_io::preview_path(&args.output);
    map_io::write_rgb_png(&map_io::preview_with_path(&map, &path), &preview)
        .with_context(|| format!("{}", preview.display()))?;
    if let Some(path) = &args.trajectory {
        let header = format!(
            "mrslam slam {}: one pose per scan ({} scans), `stamp x y theta`, the best particle's robot pose in \
             the map frame.\n{} scans were processed by the filter and carry its pose; every other scan is placed \
             by the {} from the processed scan before it and back from the processed scan after it, blended \
             by time (before the first / after the last processed scan: odometry from it).{}",
            args.log.display(),
            trajectory.len(),
            processed.len(),
            if filter.params().scan_odometry.enabled { "scan-matched odometry" } else { "odometry" },
            if loops.is_some_and(|l| l.closures > 0) {
                "\nThe processed scans' poses are the loop-closed (smoothed) ones."
            } else {
                ""
            }
        );
        write_file_atomic(path, relations::format_trajectory(&header, &trajectory).as_bytes())?;
    }

    let c = filter.counters();
    let (free, occ, unknown) = map.state_counts();
    let duration = stamps[stamps.len() - 1] - stamps[0];
    let realtime = if secs > 0.0 { duration / secs } else { f64::INFINITY };
    let peak = super::peak_memory_bytes();
    let mem = filter.memory_stats();
    println!("log: {} ({:.1} s); {}", args.log.display(), duration, log.repairs.describe());
    println!("odometry: {}", log.repairs.describe_odometry());
    if let Some(l) = &lag {
        let verdict = match (l.given_s, l.applies(), l.lag_s > 0.0) {
            (Some(g), _, _) => format!("re-timed by the {g:+.3} s given (scan_odometry_line_lag_s)"),
            (None, true, true) => format!("the scan lines' odometry is {:.3} s late; re-timed", l.lag_s),
            (None, true, false) => format!("the scan lines' odometry is {:.3} s early; re-timed", -l.lag_s),
            (None, false, _) => "none worth re-timing the scan lines' odometry by".to_string(),
        };
        println!(
            "odometry lag: {verdict} (the best lag, {:+.3} s, leaves {:.0} % of the squared heading misfit of {} \
             matched scan pairs)",
            l.lag_s,
            100.0 * l.residual_ratio,
            l.pairs
        );
    }
    if let Some(worst) = jumps.iter().max_by(|a, b| a.distance.total_cmp(&b.distance)) {
        println!(
            "warning: the odometry jumps {} times (faster than {MAX_SPEED} m/s or {MAX_TURN_RATE} rad/s between scans; \
             largest {:.2} m and {:.2} rad in {:.3} s at {}); the filter drew its particles through each jump \
             with the motion model's noise, so the map around it may be wrong",
            jumps.len(),
            worst.distance,
            worst.turn,
            worst.seconds,
            worst.at
        );
    }
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
        "time {secs:.2} s ({:.1} ms per processed scan, {realtime:.1}x real time), peak memory {}, final Neff {:.1} of {}",
        secs * 1e3 / c.processed.max(1) as f64,
        peak.map_or("unknown".to_string(), |b| format!("{:.0} MiB", b as f64 / (1024.0 * 1024.0))),
        filter.neff(),
        filter.params().filter.particles
    );
    if filter.params().scan_odometry.enabled {
        let (matched, turned, dead) = filter.scan_odometry_counts();
        let turned = match turned {
            0 => String::new(),
            n => format!(" ({n} of them moving the other way than the odometry said)"),
        };
        println!("scan odometry: {matched} scans matched{turned}, {dead} kept the raw odometry's increment");
    }
    if let Some(l) = &loops {
        println!("loop closure: {}", describe_loops(l, filter.params().loop_closure.online, c.processed));
        if l.open_loops > 0 {
            println!(
                "warning: {} stretch(es) of driving through places passed a loop ago found no loop edge: the map \
                 may show those places twice",
                l.open_loops
            );
        }
        if l.contradicts_itself() {
            println!(
                "warning: {} of {} scans of places passed a loop ago see walls where the map has open floor: the \
                 map puts places on top of each other (loops closed into a wrong building, or a turn the odometry \
                 missed)",
                l.contradicted, l.judged
            );
        }
    }
    if filter.params().filter.odometry_calibration > 0.0 {
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
    if let Some(score) = &score {
        print!("{}", super::eval::describe(score, args.tolerance, 3));
    }
    if let Some(path) = &args.summary {
        let r = &log.repairs;
        let summary = json!({
            "log": args.log.display().to_string(),
            "preset": args.preset.to_string(),
            "seed": args.seed,
            "particles": filter.params().filter.particles,
            "scans": c.readings,
            "processed": c.processed,
            "resamples": c.resamples,
            "log_duration_s": duration,
            "time_s": secs,
            "real_time_factor": realtime,
            "ms_per_scan": secs * 1e3 / c.readings.max(1) as f64,
            "peak_memory_bytes": peak,
            "held_at_end": {
                "map_tiles": mem.unique_tiles,
                "map_tile_bytes": mem.tile_bytes,
                "map_tile_bytes_unshared": mem.unshared_tile_bytes,
                "trajectory_bytes": mem.trajectory_bytes,
                "loop_graph_bytes": mem.loop_graph_bytes,
            },
            "repairs": {
                "out_of_order": r.out_of_order,
                "max_step_back_s": r.max_step_back,
                "duplicate_scans": r.duplicate_scans,
                "shared_scan_stamps": r.shared_scan_stamps,
                "duplicate_odometry": r.duplicate_odometry,
                "reversed_increments": r.reversed_increments,
                "interpolated_odometry": r.interpolated_odometry,
                "line_odometry": r.line_odometry,
                "burst_odometry_increments": r.burst_increments,
                "odometry_stamped_in_bursts": r.stamped_in_bursts,
            },
            "odometry_jumps": jumps.len(),
            "line_odometry_lag": lag.map(|l| json!({
                "lag_s": l.lag_s, "pairs": l.pairs, "residual_ratio": l.residual_ratio, "applied": l.applies(),
                "given_s": l.given_s, "used_s": l.used_s()
            })),
            "scan_odometry": filter.params().scan_odometry.enabled.then(|| {
                let (matched, turned_round, dead) = filter.scan_odometry_counts();
                json!({ "matched": matched, "turned_round": turned_round, "raw": dead })
            }),
            "loop_closure": loops.map(|l| json!({
                "online": filter.params().loop_closure.online,
                "candidates": l.candidates,
                "closures": l.closures,
                "rejected": l.rejected,
                "dropped": l.dropped,
                "optimisations": l.optimisations,
                "open_loops": l.open_loops,
                "relocalisations": l.relocalisations,
                "relocalised": l.relocalised,
                "judged": l.judged,
                "contradicted": l.contradicted,
                "contradicts_itself": l.contradicts_itself(),
                "max_correction_m": l.max_correction,
                "iterations": l.iterations,
                "reanchors": c.reanchors,
            })),
            "metric": score.as_ref().map(|s| super::eval::to_json(s, args.tolerance, 10)),
        });
        super::eval::write_json(path, &summary)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// What an interrupted `slam` says: no output written, where the recording so far is.
fn interrupted_message(args: &SlamArgs) -> String {
    let rrd = args
        .viz
        .rrd
        .as_deref()
        .map(|r| format!("; the recording so far, without its footer: {}", mrslam_viz::partial_path(r).display()));
    format!(
        "mrslam slam: interrupted: nothing written to {} (the map, trajectory and summary are written at the end){}",
        args.output.display(),
        rrd.unwrap_or_default()
    )
}

/// One line on what loop closure did.
fn describe_loops(l: &mrslam_slam::LoopClosureReport, online: bool, processed: usize) -> String {
    if online {
        format!(
            "{} searches of {processed} processed scans against places passed a loop ago: {} loop edges kept, {} \
             found nothing, {} dropped as inconsistent; {} optimisations moved a scan by at most {:.2} m; {} loops \
             left open; {} of {} scans judged against the map a loop apart contradict it",
            l.candidates,
            l.closures,
            l.rejected,
            l.dropped,
            l.optimisations,
            l.max_correction,
            l.open_loops,
            l.contradicted,
            l.judged
        )
    } else {
        format!(
            "{} of {processed} processed scans matched a place passed a loop ago; {} loop edges; the smoothing moved \
             a scan by at most {:.2} m ({} iterations)",
            l.candidates, l.closures, l.max_correction, l.iterations
        )
    }
}

/// Records the end of the run: the loop closure, the final paths (smoothed), the output map, the relations.
fn record_the_end(
    v: &mut SlamLogRecorder,
    filter: &Rbpf,
    map: &mrslam_core::OccupancyGrid,
    run: &LogRun,
    scans: &[mrslam_log::ScanRecord],
    score: Option<&relations::RelationsScore>,
) -> Result<()> {
    let stamp0 = scans[0].scan.stamp;
    let last = scans.len() - 1;
    v.set_time(last as u64, scans[last].scan.stamp - stamp0);
    if let Some(l) = &run.loop_closure {
        let level =
            if l.closures > 0 && l.open_loops == 0 && !l.contradicts_itself() { Level::Info } else { Level::Warn };
        let text =
            format!("loop closure: {}", describe_loops(l, filter.params().loop_closure.online, run.processed.len()));
        v.event(level, &text);
    }
    let smoothed: Vec<Pose2> = filter.trajectory().into_iter().map(|(_, p)| p).collect();
    v.paths(Some(&smoothed));
    v.map(map);
    if let Some(score) = score {
        let stamps: Vec<f64> = scans.iter().map(|r| r.scan.stamp).collect();
        let marks: Vec<RelationMark> = score
            .errors
            .iter()
            .map(|e| {
                // The scan nearest the relation's second stamp (the one the metric used, within its tolerance).
                let i = stamps.partition_point(|&s| s < e.t2).min(last);
                let i = if i > 0 && (stamps[i - 1] - e.t2).abs() < (stamps[i] - e.t2).abs() { i - 1 } else { i };
                RelationMark {
                    index: i as u64,
                    time: stamps[i] - stamp0,
                    at: run.poses[i],
                    translation: e.translation,
                    rotation: e.rotation,
                }
            })
            .collect();
        v.relations(&marks);
    }
    Ok(())
}

/// An odometry jump between two consecutive scans.
struct OdometryJump {
    /// Where the later scan is in the log.
    at: mrslam_log::Source,
    /// Metres moved.
    distance: f64,
    /// Radians turned.
    turn: f64,
    /// Seconds between the scans.
    seconds: f64,
}

/// The increments between consecutive scans' odometry that no robot drives ([`faster_than_a_robot`], over at
/// least 0.1 s, so that stamp jitter does not make a slow move look fast): a kidnapped robot or a reset.
fn odometry_jumps(odometry: &[Odometry], scans: &[mrslam_log::ScanRecord]) -> Vec<OdometryJump> {
    let mut jumps = Vec::new();
    for (k, w) in odometry.windows(2).enumerate() {
        let seconds = w[1].stamp - w[0].stamp;
        if faster_than_a_robot(&w[0].pose, &w[1].pose, seconds.max(0.1)) {
            let step = w[0].pose.inv_mul(&w[1].pose);
            let (distance, turn) = (step.translation.vector.norm(), step.rotation.angle().abs());
            jumps.push(OdometryJump { at: scans[k + 1].source.clone(), distance, turn, seconds });
        }
    }
    jumps
}
