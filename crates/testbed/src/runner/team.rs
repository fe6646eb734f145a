//! Robots as teams while they drive: who is in contact, the maps they exchange, the online merges that join two
//! teams (each checked against the truth as it happens), the team map, and the coverage of the building.
//!
//! Every robot starts as a team of its own, in its own SLAM frame. Two robots of different teams in contact
//! (within the range, and in line of sight when the scenario asks) exchange their teams' maps at most once per
//! exchange period and try to merge them with the scenario's team merger (the same gate as every merge), once both
//! maps know the scenario's `min_known_m2` and, after a refused try, once one of them has grown by
//! [`RETRY_GROWTH`]; an accepted transform joins the two teams, the host team's root frame becoming the frame of
//! both. A team holds one map: its robots' current maps fused in the root's frame along the accepted transforms (a
//! spanning tree: every join adds one edge between two teams). Once joined, a team's robots are taken to stay in
//! touch (a relay through teammates): each sends its map to the team once per exchange period, and those bytes are
//! counted too.
//!
//! Robots in contact are within the range of each other, and each knows where it is on its team's map: the gate
//! refuses an answer that puts them farther apart (plus [`CONTACT_MARGIN_M`]; [`mrslam_merge::Contact`]), and
//! with `search_near_contact = true` the correlative search looks only there (about 10 % faster, but blind to
//! the answers elsewhere that show a pair ambiguous: off by default).

use super::agent::Agent;
use super::coverage::Coverage;
use super::options::RunError;
use crate::eval::{map_acceptance, transform_error};
use crate::report::{MergeAttempt, TeamPlan, TeamReport};
use crate::scenario::{Coordination, Scenario, Success, TeamSetup};
use mrslam_core::{CellTraversal, OccupancyGrid, Pose2};
use mrslam_merge::{Contact, MergeParams, Merger, fuse_maps as fuse, merge};
use nalgebra::Point2;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::Range;

/// Two teams refused a merge try again only once one of their maps knows this share more area than at the refused
/// try: the gate would weigh the same evidence again (robots that stand still keep meeting, and a try of two
/// building-size maps costs 0.2-2 s).
const RETRY_GROWTH: f64 = 0.1;

/// How far two robots in contact may be apart beyond the range, metres: the error of their SLAM poses in their
/// teams' maps (a joined team's map also carries its merges' error).
const CONTACT_MARGIN_M: f64 = 2.0;

/// Header bytes of a ROS `nav_msgs/OccupancyGrid` message (header, map metadata, array length), as serialised.
const GRID_HEADER_BYTES: u64 = 80;

/// Bytes of a map sent as a ROS `nav_msgs/OccupancyGrid`: its header and one byte per cell.
fn message_bytes(map: &OccupancyGrid) -> u64 {
    GRID_HEADER_BYTES + (map.width() * map.height()) as u64
}

/// Every robot's map at one moment (if it has one yet).
pub(super) struct Snapshot {
    /// Each robot's current map in its own SLAM frame; `None` before its first processed scan.
    pub maps: Vec<Option<OccupancyGrid>>,
}

impl Snapshot {
    /// Takes every robot's map.
    pub(super) fn take(agents: &[Agent]) -> Result<Snapshot, RunError> {
        // each robot's map is its own SLAM's: build them side by side
        let maps = agents
            .par_iter()
            .map(|a| {
                if a.processed.is_empty() {
                    return Ok(None);
                }
                a.map().map(Some)
            })
            .collect::<Result<_, _>>()?;
        Ok(Snapshot { maps })
    }
}

/// What the teams did in one step, for the planner and the recording.
#[derive(Default)]
pub(super) struct TeamStep {
    /// Roots of the teams that grew (a merge was accepted).
    pub joined: Vec<usize>,
    /// Roots of the teams whose robots sent their maps to their team.
    pub shared: Vec<usize>,
    /// This step's merge attempts: their indices in `Teams::attempts`.
    pub attempts: Range<usize>,
    /// This step's coverage sample (time, share), when one was due.
    pub sample: Option<[f64; 2]>,
    /// The robots' maps the step used, when it took them.
    pub snapshot: Option<Snapshot>,
}

