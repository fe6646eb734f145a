//! `results.csv`: one row per trial and algorithm; writing, reading, and joining the shards of a study.
//!
//! Columns (README, "Studies"): `trial, overlap_target, overlap, seed, algorithm, accepted, success,
//! false_merge, rotation_error_deg, translation_error_m, time_ms, rotation_error_at_end_deg,
//! translation_error_at_end_m`. Empty cells: `overlap_target` in simulation-level studies (the overlap is
//! observed, not chosen), the errors when the algorithm found no transform, the two errors at the end in
//! map-level studies (a cut pair has no SLAM drift: its truth is exact). Booleans are `true`/`false`.

use super::StudyError;
use super::csv_row::{CsvRow, collect_rows, optional, parse_rows, read_rows, write_rows};
use std::path::{Path, PathBuf};

/// The header line of `results.csv`.
pub const HEADER: &str = "trial,overlap_target,overlap,seed,algorithm,accepted,success,false_merge,\
rotation_error_deg,translation_error_m,time_ms,rotation_error_at_end_deg,translation_error_at_end_m,stage";

/// Number of columns of `results.csv`.
const COLUMNS: usize = 14;

/// One trial of one algorithm.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialRow {
    /// Trial index within the study (shared by the algorithms of one trial).
    pub trial: usize,
    /// Overlap asked of the pair generator (map-level studies only).
    pub overlap_target: Option<f64>,
    /// Overlap measured: the pair's Jaccard overlap of known cells, or the run's observed overlap.
    pub overlap: f64,
    /// Seed of the trial.
    pub seed: u64,
    /// Algorithm.
    pub algorithm: String,
    /// Passed the verification gate.
    pub accepted: bool,
    /// Accepted and within the error thresholds of the truth.
    pub success: bool,
    /// Accepted but not a success: a wrong map the gate let through.
    pub false_merge: bool,
    /// Rotation error against the truth, degrees (None without a transform).
    pub rotation_error_deg: Option<f64>,
    /// Translation error against the truth, metres (None without a transform).
    pub translation_error_m: Option<f64>,
    /// Wall time of the merge, milliseconds.
    pub time_ms: f64,
    /// Simulation-level studies: rotation error against the maps' relative pose as the robots' last poses
    /// place them, degrees (see `MergeResult::rotation_error_at_end_deg`).
    pub rotation_error_at_end_deg: Option<f64>,
    /// Translation error against that pose, metres.
    pub translation_error_at_end_m: Option<f64>,
    /// The stage of a cascade that decided (its last stage for a refusal); empty for one algorithm.
    pub stage: String,
}

/// Every column but `time_ms` is a pure function of the trial.
impl CsvRow for TrialRow {
    const HEADER: &'static str = HEADER;

    fn trial(&self) -> usize {
        self.trial
    }

    fn to_csv(&self) -> String {
        format!(
            "{},{},{:.6},{},{},{},{},{},{},{},{:.3},{},{},{}",
            self.trial,
            self.overlap_target.map_or(String::new(), |v| v.to_string()),
            self.overlap,
            self.seed,
            self.algorithm,
            self.accepted,
            self.success,
            self.false_merge,
            optional(self.rotation_error_deg, 6),
            optional(self.translation_error_m, 6),
            self.time_ms,
            optional(self.rotation_error_at_end_deg, 6),
            optional(self.translation_error_at_end_m, 6),
            self.stage,
        )
    }

    fn from_csv(line: &str) -> Result<TrialRow, String> {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != COLUMNS {
            return Err(format!("expected {COLUMNS} columns, found {}", f.len()));
        }
        let name = |i: usize| HEADER.split(',').nth(i).unwrap_or("?");
        fn num<T: std::str::FromStr>(f: &[&str], i: usize, name: &dyn Fn(usize) -> &'static str) -> Result<T, String> {
            f[i].parse().map_err(|_| format!("{}: `{}` is not a valid value", name(i), f[i]))
        }
        let opt_num = |i: usize| -> Result<Option<f64>, String> {
            if f[i].is_empty() { Ok(None) } else { num(&f, i, &name).map(Some) }
        };
        let boolean = |i: usize| match f[i] {
            "true" => Ok(true),
            "false" => Ok(false),
            v => Err(format!("{}: `{v}` is not true or false", name(i))),
        };
        if f[4].is_empty() {
            return Err("algorithm: empty".into());
        }
        Ok(TrialRow {
            trial: num(&f, 0, &name)?,
            overlap_target: opt_num(1)?,
            overlap: num(&f, 2, &name)?,
            seed: num(&f, 3, &name)?,
            algorithm: f[4].to_string(),
            accepted: boolean(5)?,
            success: boolean(6)?,
            false_merge: boolean(7)?,
            rotation_error_deg: opt_num(8)?,
            translation_error_m: opt_num(9)?,
            time_ms: num(&f, 10, &name)?,
            rotation_error_at_end_deg: opt_num(11)?,
            translation_error_at_end_m: opt_num(12)?,
            stage: f[13].to_string(),
        })
    }
}

