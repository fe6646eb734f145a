//! mrslam-core: the types every other mrslam crate speaks.
//!
//! SE(2) poses on [`nalgebra::Isometry2<f64>`], [`LaserScan`] and [`Odometry`], the log-odds
//! [`OccupancyGrid`] with ray traversal and ray casting, ROS map_server map I/O, and the benchmark metric on relations (Kümmerle et al. 2009).
//! Units are SI (metres, radians, seconds) everywhere.
//!
//! ```
//! use mrslam_core::{OccupancyGrid, Pose2, Xyt, pose};
//!
//! // A robot at (1, 0) facing +y drives 1 m forward: it ends at (1, 1).
//! let start = pose(1.0, 0.0, std::f64::consts::FRAC_PI_2);
//! let end = Xyt::from_pose(&(start * pose(1.0, 0.0, 0.0)));
//! assert!((end.x - 1.0).abs() < 1e-12 && (end.y - 1.0).abs() < 1e-12);
//!
//! // A 5 m x 5 m grid at 5 cm, all unknown.
//! let grid = OccupancyGrid::new(100, 100, 0.05, Pose2::identity()).unwrap();
//! assert_eq!((grid.width(), grid.height()), (100, 100));
//! ```

#![deny(missing_docs)]

// Private modules, their user-facing items re-exported below; `input`, `map_io`, `output`, `pose`,
// `relations`, `toml_lines` and `truth_relations` are public namespaces of functions (`map_io::read_ros_map`,
// `output::write_file_atomic`, `pose::normalize_angle`, `relations::score`), their items not re-exported.
mod grid;
pub mod input;
pub mod map_io;
pub mod output;
pub mod pose;
mod raycast;
pub mod relations;
mod scan;
mod se2;
pub mod sensor;
pub mod toml_lines;
pub mod truth_relations;

pub use grid::{
    CellState, FREE_LOGODDS, GridError, LogOddsParams, MAX_CELLS, OCCUPIED_LOGODDS, OccupancyGrid, floor_i64, log_odds,
    probability,
};
pub use raycast::CellTraversal;
pub use scan::{LaserScan, Odometry};
pub use se2::{Pose2, Xyt, pose};