/// The teams of a run and everything they did.
pub(super) struct Teams<'s> {
    setup: &'s TeamSetup,
    success: Success,
    merger: Box<dyn Merger>,
    params: MergeParams,
    /// Per robot: the root robot of its team.
    root: Vec<usize>,
    /// Per robot: its SLAM frame in its root's SLAM frame.
    place: Vec<Pose2>,
    /// Per pair of robots (a < b): when they may next exchange maps.
    next_exchange: BTreeMap<(usize, usize), f64>,
    /// Per pair of team roots (host's first) refused at their last try: the areas their maps knew then, m².
    refused: BTreeMap<(usize, usize), [f64; 2]>,
    /// Per robot: when it next sends its map to its team.
    next_share: Vec<f64>,
    next_coverage: f64,
    coverage: Coverage,
    samples: Vec<[f64; 2]>,
    attempts: Vec<MergeAttempt>,
    plans: Vec<TeamPlan>,
    bytes: u64,
}

impl<'s> Teams<'s> {
    /// Every robot a team of its own, merging with `merger`; the reachable free area of `truth` from the robots'
    /// starts.
    pub(super) fn new(
        scenario: &Scenario,
        setup: &'s TeamSetup,
        truth: &OccupancyGrid,
        merger: Box<dyn Merger>,
    ) -> Self {
        let n = scenario.robots.len();
        let starts: Vec<Pose2> = scenario.robots.iter().map(|r| r.start).collect();
        let radius = scenario.robots.iter().map(|r| r.model.footprint.bounding_radius()).fold(f64::INFINITY, f64::min);
        Teams {
            setup,
            success: scenario.success,
            merger,
            params: MergeParams::default(),
            root: (0..n).collect(),
            place: vec![Pose2::identity(); n],
            next_exchange: BTreeMap::new(),
            refused: BTreeMap::new(),
            next_share: vec![0.0; n],
            next_coverage: 0.0,
            coverage: Coverage::new(truth, &starts, radius),
            samples: Vec::new(),
            attempts: Vec::new(),
            plans: Vec::new(),
            bytes: 0,
        }
    }

    /// The robots of `root`'s team, the root first.
    pub(super) fn members(&self, root: usize) -> Vec<usize> {
        let mut m: Vec<usize> = (0..self.root.len()).filter(|&k| self.root[k] == root).collect();
        m.sort_by_key(|&k| (k != root, k));
        m
    }

    /// The roots of the teams, in robot order.
    pub(super) fn roots(&self) -> Vec<usize> {
        (0..self.root.len()).filter(|&k| self.root[k] == k).collect()
    }

    /// Robot `k`'s team root and its SLAM frame in the root's.
    pub(super) fn place(&self, k: usize) -> (usize, Pose2) {
        (self.root[k], self.place[k])
    }

    /// Every merge attempt so far, in time order.
    pub(super) fn attempts(&self) -> &[MergeAttempt] {
        &self.attempts
    }

    /// Of the reachable free cells some robot's beams crossed so far, the share more than one robot's crossed.
    pub(super) fn redundancy(&self, agents: &[Agent]) -> f64 {
        let observed: Vec<&[bool]> = agents.iter().map(|a| &a.observed[..]).collect();
        self.coverage.redundancy(&observed)
    }

    /// Keeps a joint plan for the report.
    pub(super) fn record_plan(&mut self, plan: TeamPlan) {
        self.plans.push(plan);
    }

    /// Whether a joined team's robots plan together.
    pub(super) fn coordinated(&self) -> bool {
        self.setup.coordination == Coordination::Frontiers
    }

    /// The map of `root`'s team in the root's frame: its robots' maps in `snapshot` fused along their places.
    pub(super) fn team_map(&self, root: usize, snapshot: &Snapshot) -> Option<OccupancyGrid> {
        let mut out: Option<OccupancyGrid> = None;
        for k in self.members(root) {
            let Some(map) = &snapshot.maps[k] else { continue };
            out = Some(match out {
                None if self.place[k] == Pose2::identity() => map.clone(),
                None => fuse(&empty_like(map), map, &self.place[k], self.params.fusion),
                Some(team) => fuse(&team, map, &self.place[k], self.params.fusion),
            });
        }
        out
    }

