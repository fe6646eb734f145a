//! mrslam-core: the types every other mrslam crate speaks.
//!
//! SE(2) poses on [`nalgebra::Isometry2<f64>`], [`LaserScan`] and [`Odometry`], the log-odds
//! [`OccupancyGrid`] with ray traversal and ray casting, ROS map_server map I/O, CARMEN log reading, and the benchmark metric on relations (Kümmerle et al. 2009).
//! Units are SI (metres, radians, seconds) everywhere.

pub mod carmen;
pub mod grid;
pub mod input;
pub mod map_io;
pub mod pose;
pub mod raycast;
pub mod relations;
pub mod scan;
pub mod sensor;
pub mod toml_lines;

pub use carmen::{CarmenError, CarmenLog, LaserSource, OdometrySource, ReadOptions, Repairs, ScanRecord};
pub use grid::{CellState, GridError, LogOddsParams, OccupancyGrid};
pub use map_io::{MapIoError, MapMode, MapYaml};
pub use pose::{Pose2, Xyt, pose};
pub use raycast::CellTraversal;
pub use relations::{Relation, RelationsError, RelationsScore, StampedPose};
pub use scan::{LaserScan, Odometry};
