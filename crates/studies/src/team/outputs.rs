//! A team study's output files from its rows: `results.csv`, `summary.csv`, `coverage.csv`, `plot.png` and
//! `time90.png`.

use super::coverage::{coverage_curves, write_coverage};
use super::plot::{draw_coverage, draw_time90};
use super::row::TeamRow;
use super::summary::{TeamSummaryRow, summarise_team, write_team_summary};
use crate::StudyError;
use crate::csv_row::write_rows;
use std::path::Path;

/// The files [`write_team_outputs`] writes into a study's folder (besides `study.json`, the journal's).
pub const TEAM_FILES: [&str; 5] = ["results.csv", "summary.csv", "coverage.csv", "plot.png", "time90.png"];

/// Writes the study's files of `rows` into `dir` (created if needed), `results.csv` sorted by trial; returns the
/// summary.
pub fn write_team_outputs(rows: &[TeamRow], dir: &Path) -> Result<Vec<TeamSummaryRow>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))?;
    let mut sorted = rows.to_vec();
    sorted.sort_by_key(|r| r.trial);
    write_rows(&sorted, &dir.join("results.csv"))?;
    let summary = summarise_team(&sorted);
    write_team_summary(&summary, &dir.join("summary.csv"))?;
    let curves = coverage_curves(&sorted);
    write_coverage(&curves, &dir.join("coverage.csv"))?;
    draw_coverage(&curves, &dir.join("plot.png"))?;
    draw_time90(&summary, &dir.join("time90.png"))?;
    Ok(summary)
}
