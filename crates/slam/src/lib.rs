//! mrslam-slam: a Rao-Blackwellised particle filter grid SLAM of GMapping's class.
//!
//! Grisetti, Stachniss and Burgard (2007), "Improved techniques for grid mapping with Rao-Blackwellized
//! particle filters", as OpenSLAM's GMapping implements it: each particle carries a pose, a log weight, its
//! own grid map and its trajectory; the proposal is the odometry motion model refined by a scan matcher on
//! the particle's own map (GMapping's hill climber by default; the presets use a likelihood-field matcher,
//! `field`); weights are the scan likelihood at the matched pose; particles are resampled (systematic)
//! when the effective sample size drops below a threshold.
//!
//! Data flow per [`Rbpf::process`] call: odometry increment → `motion` sampling for every particle →
//! (when the robot moved enough) `scan_matcher` refinement and likelihood → `resample` → the scan's hits
//! go into each particle's copy-on-write `tile_map` → a new `particle` trajectory node.
//! The output map ([`Rbpf::map`]) is rebuilt by `map_build` from the best particle's trajectory. With
//! `loop_closure` on (the `matched` preset), `loop_graph` keeps a pose graph beside the filter: each processed
//! scan is a node, searched by branch and bound against the submaps passed a loop ago, the graph optimised
//! (`mrslam_matching::pose_graph`) as loops are found and the particles re-anchored on it; the trajectory and
//! the map are then the graph's. With `loop_closure.online` off, [`map_log`] smooths the trajectory at the end
//! instead ([`Rbpf::close_loops`]: `loop_closure` finds loop edges by local searches).
//!
//! [`SlamBackend`] is what code that feeds a SLAM needs of it (process a reading, the map, the best pose, the
//! trajectory, loop-closure corrections, the pose hypotheses for display); [`Rbpf`] implements it, and
//! [`map_log`] and the testbed drive any implementation.
//!
//! Modules are private: the items below are the API; [`synthetic`] (test data) is a public namespace and
//! [`dev`] holds internals public only for the development probes (`dev/` in the repository).
//!
//! Units are SI; poses are `nalgebra::Isometry2<f64>`; the map frame is the first processed robot pose.
//!
//! ```
//! use mrslam_slam::synthetic::{self, Drift, Lidar};
//! use mrslam_slam::{Rbpf, SlamParams};
//!
//! // A Hokuyo-class robot driving the first stretch of a synthetic office with drifting odometry.
//! let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.05);
//! let drift = Drift { scale: 0.02, heading_per_m: 0.01, sigma_trans: 0.01, sigma_rot: 0.01 };
//! let laser = mrslam_core::pose(0.1, 0.0, 0.0);
//! let run = synthetic::simulate(&synthetic::office_map(), &path[..60], 0.1, &Lidar::hokuyo(), laser, &drift, 1);
//! let mut slam = Rbpf::new(SlamParams::hokuyo(), run.laser_offset, 7).unwrap();
//! for (odom, scan) in run.odometry.iter().zip(&run.scans) {
//!     slam.process(odom, scan).unwrap();
//! }
//! let map = slam.map().unwrap(); // the best particle's occupancy grid
//! assert!(slam.counters().processed >= 2 && map.width() > 0);
//! ```

#![deny(missing_docs)]

mod backend;
mod calibration;
mod error;
mod every_scan;
mod field;
mod incremental_map;
mod loop_closure;
mod loop_graph;
mod map_build;
mod motion;
pub mod odometry_lag;
mod outcome;
mod params;
mod particle;
mod rbpf;
mod resample;
mod scan_matcher;
mod scan_odometry;
pub mod synthetic;
mod tile_map;

pub use backend::{Correction, Hypotheses, SlamBackend};
pub use error::SlamError;
pub use every_scan::{LogRun, LogRunError, map_log, poses_at_every_scan};
pub use loop_closure::{LoopClosureParams, LoopClosureReport};
pub use map_build::MapParams;
pub use motion::MotionModel;
pub use outcome::{Counters, SkipReason, UpdateOutcome, UpdateStats};
pub use params::{FLAT_NAMES, FilterParams, ParamError, Preset, SlamParams};
pub use rbpf::{MemoryStats, Rbpf};
pub use scan_matcher::{MatcherKind, MatcherParams};
pub use scan_odometry::ScanOdometryParams;

/// Internals public only for the development probes (`dev/src/bin/matcher_lab.rs`, `matcher_check.rs`): the
/// scan matcher on a hand-built tile map. Not part of the crate's API; the filter ([`Rbpf`]) is.
pub mod dev {
    pub use crate::field::Lookup;
    pub use crate::scan_matcher::{PreparedScan, ScanMatcher, Scratch};
    pub use crate::tile_map::TileMap;
}
