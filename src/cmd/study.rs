//! `mrslam study`: many seeded merge trials across overlaps — map level (`overlap`), simulation level
//! (`scenario`), real data (`logs`: a real log split in time into robots), and joining the shards of a study
//! split across machines (`collect`).

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_core::Xyt;
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_core::relations;
use mrslam_merge::MapEncoding;
use mrslam_merge::floorplan::FloorplanParams;
use mrslam_slam::Preset;
use mrslam_studies::journal::{Journal, StudyParams, collect_params, fingerprint};
use mrslam_studies::logs::{self, PairRow, ScoreParams};
use mrslam_studies::overlap::{MapSource, MapStyle, OverlapStudy, run_overlap_study};
use mrslam_studies::results::{TrialRow, collect, sort_rows};
use mrslam_studies::summary::{summarise, table};
use mrslam_studies::{self as study, Progress, Shard, StudyError, Sweep, parse_range, run_sweep};
use std::collections::{BTreeMap, BTreeSet};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// `mrslam study` subcommands.
#[derive(Subcommand)]
pub enum StudyCommand {
    /// Map-level study: cut ground-truth maps into pairs of chosen overlap, merge with each algorithm.
    Overlap(OverlapArgs),
    /// Simulation-level study: run a scenario sweep (simulation, SLAM, merge) and score each merge.
    Scenario(ScenarioArgs),
    /// Join the results.csv of a study's shards, then redraw summary.csv and plot.png.
    Collect(CollectArgs),
    /// Real-data study: split a CARMEN log in time into N robots, map each with the SLAM, merge every pair
    /// the relations connect with each algorithm, score against the relations.
    Logs(LogsArgs),
}

/// Arguments of `mrslam study overlap`.
#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["map", "world", "floorplans"]))]
pub struct OverlapArgs {
    /// Ground truth: a ROS map_server map (YAML); every pair is cut from it.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Ground truth: a world file (TOML); pairs are cut from its true map.
    #[arg(long)]
    pub world: Option<PathBuf>,
    /// Ground truth: this many generated floor plans (repetition r uses plan r mod N).
    #[arg(long)]
    pub floorplans: Option<usize>,
    /// Size of the generated floor plans, metres, WIDTHxHEIGHT.
    #[arg(long, default_value = "24x18")]
    pub floorplan_size: String,
    /// Cell size of a world's true map or of generated floor plans, metres.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Target overlaps: start:stop:step (stop included), a list a,b,c, or one value.
    #[arg(long, default_value = "0.05:0.7:0.05")]
    pub overlaps: String,
    /// Trials per overlap.
    #[arg(long, default_value_t = 30)]
    pub trials: usize,
    /// Algorithms, comma-separated (sift, rmap, correlative, cascade); the default compares the paper's two.
    #[arg(long, default_value = "sift,rmap", value_delimiter = ',')]
    pub algorithms: Vec<String>,
    /// Output folder: results.csv, summary.csv, plot.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Run only shard K of N (trial index mod N = K); default from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT.
    #[arg(long)]
    pub shard: Option<String>,
    /// Study seed: every trial is seeded from (seed, overlap index, trial index).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Success: rotation error at most this, degrees.
    #[arg(long, default_value_t = 2.0)]
    pub max_rotation_deg: f64,
    /// Success: translation error at most this many cells.
    #[arg(long, default_value_t = 2.0)]
    pub max_translation_cells: f64,
    /// Largest shift of the moved half of a pair, metres.
    #[arg(long, default_value_t = 5.0)]
    pub max_shift: f64,
    /// How the pairs store walls: `walls` (occupied cells, as cut) or `boundary` (walls dropped to unknown in
    /// both maps: the structure only in the free/unknown boundary, as map_server reads light-grey walls).
    #[arg(long, default_value = "walls", value_parser = ["walls", "boundary"])]
    pub map_style: String,
    /// The SIFT merger's map-to-image encoding: `walls` (the default) or `paper` (unknown grey).
    #[arg(long, default_value = "walls", value_parser = ["walls", "paper"])]
    pub encoding: String,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Continue the interrupted study in --out: run only the trials its results.csv lacks.
    #[arg(long)]
    pub resume: bool,
}

