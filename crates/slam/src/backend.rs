//! What a SLAM back-end offers the code that feeds it (the testbed's agents, [`crate::map_log`], viewers):
//! one trait, implemented by the particle filter ([`crate::Rbpf`]) and meant for a loop-closing SLAM too.

use crate::error::SlamError;
use crate::loop_closure::LoopClosureReport;
use crate::outcome::{Counters, UpdateOutcome};
use mrslam_core::{LaserScan, OccupancyGrid, Odometry, Pose2};

/// A pose of the trajectory that a loop closure moved: where it was, where it is now.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Stamp of the trajectory's pose (its scan's stamp), seconds.
    pub stamp: f64,
    /// The pose before the correction, map frame.
    pub before: Pose2,
    /// The pose after it, map frame.
    pub after: Pose2,
}

/// The hypotheses a back-end holds about the robot's pose, for display: a particle filter's particles, or a
/// single pose for a back-end that keeps one.
#[derive(Debug, Clone, PartialEq)]
pub struct Hypotheses {
    /// Each hypothesis's pose (map frame) and normalised weight.
    pub poses: Vec<(Pose2, f64)>,
    /// How many hypotheses effectively count (a particle filter's Neff), when the back-end has such a number.
    pub effective: Option<f64>,
}

/// A SLAM back-end: fed odometry and scans in time order, it keeps a map and a trajectory in its own map frame
/// (the robot's pose at the first processed scan).
///
/// `Send` so that the testbed can update the back-ends of several robots side by side, `Sync` so that it can
/// build their maps side by side.
pub trait SlamBackend: Send + Sync {
    /// Feeds one odometry reading and the scan taken with it; errors leave the back-end unchanged.
    ///
    /// The outcome's statistics describe the update's hypotheses: a back-end that keeps one pose reports an
    /// effective count of 1, no resampling and best index 0.
    fn process(&mut self, odom: &Odometry, scan: &LaserScan) -> Result<UpdateOutcome, SlamError>;

    /// Ends the data: what the back-end does once no reading will follow (the particle filter closes loops
    /// when its parameters ask for it, and says what that did; `None` when nothing was done).
    fn finish(&mut self) -> Option<LoopClosureReport>;

    /// The output map (may cost a rebuild: call it when a map is needed).
    fn map(&self) -> Result<OccupancyGrid, SlamError>;

    /// A map that is cheap to take, for watching it grow; `None` while empty.
    fn live_map(&self) -> Option<OccupancyGrid>;

    /// The current robot pose estimate (map frame), including motion since the last processed scan.
    fn best_pose(&self) -> Pose2;

    /// The estimated path: (stamp, robot pose in the map frame) per processed scan, oldest first.
    fn trajectory(&self) -> Vec<(f64, Pose2)>;

    /// Poses of the trajectory moved since the last call (by a loop closure), oldest first; empty when none
    /// moved. An online loop closer reports here what each closure changed.
    fn take_corrections(&mut self) -> Vec<Correction>;

    /// The odometry pose of the last reading as the back-end used it (it may correct the reading's, e.g. by
    /// scan matching); `None` until a scan with beams came.
    fn odometry_pose(&self) -> Option<Pose2>;

    /// The pose hypotheses, for display.
    fn hypotheses(&self) -> Hypotheses;

    /// Running totals over all readings.
    fn counters(&self) -> Counters;
}
