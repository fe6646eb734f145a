//! One robot of a run: its place in the simulator, its SLAM back-end, its controller, and what the
//! evaluation needs of its drive.

use super::options::RunError;
use super::pose_history::{PoseHistory, pairing_time};
use crate::controller::{Controller, Explorer, PurePursuit, blocked_ahead};
use crate::frontier::Clearance;
use crate::scenario::{ControllerKind, RobotSetup, Scenario};
use mrslam_core::{CellTraversal, LaserScan, OccupancyGrid, Odometry, Pose2};
use mrslam_sim::{RobotId, Sim};
use mrslam_slam::{Rbpf, SlamBackend};
use nalgebra::Point2;
use std::sync::Mutex;
use std::time::Instant;

/// A scan of one simulation step with the odometry and the true pose it was taken at.
pub(super) type Reading = (LaserScan, Odometry, Pose2);

/// Per-robot state of a run.
pub(super) struct Agent<'s> {
    pub setup: &'s RobotSetup,
    pub id: RobotId,
    /// The robot's SLAM. A trait object: each robot of a scenario may run its own back-end.
    pub slam: Box<dyn SlamBackend>,
    pub controller: Controller,
    /// The robot's recent true and odometry poses, to pair each scan with the instant it was taken.
    pub history: PoseHistory,
    /// The latest scan, for the explorer's look ahead.
    pub last_scan: Option<LaserScan>,
    /// (truth, odometry) at each processed scan, in the world and odometry frames.
    pub processed: Vec<(Pose2, Pose2)>,
    /// The odometry pose of the last reading fed to SLAM (its best pose is the robot's there).
    pub fed_odometry: Option<Pose2>,
    pub scans: usize,
    pub distance: f64,
    pub last: Pose2,
    pub contact_steps: usize,
    pub slam_s: f64,
    /// Truth-map cells this robot's beams crossed or hit.
    pub observed: Vec<bool>,
    /// The robot explores as one of a team whose planner gives it its paths (it does not plan on its own map).
    pub coordinated: bool,
    /// The SLAM's map as last built, with the number of processed scans it was built after (see [`Agent::map`]).
    map_cache: Mutex<Option<(usize, OccupancyGrid)>>,
}

impl Agent<'_> {
    /// The SLAM's current map, built once per processed scan while the robot drives: planning, coverage samples,
    /// map exchanges and the recording all ask for it, and the SLAM rebuilds it from its whole trajectory on every
    /// call. A skipped scan changes no trajectory node, so the map of the same processed count is the same map.
    pub fn map(&self) -> Result<OccupancyGrid, RunError> {
        let version = self.processed.len();
        // a poisoned lock only means another thread panicked: the cache is only ever set to a whole value
        let mut cache = self.map_cache.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((v, map)) = cache.as_ref()
            && *v == version
        {
            return Ok(map.clone());
        }
        let map = self.slam.map().map_err(|error| self.slam_error(error))?;
        *cache = Some((version, map.clone()));
        Ok(map)
    }

    /// Where the robot's SLAM frame lies in the world: its true pose at its first processed scan (the truth the
    /// evaluation places its map by); `None` before that scan.
    pub fn frame(&self) -> Option<Pose2> {
        self.processed.first().map(|p| p.0)
    }

    /// True once the controller is done.
    pub fn finished(&self) -> bool {
        self.controller.is_done()
    }

    /// Where the robot's last processed scan puts its map frame in the world (the map's pose that makes the
    /// SLAM's pose of that scan the true one): the map as seen from where the robot is now, its drift since its
    /// start left out. The pose of a processed scan, not the current one: between processed scans the SLAM's
    /// pose runs on odometry alone, and a turn since the last one put the frame 2-3° off (FR079).
    pub fn frame_here(&self) -> Option<Pose2> {
        let (truth, _) = self.processed.last()?;
        Some(truth * self.last_processed_pose()?.inverse())
    }

    /// The SLAM's pose of the robot's last processed scan (its map frame), if it processed one.
    pub fn last_processed_pose(&self) -> Option<Pose2> {
        self.slam.trajectory().last().map(|(_, pose)| *pose)
    }

    /// Where the robot's SLAM puts it now, in its map frame (its best particle's pose).
    pub fn pose_estimate(&self) -> Pose2 {
        self.slam.best_pose()
    }

    /// Where the robot's SLAM puts its odometry frame in its map (ROS's `map -> odom`): its best pose times
    /// the inverse of the odometry pose it was fed last; `None` before its first reading.
    pub fn map_to_odom(&self) -> Option<Pose2> {
        self.fed_odometry.map(|odom| self.slam.best_pose() * odom.inverse())
    }

    /// The SLAM error of this robot as a [`RunError`].
    pub fn slam_error(&self, error: mrslam_slam::SlamError) -> RunError {
        RunError::Slam { robot: self.setup.name.clone(), error }
    }

    /// Plans the explorer's next path on its own map when one is due (robots of a coordinated team get theirs
    /// from the team's planner). Independent of the other robots, so the runner plans them side by side.
    pub fn plan_if_due(&mut self) -> Result<(), RunError> {
        let due = matches!(&self.controller, Controller::Explore(e) if e.wants_plan())
            && !self.processed.is_empty()
            && !self.coordinated;
        if !due {
            return Ok(());
        }
        let map = self.map()?;
        let slam_pose = self.slam.best_pose();
        if let Controller::Explore(e) = &mut self.controller {
            e.plan(&map, &slam_pose);
        }
        Ok(())
    }

    /// The velocity command (m/s, rad/s) of this step, from the robot's true pose (a route is driven as an
    /// operator would, by looking at the robot) or its own map and pose (exploration is autonomous; the runner
    /// makes its plan with [`Agent::plan_if_due`] first).
    pub fn command(&mut self, true_pose: &Pose2, dt: f64) -> Result<(f64, f64), RunError> {
        match &mut self.controller {
            Controller::Waypoints(p) => Ok(p.command(true_pose, dt)),
            Controller::Explore(e) => {
                let slam_pose = self.slam.best_pose();
                let (front, half_width) = self.setup.model.footprint.half_extents();
                let reach = front + Explorer::STOP_DISTANCE;
                let blocked = self
                    .last_scan
                    .as_ref()
                    .is_some_and(|scan| blocked_ahead(scan, &self.setup.lidar.mount, reach, half_width + 0.05));
                Ok(e.command(&slam_pose, dt, blocked))
            }
            Controller::Idle => Ok((0.0, 0.0)),
        }
    }

    /// A scan just delivered, with the odometry and true pose of the instant it was taken (see
    /// [`pairing_time`]), as a real robot's SLAM looks its odometry up at the scan's stamp.
    pub fn reading(&self, scan: LaserScan) -> Reading {
        let time = pairing_time(&self.setup.lidar, &scan);
        let (true_pose, odometry) = self.history.at(time).expect("the history holds the step that delivered the scan");
        (scan, Odometry { stamp: time, pose: odometry }, true_pose)
    }

    /// Feeds the scans of this step to SLAM, recording truth and odometry for evaluation.
    pub fn process(&mut self, scans: Vec<Reading>, truth: &OccupancyGrid) -> Result<(), RunError> {
        for (scan, odom, true_pose) in scans {
            self.scans += 1;
            mark_observed(&mut self.observed, truth, &scan, &(true_pose * self.setup.lidar.mount));
            let t = Instant::now();
            let outcome = self.slam.process(&odom, &scan).map_err(|error| self.slam_error(error))?;
            self.slam_s += t.elapsed().as_secs_f64();
            self.fed_odometry = Some(odom.pose);
            if outcome.is_processed() {
                self.processed.push((true_pose, odom.pose));
            }
            self.last_scan = Some(scan);
        }
        Ok(())
    }
}

