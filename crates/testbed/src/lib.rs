//! mrslam-testbed: scenario files, the simulation loop, evaluation against ground truth, and reports.
//!
//! ```
//! use mrslam_testbed::scenario::Scenario;
//!
//! // The paper's first experiment: two robots in a 50 m corridor. `runner::run(&scenario, options)` runs it
//! // end to end (minutes); `runner::write_outputs` writes its maps and report.
//! let scenario = Scenario::from_file(std::path::Path::new("../../scenarios/paper_corridor.toml")).unwrap();
//! assert_eq!(scenario.robots.len(), 2);
//! ```

#![deny(missing_docs)]

// Every module is a public namespace (`scenario::Scenario`, `runner::run`...); nothing is
// re-exported at the root, so each item has one path.

pub mod assignment;
pub mod controller;
pub mod eval;
pub mod frontier;
pub mod joint_plan;
pub mod report;
pub mod runner;
pub mod scenario;
