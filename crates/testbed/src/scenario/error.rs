//! Scenario errors, and the context that places them in the file.

use mrslam_core::toml_lines::TomlLines;
use std::path::{Path, PathBuf};

/// A scenario error, naming the file, line and field.
#[derive(Debug, thiserror::Error)]
#[error("{}: {field}: {message}", at(path, *line))]
pub struct ScenarioError {
    /// File at fault.
    pub path: PathBuf,
    /// 1-based line (0 when the problem is not tied to one line).
    pub line: usize,
    /// Dotted path of the field, e.g. `robots[1].lidar`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// `file:line`, or the file alone when the problem is not tied to a line.
pub fn at(path: &Path, line: usize) -> String {
    if line == 0 { path.display().to_string() } else { format!("{}:{line}", path.display()) }
}

/// The file being resolved: its path and its lines, to name where an error lies.
pub(super) struct Ctx<'a> {
    pub(super) path: &'a Path,
    pub(super) lines: TomlLines<'a>,
}

impl Ctx<'_> {
    /// An error on `field` (a dotted path such as `robots[1].speed`), located at the line where the field is
    /// written, or where its table is when the field was left out.
    pub(super) fn err(&self, field: impl Into<String>, message: impl Into<String>) -> ScenarioError {
        let field = field.into();
        ScenarioError { path: self.path.to_path_buf(), line: self.lines.line(&field), field, message: message.into() }
    }
}

/// Overwrites each destination with its source value when one is given.
pub(super) fn apply<T: Copy>(pairs: &mut [(&mut T, Option<T>)]) {
    for (dst, src) in pairs.iter_mut() {
        if let Some(v) = *src {
            **dst = v;
        }
    }
}
