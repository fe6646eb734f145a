//! Team studies (`mrslam study team`): a team scenario run over a grid of configurations — how many of its robots
//! (the first N), communication range, coordination, online merger — and seeds; each trial one whole run, scored
//! by the run's team report (coverage of the reachable free area over time, redundancy, online merges checked
//! against the truth, bytes sent).
//!
//! What runs (`study`: the configurations, each trial's scenario, the trials one run answers), running it (`run`),
//! the rows of `results.csv` (`row`), the coverage curves on a common time grid (`curve`), the per-configuration
//! summary with Student t 95 % intervals (`summary`), the mean coverage curves (`coverage`), the pictures (`plot`)
//! and the files written from the rows (`outputs`).

mod coverage;
mod curve;
mod outputs;
mod plot;
mod row;
mod run;
mod study;
mod summary;

pub use coverage::{COVERAGE_HEADER, CoverageCurve, coverage_curves, write_coverage};
pub use curve::{grid_len, resample};
pub use outputs::{TEAM_FILES, write_team_outputs};
pub use plot::{draw_coverage, draw_time90, render_coverage, render_time90};
pub use row::{TEAM_HEADER, TeamRow, collect_team, read_team_results};
pub use run::run_team_study;
pub use study::{Config, TeamAxes, TeamStudy};
pub use summary::{
    ConfigKey, TEAM_SUMMARY_HEADER, TeamSummaryRow, configs_of, summarise_team, team_table, write_team_summary,
};
