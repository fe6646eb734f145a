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
    /// A line longer than [`ReadOptions::max_line_bytes`](crate::ReadOptions::max_line_bytes): not a text log.
    #[error("{path}:{line}: line longer than {limit} bytes: not a text log (a device or a binary file?)")]
    LineTooLong {
        /// File at fault.
        path: PathBuf,
        /// The line's number.
        line: usize,
        /// The bound, bytes.
        limit: usize,
    },
    /// More bytes than [`ReadOptions::max_bytes`](crate::ReadOptions::max_bytes), once decompressed.
    #[error(
        "{path}: more than {}{}: refused before it exhausts memory (an endless device, or a compression bomb?)",
        size_text(*.limit), if *.compressed { " once decompressed" } else { "" }
    )]
    TooLarge {
        /// File at fault.
        path: PathBuf,
        /// The bound, bytes.
        limit: u64,
        /// Whether the file is gzipped.
        compressed: bool,
    },
    /// Records that would hold more than [`ReadOptions::max_bytes`](crate::ReadOptions::max_bytes) in memory:
    /// a scan's ranges take 4 bytes each, more than the two characters `1 ` of text.
    #[error(
        "{path}: its records would hold more than {} in memory by line {line}: refused before it exhausts memory",
        size_text(*.limit)
    )]
    TooMuchHeld {
        /// File at fault.
        path: PathBuf,
        /// The line read when the bound was passed.
        line: usize,
        /// The bound, bytes.
        limit: u64,
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

/// A size as people read it: "2 GiB", "1 MiB", or bytes when it is not a whole number of either.
fn size_text(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 30 && b % (1 << 30) == 0 => format!("{} GiB", b >> 30),
        b if b >= 1 << 20 && b % (1 << 20) == 0 => format!("{} MiB", b >> 20),
        b => format!("{b} bytes"),
    }
}
