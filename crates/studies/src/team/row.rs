//! A team study's `results.csv`: one row per trial (its configuration, seed, the run's team results and its
//! coverage curve); writing, reading, and joining the shards of a study.
//!
//! Empty cells: a time to 50/90/95 % coverage the run never reached, a first correct merge that never came, the
//! team map's acceptance when no team map was judged. The coverage curve is the share of the reachable free area
//! mapped at t = 0, step, 2 step, … up to the study's duration (`coverage_step_s` apart), space-separated.

use crate::StudyError;
use crate::csv_row::{CsvRow, collect_rows, optional, read_rows};
use mrslam_merge::Algorithm;
use mrslam_testbed::scenario::Coordination;
use std::path::{Path, PathBuf};

/// The header line of a team study's `results.csv`.
pub const TEAM_HEADER: &str = "trial,n,range_m,coordination,merger,seed,time_to_50_s,time_to_90_s,time_to_95_s,\
final_coverage,redundancy,distance_m,first_correct_merge_s,merges_accepted,merges_refused,merges_false,\
bytes_exchanged,team_map_acceptance,wall_s,teams_at_end,reachable_m2,sim_s,coverage_step_s,coverage_curve";

/// Number of columns.
const COLUMNS: usize = 24;

/// One trial of a team study.
#[derive(Debug, Clone, PartialEq)]
pub struct TeamRow {
    /// Trial index within the study.
    pub trial: usize,
    /// Robots (the first N of the scenario's).
    pub n: usize,
    /// Communication range, metres.
    pub range_m: f64,
    /// How a joined team explored.
    pub coordination: Coordination,
    /// The merger of the online merges.
    pub merger: Algorithm,
    /// The scenario's seed in this trial.
    pub seed: u64,
    /// First time the coverage reached 50 %, seconds (`None`: never).
    pub time_to_50_s: Option<f64>,
    /// First time it reached 90 %.
    pub time_to_90_s: Option<f64>,
    /// First time it reached 95 %.
    pub time_to_95_s: Option<f64>,
    /// Share of the reachable free area mapped at the run's end.
    pub final_coverage: f64,
    /// Of the reachable free area the robots' beams crossed, the share more than one robot's crossed.
    pub redundancy: f64,
    /// Distance all robots drove, metres.
    pub distance_m: f64,
    /// Time of the first accepted and correct online merge, seconds.
    pub first_correct_merge_s: Option<f64>,
    /// Online merges accepted (false ones included).
    pub merges_accepted: usize,
    /// Online merges the gate refused.
    pub merges_refused: usize,
    /// Online merges accepted on a wrong transform.
    pub merges_false: usize,
    /// Bytes of maps sent.
    pub bytes_exchanged: u64,
    /// Carpin's acceptance index of the largest team's merged map against the truth.
    pub team_map_acceptance: Option<f64>,
    /// Wall time of the run, seconds (the one column that differs between identical runs).
    pub wall_s: f64,
    /// Teams at the end (1: every robot joined one team).
    pub teams_at_end: usize,
    /// Free area of the truth the robots can reach, m² (the coverage's denominator).
    pub reachable_m2: f64,
    /// Simulated time the run lasted, seconds (less than the duration when the exploration ended first).
    pub sim_s: f64,
    /// Spacing of the coverage curve, seconds.
    pub coverage_step_s: f64,
    /// Coverage at t = 0, step, 2 step, … (shares in [0, 1]).
    pub coverage: Vec<f64>,
}

impl CsvRow for TeamRow {
    const HEADER: &'static str = TEAM_HEADER;

    fn trial(&self) -> usize {
        self.trial
    }

    fn to_csv(&self) -> String {
        let curve: Vec<String> = self.coverage.iter().map(|c| format!("{c:.4}")).collect();
        format!(
            "{},{},{},{},{},{},{},{},{},{:.6},{:.6},{:.3},{},{},{},{},{},{},{:.3},{},{:.3},{:.3},{},{}",
            self.trial,
            self.n,
            self.range_m,
            self.coordination,
            self.merger,
            self.seed,
            optional(self.time_to_50_s, 3),
            optional(self.time_to_90_s, 3),
            optional(self.time_to_95_s, 3),
            self.final_coverage,
            self.redundancy,
            self.distance_m,
            optional(self.first_correct_merge_s, 3),
            self.merges_accepted,
            self.merges_refused,
            self.merges_false,
            self.bytes_exchanged,
            optional(self.team_map_acceptance, 6),
            self.wall_s,
            self.teams_at_end,
            self.reachable_m2,
            self.sim_s,
            self.coverage_step_s,
            curve.join(" "),
        )
    }

