//! mrslam-log: sensor logs for SLAM, read from any format into one neutral [`SensorLog`].
//!
//! [`read_log`] chooses the reader by the file's magic bytes or extension (today CARMEN `.clf`/`.log`,
//! plain or gzipped); each reader parses its records into a [`SensorLog`] (every scan's place in the file
//! a [`Source`]: a line, or a topic and message index) and applies the repairs every format needs, the
//! functions of [`repair`]: stamp order, repeated readings dropped, odometry interpolated at scan stamps,
//! reversed odometry increments turned round, each counted in [`Repairs`].
//!
//! ```no_run
//! use mrslam_log::{ReadOptions, read_log};
//!
//! let log = read_log(std::path::Path::new("aces.clf.gz"), &ReadOptions::default())?;
//! println!("{} scans; {}", log.scans.len(), log.repairs.describe());
//! # Ok::<(), mrslam_log::LogError>(())
//! ```

#![deny(missing_docs)]

// Private modules, their items re-exported below; `carmen` (the CARMEN reader), `carmen_writer` (the CARMEN
// writer) and `repair` (the repairs) are public namespaces, their items not re-exported.
pub mod carmen;
pub mod carmen_writer;
mod error;
mod options;
mod read;
pub mod repair;
mod sensor_log;
mod source;

pub use error::LogError;
pub use options::{MAX_LINE_BYTES, MAX_LOG_BYTES, MAX_STEP_BACK, OdometrySource, ReadOptions};
pub use read::{Format, format_by_content, format_by_extension, log_name, read_log};
pub use sensor_log::{OdometryRecord, Repairs, ScanRecord, SensorLog};
pub use source::{Source, span};
