//! mrslam-core: the types every other mrslam crate speaks.
//!
//! SE(2) poses on [`nalgebra::Isometry2<f64>`], [`LaserScan`] and [`Odometry`], the log-odds
//! [`OccupancyGrid`] with ray traversal and ray casting, ROS map_server map I/O, CARMEN log reading, and the benchmark metric on relations (Kümmerle et al. 2009).
//! Units are SI (metres, radians, seconds) everywhere.

#![deny(missing_docs)]

// Private modules, their user-facing items re-exported below; `input`, `map_io`, `pose`, `relations` and
// `toml_lines` are public namespaces of functions (`map_io::read_ros_map`, `pose::normalize_angle`,
// `relations::score`), their items not re-exported.
mod carmen;
mod grid;
pub mod input;
pub mod map_io;
pub mod pose;
mod raycast;
pub mod relations;
mod scan;
mod se2;
pub mod sensor;
pub mod toml_lines;

pub use carmen::{
    CarmenError, CarmenLog, LaserSource, MAX_STEP_BACK, OdometrySource, ReadOptions, Repairs, ScanRecord,
};
pub use grid::{
    CellState, FREE_LOGODDS, GridError, LogOddsParams, MAX_CELLS, OCCUPIED_LOGODDS, OccupancyGrid, floor_i64, log_odds,
    probability,
};
pub use raycast::CellTraversal;
pub use scan::{LaserScan, Odometry};
pub use se2::{Pose2, Xyt, pose};
