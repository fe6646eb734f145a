//! A joined team's exploration: the frontiers of its merged map assigned over its exploring robots (Burgard et
//! al. 2005), re-planned every few seconds and whenever a robot reaches its goal or the team grows (a robot the
//! last plan gave no frontier waits for the next plan on the clock).

use super::agent::Agent;
use super::options::RunError;
use super::team::{Snapshot, Teams};
use crate::assignment::AssignParams;
use crate::controller::{Controller, Explorer};
use crate::frontier::Clearance;
use crate::joint_plan::{Member, TeamParams, plan_team};
use crate::report::TeamPlan;
use nalgebra::Point2;

/// When each team plans next.
pub(super) struct Planner {
    /// Per team root: the time of its next plan.
    next: Vec<f64>,
    /// Per team root: the time of its last plan.
    last: Vec<f64>,
    /// Per robot: its team's last plan gave it no frontier. Its path is then empty, so it asks for a plan at every
    /// step; it waits for the team's next plan on the clock instead (or the team's growing), as no frontier was
    /// left for it a moment ago.
    unassigned: Vec<bool>,
    params: TeamParams,
}

impl Planner {
    /// No plan made yet for `robots` robots; `beta` weighs travel cost against information gain.
    pub(super) fn new(robots: usize, beta: f64) -> Self {
        Planner {
            next: vec![0.0; robots],
            last: vec![f64::NEG_INFINITY; robots],
            unassigned: vec![false; robots],
            params: TeamParams { assign: AssignParams { beta, ..AssignParams::default() }, ..TeamParams::default() },
        }
    }

    /// Plans again at once for the teams rooted at `roots` (they just grew).
    pub(super) fn replan(&mut self, roots: &[usize]) {
        for &r in roots {
            self.next[r] = 0.0;
        }
    }

    /// Before a step's commands: every joined team due for a plan assigns its frontiers over its exploring
    /// robots and hands each its path. A robot alone (or every robot, without coordination) plans on its own.
    pub(super) fn plan(&mut self, t: f64, teams: &mut Teams, agents: &mut [Agent]) -> Result<(), RunError> {
        if !teams.coordinated() {
            return Ok(());
        }
        for root in teams.roots() {
            let explorers: Vec<usize> = teams
                .members(root)
                .into_iter()
                .filter(|&k| matches!(agents[k].controller, Controller::Explore(_)) && !agents[k].processed.is_empty())
                .collect();
            if explorers.len() < 2 {
                continue;
            }
            let wants = explorers
                .iter()
                .any(|&k| !self.unassigned[k] && explorer(&agents[k]).is_some_and(Explorer::wants_plan));
            let due = t + 1e-9 >= self.next[root] || (wants && t >= self.last[root] + MIN_REPLAN_S);
            if !due {
                continue;
            }
            self.last[root] = t;
            self.next[root] = t + REPLAN_S;
            let snapshot = Snapshot::take(agents)?;
            let Some(map) = teams.team_map(root, &snapshot) else { continue };
            let avoids: Vec<Vec<Point2<f64>>> = explorers
                .iter()
                .map(|&k| {
                    let (_, place) = teams.place(k);
                    explorer(&agents[k]).map_or(Vec::new(), |e| e.abandoned().iter().map(|p| place * p).collect())
                })
                .collect();
            let members: Vec<Member> = explorers
                .iter()
                .zip(&avoids)
                .map(|(&k, avoid)| {
                    let (_, place) = teams.place(k);
                    let a = &agents[k];
                    let clearance = explorer(a).map_or(Clearance::uniform(0.3), |e| e.clearance);
                    Member { pose: place * a.slam.best_pose(), clearance, avoid }
                })
                .collect();
            let plans = plan_team(&map, &members, &self.params);
            let nothing_left = plans.iter().all(Option::is_none);
            teams.record_plan(TeamPlan {
                time_s: t,
                root: agents[root].setup.name.clone(),
                targets: explorers
                    .iter()
                    .zip(&plans)
                    .map(|(&k, p)| (agents[k].setup.name.clone(), p.as_ref().map(|p| [p.target.x, p.target.y])))
                    .collect(),
            });
            for (&k, plan) in explorers.iter().zip(plans) {
                self.unassigned[k] = plan.is_none();
                let (_, place) = teams.place(k);
                let to_own = place.inverse();
                let a = &mut agents[k];
                a.coordinated = true;
                let Controller::Explore(e) = &mut a.controller else { continue };
                match plan {
                    Some(p) => e.follow(p.path.iter().map(|q| to_own * q).collect()),
                    None if nothing_left => e.finish(),
                    None => e.follow(Vec::new()),
                }
            }
        }
        Ok(())
    }
}

/// A team plans at least this often, seconds (the lone explorer's period).
const REPLAN_S: f64 = 3.0;
/// A robot that reached its goal asks for a plan, but a team plans at most this often, seconds.
const MIN_REPLAN_S: f64 = 0.5;

fn explorer<'a>(a: &'a Agent) -> Option<&'a Explorer> {
    match &a.controller {
        Controller::Explore(e) => Some(e),
        _ => None,
    }
}