/// Marks the truth cells a scan's beams cross, from the sensor's true pose.
fn mark_observed(observed: &mut [bool], truth: &OccupancyGrid, scan: &LaserScan, sensor: &Pose2) {
    let origin = Point2::new(sensor.translation.x, sensor.translation.y);
    let (x0, y0) = truth.world_to_cell_f(&origin);
    let w = truth.width();
    for i in (0..scan.len()).step_by(2) {
        let r = if scan.is_valid(i) {
            scan.ranges[i] as f64
        } else if scan.is_max_range(i) {
            scan.range_max as f64
        } else {
            continue;
        };
        let (x1, y1) = truth.world_to_cell_f(&scan.point_at(sensor, i, r));
        for (cx, cy) in CellTraversal::new(x0, y0, x1, y1) {
            if truth.contains_cell(cx, cy) {
                observed[cy as usize * w + cx as usize] = true;
            }
        }
    }
}

/// Puts the scenario's robots into the simulator, each with its SLAM (the particle filter, seeded by the
/// scenario's seed and the robot's place) and its controller.
pub(super) fn add_robots<'s>(
    scenario: &'s Scenario,
    sim: &mut Sim,
    truth: &OccupancyGrid,
) -> Result<Vec<Agent<'s>>, RunError> {
    let mut agents = Vec::new();
    for (k, r) in scenario.robots.iter().enumerate() {
        let id = sim.add_robot(&r.name, r.model.clone(), r.lidar.clone(), r.slip, r.encoder, r.start)?;
        let slam = Rbpf::new(r.slam.clone(), r.lidar.mount, scenario.seed.wrapping_add(1 + k as u64))
            .map_err(|error| RunError::Slam { robot: r.name.clone(), error })?;
        let controller = match r.controller {
            ControllerKind::Waypoints => {
                let mut p = PurePursuit::new(r.route.clone(), r.speed);
                p.lookahead = r.lookahead;
                Controller::Waypoints(p)
            }
            ControllerKind::Explore => {
                let (_, half_width) = r.model.footprint.half_extents();
                let clearance = Clearance {
                    hard: half_width + Explorer::SQUEEZE_MARGIN,
                    preferred: r.model.footprint.bounding_radius() + Explorer::MARGIN,
                };
                Controller::Explore(Explorer::new(r.speed, clearance))
            }
            ControllerKind::Idle => Controller::Idle,
        };
        agents.push(Agent {
            setup: r,
            id,
            slam: Box::new(slam),
            controller,
            history: PoseHistory::default(),
            last_scan: None,
            processed: Vec::new(),
            fed_odometry: None,
            scans: 0,
            distance: 0.0,
            last: r.start,
            contact_steps: 0,
            slam_s: 0.0,
            observed: vec![false; truth.width() * truth.height()],
            coordinated: false,
            map_cache: Mutex::new(None),
        });
    }
    Ok(agents)
}
