//! `mrslam study collect`: join the results of a study's shards.

use super::{create_out, finish};
use anyhow::{Result, bail};
use clap::Args;
use mrslam_studies::journal::collect_params;
use mrslam_studies::results::collect;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam study collect`.
#[derive(Args)]
pub struct CollectArgs {
    /// Shard output folders, each with a results.csv.
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
    // A trial found twice (a shard given twice) first, then shards of other studies or missing ones.
    let rows = collect(&a.dirs)?;
    let (params, missing) = collect_params(&a.dirs, a.partial)?;
    create_out(&a.out)?;
    if let Some(p) = &params {
        p.write(&a.out)?;
    }
    let mut trials: Vec<usize> = rows.iter().map(|r| r.trial).collect();
    trials.dedup();
    println!("collected {} rows ({} trials) from {} shard folders", rows.len(), trials.len(), a.dirs.len());
    if !missing.is_empty() {
        println!("missing:   shards {} (--partial: the summary covers only the trials collected)", missing.join(", "));
    }
    finish(&rows, &a.out, trials.len(), None)
}
