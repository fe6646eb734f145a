//! The simulation loop: every step, each robot's controller sets its command, the world moves, and the scans
//! that came in are fed to the robots' SLAM back-ends, all robots side by side.

use super::agent::{Agent, Reading};
use super::coordinate::Planner;
use super::options::{RobotStep, RunError, RunOptions};
use super::record::{viz_slam, viz_step, viz_team};
use super::team::Teams;
use crate::controller::Controller;
use crate::scenario::{MergeWhen, Scenario};
use mrslam_core::{LaserScan, OccupancyGrid};
use mrslam_sim::Sim;
use nalgebra::Point2;
use rayon::prelude::*;

/// Steps the simulation until the scenario's merge time (or its duration): each step, every robot's
/// controller sets its command, the world moves, and the scans that came in are fed to the robots' SLAM.
/// Returns the number of steps.
pub(super) fn drive(
    scenario: &Scenario,
    sim: &mut Sim,
    agents: &mut [Agent],
    truth: &OccupancyGrid,
    mut teams: Option<&mut Teams>,
    opts: &mut RunOptions,
) -> Result<u64, RunError> {
    let dt = scenario.dt;
    let mut steps = 0u64;
    let mut next_progress = 0.0;
    let mut planner =
        teams.as_ref().map(|_| Planner::new(agents.len(), scenario.team.as_ref().map_or(1.0, |t| t.beta)));
    loop {
        let t = sim.time();
        if let Some(p) = opts.progress.as_mut()
            && t >= next_progress
        {
            p(t, expected_end(scenario, sim, agents, t));
            next_progress += 1.0;
        }
        let merge_now = match scenario.merge.when {
            MergeWhen::Rendezvous => agents.iter().all(Agent::finished),
            MergeWhen::End => false,
            MergeWhen::At(m) => t >= m - 1e-9,
        };
        if merge_now || t >= scenario.duration - 1e-9 {
            return Ok(steps);
        }
        if let (Some(tm), Some(p)) = (teams.as_deref_mut(), planner.as_mut()) {
            p.plan(t, tm, agents)?;
        }
        // Plans depend only on each robot's own map and pose: make them side by side, then command in order.
        let plans: Vec<Result<(), RunError>> = agents.par_iter_mut().map(Agent::plan_if_due).collect();
        plans.into_iter().collect::<Result<(), RunError>>()?;
        for a in agents.iter_mut() {
            let true_pose = sim.true_pose(a.id)?;
            if a.history.is_empty() {
                a.history.push(t, true_pose, sim.odometry(a.id)?.pose);
            }
            let (v, w) = a.command(&true_pose, dt)?;
            sim.set_velocity_command(a.id, v, w)?;
        }
        let events = sim.step();
        steps += 1;
        let mut batches: Vec<Vec<Reading>> = Vec::with_capacity(agents.len());
        for (a, ev) in agents.iter_mut().zip(&events.robots) {
            a.contact_steps += ev.contact as usize;
            let pose = sim.true_pose(a.id)?;
            a.distance += (pose.translation.vector - a.last.translation.vector).norm();
            a.last = pose;
            let odometry = sim.odometry(a.id)?;
            a.history.push(sim.time(), pose, odometry.pose);
            let mut batch = Vec::new();
            while let Some(scan) = sim.take_scan(a.id)? {
                batch.push(a.reading(scan));
            }
            batches.push(batch);
        }
        if let Some(tap) = opts.on_step.as_mut() {
            let time = sim.time();
            for (k, (a, batch)) in agents.iter().zip(&batches).enumerate() {
                let odometry = sim.odometry(a.id)?;
                let scans: Vec<&LaserScan> = batch.iter().map(|(scan, ..)| scan).collect();
                tap(&RobotStep {
                    robot: k,
                    name: &a.setup.name,
                    time,
                    true_pose: &a.last,
                    odometry: &odometry,
                    scans: &scans,
                    mount: &a.setup.lidar.mount,
                    map_to_odom: a.map_to_odom(),
                });
            }
        }
        if let Some(v) = opts.viz.as_deref_mut() {
            viz_step(v, steps, sim.time(), agents, &events, &batches);
        }
        // The robots' SLAMs are independent (each its own seeded RNG): update them side by side. The first
        // robot's error, in robot order, stops the run.
        let results: Vec<Result<(), RunError>> =
            agents.par_iter_mut().zip(batches).map(|(a, batch)| a.process(batch, truth)).collect();
        results.into_iter().collect::<Result<(), RunError>>()?;
        if let Some(v) = opts.viz.as_deref_mut() {
            viz_slam(v, agents)?;
        }
        if let Some(tm) = teams.as_deref_mut() {
            let step = tm.after_step(sim.time(), agents, truth)?;
            if let Some(v) = opts.viz.as_deref_mut() {
                viz_team(v, tm, agents, &step);
            }
            if let Some(p) = planner.as_mut() {
                p.replan(&step.joined);
            }
        }
    }
}

/// When the run is expected to end, simulated seconds: a fixed merge time or the duration; at a rendezvous
/// of robots on routes (or idle), now plus the longest time a robot's remaining route takes at its cruise speed.
fn expected_end(scenario: &Scenario, sim: &Sim, agents: &[Agent], t: f64) -> f64 {
    let to_go = |a: &Agent| -> Option<f64> {
        let p = match &a.controller {
            Controller::Waypoints(p) => p,
            Controller::Idle => return Some(0.0),
            Controller::Explore(_) => return None,
        };
        let pose = sim.true_pose(a.id).ok()?;
        Some(p.remaining(&Point2::from(pose.translation.vector)) / p.speed.max(1e-3))
    };
    match scenario.merge.when {
        MergeWhen::At(m) => m.min(scenario.duration),
        MergeWhen::End => scenario.duration,
        MergeWhen::Rendezvous => agents
            .iter()
            .map(to_go)
            .try_fold(0.0f64, |longest, s| s.map(|s| longest.max(s)))
            .map_or(scenario.duration, |s| (t + s).min(scenario.duration)),
    }
}