/// Arguments of `mrslam study scenario`.
#[derive(Args)]
pub struct ScenarioArgs {
    /// Sweep file (TOML), e.g. scenarios/corridor_sweep.toml.
    pub sweep: PathBuf,
    /// Output folder: results.csv, summary.csv, plot.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Run only shard K of N (trial index mod N = K); default from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT.
    #[arg(long)]
    pub shard: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Read and check the sweep, list its trials, run nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Continue the interrupted study in --out: run only the trials its results.csv lacks.
    #[arg(long)]
    pub resume: bool,
}

/// Arguments of `mrslam study collect`.
#[derive(Args)]
pub struct CollectArgs {
    /// Shard output folders, each with a results.csv.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder of the joined study.
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `mrslam study logs`.
#[derive(Args)]
pub struct LogsArgs {
    /// CARMEN log (.clf/.log, gzipped or not).
    pub log: PathBuf,
    /// The log's benchmark relations (Kümmerle et al. 2009): the ground truth of each pair of parts.
    #[arg(long)]
    pub relations: PathBuf,
    /// Number of parts ("robots"): consecutive stretches of the log of equal duration, at least 2.
    #[arg(long)]
    pub parts: usize,
    /// Output folder: study.json, results.csv, summary.csv, plot.png, parts.csv, part-K.yaml/.pgm and
    /// part-K.trajectory.txt (each part's map and its pose at every scan).
    #[arg(long)]
    pub out: PathBuf,
    /// How to read the log.
    #[command(flatten)]
    pub read: super::log::ReadArgs,
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
    #[arg(long, default_value = "walls", value_parser = ["walls", "paper"])]
    pub encoding: String,
    /// The verification gate's wall tolerance: a wall of map b meets a wall of map a within this many cells
    /// (1: the 3x3 neighbourhood, the gate before 2026-12-02; 2 lets the walls of two robots' SLAM runs meet).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=4))]
    pub wall_tolerance: u32,
    /// Seed of the SLAM filter (every part), of the injected drift and of the mergers' draws.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Odometry errors added to the whole log's before it is split (as `mrslam slam --drift-*`): how merging
    /// holds up when the robots' odometry is worse.
    #[command(flatten)]
    pub drift: super::slam::DriftArgs,
    /// Relation stamps match a scan's stamp within this many seconds.
    #[arg(long, default_value_t = super::eval::DEFAULT_TOLERANCE)]
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

/// Runs `mrslam study`.
pub fn run(cmd: StudyCommand) -> Result<ExitCode> {
    match cmd {
        StudyCommand::Overlap(a) => overlap(a),
        StudyCommand::Scenario(a) => scenario(a),
        StudyCommand::Collect(a) => collect_cmd(a),
        StudyCommand::Logs(a) => logs(a),
    }
}

fn shard_of(arg: Option<&str>) -> Result<Shard> {
    Ok(match arg {
        Some(s) => Shard::parse(s).context("--shard")?,
        None => Shard::from_slurm(|k| std::env::var(k).ok())?.unwrap_or(Shard::ALL),
    })
}

fn progress_bar(len: usize, quiet: bool, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} trials, {per_sec}, {elapsed} elapsed, ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

fn create_out(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create output folder", dir.display()))
}

/// A running study's progress: the trials done before a resume are skipped; each finished trial's rows are
/// appended to results.csv at once, so an interruption loses no finished trial.
struct Recorder {
    journal: Journal,
    done: BTreeSet<usize>,
    bar: ProgressBar,
}

impl Progress for Recorder {
    fn skip(&self, trial: usize) -> bool {
        self.done.contains(&trial)
    }

