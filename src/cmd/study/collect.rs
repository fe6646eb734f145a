//! `mrslam study collect`: join the results of a study's shards (a team study's by its own columns).

use super::{create_out, finish};
use anyhow::{Result, bail};
use clap::Args;
use mrslam_studies::journal::{StudyParams, collect_params};
use mrslam_studies::results::collect;
use mrslam_studies::team::collect_team;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam study collect`.
#[derive(Args)]
pub struct CollectArgs {
    /// Shard output folders, each with a results.csv (of one study: overlap, scenario or team).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder of the joined study.
    #[arg(long)]
    pub out: PathBuf,
    /// Collect the shards given although some of the study's are missing (each shard's study.json names its
    /// shard K/N); by default a missing shard is an error.
    #[arg(long)]
    pub partial: bool,
}

/// Runs `mrslam study collect`.
pub(super) fn run(a: CollectArgs) -> Result<ExitCode> {
    for d in &a.dirs {
        if d.canonicalize().ok().is_some_and(|c| a.out.canonicalize().ok() == Some(c)) {
            bail!("--out {}: is one of the shard folders; its results.csv would be overwritten", a.out.display());
        }
    }
    // The first folder's study.json says whose columns results.csv has; the others must be of the same study.
    let team = match a.dirs.first().map(|d| StudyParams::read(d)).transpose()?.flatten() {
        Some(p) => p.0.get("kind").is_some_and(|k| k == "team"),
        None => false,
    };
    // A trial found twice (a shard given twice) first, then shards of other studies or missing ones.
    if team {
        let rows = collect_team(&a.dirs)?;
        let missing = write_params(&a)?;
        report(rows.len(), rows.len(), &a, &missing);
        return super::team::finish(&rows, &a.out, rows.len(), None);
    }
    let rows = collect(&a.dirs)?;
    let missing = write_params(&a)?;
    let mut trials: Vec<usize> = rows.iter().map(|r| r.trial).collect();
    trials.dedup();
    report(rows.len(), trials.len(), &a, &missing);
    finish(&rows, &a.out, trials.len(), None)
}

/// Checks that the shards are of one study (and all there, unless `--partial`), then writes its parameters into
/// the output folder; returns the missing shards.
fn write_params(a: &CollectArgs) -> Result<Vec<String>> {
    let (params, missing) = collect_params(&a.dirs, a.partial)?;
    create_out(&a.out)?;
    if let Some(p) = &params {
        p.write(&a.out)?;
    }
    Ok(missing)
}

/// Says what was collected and which shards are missing.
fn report(rows: usize, trials: usize, a: &CollectArgs, missing: &[String]) {
    println!("collected {rows} rows ({trials} trials) from {} shard folders", a.dirs.len());
    if !missing.is_empty() {
        println!("missing:   shards {} (--partial: the summary covers only the trials collected)", missing.join(", "));
    }
}
