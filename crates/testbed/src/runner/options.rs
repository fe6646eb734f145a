//! What a run takes besides its scenario, what it gives back, and what can stop it.

use crate::report::RunReport;
use mrslam_core::map_io::MapIoError;
use mrslam_core::{LaserScan, OccupancyGrid, Odometry, Pose2};
use mrslam_merge::{Algorithm, MergeOutcome};
use mrslam_sim::SimError;
use mrslam_slam::SlamError;
use mrslam_viz::RunRecorder;
use std::collections::BTreeMap;

/// What can stop a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The simulator refused something (e.g. a start inside an obstacle).
    // Not `#[from]`: that makes the error its own source too, and a chain printer says it twice.
    #[error("simulator: {0}")]
    Sim(SimError),
    /// A SLAM filter refused its input or parameters.
    #[error("SLAM of robot `{robot}`: {error}")]
    Slam {
        /// Robot.
        robot: String,
        /// What went wrong.
        error: SlamError,
    },
    /// Writing outputs failed.
    #[error("{0}")]
    Io(#[from] MapIoError),
    /// The scenario is not one a run can take (its fields are public, so it may not come from a file).
    #[error("scenario: {0}")]
    Scenario(String),
}

impl From<SimError> for RunError {
    fn from(e: SimError) -> Self {
        RunError::Sim(e)
    }
}

/// Options of a run that are not part of the scenario.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Merge algorithms to run instead of the scenario's.
    pub algorithms: Option<Vec<Algorithm>>,
    /// Called about once per simulated second with (simulated time, expected end of the run): the merge
    /// time, the duration, or at a rendezvous of routed robots the time their remaining routes take.
    pub progress: Option<Box<dyn FnMut(f64, f64) + 'a>>,
    /// Records the run for the rerun viewer; `None` (the default) records and converts nothing.
    pub viz: Option<&'a mut RunRecorder>,
    /// Called after every simulation step for every robot, with the scans that came in (e.g. to write the run
    /// as a log), before its SLAM sees them.
    pub on_step: Option<StepTap<'a>>,
}

/// What [`RunOptions::on_step`] calls for each robot after each step.
pub type StepTap<'a> = Box<dyn FnMut(&RobotStep<'_>) + 'a>;

/// A robot after one simulation step: its true pose and odometry then, and the scans that came in.
#[derive(Debug, Clone, Copy)]
pub struct RobotStep<'s> {
    /// The robot's index in the scenario's robot order.
    pub robot: usize,
    /// The robot's name.
    pub name: &'s str,
    /// Simulation time at the end of the step, seconds.
    pub time: f64,
    /// The robot's true pose at the end of the step, in the world frame.
    pub true_pose: &'s Pose2,
    /// The robot's wheel odometry at the end of the step.
    pub odometry: &'s Odometry,
    /// Scans published during the step. Each is stamped when its first beam was cast, up to a scan period
    /// before the step's end: a log pairs it with the pose and odometry at its stamp, not at the step's end.
    pub scans: &'s [&'s LaserScan],
    /// The lidar's mount on the robot.
    pub mount: &'s Pose2,
    /// Where the robot's SLAM puts its odometry frame in its map (ROS's `map -> odom`), from its pose estimate
    /// after the scans before this step; `None` before its first scan.
    pub map_to_odom: Option<Pose2>,
}

/// Everything a run produced.
pub struct RunOutput {
    /// The report.
    pub report: RunReport,
    /// Each robot's final map (best particle), by robot name, in its own SLAM frame.
    pub maps: BTreeMap<String, OccupancyGrid>,
    /// The true map (world frame).
    pub truth: OccupancyGrid,
    /// Merge outcomes, in algorithm order (with merged maps when accepted).
    pub merges: Vec<MergeOutcome>,
    /// Each robot's SLAM frame in the world (its true pose at its first processed scan), by robot name.
    pub frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM path (the best particle's pose at every processed scan, its own frame), by robot name.
    pub paths: BTreeMap<String, Vec<Pose2>>,
}
