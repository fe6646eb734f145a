//! The map judged by what its scans see, and the search against every submap that a run of contradicted scans
//! starts.
//!
//! The loop search's windows cover drift, not a turn the odometry missed in a gap of the data: after such a kink
//! every place the robot comes back to lies beyond them. A processed scan that found no loop edge is judged
//! against the nearest submap passed a loop ago ([`super::free_space`]); [`RELOCALISE_AFTER`] contradicted scans
//! within [`RELOCALISE_TRAVEL`] metres start a search of each following node against every submap, over the whole
//! submap and headings within a quarter turn of the graph's, whose answers must agree from node to node. At the end
//! of the data every node is judged so, and the report counts the contradicted ones
//! ([`crate::LoopClosureReport::contradicts_itself`]).

use super::free_space::FreeSpace;
use super::search::{self, SearchWindow, branch_and_bound_pose, refine_to_edge, search_points};
use super::submap::{self, in_anchor_frame};
use super::{CONSISTENT_RIVALLED, CONSISTENT_TRAVEL, CONSISTENT_WINDOW, LoopGraph};
use crate::scan_matcher::PreparedScan;
use mrslam_core::Xyt;
use mrslam_matching::pose_graph::Edge;
use std::sync::Arc;

/// Points of a scan that must fall where a submap saw something for the scan to be judged against it.
const MIN_SEEN: usize = 30;
/// Share of those on the submap's open floor, beyond the window's reach of its walls, that contradicts it.
const CONTRADICTING_SHARE: f64 = 0.15;
/// Contradicted nodes that start a search against every submap ([`LoopGraph::relocalise`]).
const RELOCALISE_AFTER: usize = 4;
/// Metres of driving within which the contradicted nodes must lie.
const RELOCALISE_TRAVEL: f64 = 10.0;
/// Metres of driving after which nodes are no longer searched everywhere when none was placed.
const RELOCALISE_GIVE_UP: f64 = 20.0;
/// How closely two answers of searches everywhere must move the graph alike, metres and radians.
const RELOCALISE_AGREE_M: f64 = 0.3;
const RELOCALISE_AGREE_RAD: f64 = 0.05;
/// Headings on each side of the predicted one a search against a whole submap tries at most.
const RELOCALISE_HEADING_STEPS: usize = 1000;
/// The most a search against a whole submap turns the node from where the graph has it, radians: a corridor
/// matches turned round about as well as the right way, and its answers agree from node to node turned round too
/// (ACES with a looser scan-odometry prior: three such edges kept, turning the graph 1.05-3.12 rad, 0.21 -> 0.97 m);
/// the turns a robot's odometry missed in a gap of the data are smaller (ACES's stale scan line: 1.0 rad).
const RELOCALISE_MAX_TURN: f64 = std::f64::consts::FRAC_PI_2;
/// How far a scan may be from where the graph puts it in a good map when its map is judged.
const JUDGE_WINDOW: SearchWindow = SearchWindow { linear: 0.5, angular: 0.01 };

impl LoopGraph {
    /// The cell of the submaps' search grids and free space, metres.
    fn coarse_cell(&self) -> f64 {
        self.map.delta * submap::COARSE as f64
    }

    /// Submap `i`'s free space, drawn from its nodes' poses now, in its anchor's frame.
    pub(super) fn free_space_of(&self, i: usize) -> Option<FreeSpace> {
        let (local, prepared) = self.submap_scans(i);
        let scans: Vec<(Xyt, &PreparedScan)> = local.into_iter().zip(&prepared).collect();
        FreeSpace::build(&scans, &self.matcher, self.coarse_cell())
    }

