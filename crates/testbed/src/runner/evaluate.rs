//! Each robot's SLAM scored against the truth once driving stops.

use super::agent::Agent;
use super::options::{RunError, RunOptions};
use crate::eval::{map_acceptance, rmse};
use crate::report::RobotReport;
use mrslam_core::{OccupancyGrid, Pose2};
use std::collections::BTreeMap;

/// Each robot's evaluation against the truth, and what the merge needs of it; by robot name.
pub(super) struct Evaluated {
    /// Report of each robot's SLAM.
    pub robots: BTreeMap<String, RobotReport>,
    /// Each robot's final map (best particle), in its own SLAM frame.
    pub maps: BTreeMap<String, OccupancyGrid>,
    /// Each robot's SLAM frame in the world: its true pose at its first processed scan.
    pub frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM frame placed so that its last SLAM pose is its true pose.
    pub end_frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM path in its own frame.
    pub paths: BTreeMap<String, Vec<Pose2>>,
}

/// Scores each robot's SLAM trajectory and map against the truth and takes its final map.
pub(super) fn evaluate_robots(
    agents: &[Agent],
    truth: &OccupancyGrid,
    opts: &mut RunOptions,
) -> Result<Evaluated, RunError> {
    let mut out = Evaluated {
        robots: BTreeMap::new(),
        maps: BTreeMap::new(),
        frames: BTreeMap::new(),
        end_frames: BTreeMap::new(),
        paths: BTreeMap::new(),
    };
    for (k, a) in agents.iter().enumerate() {
        let map = a.slam.map().map_err(|error| a.slam_error(error))?;
        let traj: Vec<Pose2> = a.slam.trajectory().into_iter().map(|(_, p)| p).collect();
        let (t0, o0) = a.processed.first().copied().unwrap_or((a.setup.start, Pose2::identity()));
        let truth_rel: Vec<Pose2> = a.processed.iter().map(|(t, _)| t0.inv_mul(t)).collect();
        let odom_rel: Vec<Pose2> = a.processed.iter().map(|(_, o)| o0.inv_mul(o)).collect();
        let final_err = |est: &[Pose2]| match (est.last(), truth_rel.last()) {
            (Some(e), Some(t)) => (e.translation.vector - t.translation.vector).norm(),
            _ => 0.0,
        };
        let counters = a.slam.counters();
        let hypotheses = a.slam.hypotheses();
        out.robots.insert(
            a.setup.name.clone(),
            RobotReport {
                slam_rmse_m: rmse(&traj, &truth_rel),
                odom_rmse_m: rmse(&odom_rel, &truth_rel),
                map_acceptance: map_acceptance(truth, &map, &t0),
                slam_final_error_m: final_err(&traj),
                odom_final_error_m: final_err(&odom_rel),
                scans: a.scans,
                processed: counters.processed,
                resamples: counters.resamples,
                final_neff: hypotheses.effective.unwrap_or(hypotheses.poses.len() as f64),
                distance_m: a.distance,
                contact_steps: a.contact_steps,
                finished: a.finished(),
                slam_s: a.slam_s,
            },
        );
        if let Some(v) = opts.viz.as_deref_mut() {
            // The maps and paths that are merged and evaluated, whatever the logging rates.
            v.map(k, &map);
            v.paths(k, &traj);
        }
        let end_frame = match (a.processed.last(), traj.last()) {
            (Some((t, _)), Some(e)) => t * e.inverse(),
            _ => t0,
        };
        out.end_frames.insert(a.setup.name.clone(), end_frame);
        out.frames.insert(a.setup.name.clone(), t0);
        out.maps.insert(a.setup.name.clone(), map);
        out.paths.insert(a.setup.name.clone(), traj);
    }
    Ok(out)
}
