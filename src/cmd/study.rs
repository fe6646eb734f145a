//! `mrslam study`: many seeded merge trials across overlaps — map level (`overlap`), simulation level
//! (`scenario`), and joining the shards of a study split across machines (`collect`).

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_merge::floorplan::FloorplanParams;
use mrslam_testbed::study::journal::{collect_params, fingerprint};
use mrslam_testbed::study::results::sort_rows;
use mrslam_testbed::study::{
    self, Journal, MapSource, OverlapStudy, Progress, Shard, StudyError, StudyParams, Sweep, TrialRow, collect,
    parse_range, run_overlap_study, run_sweep, summary::table,
};
use std::collections::BTreeSet;
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
    /// Algorithms, comma-separated (sift, rmap, correlative).
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

/// Runs `mrslam study`.
pub fn run(cmd: StudyCommand) -> Result<ExitCode> {
    match cmd {
        StudyCommand::Overlap(a) => overlap(a),
        StudyCommand::Scenario(a) => scenario(a),
        StudyCommand::Collect(a) => collect_cmd(a),
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
        .set("max_shift", a.max_shift);
    let (journal, earlier) = open_study(&a.out, &params, algorithms.len(), a.resume)?;
    let selected: Vec<usize> = study.selected_trials().iter().map(|t| t.trial).collect();
    let (rows, n, seconds) = run_study(earlier, journal, &selected, &algorithms, a.quiet, "overlap study", |p| {
        run_overlap_study(&study, p)
    })?;
    finish(&rows, &a.out, n, Some(seconds))
}

/// A grid's size, resolution, origin and cells as bytes, for its fingerprint.
fn grid_bytes(g: &mrslam_core::OccupancyGrid) -> Vec<u8> {
    let (x, y, t) = mrslam_core::pose_xyt(g.origin());
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
