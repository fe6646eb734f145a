//! A study's rows as CSV lines: the shape every kind of study's `results.csv` takes (a header, then one line per
//! row, each row belonging to one trial), so that one journal resumes them all and one reader checks them.

use crate::StudyError;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A row of a study's `results.csv`: written as one CSV line under [`CsvRow::HEADER`], read back from it.
pub trait CsvRow: Sized {
    /// The header line of the file the rows go to.
    const HEADER: &'static str;
    /// The index of the trial the row belongs to.
    fn trial(&self) -> usize;
    /// The row as a CSV line (no newline).
    fn to_csv(&self) -> String;
    /// Parses a line written by [`CsvRow::to_csv`]; the error names the column at fault.
    fn from_csv(line: &str) -> Result<Self, String>;
}

/// Parses the text of a results file, checking its header: every row with its 1-based line; `path` only names
/// the file in errors.
pub(crate) fn parse_rows<R: CsvRow>(text: &str, path: &Path) -> Result<Vec<(usize, R)>, StudyError> {
    let err = |line: usize, message: String| StudyError::Results { path: path.to_path_buf(), line, message };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == R::HEADER => {}
        Some((_, h)) => return Err(err(1, format!("header `{}` is not the expected `{}`", h.trim(), R::HEADER))),
        None => return Err(err(1, "empty file, expected a header".into())),
    }
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| R::from_csv(l).map(|r| (i + 1, r)).map_err(|m| err(i + 1, m)))
        .collect()
}

/// Reads a results file (of at most [`mrslam_core::input::DATA_LIMIT`] bytes), checking its header: every row
/// with its 1-based line.
pub(crate) fn read_rows<R: CsvRow>(path: &Path) -> Result<Vec<(usize, R)>, StudyError> {
    let text = mrslam_core::input::read_text_limited(path, mrslam_core::input::DATA_LIMIT)
        .map_err(|e| StudyError::file(path, e))?;
    parse_rows(&text, path)
}

/// The header and `rows`, one line each, as the text of a results file.
pub(crate) fn rows_text<R: CsvRow>(rows: &[R]) -> String {
    let mut s = String::with_capacity(80 * (rows.len() + 1));
    s.push_str(R::HEADER);
    s.push('\n');
    for r in rows {
        let _ = writeln!(s, "{}", r.to_csv());
    }
    s
}

/// Writes `rows` under their header at `path` (through a temporary file).
pub(crate) fn write_rows<R: CsvRow>(rows: &[R], path: &Path) -> Result<(), StudyError> {
    mrslam_core::output::write_file_atomic(path, rows_text(rows).as_bytes()).map_err(|e| StudyError::file(path, e))
}

/// Joins the `results.csv` of a study's shard folders, in folder then line order, refusing a row whose `key`
/// (what one row of the study is: a trial, or a trial and an algorithm) came already; `name` says which row in
/// that error ("trial 3", "trial 3 of `sift`").
pub(crate) fn collect_rows<R: CsvRow, K: Ord>(
    dirs: &[PathBuf],
    key: impl Fn(&R) -> K,
    name: impl Fn(&R) -> String,
) -> Result<Vec<R>, StudyError> {
    if dirs.is_empty() {
        return Err(StudyError::Invalid("collect: no shard folders given".into()));
    }
    let mut seen: BTreeMap<K, (PathBuf, usize)> = BTreeMap::new();
    let mut all = Vec::new();
    for d in dirs {
        let path = d.join("results.csv");
        for (line, r) in read_rows::<R>(&path)? {
            if let Some((first, first_line)) = seen.insert(key(&r), (path.clone(), line)) {
                let message = format!(
                    "{} is also in {}:{first_line}: shards overlap (same shard collected twice?)",
                    name(&r),
                    first.display()
                );
                return Err(StudyError::Results { path, line, message });
            }
            all.push(r);
        }
    }
    Ok(all)
}

/// A number with `digits` decimals, or an empty column for none.
pub(crate) fn optional(v: Option<f64>, digits: usize) -> String {
    v.map_or(String::new(), |x| format!("{x:.digits$}"))
}
