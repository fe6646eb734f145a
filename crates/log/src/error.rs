//! Errors reading a log.

use crate::source::Source;
use std::path::PathBuf;

/// Errors reading a log.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A compressed log ends before its stream does.
    #[error("{path}: cut off after line {line}: the gzip stream ends early (a truncated download or copy?)")]
    Truncated {
        /// File at fault.
        path: PathBuf,
        /// Last complete line.
        line: usize,
    },
    /// A record of a known kind is malformed, or stamped too long before the records above it.
    #[error("{}: {kind}: {message}", at.in_file(path))]
    Record {
        /// File at fault.
        path: PathBuf,
        /// Where the record is.
        at: Source,
        /// Record kind (FLASER, ODOM, ...).
        kind: String,
        /// What is wrong.
        message: String,
    },
    /// The file is in no format a reader of this crate knows.
    #[error(
        "{path}: not a log format mrslam reads (expected a CARMEN log: .clf or .log, plain or gzipped, text lines \
         such as FLASER, ROBOTLASER1, ODOM, PARAM)"
    )]
    UnknownFormat {
        /// File at fault.
        path: PathBuf,
    },
}
