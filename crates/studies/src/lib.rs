//! mrslam-studies: many seeded merge trials across overlaps, summarised with confidence intervals and plotted.
//!
//! Two kinds of trial produce the same rows ([`results::TrialRow`]):
//! - **map level** ([`overlap`]): a ground-truth map (generated floor plan, a world's true map, or a real
//!   map) is cut into a pair with a chosen overlap ([`mrslam_merge::pairs::cut_pair`]); every algorithm
//!   merges the pair through the verification gate and is scored against the pair's true transform;
//! - **simulation level** (`sweep`): a sweep file varies a scenario (seeds, how far each robot's route
//!   reaches); each variant runs the whole simulation, SLAM and merge, and its overlap is the one the
//!   robots actually observed.
//!
//! A third kind, **real data** ([`logs`]), splits a real robot's log in time into parts ("robots"), maps each
//! part with the SLAM, merges the pairs that benchmark relations connect and scores them against the
//! relations; it writes its own `results.csv` columns (one row per pair and algorithm).
//!
//! Rows go to `results.csv` ([`results`]); [`summary`] bins them by overlap with Wilson intervals
//! (`wilson`) into `summary.csv`; [`plot`] draws `plot.png`. `shard` splits one study across processes
//! and [`results::collect`] joins the shards again. Every trial is seeded from (study seed, overlap index,
//! trial index) alone (`trial`), so a shard computes exactly the rows the whole study would.
//!
//! ```
//! use mrslam_studies::{Z95, parse_range, wilson_interval};
//!
//! // The overlaps of a study (`--overlaps 0.1:0.5:0.1`) and the 95 % interval of 8 successes in 10 trials.
//! assert_eq!(parse_range("0.1:0.5:0.1").unwrap().len(), 5);
//! let (lo, hi) = wilson_interval(8, 10, Z95);
//! assert!(lo > 0.49 && hi < 0.95);
//! ```

#![deny(missing_docs)]

// `journal`, `logs`, `overlap`, `plot`, `results` and `summary` are public namespaces (their items are not
// re-exported); the other modules are private, their items re-exported below: each item has one path.
mod algorithms;
pub mod journal;
pub mod logs;
pub mod overlap;
pub mod plot;
mod range;
pub mod results;
mod shard;
pub mod summary;
mod sweep;
mod trial;
mod wilson;

use std::path::PathBuf;

/// Why a study could not run or its files could not be read.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A parameter is out of range or malformed; the message names it.
    #[error("{0}")]
    Invalid(String),
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    File {
        /// File at fault.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A results file is malformed, or shards disagree.
    #[error("{}: {message}", mrslam_testbed::scenario::at(path, *line))]
    Results {
        /// File at fault.
        path: PathBuf,
        /// 1-based line (0 when not tied to one line).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A simulation trial failed.
    #[error("trial {trial}: {message}")]
    Trial {
        /// Trial index.
        trial: usize,
        /// What went wrong.
        message: String,
    },
}

impl StudyError {
    pub(crate) fn file(path: impl Into<PathBuf>, e: impl std::fmt::Display) -> StudyError {
        StudyError::File { path: path.into(), message: e.to_string() }
    }
}

/// What a study does as it goes: it asks whether to run each selected trial (a resumed study skips those it
/// has), and hands over each finished trial's rows at once (the CLI appends them to `results.csv`).
pub trait Progress: Sync {
    /// Whether trial `trial` is already done and is to be skipped.
    fn skip(&self, _trial: usize) -> bool {
        false
    }
    /// Called with the rows of each finished trial, from the worker thread that ran it.
    fn finished(&self, _rows: &[TrialRow]) -> Result<(), StudyError> {
        Ok(())
    }
}

/// No resume, nothing reported.
impl Progress for () {}

pub use algorithms::{check_algorithms, parse_algorithms};
pub use range::parse_range;
pub use shard::Shard;
pub use sweep::{Sweep, run_sweep};
pub use wilson::{Z95, wilson_interval};

use results::{TrialRow, write_results};
use summary::{SummaryRow, summarise, write_summary};

/// Writes `results.csv`, `summary.csv` and `plot.png` of `rows` into `dir` (created if needed).
pub fn write_outputs(rows: &[TrialRow], dir: &std::path::Path) -> Result<Vec<SummaryRow>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))?;
    write_results(rows, &dir.join("results.csv"))?;
    let summary = summarise(rows);
    write_summary(&summary, &dir.join("summary.csv"))?;
    plot::draw(&summary, &dir.join("plot.png"))?;
    Ok(summary)
}