    fn finished(&self, rows: &[TrialRow]) -> Result<(), StudyError> {
        self.journal.append(rows)?;
        self.bar.inc(1);
        Ok(())
    }
}

/// Opens the study folder (fresh or resumed) and says what a resume found.
fn open_study(
    out: &Path,
    params: &StudyParams,
    rows_per_trial: usize,
    resume: bool,
) -> Result<(Journal, Vec<TrialRow>)> {
    create_out(out)?;
    let (journal, earlier) = Journal::open(out, params, rows_per_trial, resume)?;
    if resume {
        let trials: BTreeSet<usize> = earlier.iter().map(|r| r.trial).collect();
        println!("resuming {}: {} trials already done", out.display(), trials.len());
    }
    Ok((journal, earlier))
}

/// Runs the trials not yet done, then joins the rows with those of before the resume.
fn run_study(
    earlier: Vec<TrialRow>,
    journal: Journal,
    selected: &[usize],
    algorithms: &[String],
    quiet: bool,
    what: &str,
    run: impl FnOnce(&Recorder) -> Result<Vec<TrialRow>, StudyError>,
) -> Result<(Vec<TrialRow>, usize, f64)> {
    let done: BTreeSet<usize> = earlier.iter().map(|r| r.trial).collect();
    let n = selected.iter().filter(|t| !done.contains(t)).count();
    let recorder = Recorder { journal, done, bar: progress_bar(n, quiet, what) };
    let start = Instant::now();
    let new = run(&recorder)?;
    let seconds = start.elapsed().as_secs_f64();
    recorder.bar.finish_and_clear();
    let mut rows = earlier;
    rows.extend(new);
    sort_rows(&mut rows, algorithms);
    Ok((rows, n, seconds))
}

fn finish(rows: &[TrialRow], out: &Path, trials: usize, seconds: Option<f64>) -> Result<ExitCode> {
    let summary = study::write_outputs(rows, out)?;
    print!("{}", table(&summary));
    if let Some(s) = seconds {
        println!("{trials} trials ({} rows) in {s:.1} s: {:.2} trials/s", rows.len(), trials as f64 / s.max(1e-9));
    }
    println!("outputs:  {} (study.json, results.csv, summary.csv, plot.png)", out.display());
    Ok(ExitCode::SUCCESS)
}

fn floorplan_size(s: &str) -> Result<(f64, f64)> {
    s.split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?)))
        .filter(|(w, h)| (4.0..=500.0).contains(w) && (4.0..=500.0).contains(h))
        .with_context(|| format!("--floorplan-size {s}: expected WIDTHxHEIGHT in metres, each 4..500, e.g. 24x18"))
}

fn overlap(a: OverlapArgs) -> Result<ExitCode> {
    let shard = shard_of(a.shard.as_deref())?;
    let overlaps = parse_range(&a.overlaps).context("--overlaps")?;
    if a.trials == 0 {
        bail!("--trials must be at least 1");
    }
    if !(a.resolution > 0.0 && a.resolution.is_finite()) {
        bail!("--resolution must be positive, got {}", a.resolution);
    }
    let mut params = StudyParams::default();
    params.set("kind", "overlap");
    let source = if let Some(path) = &a.map {
        let grid = super::map::read_yaml_map(path).with_context(|| format!("--map {}", path.display()))?;
        params.set("map", fingerprint(&grid_bytes(&grid)));
        MapSource::Map(grid)
    } else if let Some(path) = &a.world {
        let grid = study::overlap::world_truth(path, a.resolution).context("--world")?;
        params.set("world", fingerprint(&grid_bytes(&grid)));
        MapSource::Map(grid)
    } else {
        let (w, h) = floorplan_size(&a.floorplan_size)?;
        let count = a.floorplans.unwrap_or(1);
        params.set("floorplans", format!("{count} of {w}x{h} m"));
        let fp = FloorplanParams { width_m: w, height_m: h, resolution: a.resolution, ..FloorplanParams::default() };
        MapSource::Floorplans { count, params: fp }
    };
    let study = OverlapStudy {
        source,
        overlaps,
        trials: a.trials,
        algorithms: study::parse_algorithms(&a.algorithms.iter().map(|s| s.trim()).collect::<Vec<_>>())?,
        seed: a.seed,
        max_rotation_deg: a.max_rotation_deg,
        max_translation_cells: a.max_translation_cells,
        max_shift_m: a.max_shift,
        shard,
        style: if a.map_style == "boundary" { MapStyle::Boundary } else { MapStyle::Walls },
        encoding: if a.encoding == "paper" { MapEncoding::PAPER } else { MapEncoding::WALLS },
    };
    study.validate()?;
    let overlaps: Vec<String> = study.overlaps.iter().map(|o| o.to_string()).collect();
    let algorithms: Vec<String> = study.algorithms.iter().map(|x| x.name().to_string()).collect();
    params
        .set("resolution", a.resolution)
        .set("overlaps", overlaps.join(","))
        .set("trials", a.trials)
        .set("algorithms", algorithms.join(","))
        .set("seed", a.seed)
        .set("max_rotation_deg", a.max_rotation_deg)
        .set("max_translation_cells", a.max_translation_cells)
        .set("max_shift", a.max_shift)
        .set("map_style", &a.map_style)
        .set("encoding", &a.encoding);
    let (journal, earlier) = open_study(&a.out, &params, algorithms.len(), a.resume)?;
    let selected: Vec<usize> = study.selected_trials().iter().map(|t| t.trial).collect();
    let (rows, n, seconds) = run_study(earlier, journal, &selected, &algorithms, a.quiet, "overlap study", |p| {
        run_overlap_study(&study, p)
    })?;
    finish(&rows, &a.out, n, Some(seconds))
}

