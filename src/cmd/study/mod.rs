//! `mrslam study`: many seeded merge trials across overlaps — map level (`overlap`), simulation level
//! (`scenario`), real data (`logs`: a real log split in time into robots) — team exploration over numbers of
//! robots, ranges, coordinations and mergers (`team`), and joining the shards of a study split across machines
//! (`collect`). One module per subcommand; the progress, resume and output helpers they share here.

mod collect;
mod logs;
mod overlap;
mod scenario;
mod team;

use crate::cmd::{Outputs, kind};
use anyhow::{Context, Result, bail};
use clap::Subcommand;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrslam_studies::journal::{Journal, StudyParams};
use mrslam_studies::results::TrialRow;
use mrslam_studies::summary::table;
use mrslam_studies::{self as study, CsvRow, Progress, Shard, StudyError};
use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// `mrslam study` subcommands.
#[derive(Subcommand)]
pub enum StudyCommand {
    /// Map-level study: cut ground-truth maps into pairs of chosen overlap, merge with each algorithm.
    Overlap(overlap::OverlapArgs),
    /// Simulation-level study: run a scenario sweep (simulation, SLAM, merge) and score each merge.
    Scenario(scenario::ScenarioArgs),
    /// Join the results.csv of a study's shards, then redraw summary.csv and plot.png.
    Collect(collect::CollectArgs),
    /// Real-data study: split a CARMEN log in time into N robots, map each with the SLAM, merge every pair
    /// the relations connect with each algorithm, score against the relations.
    Logs(logs::LogsArgs),
    /// Team study: run a team scenario with the first N robots, each range, coordination and online merger, and
    /// each seed; coverage over time, time to 90 %, redundancy and online merges per configuration.
    Team(team::TeamArgs),
}

/// Runs `mrslam study`.
pub fn run(cmd: StudyCommand) -> Result<ExitCode> {
    match cmd {
        StudyCommand::Overlap(a) => overlap::run(a),
        StudyCommand::Scenario(a) => scenario::run(a),
        StudyCommand::Collect(a) => collect::run(a),
        StudyCommand::Logs(a) => logs::run(a),
        StudyCommand::Team(a) => team::run(a),
    }
}

/// The flags every sharded study takes: which shard, whether to resume, whether to draw progress.
#[derive(clap::Args)]
pub struct StudyRun {
    /// Run only shard K of N (trial index mod N = K); default from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT.
    #[arg(long, allow_hyphen_values = true)]
    pub shard: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Continue the interrupted study in --out: run only the trials its results.csv lacks.
    #[arg(long)]
    pub resume: bool,
}

pub(super) fn shard_of(arg: Option<&str>) -> Result<Shard> {
    Ok(match arg {
        Some(s) => Shard::parse(s).context("--shard")?,
        None => Shard::from_slurm(|k| std::env::var(k).ok())?.unwrap_or(Shard::ALL),
    })
}

/// Names the shard in a sharded study's parameters, and how many trials it runs, so that `collect` can tell
/// when one is missing or incomplete.
pub(super) fn name_shard(params: &mut StudyParams, shard: Shard, trials: usize) {
    if shard.count > 1 {
        params.set(mrslam_studies::journal::SHARD_PARAM, format!("{}/{}", shard.index, shard.count));
        params.set(mrslam_studies::journal::SHARD_TRIALS_PARAM, trials);
    }
}

pub(super) fn progress_bar(len: usize, quiet: bool, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} trials, {rate}, {elapsed} elapsed, ETA {eta}")
            .expect("valid template")
            .with_key("rate", |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&rate_text(s.per_sec()));
            })
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

/// A rate of trials as people read it: three significant figures, per minute when under one a second.
fn rate_text(per_sec: f64) -> String {
    let (rate, unit) = if per_sec < 1.0 { (per_sec * 60.0, "min") } else { (per_sec, "s") };
    let decimals = if rate >= 100.0 {
        0
    } else if rate >= 10.0 {
        1
    } else {
        2
    };
    format!("{rate:.decimals$}/{unit}")
}

/// Makes the study folder `dir` when it is not there; as every command's outputs, its parent must exist (a typo
/// in `--out` makes no chain of folders).
pub(super) fn create_out(dir: &Path) -> Result<()> {
    crate::cmd::paths::create_out_folder(dir)
}

