//! mrslam-log: sensor logs for SLAM, read from any format into one neutral [`SensorLog`].
//!
//! [`read_log`] chooses the reader by the file's magic bytes or extension (CARMEN `.clf`/`.log`, plain or
//! gzipped; ROS 1 `.bag`; ROS 2 `.mcap`, `.db3` or a bag folder with `metadata.yaml`); each reader parses its records into a [`SensorLog`] (every scan's place in the file
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
mod bag_assemble;
mod bag_messages;
mod bag_read;
mod bag_summary;
pub mod carmen;
pub mod carmen_writer;
mod cdr_msg;
mod error;
mod format;
mod mcap_bag;
mod mcap_chunk;
mod mcap_frames;
mod mcap_writer;
mod options;
mod read;
pub mod repair;
mod robot_speed;
mod ros1_bag;
mod ros1_msg;
mod ros2_folder;
mod ros2_msg;
mod ros_msg;
mod sensor_log;
mod source;
mod sqlite_bag;

pub use bag_summary::{BagSummary, TopicSummary};
pub use error::LogError;
pub use format::{Format, format_by_content, format_by_extension};
pub use mcap_writer::{McapWriteError, RunBagWriter, WORLD_FRAME, robot_frame};
pub use options::{MAX_LINE_BYTES, MAX_LOG_BYTES, MAX_STEP_BACK, OdometrySource, ReadOptions, TopicChoice};
pub use read::{log_name, read_log};
pub use robot_speed::{MAX_SPEED, MAX_TURN_RATE, faster_than_a_robot};
pub use sensor_log::{OdometryRecord, Repairs, ScanRecord, SensorLog};
pub use source::{Source, span};
