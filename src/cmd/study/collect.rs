//! `mrslam study collect`: join the results of a study's shards (a team study's by its own columns).

use super::{create_out, finish};
use anyhow::{Result, bail};
use clap::Args;
use mrslam_studies::journal::{PARAMS_FILE, RESULTS_FILE, StudyParams, collect_params, incomplete_shards};
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
    /// Output folder of the joined study (made when its parent exists; a folder holding another study's results
    /// is refused).
    #[arg(long)]
    pub out: PathBuf,
    /// Collect the shards given although some of the study's are missing, or hold fewer trials than they run
    /// (interrupted); each shard's study.json names its shard K/N. By default either is an error.
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
    // Before anything is written: no trial found twice (a shard given twice), the shards of one study, all there
    // and complete (unless `--partial`), and the output folder holding no other study's results.
    if team {
        let rows = collect_team(&a.dirs)?;
        let missing = check_shards(&a)?;
        report(rows.len(), rows.len(), &a, &missing);
        return super::team::finish(&rows, &a.out, rows.len(), None);
    }
    let rows = collect(&a.dirs)?;
    let missing = check_shards(&a)?;
    let mut trials: Vec<usize> = rows.iter().map(|r| r.trial).collect();
    trials.dedup();
    report(rows.len(), trials.len(), &a, &missing);
    finish(&rows, &a.out, trials.len(), None)
}

/// Checks the shards (one study; all there and complete unless `--partial`) and the output folder, then writes
/// the study's parameters there; returns what is missing (shards, and the trials of incomplete shards).
fn check_shards(a: &CollectArgs) -> Result<Vec<String>> {
    let (params, mut missing) = collect_params(&a.dirs, a.partial)?;
    let incomplete = incomplete_shards(&a.dirs)?;
    if !incomplete.is_empty() && !a.partial {
        bail!(
            "collect: incomplete shard{} (interrupted? `--resume` it, or --partial to collect it anyway): {}",
            if incomplete.len() > 1 { "s" } else { "" },
            incomplete.join("; ")
        );
    }
    missing.extend(incomplete.iter().map(|s| format!("part of {s}")));
    check_out(a, params.as_ref())?;
    create_out(&a.out)?;
    if let Some(p) = &params {
        p.write(&a.out)?;
    }
    Ok(missing)
}

/// Refuses an output folder that holds the results of a study other than the one collected (`params`); the
/// same study collected again (more shards, say) is replaced.
fn check_out(a: &CollectArgs, params: Option<&StudyParams>) -> Result<()> {
    let results = a.out.join(RESULTS_FILE);
    if !results.exists() {
        return Ok(());
    }
    let found = StudyParams::read(&a.out)?;
    match (found, params) {
        (Some(found), Some(p)) => {
            p.check_same(&found, &a.out.join(PARAMS_FILE), "--out holds another study: choose another --out")?;
            Ok(())
        }
        _ => bail!(
            "{}: --out already holds a study's results, and its study.json does not say it is this study: choose \
             another --out",
            results.display()
        ),
    }
}

/// Says what was collected and which shards are missing.
fn report(rows: usize, trials: usize, a: &CollectArgs, missing: &[String]) {
    println!("collected {rows} rows ({trials} trials) from {} shard folders", a.dirs.len());
    if !missing.is_empty() {
        println!("missing:   shards {} (--partial: the summary covers only the trials collected)", missing.join(", "));
    }
}
