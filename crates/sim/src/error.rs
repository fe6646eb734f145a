//! The simulator's error type.

use std::path::PathBuf;

/// Everything that can go wrong building a world or driving the simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A world file is malformed or describes impossible geometry.
    #[error("{path}:{line}: field `{field}`: {message}")]
    WorldFile {
        /// File at fault (`<memory>` for text without a file).
        path: PathBuf,
        /// 1-based line number of the offending field.
        line: usize,
        /// Dotted path of the field at fault, e.g. `boxes[2].size`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The bitmap layer's ROS map could not be loaded.
    #[error("{path}: bitmap layer: {cause}")]
    Bitmap {
        /// World file that names the map.
        path: PathBuf,
        /// Underlying map error.
        cause: mrslam_core::map_io::MapIoError,
    },
    /// A robot's start pose places its footprint inside an obstacle or another robot.
    #[error("robot `{name}`: start pose ({x:.3}, {y:.3}) overlaps an obstacle or another robot")]
    StartInObstacle {
        /// Robot name.
        name: String,
        /// Start x, metres.
        x: f64,
        /// Start y, metres.
        y: f64,
    },
    /// A robot of this name already exists.
    #[error("robot `{0}` already exists")]
    DuplicateRobot(String),
    /// A robot id that this simulator did not hand out.
    #[error("unknown robot id {0}")]
    UnknownRobot(usize),
    /// A model or simulator parameter is out of its allowed range.
    #[error("parameter `{field}`: {message}")]
    BadParameter {
        /// Parameter at fault, e.g. `LidarModel.resolution`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// Builds a [`SimError::BadParameter`].
pub(crate) fn bad_param(field: &str, message: impl Into<String>) -> SimError {
    SimError::BadParameter { field: field.to_string(), message: message.into() }
}

/// Checks that `v` is finite and strictly positive.
pub(crate) fn check_positive(field: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(bad_param(field, format!("must be positive and finite, got {v}")))
    }
}

/// Checks that `v` is finite and not negative.
pub(crate) fn check_non_negative(field: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(bad_param(field, format!("must be non-negative and finite, got {v}")))
    }
}
