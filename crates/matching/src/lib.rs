//! mrslam-matching: scan matching that knows no map format beyond core's grid, shared by the SLAM (loop
//! closure) and the map merger.
//!
//! - The correlative search (Olson 2009; Hess et al. 2016): a [`ScoreField`] of a grid (blurred walls,
//!   penalised free space, from its [`BlockStates`]), its max-pooled [`Pyramid`], a point set ([`WallScan`])
//!   placed over every translation of a rotation by [`branch_and_bound`], and the exhaustive search of a small
//!   window of angles and offsets around a pose ([`local_search`] on a [`WindowField`]).
//! - A 2D pose graph and its sparse Gauss-Newton optimiser with Huber's kernel ([`pose_graph`]).
//! - [`Information`]: the information matrix of an (x, y, θ) estimate.
//!
//! Modules are private except the [`pose_graph`] namespace; every other item is at the root.

#![deny(missing_docs)]

mod field;
mod information;
mod local;
pub mod pose_graph;
mod pyramid;
mod scan;
mod search;

pub use field::{BlockStates, HIT, ScoreField};
pub use information::Information;
pub use local::{LocalScratch, LocalWindow, ScanPose, WindowField, WindowKey, local_search, window_key};
pub use pyramid::{PooledGrid, Pyramid};
pub use scan::WallScan;
pub use search::{Best, Candidate, Window, branch_and_bound};
