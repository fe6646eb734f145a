//! `mrslam run SCENARIO.toml`: a paper scenario end to end — simulate, map, merge, evaluate, report.

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_merge::Algorithm;
use mrslam_testbed::runner::{RunOptions, run as run_scenario, write_outputs};
use mrslam_testbed::scenario::Scenario;
use mrslam_viz::RunRecorder;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `mrslam run`.
#[derive(Args)]
pub struct RunArgs {
    /// Scenario file (TOML), e.g. scenarios/paper_corridor.toml.
    pub scenario: PathBuf,
    /// Output folder (default: out/NAME, NAME being the scenario's name).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Merge algorithm to run instead of the scenario's: one name, or `all` to compare them on the same maps.
    #[arg(long)]
    pub algorithm: Option<String>,
    /// Override the scenario's seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Rerun recording of the run.
    #[command(flatten)]
    pub viz: super::viz::VizArgs,
}

/// Runs `mrslam run`.
pub fn run(args: RunArgs) -> Result<ExitCode> {
    if let Some(rrd) = &args.viz.rrd {
        // A folder or a missing folder is reported when the recording opens.
        if !rrd.is_dir() {
            super::paths::check_extension(rrd, "--rrd", &["rrd"])?;
        }
        super::paths::check_not_input(rrd, &[&args.scenario])?;
    }
    let mut scenario = Scenario::from_file(&args.scenario)?;
    if let Some(s) = args.seed {
        scenario.seed = s;
    }
    let algorithms = match args.algorithm.as_deref() {
        None => None,
        Some("all") => Some(Algorithm::ALL.to_vec()),
        Some(a) => match a.parse::<Algorithm>() {
            Ok(a) => Some(vec![a]),
            Err(_) => bail!("--algorithm {a}: unknown (expected {} or all)", Algorithm::names()),
        },
    };
    let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from("out").join(&scenario.name));
    // Fail before a long run if the output folder cannot be made.
    std::fs::create_dir_all(&out_dir)
        .map_err(|e| anyhow::anyhow!("{}: cannot create output folder: {e}", out_dir.display()))?;
    // The same for the recording: a file that cannot be written, or no viewer, fails here.
    let recording_id = format!("{}-seed{}", scenario.name, scenario.seed);
    let name = format!("{} (seed {})", scenario.name, scenario.seed);
    let mut viz = args.viz.open(&recording_id, &name)?.map(RunRecorder::new);
    let bar = ProgressBar::new((scenario.duration * 10.0) as u64);
    if args.quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {prefix} sim s, {elapsed} wall, ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(scenario.name.clone());
    let opts = RunOptions {
        algorithms,
        // The bar runs to the expected end of the run (a rendezvous usually comes long before the duration).
        progress: Some(Box::new(|t: f64, end: f64| {
            bar.set_length((end.max(t) * 10.0) as u64);
            bar.set_position((t * 10.0) as u64);
            bar.set_prefix(format!("{t:.0}/{end:.0}"));
        })),
        viz: viz.as_mut(),
        on_step: None,
    };
    let out = run_scenario(&scenario, opts)?;
    bar.finish_and_clear();
    write_outputs(&out, &out_dir)?;
    remove_stale_recordings(&out_dir, args.viz.rrd.as_deref())?;
    print!("{}", out.report.summary());
    println!("outputs:  {}", out_dir.display());
    if let Some(v) = viz {
        let stats = v.finish()?;
        println!("rerun:    {} ({} rows in {} chunks)", args.viz.describe(), stats.rows, stats.chunks);
    }
    Ok(ExitCode::SUCCESS)
}

/// Removes the `.rrd` recordings an earlier run left in `dir`, keeping this run's (`keep`, and the partial file
/// it is being written to): a folder's recording always shows the run whose report and maps sit beside it.
fn remove_stale_recordings(dir: &Path, keep: Option<&Path>) -> Result<()> {
    let kept: Vec<PathBuf> = keep
        .into_iter()
        .flat_map(|k| [k.to_path_buf(), mrslam_viz::partial_path(k)])
        .filter_map(|k| k.canonicalize().ok())
        .collect();
    let entries = std::fs::read_dir(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    for entry in entries.flatten() {
        let path = entry.path();
        let is_rrd = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("rrd")) && path.is_file();
        if is_rrd && !path.canonicalize().is_ok_and(|p| kept.contains(&p)) {
            std::fs::remove_file(&path)
                .map_err(|e| anyhow::anyhow!("{}: cannot remove a stale recording: {e}", path.display()))?;
            println!("removed:  {} (the recording of an earlier run)", path.display());
        }
    }
    Ok(())
}
