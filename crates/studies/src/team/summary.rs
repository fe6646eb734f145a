//! A team study's `summary.csv`: per configuration (robots, range, coordination, merger), how many trials reached
//! 90 % coverage (with its Wilson 95 % interval), the mean time to 90 % of the trials that reached it and the mean
//! redundancy, final coverage and distance of all trials, each with its Student t 95 % interval, and the online
//! merges counted.
//!
//! A trial that never reached 90 % has no time to 90 %: it is not dropped silently but counted in `trials` and not
//! in `reached_90`, and the time's mean and interval are over the `reached_90` trials alone (the column names
//! say so). With fewer than two such trials the interval is empty, with none the mean too.

use super::row::TeamRow;
use crate::StudyError;
use crate::student_t::{MeanCi, mean_ci};
use crate::wilson::{Z95, wilson_interval};
use mrslam_merge::Algorithm;
use mrslam_testbed::scenario::Coordination;
use std::fmt::Write as _;
use std::path::Path;

/// The header line of a team study's `summary.csv`.
pub const TEAM_SUMMARY_HEADER: &str = "n,range_m,coordination,merger,trials,reached_90,reached_90_share,\
reached_90_lo,reached_90_hi,time_to_90_mean_s_of_reached,time_to_90_lo_s,time_to_90_hi_s,redundancy_mean,\
redundancy_lo,redundancy_hi,final_coverage_mean,final_coverage_lo,final_coverage_hi,distance_mean_m,\
merges_accepted,merges_refused,false_merges,reachable_m2";

/// The key of a configuration: robots, range, coordination, merger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigKey {
    /// Robots.
    pub n: usize,
    /// Communication range, metres.
    pub range_m: f64,
    /// Coordination.
    pub coordination: Coordination,
    /// Online merger.
    pub merger: Algorithm,
}

impl ConfigKey {
    /// The configuration of a row.
    pub fn of(r: &TeamRow) -> ConfigKey {
        ConfigKey { n: r.n, range_m: r.range_m, coordination: r.coordination, merger: r.merger }
    }

    /// The configuration in words: `N=2, 6 m, frontiers, cascade`.
    pub fn label(&self) -> String {
        format!("N={}, {} m, {}, {}", self.n, self.range_m, self.coordination, self.merger)
    }
}

/// The configurations of `rows`, in order of first appearance.
pub fn configs_of(rows: &[TeamRow]) -> Vec<ConfigKey> {
    let mut out: Vec<ConfigKey> = Vec::new();
    for r in rows {
        let k = ConfigKey::of(r);
        if !out.contains(&k) {
            out.push(k);
        }
    }
    out
}

/// One configuration over its trials.
#[derive(Debug, Clone, PartialEq)]
pub struct TeamSummaryRow {
    /// The configuration.
    pub config: ConfigKey,
    /// Trials run.
    pub trials: usize,
    /// Trials whose coverage reached 90 %.
    pub reached_90: usize,
    /// Wilson 95 % interval of the share that reached 90 %, (lower, upper).
    pub reached_90_ci: (f64, f64),
    /// Time to 90 % over the trials that reached it (`n` = `reached_90`), seconds.
    pub time_to_90: MeanCi,
    /// Redundancy over all trials.
    pub redundancy: MeanCi,
    /// Final coverage over all trials.
    pub final_coverage: MeanCi,
    /// Mean distance driven by all robots, metres.
    pub distance_mean_m: f64,
    /// Online merges accepted, all trials.
    pub merges_accepted: usize,
    /// Online merges refused, all trials.
    pub merges_refused: usize,
    /// Online merges accepted on a wrong transform, all trials.
    pub false_merges: usize,
    /// Mean reachable free area, m² (the coverage's denominator: it depends on the robots' starts and sizes).
    pub reachable_m2: f64,
}

/// Summarises rows per configuration, in order of first appearance.
pub fn summarise_team(rows: &[TeamRow]) -> Vec<TeamSummaryRow> {
    configs_of(rows)
        .into_iter()
        .map(|config| {
            let sel: Vec<&TeamRow> = rows.iter().filter(|r| ConfigKey::of(r) == config).collect();
            let n = sel.len();
            let times: Vec<f64> = sel.iter().filter_map(|r| r.time_to_90_s).collect();
            let of = |f: fn(&TeamRow) -> f64| sel.iter().map(|r| f(r)).collect::<Vec<f64>>();
            TeamSummaryRow {
                config,
                trials: n,
                reached_90: times.len(),
                reached_90_ci: wilson_interval(times.len(), n, Z95),
                time_to_90: mean_ci(&times).clamped(0.0, f64::INFINITY),
                redundancy: mean_ci(&of(|r| r.redundancy)).clamped(0.0, 1.0),
                final_coverage: mean_ci(&of(|r| r.final_coverage)).clamped(0.0, 1.0),
                distance_mean_m: of(|r| r.distance_m).iter().sum::<f64>() / n as f64,
                merges_accepted: sel.iter().map(|r| r.merges_accepted).sum(),
                merges_refused: sel.iter().map(|r| r.merges_refused).sum(),
                false_merges: sel.iter().map(|r| r.merges_false).sum(),
                reachable_m2: of(|r| r.reachable_m2).iter().sum::<f64>() / n as f64,
            }
        })
        .collect()
}