/// Sorts rows by trial, then by the order the algorithms were given in (`order`; others by name after).
pub fn sort_rows<S: AsRef<str>>(rows: &mut [TrialRow], order: &[S]) {
    let rank = |a: &str| order.iter().position(|o| o.as_ref() == a).unwrap_or(usize::MAX);
    rows.sort_by(|x, y| {
        x.trial.cmp(&y.trial).then(rank(&x.algorithm).cmp(&rank(&y.algorithm))).then(x.algorithm.cmp(&y.algorithm))
    });
}

/// Writes `results.csv`.
pub fn write_results(rows: &[TrialRow], path: &Path) -> Result<(), StudyError> {
    write_rows(rows, path)
}

/// Reads a `results.csv`, checking its header.
pub fn read_results(path: &Path) -> Result<Vec<TrialRow>, StudyError> {
    Ok(read_rows(path)?.into_iter().map(|(_, r)| r).collect())
}

/// Parses the text of a `results.csv`, checking its header; `path` only names it in errors.
pub fn parse_results(text: &str, path: &Path) -> Result<Vec<TrialRow>, StudyError> {
    Ok(parse_rows(text, path)?.into_iter().map(|(_, r)| r).collect())
}

/// Joins the `results.csv` of several shard folders, refusing a (trial, algorithm) found twice.
/// Rows come back sorted by trial, then algorithm in order of first appearance.
pub fn collect(dirs: &[PathBuf]) -> Result<Vec<TrialRow>, StudyError> {
    let mut all = collect_rows(
        dirs,
        |r: &TrialRow| (r.trial, r.algorithm.clone()),
        |r| format!("trial {} of `{}`", r.trial, r.algorithm),
    )?;
    let mut order: Vec<String> = Vec::new();
    for r in &all {
        if !order.contains(&r.algorithm) {
            order.push(r.algorithm.clone());
        }
    }
    sort_rows(&mut all, &order);
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(trial: usize, alg: &str) -> TrialRow {
        TrialRow {
            trial,
            overlap_target: Some(0.05),
            overlap: 0.0512345678,
            seed: 123456789012345,
            algorithm: alg.into(),
            accepted: true,
            success: false,
            false_merge: true,
            rotation_error_deg: Some(12.5),
            translation_error_m: None,
            time_ms: 3.25,
            rotation_error_at_end_deg: None,
            translation_error_at_end_m: Some(0.125),
            stage: "sift+boundary".into(),
        }
    }

    #[test]
    fn rows_round_trip() {
        let r = row(3, "sift");
        let line = r.to_csv();
        assert_eq!(
            line,
            "3,0.05,0.051235,123456789012345,sift,true,false,true,12.500000,,3.250,,0.125000,sift+boundary"
        );
        let back = TrialRow::from_csv(&line).unwrap();
        assert_eq!(back.to_csv(), line);
        assert!(TrialRow::from_csv("1,2,3").unwrap_err().contains("14 columns"));
        assert!(TrialRow::from_csv(&line.replace("true,false", "yes,false")).unwrap_err().contains("accepted"));
    }

    #[test]
    fn collect_joins_and_refuses_duplicates_and_bad_headers() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (dir.path().join("a"), dir.path().join("b"), dir.path().join("c"));
        for d in [&a, &b, &c] {
            std::fs::create_dir_all(d).unwrap();
        }
        write_results(&[row(0, "sift"), row(0, "rmap"), row(2, "sift"), row(2, "rmap")], &a.join("results.csv"))
            .unwrap();
        write_results(&[row(1, "sift"), row(1, "rmap")], &b.join("results.csv")).unwrap();
        let all = collect(&[a.clone(), b.clone()]).unwrap();
        let keys: Vec<(usize, &str)> = all.iter().map(|r| (r.trial, r.algorithm.as_str())).collect();
        assert_eq!(keys, [(0, "sift"), (0, "rmap"), (1, "sift"), (1, "rmap"), (2, "sift"), (2, "rmap")]);
        let e = collect(&[a.clone(), a.clone()]).unwrap_err().to_string();
        assert!(e.contains("trial 0") && e.contains("also in"), "{e}");
        std::fs::write(c.join("results.csv"), "trial,overlap\n1,0.2\n").unwrap();
        let e = collect(&[a, c]).unwrap_err().to_string();
        assert!(e.contains("header"), "{e}");
    }
}
