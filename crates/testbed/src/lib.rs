//! mrslam-testbed: scenario files, the simulation loop, evaluation against ground truth, and reports.

pub mod controller;
pub mod eval;
pub mod report;
pub mod runner;
pub mod scenario;
pub mod study;
