//! A team study's `coverage.csv`: per configuration and time of the common grid, the mean coverage of its trials
//! with the Student t 95 % interval (clamped to [0, 1]), and the lowest and highest trial.

use super::row::TeamRow;
use super::summary::{ConfigKey, cell, configs_of};
use crate::StudyError;
use crate::student_t::{MeanCi, mean_ci};
use std::fmt::Write as _;
use std::path::Path;

/// The header line of `coverage.csv`.
pub const COVERAGE_HEADER: &str = "n,range_m,coordination,merger,t_s,trials,mean,lo,hi,min,max";

/// One configuration's coverage over time.
#[derive(Debug, Clone, PartialEq)]
pub struct CoverageCurve {
    /// The configuration.
    pub config: ConfigKey,
    /// Grid times, seconds.
    pub times: Vec<f64>,
    /// At each time: the trials' mean coverage and its 95 % interval.
    pub mean: Vec<MeanCi>,
    /// At each time: the lowest trial's coverage.
    pub min: Vec<f64>,
    /// At each time: the highest trial's coverage.
    pub max: Vec<f64>,
}

/// The mean curve of each configuration of `rows`, in order of first appearance. Rows of one study share their
/// grid; should lengths differ (shards of different durations cannot be collected, so only by hand), the curve
/// stops where the shortest does.
pub fn coverage_curves(rows: &[TeamRow]) -> Vec<CoverageCurve> {
    configs_of(rows)
        .into_iter()
        .map(|config| {
            let sel: Vec<&TeamRow> = rows.iter().filter(|r| ConfigKey::of(r) == config).collect();
            let len = sel.iter().map(|r| r.coverage.len()).min().unwrap_or(0);
            let step = sel.first().map_or(1.0, |r| r.coverage_step_s);
            let mut curve =
                CoverageCurve { config, times: Vec::new(), mean: Vec::new(), min: Vec::new(), max: Vec::new() };
            for k in 0..len {
                let at: Vec<f64> = sel.iter().map(|r| r.coverage[k]).collect();
                curve.times.push(k as f64 * step);
                curve.mean.push(mean_ci(&at).clamped(0.0, 1.0));
                curve.min.push(at.iter().copied().fold(f64::INFINITY, f64::min));
                curve.max.push(at.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            }
            curve
        })
        .collect()
}

/// Writes `coverage.csv` (through a temporary file).
pub fn write_coverage(curves: &[CoverageCurve], path: &Path) -> Result<(), StudyError> {
    let mut s = format!("{COVERAGE_HEADER}\n");
    for c in curves {
        let k = &c.config;
        for (i, t) in c.times.iter().enumerate() {
            let m = &c.mean[i];
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{:.4},{:.4}",
                k.n,
                k.range_m,
                k.coordination,
                k.merger,
                (t * 1e6).round() / 1e6,
                m.n,
                cell(m.mean, 4),
                cell(m.lo, 4),
                cell(m.hi, 4),
                c.min[i],
                c.max[i]
            );
        }
    }
    mrslam_core::output::write_file_atomic(path, s.as_bytes()).map_err(|e| StudyError::file(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::row::tests::row;
    use mrslam_testbed::scenario::Coordination;

    #[test]
    fn curves_average_point_by_point() {
        let mut a = row(0, 2, Coordination::None, Some(6.0));
        let mut b = row(1, 2, Coordination::None, Some(6.0));
        a.coverage = vec![0.0, 0.2, 0.6, 1.0];
        b.coverage = vec![0.0, 0.4, 0.8, 1.0];
        let c = row(2, 1, Coordination::None, None);
        let curves = coverage_curves(&[a, b, c]);
        assert_eq!(curves.len(), 2);
        let two = &curves[0];
        assert_eq!(two.times, [0.0, 2.0, 4.0, 6.0]);
        let means: Vec<f64> = two.mean.iter().map(|m| (m.mean * 1e9).round() / 1e9).collect();
        assert_eq!(means, [0.0, 0.3, 0.7, 1.0]);
        // Two trials 0.2 apart: s = 0.1414, t(0.975, 1) = 12.706: the interval is [0, 1] once clamped.
        assert_eq!((two.mean[1].lo, two.mean[1].hi), (0.0, 1.0));
        assert_eq!((two.min[2], two.max[2]), (0.6, 0.8));
        assert_eq!(curves[1].mean[1].n, 1);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("coverage.csv");
        write_coverage(&curves, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 1 + 4 + 4);
        assert_eq!(lines[0], COVERAGE_HEADER);
        assert_eq!(lines[2], "2,6,none,cascade,2,2,0.3000,0.0000,1.0000,0.2000,0.4000");
        assert_eq!(lines[6], "1,6,none,cascade,2,1,0.2500,,,0.2500,0.2500");
    }
}
