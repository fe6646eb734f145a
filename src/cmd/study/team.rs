//! `mrslam study team`: a team scenario over numbers of robots, ranges, coordinations, online mergers and seeds.

use super::{open_study, run_study, shard_of};
use anyhow::{Context, Result};
use clap::Args;
use mrslam_merge::Algorithm;
use mrslam_studies::journal::{StudyParams, fingerprint};
use mrslam_studies::team::{TEAM_FILES, TeamAxes, TeamRow, TeamStudy, run_team_study, team_table, write_team_outputs};
use mrslam_studies::{parse_numbers, parse_whole_numbers};
use mrslam_testbed::scenario::{Coordination, Scenario};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `mrslam study team`.
#[derive(Args)]
pub struct TeamArgs {
    /// Team scenario (TOML with a `[team]` table), e.g. scenarios/team_two_rooms.toml.
    pub scenario: PathBuf,
    /// Output folder: study.json, results.csv, summary.csv, coverage.csv, plot.png, time90.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Sharding, resuming and progress.
    #[command(flatten)]
    pub run: super::StudyRun,
    /// Numbers of robots: a trial takes the first N of the scenario's `[[robots]]`. A list a,b,c or start:stop
    /// (both included); default: all of them.
    #[arg(long, allow_hyphen_values = true)]
    pub robots: Option<String>,
    /// Communication ranges, metres: a list a,b,c or start:stop:step; default: the scenario's team.range.
    #[arg(long, allow_hyphen_values = true)]
    pub range: Option<String>,
    /// Coordinations, comma-separated: none, frontiers; default: the scenario's team.coordination.
    #[arg(long, allow_hyphen_values = true)]
    pub coordination: Option<String>,
    /// Online mergers, comma-separated (sift, rmap, correlative, cascade); default: the scenario's team.merger.
    #[arg(long, allow_hyphen_values = true)]
    pub merger: Option<String>,
    /// Seeds (each replaces the scenario's): a list a,b,c, start:stop (both included) or start:stop:step. Every
    /// configuration runs once per seed.
    #[arg(long, default_value = "0:9", allow_hyphen_values = true)]
    pub seeds: String,
    /// Simulated seconds a run lasts at most, instead of the scenario's duration.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Read and check the scenario and the lists, list the trials, run nothing.
    #[arg(long)]
    pub dry_run: bool,
}

/// Each comma-separated name of `s` read by `T`'s parser; `flag` names the list in errors.
fn names<T: std::str::FromStr>(s: &str, flag: &str) -> Result<Vec<T>>
where
    T::Err: std::fmt::Display,
{
    s.split(',').map(|n| n.trim().parse::<T>().map_err(|e| anyhow::anyhow!("{flag} `{s}`: {e}"))).collect()
}

/// The study the arguments ask for, checked against its scenario.
fn study_of(a: &TeamArgs) -> Result<TeamStudy> {
    let scenario = Scenario::from_file(&a.scenario)?;
    let robots = a
        .robots
        .as_deref()
        .map(|s| parse_whole_numbers(s, "--robots").map(|v| v.into_iter().map(|n| n as usize).collect()))
        .transpose()?;
    let axes = TeamAxes {
        robots,
        ranges: a.range.as_deref().map(|s| parse_numbers(s, "--range")).transpose()?,
        coordinations: a.coordination.as_deref().map(|s| names::<Coordination>(s, "--coordination")).transpose()?,
        mergers: a.merger.as_deref().map(|s| names::<Algorithm>(s, "--merger")).transpose()?,
        seeds: parse_whole_numbers(&a.seeds, "--seeds")?,
        duration: a.duration,
    };
    Ok(TeamStudy::new(scenario, axes)?)
}

/// A file's name and the fingerprint of its content, for `study.json`.
fn file_id(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    Ok(format!("{} {}", path.file_name().map(|f| f.to_string_lossy()).unwrap_or_default(), fingerprint(&bytes)))
}

/// A list as `study.json` records it.
fn joined<T: std::fmt::Display>(values: &[T]) -> String {
    values.iter().map(T::to_string).collect::<Vec<_>>().join(",")
}

/// Runs `mrslam study team`.
pub(super) fn run(a: TeamArgs) -> Result<ExitCode> {
    let shard = shard_of(a.run.shard.as_deref())?;
    let study = study_of(&a)?;
    let selected: Vec<usize> = (0..study.trials()).filter(|t| shard.selects(*t)).collect();
    let runs: BTreeSet<usize> = selected.iter().map(|&t| study.run_of(t)).collect();
    if a.dry_run {
        let s = &study.scenario;
        println!(
            "{}: scenario {}, {} trials ({} configurations x {} seeds), {} s simulated at most per run",
            a.scenario.display(),
            s.name,
            study.trials(),
            study.configs().len(),
            study.seeds.len(),
            s.duration
        );
        if let Some(d) = &s.description {
            println!("  {d}");
        }
        for &t in &selected {
            let shared = study.run_of(t);
            let note = if shared == t { String::new() } else { format!(" (one robot: the run of trial {shared})") };
            println!("trial {t}: {}{note}", study.describe(t));
        }
        println!("{} trials in this shard, {} runs", selected.len(), runs.len());
        return Ok(ExitCode::SUCCESS);
    }
    let mut params = StudyParams::default();
    params.set("kind", "team");
    super::name_shard(&mut params, shard, selected.len());
    params
        .set("scenario", file_id(&study.scenario.path)?)
        .set("world", file_id(&study.scenario.world_path)?)
        .set("robots", joined(&study.robots))
        .set("range", joined(&study.ranges))
        .set("coordination", joined(&study.coordinations))
        .set("merger", joined(&study.mergers))
        .set("seeds", joined(&study.seeds))
        .set("duration", study.scenario.duration)
        .set("coverage_step", study.coverage_step());
    let inputs = [study.scenario.path.as_path(), study.scenario.world_path.as_path()];
    let more: Vec<PathBuf> = ["coverage.csv", "time90.png"].iter().map(|f| a.out.join(f)).collect();
    let (journal, earlier) = open_study::<TeamRow>(&a.out, inputs, &more, &params, 1, a.run.resume)?;
    let (rows, n, seconds) = run_study(earlier, journal, &selected, a.run.quiet, &study.scenario.name, |p| {
        run_team_study(&study, shard, p)
    })?;
    finish(&rows, &a.out, n, Some(seconds))
}

/// Writes the study's files from `rows` and prints the summary (with `seconds`, how long `trials` took).
pub(super) fn finish(rows: &[TeamRow], out: &Path, trials: usize, seconds: Option<f64>) -> Result<ExitCode> {
    let summary = write_team_outputs(rows, out)?;
    print!("{}", team_table(&summary));
    if let Some(s) = seconds {
        println!("{trials} trials in {s:.1} s: {:.2} trials/min", 60.0 * trials as f64 / s.max(1e-9));
    }
    println!("outputs:  {} (study.json, {})", out.display(), TEAM_FILES.join(", "));
    Ok(ExitCode::SUCCESS)
}
