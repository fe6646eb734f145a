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
}

/// Runs `mrslam study collect`.
pub(super) fn run(a: CollectArgs) -> Result<ExitCode> {
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
