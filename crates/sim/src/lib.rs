//! mrslam-sim: a rapier2d world with differential-drive robots, wheel slip, encoders and lidar models.
//!
//! Build a [`WorldSpec`] (from a TOML world file), a [`Sim`] over it, add robots with
//! [`Sim::add_robot`], command their wheels, [`Sim::step`], and read [`Sim::odometry`],
//! [`Sim::take_scan`] and the ground truth ([`Sim::true_pose`], [`World::true_map`]).
//! Units are SI; poses are [`mrslam_core::Pose2`]; rapier's glam types stay inside this crate.
//!
//! Modules are private; the items re-exported below are the API.
//!
//! ```
//! use mrslam_sim::{EncoderParams, LidarModel, RobotModel, Sim, SlipParams, WorldSpec};
//!
//! let world = WorldSpec::from_toml_file("../../worlds/corridor.toml").unwrap();
//! let mut sim = Sim::new(&world, 0).unwrap();
//! let start = mrslam_core::pose(2.0, 2.5, 0.0);
//! let robot = sim
//!     .add_robot("experia", RobotModel::experia(), LidarModel::hokuyo_urg_04lx(), SlipParams::default(),
//!                EncoderParams::default(), start)
//!     .unwrap();
//! sim.set_velocity_command(robot, 0.3, 0.0).unwrap();
//! let mut scans = 0;
//! while sim.time() < 1.0 {
//!     sim.step();
//!     while sim.take_scan(robot).unwrap().is_some() {
//!         scans += 1;
//!     }
//! }
//! // The truth moved east; the lidar scanned at its 10 Hz.
//! assert!(sim.true_pose(robot).unwrap().translation.x > 2.1 && scans >= 9);
//! ```

#![deny(missing_docs)]

mod bitmap;
mod drive;
mod encoder;
mod error;
pub mod from_map;
mod geometry;
mod lidar;
pub mod odometry_errors;
pub mod odometry_fit;
mod raycast;
pub mod replay;
mod sim;
mod slip;
mod truth;
mod world;
mod world_file;

pub use drive::{DiffDrive, Footprint, RobotModel};
pub use encoder::{EncoderParams, Encoders};
pub use error::SimError;
pub use geometry::Obstacle;
pub use lidar::LidarModel;
pub use sim::{RayBackend, RobotId, RobotStep, Sim, SimConfig, StepEvents};
pub use slip::{SlipParams, SlipState};
pub use world::World;
pub use world_file::{
    BitmapLayer, BoxSpec, CircleSpec, MAX_WORLD_COORDINATE, NamedPoint, PolygonSpec, WallSpec, WorldSpec,
};
