//! `summary.csv`: per overlap bin and algorithm, success rate with its Wilson 95 % interval, false merges,
//! median merge time.
//!
//! Bins: map-level rows by their target overlap; simulation-level rows (no target) by observed overlap in
//! bins [`SIM_BIN_WIDTH`] wide, named by their centre.

use super::StudyError;
use super::logs::median;
use super::results::TrialRow;
use super::wilson::{Z95, wilson_interval};
use std::fmt::Write as _;
use std::path::Path;

/// Width of the observed-overlap bins of simulation-level studies.
pub const SIM_BIN_WIDTH: f64 = 0.05;

/// The header line of `summary.csv`.
pub const SUMMARY_HEADER: &str = "overlap_bin,algorithm,trials,successes,success_rate,success_lo,success_hi,\
false_merges,false_merge_rate,median_time_ms,mean_overlap";

/// One bin of one algorithm.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryRow {
    /// The bin: target overlap, or centre of the observed-overlap bin.
    pub overlap_bin: f64,
    /// Algorithm.
    pub algorithm: String,
    /// Trials in the bin.
    pub trials: usize,
    /// Successful trials.
    pub successes: usize,
    /// successes / trials.
    pub success_rate: f64,
    /// Wilson 95 % interval of the success rate, lower end.
    pub success_lo: f64,
    /// Upper end.
    pub success_hi: f64,
    /// Accepted but wrong.
    pub false_merges: usize,
    /// false_merges / trials.
    pub false_merge_rate: f64,
    /// Median merge wall time, milliseconds.
    pub median_time_ms: f64,
    /// Mean measured overlap of the bin's trials.
    pub mean_overlap: f64,
}

/// The bin of a row.
pub fn bin_of(r: &TrialRow) -> f64 {
    match r.overlap_target {
        Some(t) => t,
        None => {
            let k = (r.overlap / SIM_BIN_WIDTH).floor();
            ((k + 0.5) * SIM_BIN_WIDTH * 1e9).round() / 1e9
        }
    }
}

/// Summarises rows: sorted by bin, then algorithm in order of first appearance.
pub fn summarise(rows: &[TrialRow]) -> Vec<SummaryRow> {
    let mut order: Vec<&str> = Vec::new();
    for r in rows {
        if !order.contains(&r.algorithm.as_str()) {
            order.push(&r.algorithm);
        }
    }
    let mut bins: Vec<f64> = rows.iter().map(bin_of).collect();
    bins.sort_by(f64::total_cmp);
    bins.dedup();
    let mut out = Vec::new();
    for &b in &bins {
        for &alg in &order {
            let sel: Vec<&TrialRow> = rows.iter().filter(|r| r.algorithm == alg && bin_of(r) == b).collect();
            if sel.is_empty() {
                continue;
            }
            let n = sel.len();
            let successes = sel.iter().filter(|r| r.success).count();
            let false_merges = sel.iter().filter(|r| r.false_merge).count();
            let (lo, hi) = wilson_interval(successes, n, Z95);
            let mut times: Vec<f64> = sel.iter().map(|r| r.time_ms).collect();
            out.push(SummaryRow {
                overlap_bin: b,
                algorithm: alg.to_string(),
                trials: n,
                successes,
                success_rate: successes as f64 / n as f64,
                success_lo: lo,
                success_hi: hi,
                false_merges,
                false_merge_rate: false_merges as f64 / n as f64,
                median_time_ms: median(&mut times),
                mean_overlap: sel.iter().map(|r| r.overlap).sum::<f64>() / n as f64,
            });
        }
    }
    out
}

/// Writes `summary.csv`.
pub fn write_summary(rows: &[SummaryRow], path: &Path) -> Result<(), StudyError> {
    let mut s = String::new();
    s.push_str(SUMMARY_HEADER);
    s.push('\n');
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.4},{:.4},{:.4},{},{:.4},{:.3},{:.4}",
            r.overlap_bin,
            r.algorithm,
            r.trials,
            r.successes,
            r.success_rate,
            r.success_lo,
            r.success_hi,
            r.false_merges,
            r.false_merge_rate,
            r.median_time_ms,
            r.mean_overlap
        );
    }
    mrslam_core::output::write_file_atomic(path, s.as_bytes()).map_err(|e| StudyError::file(path, e))
}

/// The summary as an aligned text table (what the CLI prints).
pub fn table(rows: &[SummaryRow]) -> String {
    let mut s = format!(
        "{:>7}  {:<6} {:>6} {:>5} {:>6}  {:<15} {:>7} {:>11}\n",
        "overlap", "algo", "trials", "succ", "rate", "95% CI", "false", "median ms"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:>7.3}  {:<6} {:>6} {:>5} {:>6.2}  [{:.2}, {:.2}]    {:>7.2} {:>11.1}",
            r.overlap_bin,
            r.algorithm,
            r.trials,
            r.successes,
            r.success_rate,
            r.success_lo,
            r.success_hi,
            r.false_merge_rate,
            r.median_time_ms
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(trial: usize, target: Option<f64>, overlap: f64, alg: &str, success: bool, t: f64) -> TrialRow {
        TrialRow {
            trial,
            overlap_target: target,
            overlap,
            seed: 1,
            algorithm: alg.into(),
            accepted: true,
            success,
            false_merge: !success,
            rotation_error_deg: Some(0.0),
            translation_error_m: Some(0.0),
            time_ms: t,
            rotation_error_at_end_deg: None,
            translation_error_at_end_m: None,
            stage: String::new(),
        }
    }

    #[test]
    fn bins_by_target_and_counts() {
        let rows = vec![
            row(0, Some(0.1), 0.1, "sift", true, 1.0),
            row(0, Some(0.1), 0.1, "rmap", false, 10.0),
            row(1, Some(0.1), 0.1, "sift", false, 3.0),
            row(1, Some(0.1), 0.1, "rmap", false, 20.0),
            row(2, Some(0.3), 0.3, "sift", true, 2.0),
            row(2, Some(0.3), 0.3, "rmap", true, 30.0),
        ];
        let s = summarise(&rows);
        assert_eq!(s.len(), 4);
        assert_eq!((s[0].overlap_bin, s[0].algorithm.as_str(), s[0].trials, s[0].successes), (0.1, "sift", 2, 1));
        assert_eq!(s[0].median_time_ms, 2.0);
        assert_eq!(s[1].algorithm, "rmap");
        assert_eq!(s[1].false_merges, 2);
        assert_eq!(s[3].success_rate, 1.0);
    }

    #[test]
    fn observed_overlaps_fall_in_bins() {
        assert_eq!(bin_of(&row(0, None, 0.12, "sift", true, 1.0)), 0.125);
        assert_eq!(bin_of(&row(0, None, 0.0, "sift", true, 1.0)), 0.025);
    }
}