/// A grid's size, resolution, origin and cells as bytes, for its fingerprint.
fn grid_bytes(g: &mrslam_core::OccupancyGrid) -> Vec<u8> {
    let Xyt { x, y, theta: t } = Xyt::from_pose(g.origin());
    let mut b = format!("{} {} {} {x} {y} {t}\n", g.width(), g.height(), g.resolution()).into_bytes();
    for c in g.cells() {
        b.extend_from_slice(&c.to_bits().to_le_bytes());
    }
    b
}

fn scenario(a: ScenarioArgs) -> Result<ExitCode> {
    let shard = shard_of(a.shard.as_deref())?;
    let sweep = Sweep::from_file(&a.sweep)?;
    if a.dry_run {
        println!(
            "{}: scenario {}, {} trials ({} variants x {} seeds), algorithms {}",
            a.sweep.display(),
            sweep.scenario.name,
            sweep.trials(),
            sweep.variants(),
            sweep.seeds.len(),
            sweep.algorithms.iter().map(|a| a.name()).collect::<Vec<_>>().join(",")
        );
        if let Some(d) = &sweep.scenario.description {
            println!("  {d}");
        }
        for t in (0..sweep.trials()).filter(|t| shard.selects(*t)) {
            println!("trial {t}: {}", sweep.describe(t));
        }
        return Ok(ExitCode::SUCCESS);
    }
    let mut params = StudyParams::default();
    params.set("kind", "scenario");
    for (name, path) in
        [("sweep", &sweep.path), ("scenario", &sweep.scenario.path), ("world", &sweep.scenario.world_path)]
    {
        let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
        params.set(
            name,
            format!("{} {}", path.file_name().map(|f| f.to_string_lossy()).unwrap_or_default(), fingerprint(&bytes)),
        );
    }
    let algorithms: Vec<String> = sweep.algorithms.iter().map(|x| x.name().to_string()).collect();
    params.set("algorithms", algorithms.join(","));
    params.set("seeds", sweep.seeds.iter().map(u64::to_string).collect::<Vec<_>>().join(","));
    let (journal, earlier) = open_study(&a.out, &params, algorithms.len(), a.resume)?;
    let selected: Vec<usize> = (0..sweep.trials()).filter(|t| shard.selects(*t)).collect();
    let (rows, n, seconds) = run_study(earlier, journal, &selected, &algorithms, a.quiet, &sweep.scenario.name, |p| {
        run_sweep(&sweep, shard, p)
    })?;
    finish(&rows, &a.out, n, Some(seconds))
}

fn collect_cmd(a: CollectArgs) -> Result<ExitCode> {
    for d in &a.dirs {
        if d.canonicalize().ok().is_some_and(|c| a.out.canonicalize().ok() == Some(c)) {
            bail!("--out {}: is one of the shard folders; its results.csv would be overwritten", a.out.display());
        }
    }
    let params = collect_params(&a.dirs)?;
    let rows = collect(&a.dirs)?;
    create_out(&a.out)?;
    if let Some(p) = &params {
        p.write(&a.out)?;
    }
    let mut trials: Vec<usize> = rows.iter().map(|r| r.trial).collect();
    trials.dedup();
    println!("collected {} rows ({} trials) from {} shard folders", rows.len(), trials.len(), a.dirs.len());
    finish(&rows, &a.out, trials.len(), None)
}