    /// Judges node `k`, whose searches found no loop edge, against submap `i` beside it. After
    /// [`RELOCALISE_AFTER`] contradicted nodes within [`RELOCALISE_TRAVEL`] metres of driving with no loop edge, the
    /// graph is wrong beyond what its windows reach: the node is searched against every submap passed a loop ago
    /// ([`LoopGraph::relocalise`]), and so is every node after it until one is placed or [`RELOCALISE_GIVE_UP`]
    /// metres have been driven.
    pub(super) fn judge_revisit(&mut self, k: usize, i: usize, scan: &PreparedScan) {
        let space = match &self.free_space {
            Some((j, v, f)) if *j == i && *v == self.version => f.clone(),
            _ => {
                let Some(f) = self.free_space_of(i) else { return };
                let f = Arc::new(f);
                self.free_space = Some((i, self.version, f.clone()));
                f
            }
        };
        let anchor = self.nodes[self.submaps[i].first].pose;
        let at = in_anchor_frame(&anchor, &[self.nodes[k].pose])[0];
        let j = space.judge(&search_points(scan, &self.matcher, self.coarse_cell()), &at, JUDGE_WINDOW);
        if !(j.seen >= MIN_SEEN && j.contradicting as f64 >= CONTRADICTING_SHARE * j.seen as f64) {
            return;
        }
        let travel = self.travel[k];
        self.contradicted.retain(|&t| travel - t <= RELOCALISE_TRAVEL);
        self.contradicted.push(travel);
        if self.contradicted.len() < RELOCALISE_AFTER || !self.params.relocalise {
            return;
        }
        self.contradicted.clear();
        self.lost.get_or_insert(travel);
    }