/// `v` with `digits` decimals; empty when not a number (no value to give).
pub(crate) fn cell(v: f64, digits: usize) -> String {
    if v.is_finite() { format!("{v:.digits$}") } else { String::new() }
}

/// Writes `summary.csv` (through a temporary file).
pub fn write_team_summary(rows: &[TeamSummaryRow], path: &Path) -> Result<(), StudyError> {
    let mut s = format!("{TEAM_SUMMARY_HEADER}\n");
    for r in rows {
        let c = &r.config;
        let ci = |m: &MeanCi, d: usize| format!("{},{},{}", cell(m.mean, d), cell(m.lo, d), cell(m.hi, d));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{},{},{:.3},{},{},{},{:.3}",
            c.n,
            c.range_m,
            c.coordination,
            c.merger,
            r.trials,
            r.reached_90,
            r.reached_90 as f64 / r.trials.max(1) as f64,
            r.reached_90_ci.0,
            r.reached_90_ci.1,
            ci(&r.time_to_90, 3),
            ci(&r.redundancy, 4),
            ci(&r.final_coverage, 4),
            r.distance_mean_m,
            r.merges_accepted,
            r.merges_refused,
            r.false_merges,
            r.reachable_m2,
        );
    }
    mrslam_core::output::write_file_atomic(path, s.as_bytes()).map_err(|e| StudyError::file(path, e))
}

/// The summary as an aligned text table (what the CLI prints), with a note under it when some configuration has
/// trials that never reached 90 %.
pub fn team_table(rows: &[TeamSummaryRow]) -> String {
    let mut s = format!(
        "{:>3} {:>7} {:<10} {:<11} {:>10}  {:<27} {:<22} {:>9} {:>6}\n",
        "N",
        "range m",
        "coord",
        "merger",
        "reached 90",
        "time to 90 % s (95% CI)",
        "redundancy (95% CI)",
        "final cov",
        "false"
    );
    for r in rows {
        let c = &r.config;
        let t = &r.time_to_90;
        let time = match t.n {
            0 => "-".to_string(),
            1 => format!("{:.1} (one trial)", t.mean),
            _ => format!("{:.1} [{:.1}, {:.1}]", t.mean, t.lo, t.hi),
        };
        let red = &r.redundancy;
        let redundancy = if red.n < 2 {
            format!("{:.3}", red.mean)
        } else {
            format!("{:.3} [{:.3}, {:.3}]", red.mean, red.lo, red.hi)
        };
        let _ = writeln!(
            s,
            "{:>3} {:>7} {:<10} {:<11} {:>10}  {:<27} {:<22} {:>9.3} {:>6}",
            c.n,
            c.range_m,
            c.coordination.name(),
            c.merger.name(),
            format!("{}/{}", r.reached_90, r.trials),
            time,
            redundancy,
            r.final_coverage.mean,
            r.false_merges
        );
    }
    if rows.iter().any(|r| r.reached_90 < r.trials) {
        s += "time to 90 %: mean and Student t 95 % interval over the trials that reached 90 % (reached 90 = k/n); \
              the others never did and have no time\n";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::row::tests::row;

    #[test]
    fn configurations_are_summarised_with_honest_counts() {
        let mut rows = vec![
            row(0, 1, Coordination::None, Some(100.0)),
            row(1, 1, Coordination::None, Some(120.0)),
            row(2, 1, Coordination::None, None),
            row(3, 2, Coordination::Frontiers, Some(60.0)),
            row(4, 2, Coordination::Frontiers, None),
        ];
        rows[3].merges_false = 1;
        let s = summarise_team(&rows);
        assert_eq!(s.len(), 2);
        let one = &s[0];
        assert_eq!((one.config.n, one.trials, one.reached_90), (1, 3, 2));
        // Times 100 and 120: mean 110, s = 14.142, t(0.975, 1) = 12.706: ±127.06, the lower end clamped at 0.
        assert_eq!((one.time_to_90.n, one.time_to_90.mean), (2, 110.0));
        assert!((one.time_to_90.hi - (110.0 + 12.7062 * 10.0)).abs() < 1e-2, "{:?}", one.time_to_90);
        assert_eq!(one.time_to_90.lo, 0.0);
        let (lo, hi) = one.reached_90_ci;
        assert!(lo < 2.0 / 3.0 && hi > 2.0 / 3.0);
        assert_eq!((one.redundancy.mean, one.redundancy.lo, one.redundancy.hi), (0.0, 0.0, 0.0));
        let two = &s[1];
        assert_eq!((two.trials, two.reached_90, two.false_merges, two.merges_accepted), (2, 1, 1, 2));
        assert_eq!(two.time_to_90.mean, 60.0);
        assert!(two.time_to_90.lo.is_nan(), "one trial: no interval");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.csv");
        write_team_summary(&s, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], TEAM_SUMMARY_HEADER);
        assert_eq!(lines[2].split(',').count(), TEAM_SUMMARY_HEADER.split(',').count());
        assert!(lines[2].starts_with("2,6,frontiers,cascade,2,1,0.5000,"), "{}", lines[2]);
        assert!(lines[2].contains(",60.000,,,"), "an empty interval: {}", lines[2]);
        let table = team_table(&s);
        assert!(table.contains("2/3") && table.contains("(one trial)") && table.contains("never did"), "{table}");
    }
}