    fn from_csv(line: &str) -> Result<TeamRow, String> {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != COLUMNS {
            return Err(format!("expected {COLUMNS} columns, found {}", f.len()));
        }
        let name = |i: usize| TEAM_HEADER.split(',').nth(i).unwrap_or("?");
        let bad = |i: usize| format!("{}: `{}` is not a valid value", name(i), f[i]);
        fn parse<T: std::str::FromStr>(s: &str) -> Option<T> {
            s.parse().ok()
        }
        let num = |i: usize| parse::<f64>(f[i]).filter(|v| v.is_finite()).ok_or_else(|| bad(i));
        let opt_num = |i: usize| if f[i].is_empty() { Ok(None) } else { num(i).map(Some) };
        let share = |i: usize| num(i).and_then(|v| if (0.0..=1.0).contains(&v) { Ok(v) } else { Err(bad(i)) });
        let count = |i: usize| parse::<usize>(f[i]).ok_or_else(|| bad(i));
        let coverage = f[23]
            .split_whitespace()
            .map(|c| parse::<f64>(c).filter(|v| (0.0..=1.0).contains(v)))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| format!("{}: not a list of shares in [0, 1] separated by spaces", name(23)))?;
        let step = num(22)?;
        if step <= 0.0 {
            return Err(bad(22));
        }
        Ok(TeamRow {
            trial: count(0)?,
            n: count(1)?,
            range_m: num(2)?,
            coordination: f[3].parse().map_err(|e: String| format!("{}: {e}", name(3)))?,
            merger: f[4].parse().map_err(|e: mrslam_merge::UnknownAlgorithm| format!("{}: {e}", name(4)))?,
            seed: parse(f[5]).ok_or_else(|| bad(5))?,
            time_to_50_s: opt_num(6)?,
            time_to_90_s: opt_num(7)?,
            time_to_95_s: opt_num(8)?,
            final_coverage: share(9)?,
            redundancy: share(10)?,
            distance_m: num(11)?,
            first_correct_merge_s: opt_num(12)?,
            merges_accepted: count(13)?,
            merges_refused: count(14)?,
            merges_false: count(15)?,
            bytes_exchanged: parse(f[16]).ok_or_else(|| bad(16))?,
            team_map_acceptance: opt_num(17)?,
            wall_s: num(18)?,
            teams_at_end: count(19)?,
            reachable_m2: num(20)?,
            sim_s: num(21)?,
            coverage_step_s: step,
            coverage,
        })
    }
}

/// Joins the `results.csv` of a team study's shard folders, refusing a trial found twice; rows come back sorted
/// by trial.
pub fn collect_team(dirs: &[PathBuf]) -> Result<Vec<TeamRow>, StudyError> {
    let mut all = collect_rows(dirs, |r: &TeamRow| r.trial, |r| format!("trial {}", r.trial))?;
    all.sort_by_key(|r| r.trial);
    Ok(all)
}

