//! Running a team study: each run the selected trials need, in parallel, and each trial's row from its run's
//! team report.
//!
//! A run is one `runner::run` of the trial's scenario with no recording and no merge after driving (a team trial
//! measures the merges while driving). Trials that are one run ([`TeamStudy::run_of`]: one robot, the same seed)
//! share it: it runs once and each of them gets its row, the same run's `wall_s` in each. Rows go through their
//! CSV form before they are handed over, so a resumed study computes from exactly what a whole one does.

use super::curve::{grid_len, resample};
use super::row::TeamRow;
use super::study::TeamStudy;
use crate::csv_row::CsvRow;
use crate::{Progress, Shard, StudyError};
use mrslam_testbed::runner::{RunOptions, run};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Runs the trials of this shard that `progress` does not skip, the runs side by side (the largest teams first),
/// handing each run's rows to `progress` as it finishes; returns the rows sorted by trial.
pub fn run_team_study(
    study: &TeamStudy,
    shard: Shard,
    progress: &dyn Progress<TeamRow>,
) -> Result<Vec<TeamRow>, StudyError> {
    let mut runs: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for t in (0..study.trials()).filter(|t| shard.selects(*t) && !progress.skip(*t)) {
        runs.entry(study.run_of(t)).or_default().push(t);
    }
    // The largest teams take longest: started first, they do not keep the last core busy alone at the end.
    let mut order: Vec<(usize, Vec<usize>)> = runs.into_iter().collect();
    order.sort_by_key(|(run, _)| (std::cmp::Reverse(study.trial(*run).0.robots), *run));
    let rows: Vec<Vec<TeamRow>> = order
        .into_iter()
        .par_bridge()
        .map(|(run_trial, trials)| {
            let rows = run_trial_rows(study, run_trial, &trials)?;
            progress.finished(&rows)?;
            Ok(rows)
        })
        .collect::<Result<_, StudyError>>()?;
    let mut rows: Vec<TeamRow> = rows.into_iter().flatten().collect();
    rows.sort_by_key(|r| r.trial);
    Ok(rows)
}

/// Runs trial `run_trial`'s scenario once and makes the row of each of `trials` (which share that run).
fn run_trial_rows(study: &TeamStudy, run_trial: usize, trials: &[usize]) -> Result<Vec<TeamRow>, StudyError> {
    let scenario = study.scenario_of(run_trial);
    let fail = |message: String| StudyError::Trial { trial: run_trial, message };
    let out = run(&scenario, RunOptions { algorithms: Some(Vec::new()), ..RunOptions::default() })
        .map_err(|e| fail(format!("{}: {e}", study.describe(run_trial))))?;
    let report = &out.report;
    let team = report.team.as_ref().ok_or_else(|| fail("the run made no team report".into()))?;
    let step = study.coverage_step();
    let coverage = resample(&team.coverage, step, grid_len(scenario.duration, step), 1.5 * scenario.dt);
    let finite = |v: Option<f64>| v.filter(|x| x.is_finite());
    trials
        .iter()
        .map(|&trial| {
            let (c, seed) = study.trial(trial);
            let row = TeamRow {
                trial,
                n: c.robots,
                range_m: c.range,
                coordination: c.coordination,
                merger: c.merger,
                seed,
                time_to_50_s: finite(team.time_to_50_s),
                time_to_90_s: finite(team.time_to_90_s),
                time_to_95_s: finite(team.time_to_95_s),
                final_coverage: team.final_coverage,
                redundancy: team.redundancy,
                distance_m: team.distance_m,
                first_correct_merge_s: finite(team.first_correct_merge_s),
                merges_accepted: team.merges_accepted,
                merges_refused: team.merges_refused,
                merges_false: team.merges_false,
                bytes_exchanged: team.bytes_exchanged,
                team_map_acceptance: finite(team.team_map_acceptance),
                wall_s: report.wall_s,
                teams_at_end: team.teams.len(),
                reachable_m2: team.reachable_free_m2,
                sim_s: report.sim_s,
                coverage_step_s: step,
                coverage: coverage.clone(),
            };
            // As results.csv holds it (rounded), so that a resumed study's rows equal a whole one's.
            TeamRow::from_csv(&row.to_csv()).map_err(|e| fail(format!("its row does not read back: {e}")))
        })
        .collect()
}
