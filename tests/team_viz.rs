//! A team run recorded for the rerun viewer: read back with rerun's own decoder, the recording shows the team part
//! (every merge attempt, the team maps as they grow, the explorers' goals, coverage and merge counts) in numbers that
//! match the run's report, and recording it does not change the run.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_testbed::report::{MergeAttempt, RunReport};
use mrslam_testbed::runner::{RunOptions, RunOutput, run};
use mrslam_testbed::scenario::Scenario;
use mrslam_viz::inspect::{first_difference, summarize};
use mrslam_viz::{Recorder, RunRecorder, Target};
use std::path::Path;

/// What a run's report says that must not depend on the recording (wall-clock times left out).
fn outcome(r: &RunReport) -> String {
    let team = r.team.as_ref().unwrap();
    let attempts: Vec<MergeAttempt> = team
        .attempts
        .iter()
        .map(|a| MergeAttempt { time_ms: 0.0, stage_ms: Default::default(), ..a.clone() })
        .collect();
    let robots: Vec<(f64, f64, usize)> =
        r.robots.values().map(|x| (x.distance_m, x.slam_rmse_m, x.processed)).collect();
    format!("{:?} {:?} {:?} {} {:?} {robots:?}", team.coverage, attempts, team.plans, team.bytes_exchanged, r.sim_s)
}

/// Runs `scenario` recorded into `rrd`.
fn recorded_run(scenario: &Scenario, rrd: &Path) -> RunOutput {
    let rec = Recorder::open(&[Target::File(rrd.to_path_buf())], "team-test", "team test").unwrap();
    let mut viz = RunRecorder::new(rec);
    let out = run(scenario, RunOptions { viz: Some(&mut viz), ..RunOptions::default() }).unwrap();
    viz.finish().unwrap();
    out
}

#[test]
fn a_team_runs_recording_shows_merge_attempts_team_maps_goals_and_coverage() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/team_two_rooms.toml");
    let scenario = Scenario::from_file(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("team.rrd");
    let out = recorded_run(&scenario, &rrd);
    let team = out.report.team.as_ref().unwrap();
    eprint!("{}", out.report.summary());
    assert!(!team.attempts.is_empty(), "the robots met: {team:?}");
    let s = summarize(&rrd).unwrap();
    // Rows logged over time (series styles and placements, static, left out).
    let at = |e: &str| s.rows_at(e) - s.static_rows.get(e).copied().unwrap_or(0);

    // Every attempt is one entry of the team's text log; each moment with attempts draws their lines once, and
    // the lines are cleared once at most.
    assert_eq!(at("/team/events"), team.attempts.len(), "{:?}", s.rows);
    let mut moments: Vec<f64> = team.attempts.iter().map(|a| a.time_s).collect();
    moments.dedup();
    let lines = at("/team/attempts");
    assert!(lines >= moments.len() && lines <= team.attempts.len() + moments.len(), "{lines} rows of lines");

    // The merge counts: a zero at the start, a value at every coverage sample, and a step (old value, new value)
    // at every attempt that changed them.
    let samples = at("/metrics/coverage/mapped");
    let recorded = team.coverage.len();
    assert!(samples + 1 >= recorded && samples <= recorded, "{samples} coverage samples recorded of {recorded}");
    assert_eq!(at("/metrics/coverage/redundancy"), samples);
    let counts = [("accepted", team.merges_accepted), ("refused", team.merges_refused), ("false", team.merges_false)];
    for (leaf, changes) in counts {
        let n = at(&format!("/metrics/merges/{leaf}"));
        assert_eq!(n, 1 + samples + team.attempts.len() + changes, "metrics/merges/{leaf}");
    }

    // The team map, in the root's frame: drawn when the teams joined and then once per exchange period while
    // the team's robots send their maps; no map for a team of one robot.
    let root = &team.teams[0][0];
    let maps = at(&format!("/team/maps/{root}"));
    let periods = (out.report.sim_s / 5.0).ceil() as usize;
    assert!(maps >= 2 && maps <= periods + team.merges_accepted + 1, "{maps} team maps");
    let others: usize =
        s.rows.keys().filter(|e| e.starts_with("/team/maps/") && **e != format!("/team/maps/{root}")).count();
    assert_eq!(others, 0, "the team of one robot draws no team map: {:?}", s.rows);

    // Each explorer's goal and path, drawn when they change: the lone explorer's replans and the team's plans.
    for name in out.report.robots.keys() {
        let goals = at(&format!("/robots/{name}/slam/goal"));
        let paths = at(&format!("/robots/{name}/slam/goal/path"));
        assert!(goals >= 2 && goals < at(&format!("/robots/{name}/scan")), "{name}: {goals} goals");
        // A goal that is gone (reached with nothing left, given up, none assigned) is cleared, its path with it.
        assert!(paths >= 2 && paths <= goals, "{name}: {paths} paths for {goals} goals");
    }
    assert!(s.blueprint_entities.iter().any(|e| e.starts_with("/view/")), "{:?}", s.blueprint_entities);

    // Recording changes nothing of the run, and the recording is reproducible.
    let plain = run(&scenario, RunOptions::default()).unwrap();
    assert_eq!(outcome(&plain.report), outcome(&out.report));
    let again = dir.path().join("again.rrd");
    recorded_run(&scenario, &again);
    assert_eq!(first_difference(&rrd, &again).unwrap(), None, "two recordings of one team run differ");
}