/// The files of part `k` in a logs study's folder: its map (YAML, a PGM beside it) and its trajectory.
fn part_files(out: &Path, k: usize) -> (PathBuf, PathBuf) {
    (out.join(format!("part-{k}.yaml")), out.join(format!("part-{k}.trajectory.txt")))
}

/// A file's name and fingerprint, for `study.json`.
fn file_id(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    Ok(format!("{} {}", path.file_name().map(|f| f.to_string_lossy()).unwrap_or_default(), fingerprint(&bytes)))
}

fn logs(a: LogsArgs) -> Result<ExitCode> {
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
    for kv in &a.slam_set {
        let Some((name, value)) = kv.split_once('=') else {
            bail!("--slam-set {kv}: expected NAME=VALUE");
        };
        slam.set(name.trim(), value).map_err(|e| anyhow::anyhow!("--slam-set {kv}: {e}"))?;
    }
    slam.validate().map_err(|e| anyhow::anyhow!("slam parameters: {e}"))?;
    // Outputs: never over an input; checked before any work.
    if a.out.is_file() {
        bail!("--out {}: is a file, expected a folder", a.out.display());
    }
    let inputs = [a.log.as_path(), a.relations.as_path()];
    let mut outputs: Vec<PathBuf> =
        ["study.json", "results.csv", "summary.csv", "plot.png", "parts.csv"].iter().map(|f| a.out.join(f)).collect();
    for k in 0..a.parts {
        let (map, traj) = part_files(&a.out, k);
        outputs.extend([map, traj]);
    }
    if a.out.is_dir() {
        for o in &outputs {
            super::check_not_input(o, &inputs)?;
        }
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
                "odometry {}, max_step_back {}, keep_reversing {}, scan_latency {}",
                a.read.odometry, a.read.max_step_back, a.read.keep_reversing, a.read.scan_latency
            ),
        )
        .set("preset", a.preset)
        .set("slam_set", a.slam_set.join(" "))
        .set("seed", a.seed)
        .set("algorithms", algorithms.iter().map(|x| x.name()).collect::<Vec<_>>().join(","))
        .set("encoding", &a.encoding)
        .set("wall_tolerance", a.wall_tolerance)
        .set("tolerance", a.tolerance)
        .set("max_error_m", a.max_error_m)
        .set("max_error_deg", a.max_error_deg);
    if !a.drift.is_none() {
        // Only with drift: a study folder from before the flags existed resumes as it was.
        params.set("drift", a.drift.describe());
    }
    create_out(&a.out)?;
    for o in &outputs {
        super::check_not_input(o, &inputs)?;
    }
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
        params.write(&a.out)?;
    }

    let mut log = a.read.read(&a.log)?;
    if log.scans.is_empty() {
        bail!("{}: no laser scans in the log", a.log.display());
    }
    if !a.drift.is_none() {
        let mut odometry: Vec<_> = log.scans.iter().map(|r| r.odometry).collect();
        a.drift.inject(&mut odometry, a.seed);
        for (r, o) in log.scans.iter_mut().zip(odometry) {
            r.odometry = o;
        }
    }
    let stamps: Vec<f64> = log.scans.iter().map(|r| r.scan.stamp).collect();
    let ranges = logs::split_by_time(&stamps, a.parts).with_context(|| format!("{}", a.log.display()))?;
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
                "mrslam study logs: part {k} of {} of {} (lines {} to {}), one pose per scan, `stamp x y theta`, \
                 in the part's map frame ({} scans processed by the filter, the others placed by odometry)",
                a.parts,
                a.log.display(),
                scans[0].line,
                scans[scans.len() - 1].line,
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
    let encoding = if a.encoding == "paper" { MapEncoding::PAPER } else { MapEncoding::WALLS };
    let score = ScoreParams {
        max_error_m: a.max_error_m,
        max_error_deg: a.max_error_deg,
        seed: a.seed,
        encoding,
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
        "outputs:  {} (study.json, results.csv, summary.csv, plot.png, parts.csv, part-K.yaml, part-K.trajectory.txt)",
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
