//! `mrslam study scenario`: a scenario sweep (simulation, SLAM, merge), each merge scored.

use super::{finish, open_study, run_study, shard_of};
use anyhow::{Context, Result};
use clap::Args;
use mrslam_studies::journal::{StudyParams, fingerprint};
use mrslam_studies::results::sort_rows;
use mrslam_studies::{Sweep, run_sweep};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam study scenario`.
#[derive(Args)]
pub struct ScenarioArgs {
    /// Sweep file (TOML), e.g. scenarios/corridor_sweep.toml.
    pub sweep: PathBuf,
    /// Output folder: study.json, results.csv, summary.csv, plot.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Sharding, resuming and progress.
    #[command(flatten)]
    pub run: super::StudyRun,
    /// Read and check the sweep, list its trials, run nothing.
    #[arg(long)]
    pub dry_run: bool,
}

/// Runs `mrslam study scenario`.
pub(super) fn run(a: ScenarioArgs) -> Result<ExitCode> {
    let shard = shard_of(a.run.shard.as_deref())?;
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
    super::name_shard(&mut params, shard, (0..sweep.trials()).filter(|t| shard.selects(*t)).count());
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
    let inputs = [sweep.path.as_path(), sweep.scenario.path.as_path(), sweep.scenario.world_path.as_path()];
    let (journal, earlier) = open_study(&a.out, inputs, &[], &params, algorithms.len(), a.run.resume)?;
    let selected: Vec<usize> = (0..sweep.trials()).filter(|t| shard.selects(*t)).collect();
    let (mut rows, n, seconds) =
        run_study(earlier, journal, &selected, a.run.quiet, &sweep.scenario.name, |p| run_sweep(&sweep, shard, p))?;
    sort_rows(&mut rows, &algorithms);
    finish(&rows, &a.out, n, Some(seconds))
}