/// A running study's progress: the trials done before a resume are skipped; each finished trial's rows are
/// appended to results.csv at once, so an interruption loses no finished trial.
pub(super) struct Recorder<R> {
    journal: Journal<R>,
    done: BTreeSet<usize>,
    bar: ProgressBar,
}

impl<R: CsvRow> Progress<R> for Recorder<R> {
    fn skip(&self, trial: usize) -> bool {
        self.done.contains(&trial)
    }

    fn finished(&self, rows: &[R]) -> Result<(), StudyError> {
        self.journal.append(rows)?;
        let trials: BTreeSet<usize> = rows.iter().map(CsvRow::trial).collect();
        self.bar.inc(trials.len() as u64);
        Ok(())
    }
}

/// Opens the study folder (fresh or resumed) and says what a resume found.
/// The files every study writes in its folder, and their kinds.
const STUDY_FILES: [(&str, &[&str]); 4] =
    [("study.json", kind::JSON), ("results.csv", kind::CSV), ("summary.csv", kind::CSV), ("plot.png", kind::PNG)];

/// A study's outputs in `out` (the files every study writes, then `more`), for the one output rule.
pub(super) fn study_outputs<'p>(out: &Path, inputs: impl IntoIterator<Item = &'p Path>, more: &[PathBuf]) -> Outputs {
    let mut rule = Outputs::reading(inputs);
    for (name, k) in STUDY_FILES {
        rule = rule.file("--out", &out.join(name), k);
    }
    for m in more {
        rule = rule.file("--out", m, kind::ANY);
    }
    rule
}

/// Creates the study folder `out` (its outputs, the usual four and `more`, checked against `inputs` first) and
/// opens its journal.
pub(super) fn open_study<'p, R: CsvRow>(
    out: &Path,
    inputs: impl IntoIterator<Item = &'p Path>,
    more: &[PathBuf],
    params: &StudyParams,
    rows_per_trial: usize,
    resume: bool,
) -> Result<(Journal<R>, Vec<R>)> {
    if out.is_file() {
        bail!("--out {}: is a file, expected a folder", out.display());
    }
    let rule = study_outputs(out, inputs, more);
    if out.is_dir() {
        rule.check()?;
    }
    create_out(out)?;
    rule.check()?;
    let (journal, earlier) = Journal::open(out, params, rows_per_trial, resume)?;
    if resume {
        let trials: BTreeSet<usize> = earlier.iter().map(CsvRow::trial).collect();
        println!("resuming {}: {} trials already done", out.display(), trials.len());
    }
    Ok((journal, earlier))
}

/// Runs the trials not yet done, then joins the rows with those of before the resume (the caller sorts them).
pub(super) fn run_study<R: CsvRow>(
    earlier: Vec<R>,
    journal: Journal<R>,
    selected: &[usize],
    quiet: bool,
    what: &str,
    run: impl FnOnce(&Recorder<R>) -> Result<Vec<R>, StudyError>,
) -> Result<(Vec<R>, usize, f64)> {
    let done: BTreeSet<usize> = earlier.iter().map(CsvRow::trial).collect();
    let n = selected.iter().filter(|t| !done.contains(t)).count();
    let recorder = Recorder { journal, done, bar: progress_bar(n, quiet, what) };
    let start = Instant::now();
    let new = match run(&recorder) {
        Ok(new) => new,
        Err(e) => {
            recorder.bar.finish_and_clear();
            // A fresh start that failed before its first trial leaves nothing to block the corrected retry.
            recorder.journal.abandon();
            return Err(e.into());
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    recorder.bar.finish_and_clear();
    let mut rows = earlier;
    rows.extend(new);
    Ok((rows, n, seconds))
}

pub(super) fn finish(rows: &[TrialRow], out: &Path, trials: usize, seconds: Option<f64>) -> Result<ExitCode> {
    let summary = study::write_outputs(rows, out)?;
    print!("{}", table(&summary));
    if let Some(s) = seconds {
        println!("{trials} trials ({} rows) in {s:.1} s: {:.2} trials/s", rows.len(), trials as f64 / s.max(1e-9));
    }
    println!("outputs:  {} (study.json, results.csv, summary.csv, plot.png)", out.display());
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rate_shows_three_significant_figures() {
        assert_eq!(rate_text(15.2117), "15.2/s");
        assert_eq!(rate_text(152.117), "152/s");
        assert_eq!(rate_text(2.5), "2.50/s");
        assert_eq!(rate_text(0.05), "3.00/min");
    }
}
