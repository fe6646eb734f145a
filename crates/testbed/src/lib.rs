//! mrslam-testbed: scenario files, the simulation loop, evaluation against ground truth, and reports.

#![deny(missing_docs)]

// Every module is a public namespace (`scenario::Scenario`, `runner::run`...); nothing is
// re-exported at the root, so each item has one path.

pub mod controller;
pub mod eval;
pub mod report;
pub mod runner;
pub mod scenario;
