//! The rerun hooks of a run: called only when `RunOptions::viz` is set; they hand plain data to mrslam-viz.

use super::agent::{Agent, Reading};
use super::options::RunError;
use super::team::{TeamStep, Teams};
use crate::controller::Controller;
use crate::report::MergeAttempt;
use mrslam_core::{OccupancyGrid, Pose2};
use mrslam_merge::{Algorithm, MergeOutcome};
use mrslam_sim::{Obstacle, Sim, StepEvents};
use mrslam_viz::{AttemptOutcome, AttemptView, MergeView, RobotInfo, RunRecorder, SlamState};
use nalgebra::Point2;

/// What the rerun recording shows of a merge of `host`'s map (a) and `other`'s (b); `error` against the truth
/// (rotation radians, translation metres) when known.
pub fn merge_view<'a>(
    out: &'a MergeOutcome,
    host: &'a str,
    other: &'a str,
    error: Option<(f64, f64)>,
) -> MergeView<'a> {
    MergeView {
        algorithm: &out.report.algorithm,
        host,
        other,
        accepted: out.report.accepted,
        reason: out.report.reason.as_deref(),
        matches: out.report.matches,
        inliers: out.report.inliers,
        transform: out.report.transform.map(|t| t.to_pose()),
        error,
        points_a: &out.evidence.points_a,
        points_b: &out.evidence.points_b,
        inlier_pairs: &out.evidence.inlier_pairs,
        merged: out.merged.as_ref(),
    }
}

/// The world's obstacles as closed outlines (circles as 24-gons).
fn viz_walls(sim: &Sim) -> Vec<Vec<Point2<f64>>> {
    sim.world()
        .obstacles()
        .iter()
        .map(|o| match o {
            Obstacle::Circle { center, radius } => (0..24)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 24.0;
                    Point2::new(center.x + radius * a.cos(), center.y + radius * a.sin())
                })
                .collect(),
            other => other.outline(),
        })
        .collect()
}

/// Static content and layout; `team` when the robots form teams as they meet.
pub(super) fn viz_begin(
    v: &mut RunRecorder,
    sim: &Sim,
    truth: &OccupancyGrid,
    agents: &[Agent],
    algorithms: &[Algorithm],
    team: bool,
) {
    let robots: Vec<RobotInfo> =
        agents.iter().map(|a| RobotInfo { name: a.setup.name.clone(), start: a.setup.start }).collect();
    let algorithms: Vec<String> = algorithms.iter().map(Algorithm::to_string).collect();
    v.set_time(0, sim.time());
    v.begin(&viz_walls(sim), truth, &robots, &algorithms, team);
}

/// A step: slip and contacts, this step's scans with the true and odometry poses they were taken at, and each
/// explorer's goal (drawn only when it changed).
pub(super) fn viz_step(
    v: &mut RunRecorder,
    step: u64,
    time: f64,
    agents: &[Agent],
    events: &StepEvents,
    batches: &[Vec<Reading>],
) {
    v.set_time(step, time);
    for (k, ((a, ev), batch)) in agents.iter().zip(&events.robots).zip(batches).enumerate() {
        v.robot_step(k, ev.slipping, ev.contact);
        for (scan, odom, pose) in batch {
            v.scan(k, pose, &odom.pose, scan, &a.setup.lidar.mount);
        }
        if let Controller::Explore(e) = &a.controller {
            v.goal(k, e.path(), a.coordinated);
        }
    }
}

/// The teams after a step: its merge attempts (between which robots, judged against the truth), the maps of the
/// teams that grew or whose robots sent their maps (a team of one robot is its map, drawn already), its coverage
/// sample.
pub(super) fn viz_team(v: &mut RunRecorder, teams: &Teams, agents: &[Agent], step: &TeamStep) {
    for a in &teams.attempts()[step.attempts.clone()] {
        v.attempt(&attempt_view(a, agents));
    }
    if let Some(snapshot) = &step.snapshot {
        let mut roots: Vec<usize> = step.joined.iter().chain(&step.shared).copied().collect();
        roots.sort_unstable();
        roots.dedup();
        for r in roots {
            if teams.members(r).len() > 1
                && let Some(map) = teams.team_map(r, snapshot)
            {
                v.team_map(r, &map);
            }
        }
    }
    if let Some([_, share]) = step.sample {
        v.coverage(share, teams.redundancy(agents));
    }
}

/// What the recording shows of a merge attempt: the robots at their true positions now, the verdict.
fn attempt_view<'a>(a: &'a MergeAttempt, agents: &[Agent]) -> AttemptView<'a> {
    let at = |name: &str| {
        agents
            .iter()
            .find(|g| g.setup.name == name)
            .map_or_else(Point2::origin, |g| Point2::from(g.last.translation.vector))
    };
    let outcome = match (a.accepted, a.correct) {
        (true, true) => AttemptOutcome::Correct,
        (true, false) => AttemptOutcome::False,
        (false, _) => AttemptOutcome::Refused,
    };
    AttemptView {
        robots: [&a.robots[0], &a.robots[1]],
        at: [at(&a.robots[0]), at(&a.robots[1])],
        teams: [&a.teams[0], &a.teams[1]],
        outcome,
        stage: a.stage.as_deref(),
        reason: a.reason.as_deref(),
        error: a.rotation_error_deg.zip(a.translation_error_m),
    }
}

/// The SLAMs after this step's updates: best pose, hypotheses (particles and Neff); paths and maps when due.
pub(super) fn viz_slam(v: &mut RunRecorder, agents: &[Agent]) -> Result<(), RunError> {
    for (k, a) in agents.iter().enumerate() {
        let hypotheses = a.slam.hypotheses();
        let state = SlamState {
            scans: a.scans,
            best: &a.slam.best_pose(),
            hypotheses: &hypotheses.poses,
            effective: hypotheses.effective,
            resamples: a.slam.counters().resamples,
            frame: a.frame(),
        };
        v.slam(k, state);
        if v.paths_due(k) {
            let traj: Vec<Pose2> = a.slam.trajectory().into_iter().map(|(_, p)| p).collect();
            v.paths(k, &traj);
        }
        if v.map_due(k) {
            let map = a.map()?;
            v.map(k, &map);
        }
    }
    Ok(())
}