    /// Searches node `k` against every finished submap passed a loop ago, over the whole submap and headings within
    /// [`RELOCALISE_MAX_TURN`] of the graph's. An answer is kept as a loop edge when the answers of earlier such
    /// searches, at least [`CONSISTENT_RIVALLED`] - 1 of them over [`CONSISTENT_TRAVEL`] metres of driving, move the
    /// graph alike (a scan along a corridor matches many places of it; the true one agrees from node to node).
    /// Returns whether one was kept.
    pub(super) fn relocalise(&mut self, k: usize, scan: &PreparedScan) -> bool {
        self.report.relocalisations += 1;
        let travel = self.travel[k];
        let node = self.nodes[k].pose.to_pose();
        // Every submap's best answer: where it puts the node (map frame), its score, the submap and the answer.
        let mut answers: Vec<(mrslam_core::Pose2, f64, usize, search::Found)> = Vec::new();
        let points = search_points(scan, &self.matcher, self.coarse_cell());
        for i in 0..self.submaps.len() {
            let s = self.submaps[i];
            if travel - self.travel[s.last] < self.params.min_travel {
                continue;
            }
            let Some(grids) = self.grids(i) else { continue };
            let anchor = self.nodes[s.first].pose;
            let local = in_anchor_frame(&anchor, &(s.first..=s.last).map(|n| self.nodes[n].pose).collect::<Vec<_>>());
            let (x0, x1) = local.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x), b.max(p.x)));
            let (y0, y1) = local.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
            let predicted = in_anchor_frame(&anchor, &[self.nodes[k].pose])[0];
            let centre = Xyt { x: 0.5 * (x0 + x1), y: 0.5 * (y0 + y1), theta: predicted.theta };
            let window = SearchWindow {
                linear: 0.5 * (x1 - x0).hypot(y1 - y0) + self.params.search_radius,
                angular: RELOCALISE_MAX_TURN,
            };
            let steps = RELOCALISE_HEADING_STEPS;
            let Some(found) = branch_and_bound_pose(&grids, &points, &centre, window, self.params.min_score, steps)
            else {
                continue;
            };
            // An answer within the loop search's own window is one that search refused: only the places beyond it
            // are new.
            let usual = self.window((s.first..=s.last).map(|n| self.reach[n]).fold(f64::INFINITY, f64::min));
            let beyond = (found.pose.x - predicted.x).hypot(found.pose.y - predicted.y) > usual.linear
                || mrslam_core::pose::normalize_angle(found.pose.theta - predicted.theta).abs() > usual.angular;
            if beyond {
                answers.push((anchor.to_pose() * found.pose.to_pose(), found.score, i, found));
            }
        }
        answers.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.2.cmp(&b.2)));
        self.relocalising.retain(|r| travel - r.0 <= CONSISTENT_WINDOW);
        // The best answer the earlier searches agree with: the move it makes of the graph moves their nodes onto
        // one of their answers.
        let agreed = answers.iter().find(|(at, ..)| {
            let correction = at * node.inverse();
            let agreeing: Vec<f64> = self
                .relocalising
                .iter()
                .filter(|(_, earlier, found)| {
                    let moved = Xyt::from_pose(&(correction * earlier));
                    found.iter().any(|f| {
                        let f = Xyt::from_pose(f);
                        (f.x - moved.x).hypot(f.y - moved.y) <= RELOCALISE_AGREE_M
                            && mrslam_core::pose::normalize_angle(f.theta - moved.theta).abs() <= RELOCALISE_AGREE_RAD
                    })
                })
                .map(|r| r.0)
                .collect();
            let first = agreeing.iter().copied().fold(travel, f64::min);
            agreeing.len() + 1 >= CONSISTENT_RIVALLED && travel - first >= CONSISTENT_TRAVEL
        });
        let kept = agreed.and_then(|&(_, _, i, found)| {
            let s = self.submaps[i];
            let grids = self.grids(i)?;
            let edge = refine_to_edge(&grids, &self.matcher, scan, &found, &self.params, (s.first, k))?;
            Some(self.held_from_nearest_node(edge, s))
        });
        self.relocalising.push((travel, node, answers.iter().map(|a| a.0).collect()));
        match kept {
            Some(edge) => {
                // Agreed over metres of driving: no robust kernel, which would let the graph keep most of its error.
                self.loops.push(Edge { huber: f64::INFINITY, ..edge });
                self.relocalised_now = true;
                self.pending += 1;
                self.report.closures += 1;
                self.report.relocalised += 1;
                self.lost = None;
                self.relocalising.clear();
                self.contradicted.clear();
                true
            }
            None => {
                if self.lost.is_some_and(|start| travel - start > RELOCALISE_GIVE_UP) {
                    self.lost = None;
                    self.relocalising.clear();
                }
                false
            }
        }
    }

    /// Judges the map the graph holds: every node against the submaps near it that it is at least a loop's
    /// driving away from ([`super::free_space`]); counts the nodes whose scan sees surfaces on a submap's open floor.
    pub(super) fn judge_map(&mut self) {
        let cell = self.coarse_cell();
        // The submaps each node is judged against, as (submap, node) pairs by submap: one free-space grid at a time.
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for (k, node) in self.nodes.iter().enumerate() {
            let mut near: Vec<(f64, usize)> = Vec::new();
            for (i, s) in self.submaps.iter().enumerate() {
                let apart =
                    (self.travel[k] - self.travel[s.last]).abs().min((self.travel[k] - self.travel[s.first]).abs());
                if (s.first..=s.last).contains(&k) || apart < self.params.min_travel {
                    continue;
                }
                let d = (s.first..=s.last)
                    .map(|n| (self.nodes[n].pose.x - node.pose.x).hypot(self.nodes[n].pose.y - node.pose.y))
                    .fold(f64::INFINITY, f64::min);
                if d <= self.params.search_radius {
                    near.push((d, i));
                }
            }
            near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            pairs.extend(near.iter().take(self.params.max_searches).map(|&(_, i)| (i, k)));
        }
        pairs.sort_unstable();
        // Each judged node's most contradicted judgement: (contradicting, seen).
        let mut worst: Vec<Option<(usize, usize)>> = vec![None; self.nodes.len()];
        for group in pairs.chunk_by(|a, b| a.0 == b.0) {
            let anchor = self.nodes[self.submaps[group[0].0].first].pose;
            let Some(space) = self.free_space_of(group[0].0) else { continue };
            for &(_, k) in group {
                let scan = self.prepare(&self.nodes[k].scan);
                let at = in_anchor_frame(&anchor, &[self.nodes[k].pose])[0];
                let j = space.judge(&search_points(&scan, &self.matcher, cell), &at, JUDGE_WINDOW);
                let w = &mut worst[k];
                if j.seen >= MIN_SEEN && w.is_none_or(|(c, n)| j.contradicting * n > c * j.seen) {
                    *w = Some((j.contradicting, j.seen));
                }
            }
        }
        let judged: Vec<(usize, usize)> = worst.into_iter().flatten().collect();
        self.report.judged = judged.len();
        self.report.contradicted = judged.iter().filter(|&&(c, n)| c as f64 >= CONTRADICTING_SHARE * n as f64).count();
    }
}
