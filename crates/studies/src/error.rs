//! Why a study could not run or its files could not be read.

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