/// Reads a team study's `results.csv`, checking its header.
pub fn read_team_results(path: &Path) -> Result<Vec<TeamRow>, StudyError> {
    Ok(read_rows(path)?.into_iter().map(|(_, r)| r).collect())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::csv_row::write_rows;

    /// A row of `n` robots with `coordination`, reaching 90 % at `t90`.
    pub(crate) fn row(trial: usize, n: usize, coordination: Coordination, t90: Option<f64>) -> TeamRow {
        TeamRow {
            trial,
            n,
            range_m: 6.0,
            coordination,
            merger: Algorithm::Cascade,
            seed: trial as u64,
            time_to_50_s: Some(10.0),
            time_to_90_s: t90,
            time_to_95_s: None,
            final_coverage: if t90.is_some() { 0.93 } else { 0.8 },
            redundancy: if n > 1 { 0.25 } else { 0.0 },
            distance_m: 40.5,
            first_correct_merge_s: (n > 1).then_some(30.0),
            merges_accepted: usize::from(n > 1),
            merges_refused: 2 * usize::from(n > 1),
            merges_false: 0,
            bytes_exchanged: 12345,
            team_map_acceptance: Some(0.97),
            wall_s: 3.25,
            teams_at_end: 1,
            reachable_m2: 120.5,
            sim_s: 80.0,
            coverage_step_s: 2.0,
            coverage: vec![0.0, 0.25, 0.5, 0.93],
        }
    }

    #[test]
    fn rows_round_trip() {
        let r = row(3, 2, Coordination::Frontiers, Some(61.5));
        let line = r.to_csv();
        assert_eq!(
            line,
            "3,2,6,frontiers,cascade,3,10.000,61.500,,0.930000,0.250000,40.500,30.000,1,2,0,12345,0.970000,3.250,1,\
             120.500,80.000,2,0.0000 0.2500 0.5000 0.9300"
        );
        assert_eq!(line.split(',').count(), TEAM_HEADER.split(',').count());
        let back = TeamRow::from_csv(&line).unwrap();
        assert_eq!(back, r);
        assert!(TeamRow::from_csv("1,2,3").unwrap_err().contains("24 columns"));
        let e = TeamRow::from_csv(&line.replace("frontiers", "swarm")).unwrap_err();
        assert!(e.contains("coordination: unknown coordination `swarm`"), "{e}");
        let e = TeamRow::from_csv(&line.replace("0.930000", "1.5")).unwrap_err();
        assert_eq!(e, "final_coverage: `1.5` is not a valid value");
        let e = TeamRow::from_csv(&line.replace("0.5000 0.9300", "0.5 x")).unwrap_err();
        assert!(e.starts_with("coverage_curve:"), "{e}");
    }

    #[test]
    fn an_interrupted_team_study_resumes_with_its_whole_rows() {
        use crate::journal::{Journal, RESULTS_FILE, StudyParams};
        use std::io::Write as _;
        let dir = tempfile::tempdir().unwrap();
        let mut params = StudyParams::default();
        params.set("kind", "team");
        let (j, done) = Journal::<TeamRow>::open(dir.path(), &params, 1, false).unwrap();
        assert!(done.is_empty());
        let rows: Vec<TeamRow> = (0..3).map(|t| row(t, 1, Coordination::None, None)).collect();
        j.append(&rows[..2]).unwrap(); // one run's two trials in one write
        drop(j);
        // The third trial's row cut off in the middle.
        let mut f = std::fs::OpenOptions::new().append(true).open(dir.path().join(RESULTS_FILE)).unwrap();
        f.write_all(&rows[2].to_csv().as_bytes()[..40]).unwrap();
        drop(f);
        let (_, done) = Journal::<TeamRow>::open(dir.path(), &params, 1, true).unwrap();
        assert_eq!(done, rows[..2]);
        assert_eq!(read_team_results(&dir.path().join(RESULTS_FILE)).unwrap(), rows[..2]);
    }

    #[test]
    fn collect_joins_shards_and_refuses_a_trial_twice() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        for d in [&a, &b] {
            std::fs::create_dir_all(d).unwrap();
        }
        let rows: Vec<TeamRow> = (0..4).map(|t| row(t, 1 + t % 2, Coordination::None, Some(50.0))).collect();
        write_rows(&[rows[2].clone(), rows[0].clone()], &a.join("results.csv")).unwrap();
        write_rows(&[rows[1].clone(), rows[3].clone()], &b.join("results.csv")).unwrap();
        assert_eq!(collect_team(&[b.clone(), a.clone()]).unwrap(), rows);
        assert_eq!(read_team_results(&b.join("results.csv")).unwrap(), [rows[1].clone(), rows[3].clone()]);
        let e = collect_team(&[a.clone(), a]).unwrap_err().to_string();
        assert!(e.contains("trial 2 is also in"), "{e}");
    }
}
