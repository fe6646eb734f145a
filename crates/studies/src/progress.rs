//! What a study does as it goes: resume and hand over finished rows.

use crate::StudyError;
use crate::results::TrialRow;

/// What a study does as it goes: it asks whether to run each selected trial (a resumed study skips those it
/// has), and hands over each finished trial's rows at once (the CLI appends them to `results.csv`). `R` is the
/// study's row: a merge study's [`TrialRow`] by default.
pub trait Progress<R = TrialRow>: Sync {
    /// Whether trial `trial` is already done and is to be skipped.
    fn skip(&self, _trial: usize) -> bool {
        false
    }
    /// Called with the rows of each finished trial (or of several trials one run answers at once), from the
    /// worker thread that ran it.
    fn finished(&self, _rows: &[R]) -> Result<(), StudyError> {
        Ok(())
    }
}

/// No resume, nothing reported.
impl<R> Progress<R> for () {}
