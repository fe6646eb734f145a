//! End-to-end tests of the `mrslam` command line, one module per command, run as a user would run it.

#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

mod eval;
mod features;
mod long_loop;
mod map;
mod merge;
mod merge_many;
mod reliability;
mod reliability_inputs;
mod reliability_outputs;
mod reliability_walk;
mod run;
mod run_mcap;
mod sim;
mod sim_log;
mod slam;
mod slam_bags;
mod study;
mod study_logs;
mod study_team;
mod util;
mod viz;
mod world;
