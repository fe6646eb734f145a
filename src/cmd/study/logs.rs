//! `mrslam study logs`: a laser log (CARMEN or a ROS bag) split in time into robots, each part mapped, every connected pair merged.

use super::create_out;
use crate::cmd::args::{one_of, set_each};
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_core::relations;
use mrslam_merge::Encoding;
use mrslam_slam::Preset;
use mrslam_studies::journal::{StudyParams, fingerprint};
use mrslam_studies::logs::{self, PairRow, ScoreParams};
use mrslam_studies::results::TrialRow;
use mrslam_studies::summary::summarise;
use mrslam_studies::{self as study};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Arguments of `mrslam study logs`.
#[derive(Args)]
pub struct LogsArgs {
    /// Laser log: CARMEN (.clf/.log, gzipped or not), ROS 1 .bag, ROS 2 .mcap or .db3, or a ROS 2 bag folder.
    pub log: PathBuf,
    /// The log's benchmark relations (Kümmerle et al. 2009): the ground truth of each pair of parts.
    #[arg(long)]
    pub relations: PathBuf,
    /// Number of parts ("robots"): consecutive stretches of the log of equal duration, at least 2.
    #[arg(long)]
    pub parts: usize,
    /// Output folder: study.json, results.csv, summary.csv, plot.png, parts.csv, part-K.yaml with its .pgm and
    /// its PNG preview part-K.png, and part-K.trajectory.txt (each part's map and its pose at every scan).
    #[arg(long)]
    pub out: PathBuf,
    /// How to read the log.
    #[command(flatten)]
    pub read: crate::cmd::log::ReadArgs,
    /// SLAM parameter preset (as `mrslam slam --preset`).
    #[arg(long, default_value_t = Preset::Matched)]
    pub preset: Preset,
    /// Set any SLAM parameter by its name (repeatable; after the preset), as `mrslam slam --set`.
    #[arg(long = "slam-set", value_name = "NAME=VALUE")]
    pub slam_set: Vec<String>,
    /// Algorithms, comma-separated (sift, rmap, correlative, cascade); the default compares the paper's merger
    /// with `mrslam merge`'s.
    #[arg(long, default_value = "sift,cascade", value_delimiter = ',')]
    pub algorithms: Vec<String>,
    /// The SIFT merger's map-to-image encoding: `walls` (free and unknown alike, the default) or `paper`
    /// (unknown grey, the paper's).
    #[arg(long, default_value = "walls", value_parser = one_of::<Encoding>(Encoding::ALL.map(Encoding::name)))]
    pub encoding: Encoding,
    /// The verification gate's wall tolerance: a wall of map b meets a wall of map a within this many cells
    /// (1: the 3x3 neighbourhood; 2 lets the walls of two robots' SLAM runs meet).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=4))]
    pub wall_tolerance: u32,
    /// Seed of the SLAM filter (every part), of the injected drift and of the mergers' draws.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Odometry errors added to the whole log's before it is split (as `mrslam slam --drift-*`): how merging
    /// holds up when the robots' odometry is worse.
    #[command(flatten)]
    pub drift: crate::cmd::slam::DriftArgs,
    /// Relation stamps match a scan's stamp within this many seconds.
    #[arg(long, default_value_t = crate::cmd::eval::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    /// Success: median cross-relation translation error at most this, metres.
    #[arg(long, default_value_t = logs::MAX_ERROR_M)]
    pub max_error_m: f64,
    /// Success: median cross-relation rotation error at most this, degrees.
    #[arg(long, default_value_t = logs::MAX_ERROR_DEG)]
    pub max_error_deg: f64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Continue the interrupted study in --out: parts already mapped there are read back, not mapped again.
    #[arg(long)]
    pub resume: bool,
}

/// The files of part `k` in a logs study's folder: its map (YAML, a PGM beside it) and its trajectory.
fn part_files(out: &Path, k: usize) -> (PathBuf, PathBuf) {
    (out.join(format!("part-{k}.yaml")), out.join(format!("part-{k}.trajectory.txt")))
}