    /// After a step: robots of different teams in contact exchange and try to merge their teams' maps; teammates
    /// share their maps; coverage is sampled when due.
    pub(super) fn after_step(&mut self, t: f64, agents: &[Agent], truth: &OccupancyGrid) -> Result<TeamStep, RunError> {
        let n = agents.len();
        let frames: Vec<Option<Pose2>> = agents.iter().map(Agent::frame).collect();
        let positions: Vec<Point2<f64>> = agents.iter().map(|a| Point2::from(a.last.translation.vector)).collect();
        let mut contacts = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                if self.root[a] == self.root[b] || frames[a].is_none() || frames[b].is_none() {
                    continue;
                }
                if t + 1e-9 < self.next_exchange.get(&(a, b)).copied().unwrap_or(0.0) {
                    continue;
                }
                if self.in_contact(&positions[a], &positions[b], truth) {
                    contacts.push((a, b));
                }
            }
        }
        let sharing: Vec<usize> = (0..n)
            .filter(|&k| frames[k].is_some() && self.members(self.root[k]).len() > 1 && t + 1e-9 >= self.next_share[k])
            .collect();
        let coverage_due = t + 1e-9 >= self.next_coverage;
        if contacts.is_empty() && sharing.is_empty() && !coverage_due {
            return Ok(TeamStep::default());
        }
        let snapshot = Snapshot::take(agents)?;
        for &k in &sharing {
            self.next_share[k] = t + self.setup.exchange_period;
            if let Some(m) = &snapshot.maps[k] {
                self.bytes += message_bytes(m);
            }
        }
        let mut joined = Vec::new();
        let first_attempt = self.attempts.len();
        for (a, b) in contacts {
            // An earlier contact of this step may have joined the two teams already.
            if self.root[a] == self.root[b] {
                continue;
            }
            self.next_exchange.insert((a, b), t + self.setup.exchange_period);
            let (ra, rb) = (self.root[a], self.root[b]);
            let (host, other, ra, rb) = if ra < rb { (a, b, ra, rb) } else { (b, a, rb, ra) };
            let (Some(map_a), Some(map_b)) = (self.team_map(ra, &snapshot), self.team_map(rb, &snapshot)) else {
                continue;
            };
            let known = [map_a.known_area(), map_b.known_area()];
            if known[0].min(known[1]) < self.setup.min_known_m2 {
                continue;
            }
            // The last refused try of these two teams stands until one of their maps has grown.
            if let Some(last) = self.refused.get(&(ra, rb))
                && known.iter().zip(last).all(|(now, then)| *now < then * (1.0 + RETRY_GROWTH))
            {
                continue;
            }
            self.bytes += message_bytes(&map_a) + message_bytes(&map_b);
            // Each robot where its team's map puts it: they are within range of each other now.
            let at = |k: usize| Point2::from((self.place[k] * agents[k].pose_estimate()).translation.vector);
            let contact = Contact {
                a: at(host),
                b: at(other),
                within_m: self.setup.range + CONTACT_MARGIN_M,
                search_within: self.setup.search_near_contact,
            };
            let out =
                merge(self.merger.as_ref(), &map_a, &map_b, &MergeParams { contact: Some(contact), ..self.params });
            if out.report.accepted {
                self.refused.remove(&(ra, rb));
            } else {
                self.refused.insert((ra, rb), known);
            }
            let (fa, fb) = (frames[ra].unwrap_or_default(), frames[rb].unwrap_or_default());
            let true_t = fa.inv_mul(&fb);
            let err = out.report.transform.map(|x| transform_error(&x.to_pose(), &true_t));
            // Each team's frame as its robot in contact places it: that robot's map frame where its pose is
            // true, times where the team's map puts that robot's frame.
            let here = |k: usize| agents[k].frame_here().map(|f| f * self.place[k].inverse());
            let contact_t = here(host).zip(here(other)).map(|(fa, fb)| fa.inv_mul(&fb));
            // Measured at the other robot, where the two maps meet, rather than at its team frame's origin.
            let at_other = self.place[other] * agents[other].last_processed_pose().unwrap_or_default();
            let err_here = out
                .report
                .transform
                .zip(contact_t)
                .map(|(x, t)| transform_error(&(x.to_pose() * at_other), &(t * at_other)));
            let correct = out.report.accepted
                && err_here.is_some_and(|(r, d)| {
                    r.to_degrees() <= self.success.rotation_deg && d <= self.success.translation_m
                });
            let name = |k: usize| agents[k].setup.name.clone();
            let team_names = |r: usize| self.members(r).into_iter().map(name).collect::<Vec<_>>();
            self.attempts.push(MergeAttempt {
                time_s: t,
                robots: [name(host), name(other)],
                teams: [team_names(ra), team_names(rb)],
                known_m2: known,
                accepted: out.report.accepted,
                correct,
                rotation_error_deg: err.map(|e| e.0.to_degrees()),
                translation_error_m: err.map(|e| e.1),
                rotation_error_at_contact_deg: err_here.map(|e| e.0.to_degrees()),
                translation_error_at_contact_m: err_here.map(|e| e.1),
                stage: out.report.stage.clone(),
                reason: out.report.reason.clone(),
                time_ms: out.report.time_ms,
                stage_ms: out
                    .report
                    .timings_ms
                    .iter()
                    .filter(|(k, _)| !k.contains('/'))
                    .map(|(k, v)| (k.clone(), *v))
                    .collect(),
            });
            if let (true, Some(x)) = (out.report.accepted, out.report.transform) {
                let t_ra_rb = x.to_pose();
                for k in 0..n {
                    if self.root[k] == rb {
                        self.root[k] = ra;
                        self.place[k] = t_ra_rb * self.place[k];
                    }
                }
                joined.push(ra);
            }
        }
        let mut sample = None;
        if coverage_due {
            self.next_coverage = t + self.setup.coverage_period;
            self.sample(t, &snapshot, &frames, truth);
            sample = self.samples.last().copied();
        }
        let mut shared: Vec<usize> = sharing.iter().map(|&k| self.root[k]).collect();
        shared.sort_unstable();
        shared.dedup();
        Ok(TeamStep { joined, shared, attempts: first_attempt..self.attempts.len(), sample, snapshot: Some(snapshot) })
    }

    /// Samples the share of the reachable free area the robots' maps mark free.
    fn sample(&mut self, t: f64, snapshot: &Snapshot, frames: &[Option<Pose2>], truth: &OccupancyGrid) {
        let placed: Vec<(&OccupancyGrid, Pose2)> =
            snapshot.maps.iter().zip(frames).filter_map(|(m, f)| Some((m.as_ref()?, (*f)?))).collect();
        let share = self.coverage.fraction(truth, &placed);
        self.samples.push([t, share]);
    }

    /// Whether robots at `a` and `b` can talk: within range, and no true wall between them when line of sight
    /// is asked for.
    fn in_contact(&self, a: &Point2<f64>, b: &Point2<f64>, truth: &OccupancyGrid) -> bool {
        if (a - b).norm() > self.setup.range {
            return false;
        }
        if !self.setup.line_of_sight {
            return true;
        }
        let (x0, y0) = truth.world_to_cell_f(a);
        let (x1, y1) = truth.world_to_cell_f(b);
        !CellTraversal::new(x0, y0, x1, y1).any(|(x, y)| truth.get_checked(x, y).is_some_and(|l| l > 0.0))
    }

    /// The report: a last coverage sample at `t`, the metrics, the teams and the largest team's map against the
    /// truth.
    pub(super) fn report(mut self, t: f64, agents: &[Agent], truth: &OccupancyGrid) -> Result<TeamReport, RunError> {
        let snapshot = Snapshot::take(agents)?;
        let frames: Vec<Option<Pose2>> = agents.iter().map(Agent::frame).collect();
        if self.samples.last().is_none_or(|s| s[0] < t - 1e-9) {
            self.sample(t, &snapshot, &frames, truth);
        }
        let reached = |share: f64| self.samples.iter().find(|s| s[1] >= share).map(|s| s[0]);
        let roots = self.roots();
        let largest = roots.iter().copied().max_by_key(|&r| (self.members(r).len(), std::cmp::Reverse(r)));
        let team_map_acceptance = match largest {
            Some(r) if self.members(r).len() > 1 => {
                self.team_map(r, &snapshot).zip(frames[r]).map(|(m, f)| map_acceptance(truth, &m, &f))
            }
            _ => None,
        };
        let name = |k: usize| agents[k].setup.name.clone();
        Ok(TeamReport {
            coordination: self.setup.coordination.to_string(),
            range_m: self.setup.range,
            merger: self.setup.merger.to_string(),
            reachable_free_m2: self.coverage.reachable_m2(),
            final_coverage: self.samples.last().map_or(0.0, |s| s[1]),
            time_to_50_s: reached(0.5),
            time_to_90_s: reached(0.9),
            time_to_95_s: reached(0.95),
            distance_m: agents.iter().map(|a| a.distance).sum(),
            redundancy: self.redundancy(agents),
            first_correct_merge_s: self.attempts.iter().find(|a| a.correct).map(|a| a.time_s),
            merges_accepted: self.attempts.iter().filter(|a| a.accepted).count(),
            merges_refused: self.attempts.iter().filter(|a| !a.accepted).count(),
            merges_false: self.attempts.iter().filter(|a| a.accepted && !a.correct).count(),
            bytes_exchanged: self.bytes,
            teams: roots.iter().map(|&r| self.members(r).into_iter().map(name).collect()).collect(),
            team_map_acceptance,
            coverage: self.samples,
            attempts: self.attempts,
            plans: self.plans,
        })
    }
}

/// An unknown grid with `map`'s geometry (the fusion's frame when a team's root has no map yet).
fn empty_like(map: &OccupancyGrid) -> OccupancyGrid {
    let mut g = map.clone();
    g.cells_mut().fill(0.0);
    g
}
