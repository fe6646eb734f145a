//! mrslam-core: the types every other mrslam crate speaks.
//!
//! SE(2) poses on [`nalgebra::Isometry2<f64>`], [`LaserScan`] and [`Odometry`], the log-odds
//! [`OccupancyGrid`] with ray traversal and ray casting, ROS map_server map I/O and CARMEN log reading.
//! Units are SI (metres, radians, seconds) everywhere.

pub mod carmen;
pub mod grid;
pub mod map_io;
pub mod pose;
pub mod raycast;
pub mod scan;

pub use carmen::{CarmenError, CarmenLog, LaserSource, ScanRecord};
pub use grid::{CellState, GridError, LogOddsParams, OccupancyGrid};
pub use map_io::{MapIoError, MapMode, MapYaml};
pub use pose::{Pose2, pose, pose_xyt};
pub use raycast::CellTraversal;
pub use scan::{LaserScan, Odometry};
