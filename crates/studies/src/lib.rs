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
//! A fourth kind, **team studies** ([`team`]), runs a team scenario (robots that merge their maps while they
//! drive) over numbers of robots, communication ranges, coordinations and online mergers, and reports coverage over
//! time, time to 90 % coverage and redundancy per configuration with Student t 95 % intervals (`student_t`); it
//! too writes its own `results.csv` columns (one row per trial).
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

// `journal`, `logs`, `overlap`, `plot`, `results`, `summary` and `team` are public namespaces (their items are
// not re-exported); the other modules are private, their items re-exported below: each item has one path.
mod algorithms;
mod csv_row;
mod error;
pub mod journal;
mod list;
pub mod logs;
mod outputs;
pub mod overlap;
pub mod plot;
mod progress;
mod range;
pub mod results;
mod shard;
mod student_t;
pub mod summary;
mod sweep;
pub mod team;
mod trial;
mod wilson;

pub use algorithms::{check_algorithms, parse_algorithms};
pub use csv_row::CsvRow;
pub use error::StudyError;
pub use list::{parse_numbers, parse_whole_numbers};
pub use outputs::write_outputs;
pub use progress::Progress;
pub use range::parse_range;
pub use shard::Shard;
pub use student_t::{MeanCi, mean_ci, t_quantile};
pub use sweep::{Sweep, run_sweep};
pub use wilson::{Z95, wilson_interval};
