//! mrslam-sim: a rapier2d world with differential-drive robots, wheel slip, encoders and lidar models.
//!
//! Build a [`WorldSpec`] (from a TOML world file), a [`Sim`] over it, add robots with
//! [`Sim::add_robot`], command their wheels, [`Sim::step`], and read [`Sim::odometry`],
//! [`Sim::take_scan`] and the ground truth ([`Sim::true_pose`], [`World::true_map`]).
//! Units are SI; poses are [`mrslam_core::Pose2`]; rapier's glam types stay inside [`sim`].

#![warn(missing_docs)]

pub mod bitmap;
pub mod drive;
pub mod encoder;
pub mod error;
pub mod geometry;
pub mod lidar;
pub mod raycast;
pub mod sim;
pub mod slip;
pub mod truth;
pub mod world;
pub mod world_file;

pub use drive::{DiffDrive, Footprint, RobotModel};
pub use encoder::{EncoderParams, Encoders};
pub use error::SimError;
pub use lidar::LidarModel;
pub use sim::{RayBackend, RobotId, RobotStep, Sim, SimConfig, StepEvents};
pub use slip::{SlipParams, SlipState};
pub use world::World;
pub use world_file::{BitmapLayer, BoxSpec, CircleSpec, NamedPoint, PolygonSpec, WallSpec, WorldSpec};
