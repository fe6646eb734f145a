//! A study's output files: results, summary and plot.

use crate::StudyError;
use crate::plot;
use crate::results::{TrialRow, write_results};
use crate::summary::{SummaryRow, summarise, write_summary};

/// Writes `results.csv`, `summary.csv` and `plot.png` of `rows` into `dir` (created if needed).
pub fn write_outputs(rows: &[TrialRow], dir: &std::path::Path) -> Result<Vec<SummaryRow>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))?;
    write_results(rows, &dir.join("results.csv"))?;
    let summary = summarise(rows);
    write_summary(&summary, &dir.join("summary.csv"))?;
    plot::draw(&summary, &dir.join("plot.png"))?;
    Ok(summary)
}