/// A file's name and fingerprint, for `study.json` (a ROS 2 bag folder's: its files' in name order).
fn file_id(path: &Path) -> Result<String> {
    let bytes = if path.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .and_then(|d| d.map(|e| e.map(|e| e.path())).collect())
            .with_context(|| format!("{}", path.display()))?;
        files.sort();
        let mut bytes = Vec::new();
        for f in files.iter().filter(|f| f.is_file()) {
            bytes.extend(std::fs::read(f).with_context(|| format!("{}", f.display()))?);
        }
        bytes
    } else {
        std::fs::read(path).with_context(|| format!("{}", path.display()))?
    };
    Ok(format!("{} {}", path.file_name().map(|f| f.to_string_lossy()).unwrap_or_default(), fingerprint(&bytes)))
}

/// Runs `mrslam study logs`.
pub(super) fn run(a: LogsArgs) -> Result<ExitCode> {
    if a.parts < 2 {
        bail!("--parts {}: a study needs at least 2 parts (robots)", a.parts);
    }
    if !(a.tolerance.is_finite() && a.tolerance >= 0.0) {
        bail!("--tolerance {}: must be a non-negative number of seconds", a.tolerance);
    }
    if !(a.max_error_m >= 0.0 && a.max_error_deg >= 0.0) {
        bail!("--max-error-m and --max-error-deg must not be negative");
    }
    a.drift.validate()?;
    let algorithms = study::parse_algorithms(&a.algorithms.iter().map(|s| s.trim()).collect::<Vec<_>>())?;
    let mut slam = a.preset.params();
    set_each("--slam-set", &a.slam_set, |name, value| slam.set(name, value))?;
    slam.validate().map_err(|e| anyhow::anyhow!("slam parameters: {e}"))?;
    crate::cmd::slam::check_map_resolution("--slam-set", &slam)?;
    // Outputs: never over an input; checked before any work.
    if a.out.is_file() {
        bail!("--out {}: is a file, expected a folder", a.out.display());
    }
    let mut more = vec![a.out.join("parts.csv")];
    for k in 0..a.parts {
        let (map, traj) = part_files(&a.out, k);
        more.extend([map, traj]);
    }
    let outputs = super::study_outputs(&a.out, [a.log.as_path(), a.relations.as_path()], &more);
    if a.out.is_dir() {
        outputs.check()?;
    }
    // The relations before the log: a bad file costs nothing.
    let rels = relations::read_relations(&a.relations)?;

    let mut params = StudyParams::default();
    params
        .set("kind", "logs")
        .set("log", file_id(&a.log)?)
        .set("relations", file_id(&a.relations)?)
        .set("parts", a.parts)
        .set(
            "read",
            format!(
                "odometry {}, max_step_back {}, keep_reversing {}, scan_latency {}{}",
                a.read.odometry,
                a.read.max_step_back,
                a.read.keep_reversing,
                a.read.scan_latency,
                a.read.topics_text()
            ),
        )
        .set("preset", a.preset)
        .set("slam_set", a.slam_set.join(" "))
        .set("seed", a.seed)
        .set("algorithms", algorithms.iter().map(|x| x.name()).collect::<Vec<_>>().join(","))
        .set("encoding", a.encoding)
        .set("wall_tolerance", a.wall_tolerance)
        .set("tolerance", a.tolerance)
        .set("max_error_m", a.max_error_m)
        .set("max_error_deg", a.max_error_deg);
    if !a.drift.is_none() {
        // Only with drift: a study folder from before the flags existed resumes as it was.
        params.set("drift", a.drift.describe());
    }
    create_out(&a.out)?;
    outputs.check()?;
    if a.resume {
        let found = StudyParams::read(&a.out)?.with_context(|| {
            format!("{}: nothing to resume: no study was started in this folder", a.out.join("study.json").display())
        })?;
        params.check_same(&found, &a.out.join("study.json"), "cannot resume")?;
    } else {
        for f in ["study.json", "results.csv"] {
            let p = a.out.join(f);
            if p.exists() {
                bail!(
                    "{}: the folder already holds a study: --resume continues it, or choose another --out",
                    p.display()
                );
            }
        }
    }

    let mut log = a.read.read(&a.log)?;
    if log.scans.is_empty() {
        bail!("{}: no laser scans in the log", a.log.display());
    }
    // The drift asked for; then the scan lines' odometry of a log without a stream re-timed by its lag, as
    // `mrslam slam` does.
    let retimed = log.odometry.is_empty() && slam.scan_odometry.enabled && slam.scan_odometry.line_lag;
    if retimed || !a.drift.is_none() {
        let mut odometry: Vec<_> = log.scans.iter().map(|r| r.odometry).collect();
        a.drift.inject(&mut odometry, a.seed);
        if retimed {
            let scans: Vec<&mrslam_core::LaserScan> = log.scans.iter().map(|r| &r.scan).collect();
            let offset = log.scans[0].laser_offset;
            mrslam_slam::odometry_lag::retime_line_odometry(&mut odometry, &scans, &slam, offset);
        }
        for (r, o) in log.scans.iter_mut().zip(odometry) {
            r.odometry = o;
        }
    }
    let stamps: Vec<f64> = log.scans.iter().map(|r| r.scan.stamp).collect();
    let ranges = logs::split_by_time(&stamps, a.parts).with_context(|| format!("{}", a.log.display()))?;
    // The study starts producing here: study.json is written only now, so that a start that fails on its log
    // leaves nothing that blocks the corrected retry.
    if !a.resume {
        params.write(&a.out)?;
    }
    let start = Instant::now();
    let mut parts = Vec::with_capacity(a.parts);
    let mut parts_csv = String::from("part,first_stamp,last_stamp,scans,processed,slam_s,width,height,known_cells\n");
    // A resumed study keeps what its parts.csv said of the parts it reads back (their SLAM counts and time).
    let earlier: BTreeMap<usize, String> = std::fs::read_to_string(a.out.join("parts.csv"))
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter_map(|l| Some((l.split(',').next()?.parse().ok()?, format!("{l}\n"))))
        .collect();
    for (k, range) in ranges.iter().enumerate() {
        let scans = &log.scans[range.clone()];
        let (map_path, traj_path) = part_files(&a.out, k);
        let (first, last) = (scans[0].scan.stamp, scans[scans.len() - 1].scan.stamp);
        let (part, line) = if a.resume && map_path.exists() && traj_path.exists() {
            let map = map_io::read_ros_map(&map_path).with_context(|| format!("{}", map_path.display()))?;
            let trajectory = relations::read_trajectory(&traj_path)?;
            println!(
                "part {k}: {} scans ({first:.1} s to {last:.1} s): read back from {}",
                scans.len(),
                map_path.display()
            );
            (logs::PartMap { map, trajectory, processed: 0, seconds: 0.0 }, earlier.get(&k).cloned())
        } else {
            let bar = ProgressBar::new(scans.len() as u64);
            if a.quiet || !std::io::stderr().is_terminal() {
                bar.set_draw_target(ProgressDrawTarget::hidden());
            }
            bar.set_style(
                ProgressStyle::with_template("{msg} {bar:40} {pos}/{len} scans [{elapsed_precise}<{eta_precise}]")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar.set_message(format!("part {k}/{}", a.parts));
            let part = logs::map_part(scans, &slam, a.seed, &a.log, &mut || bar.inc(1))?;
            bar.finish_and_clear();
            map_io::write_ros_map_with_preview(&part.map, &map_path)
                .with_context(|| format!("{}", map_path.display()))?;
            let header = format!(
                "mrslam study logs: part {k} of {} of {} ({}), one pose per scan, `stamp x y theta`, \
                 in the part's map frame ({} scans processed by the filter, the others placed by odometry)",
                a.parts,
                a.log.display(),
                readings(&scans[0].source, &scans[scans.len() - 1].source),
                part.processed
            );
            write_file_atomic(&traj_path, relations::format_trajectory(&header, &part.trajectory).as_bytes())?;
            println!(
                "part {k}: {} scans ({first:.1} s to {last:.1} s), {} processed, mapped in {:.1} s: {}",
                scans.len(),
                part.processed,
                part.seconds,
                map_path.display()
            );
            // Merge the map and trajectory as written (what `mrslam merge part-0.yaml part-1.yaml` reads), so
            // that a resumed study computes exactly the rows of an uninterrupted one.
            let map = map_io::read_ros_map(&map_path).with_context(|| format!("{}", map_path.display()))?;
            let trajectory = relations::read_trajectory(&traj_path)?;
            (logs::PartMap { map, trajectory, ..part }, None)
        };
        let (free, occ, _) = part.map.state_counts();
        parts_csv += &line.unwrap_or_else(|| {
            format!(
                "{k},{first:.6},{last:.6},{},{},{:.3},{},{},{}\n",
                scans.len(),
                part.processed,
                part.seconds,
                part.map.width(),
                part.map.height(),
                free + occ
            )
        });
        // Rewritten after each part, so that a resume knows what the parts it reads back cost.
        write_file_atomic(&a.out.join("parts.csv"), parts_csv.as_bytes())?;
        parts.push(part);
    }

    let trajectories: Vec<&[relations::StampedPose]> = parts.iter().map(|p| p.trajectory.as_slice()).collect();
    let cross = logs::cross_relations(&rels, &trajectories, a.tolerance);
    for i in 0..a.parts {
        for j in i + 1..a.parts {
            if !cross.contains_key(&(i, j)) {
                println!("parts {i} and {j}: no relation connects them; not merged");
            }
        }
    }
    if cross.is_empty() {
        bail!(
            "{}: no relation has its two stamps in two different parts (within --tolerance {} s): nothing to merge",
            a.relations.display(),
            a.tolerance
        );
    }
    let score = ScoreParams {
        max_error_m: a.max_error_m,
        max_error_deg: a.max_error_deg,
        seed: a.seed,
        encoding: a.encoding,
        wall_tolerance_cells: a.wall_tolerance as usize,
    };
    let mut rows: Vec<PairRow> = Vec::new();
    for (&(i, j), c) in &cross {
        for &alg in &algorithms {
            rows.push(logs::merge_pair(alg, (i, &parts[i].map), (j, &parts[j].map), c, &score)?);
        }
    }
    let summary = logs::summarise_pairs(&rows);
    logs::write_pair_rows(&rows, &a.out.join("results.csv"))?;
    logs::write_algorithm_summary(&summary, &a.out.join("summary.csv"))?;
    let trial_rows: Vec<TrialRow> = rows.iter().enumerate().map(|(k, r)| r.to_trial_row(k)).collect();
    study::plot::draw(&summarise(&trial_rows), &a.out.join("plot.png"))?;
    print!("{}", logs::pairs_table(&rows, &summary));
    println!(
        "{} parts, {} connected pairs, {} merges in {:.1} s",
        a.parts,
        cross.len(),
        rows.len(),
        start.elapsed().as_secs_f64()
    );
    println!(
        "outputs:  {} (study.json, results.csv, summary.csv, plot.png, parts.csv, part-K.yaml + .pgm + .png, \
         part-K.trajectory.txt)",
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The part's readings as its trajectory header names them: "lines 5 to 900" in a text log.
fn readings(first: &mrslam_log::Source, last: &mrslam_log::Source) -> String {
    match (first, last) {
        (mrslam_log::Source::Line(a), mrslam_log::Source::Line(b)) => format!("lines {a} to {b}"),
        _ => mrslam_log::span(first, last),
    }
}
