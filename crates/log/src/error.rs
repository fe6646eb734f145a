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
    /// A recorded bag that cannot be read as asked: cut off, a chunk that does not decompress, no scan topic
    /// or several without a choice.
    #[error("{path}: {message}")]
    Bag {
        /// File at fault.
        path: PathBuf,
        /// What is wrong, and where (topic, byte offset).
        message: String,
    },
    /// The file is in no format a reader of this crate knows.
    #[error(
        "{path}: not a log format mrslam reads (expected a CARMEN log: .clf or .log, plain or gzipped, text lines \
         such as FLASER, ROBOTLASER1, ODOM, PARAM; a ROS 1 .bag; a ROS 2 bag: .mcap, .db3 or a folder with \
         metadata.yaml)"
    )]
    UnknownFormat {
        /// File at fault.
        path: PathBuf,
    },
}
