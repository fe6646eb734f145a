//! Loop closure: the best particle's trajectory smoothed by a pose graph whose loop edges match each scan
//! against the map of the scans taken where the robot passed a loop ago.
//!
//! Not in GMapping. The particle filter closes a loop by keeping the particles whose maps agree with what
//! the robot sees when it comes back; on a long log every surviving particle may descend from one ancestor
//! long before the loop, and then the drift of the way round is in all of them: the returning scans are
//! matched against walls mapped a loop ago *and* walls mapped on the way, and the history keeps its drift
//! (on ACES the relations across 500 s loops were 0.2-0.4 m off on every seed). Graph SLAM's back end
//! (Lu and Milios 1997; Cartographer's sparse pose adjustment) fixes exactly that: after the filter, each
//! processed scan is matched against a local map built only from the scans around the nearest place the
//! robot passed at least `loop_min_travel` metres of driving ago, and the trajectory is re-optimised with
//! those matches as loop edges and the filter's own increments as the chain. Loop edges carry the
//! matcher's information (the scan's curvature, so a corridor constrains nothing along itself) and Huber's
//! kernel (a wrong match pulls linearly); only local searches are made (`loop_window` around where the
//! filter put the scan), so the filter must have kept the loop within that window: loop closure corrects a
//! filter's residual drift, it does not replace the filter.

use crate::map_build::MapParams;
use crate::particle::TrajectoryNode;
use crate::scan_matcher::{Beam, MatcherParams, PreparedScan, ScanMatcher, Scratch};
use crate::tile_map::TileMap;
use mrslam_core::Xyt;
use mrslam_core::pose::relative;
use mrslam_matching::Information;
use mrslam_matching::pose_graph::{Edge, optimize};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Loop closure's settings (not GMapping).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopClosureParams {
    /// `loop_closure`: close loops with a pose graph over the processed scans: while the robot drives (`online`,
    /// see `loop_graph`), or when the log ends (smoothing the best particle's trajectory with loop edges that
    /// match each processed scan against the scans around the place it passed a loop ago, see `loop_closure`);
    /// the map is drawn from the graph's poses. Off (the default): the filter's trajectory, as GMapping.
    pub enabled: bool,
    /// `loop_min_travel`, metres driven: a place is a loop ago when the robot drove at least this far since it
    /// passed there.
    pub min_travel: f64,
    /// `loop_search_radius`, metres: a scan is matched against the place passed a loop ago nearest to it, when
    /// nearer than this.
    pub search_radius: f64,
    /// `loop_submap_nodes`: the local map of a place is the processed scans within this many of it, before and
    /// after.
    pub submap_nodes: usize,
    /// `loop_window`, metres: the loop match searches translations within ± this of where the filter put the
    /// scan.
    pub window: f64,
    /// `loop_heading_window`, radians: the loop match searches headings within ± this.
    pub heading_window: f64,
    /// `loop_min_matched`: a loop match is kept when at least this fraction of the scan's beams found a surface
    /// of the local map.
    pub min_matched: f64,
    /// `loop_chain_sigma`, metres: the standard deviation of the filter's own increment between two processed
    /// scans (each axis), as the pose graph's chain trusts it.
    pub chain_sigma: f64,
    /// `loop_chain_heading_sigma`, radians: the same for the increment's heading.
    pub chain_heading_sigma: f64,
    /// `loop_sigma`, metres: added (in quadrature, each axis) to a loop match's standard deviation from the
    /// matcher's information, which counts every beam as independent.
    pub sigma: f64,
    /// `loop_heading_sigma`, radians: the same for the loop match's heading.
    pub heading_sigma: f64,
    /// `loop_range`, metres: beams longer than this (or than the map's `max_urange`) are not used by the loop
    /// matches.
    pub range: f64,
    /// `loop_online`: close loops while the robot drives (a pose graph searched at every processed scan and
    /// optimised as loops are found, the filter re-anchored on it; see `loop_graph`); off: only when the log
    /// ends, by local searches around the filter's trajectory (see `loop_closure`).
    pub online: bool,
    /// `loop_submap_scans`: processed scans per submap of the online graph.
    pub submap_scans: usize,
    /// `loop_window_per_metre`: the online search's translation window grows by this many metres per metre
    /// driven since the last closure (or since the submap), from `loop_window`; wider once a closure showed
    /// more drift.
    pub window_per_metre: f64,
    /// `loop_heading_window_per_metre`, radians per metre: the same for the heading window, from
    /// `loop_heading_window`.
    pub heading_window_per_metre: f64,
    /// `loop_max_window`, metres: the translation window is never wider than this.
    pub max_window: f64,
    /// `loop_max_heading_window`, radians: the heading window is never wider than this.
    pub max_heading_window: f64,
    /// `loop_min_score`: the branch and bound keeps a pose whose scan points score at least this on average (1 on
    /// a wall of the submap, falling as a Gaussian of the distance, σ 2 cells).
    pub min_score: f64,
    /// `loop_max_rival`: a branch and bound answer is refused when another pose at least a metre from it scores
    /// this fraction of its score or more (along a featureless corridor every offset scores alike), unless the
    /// answers so refused lately agree (see the online graph's `agrees_with_rivalled`).
    pub max_rival: f64,
    /// `loop_max_searches`: submaps a processed scan is searched against at most (the nearest).
    pub max_searches: usize,
    /// `loop_optimize_every`: processed scans between optimisations while loop edges wait.
    pub optimize_every: usize,
    /// `loop_max_residual`: once optimised, loop edges farther than this Mahalanobis distance from the graph's
    /// poses are dropped (worst first).
    pub max_residual: f64,
    /// `loop_open_travel`, metres: driving this far through places passed a loop ago without a loop edge is a
    /// loop left open (counted in the report).
    pub open_loop_travel: f64,
    /// `loop_relocalise` (online only): when scans of places passed a loop ago keep seeing walls on the map's open
    /// floor where the graph puts them, the graph is wrong beyond what its windows reach (a turn the odometry
    /// missed in a gap of the data); the scans are then searched against every submap, over the whole submap and
    /// headings within a quarter turn of the graph's, and an answer that agrees from node to node becomes a loop
    /// edge. Off: the windows only.
    pub relocalise: bool,
}

impl Default for LoopClosureParams {
    fn default() -> Self {
        LoopClosureParams {
            enabled: false,
            min_travel: 20.0,
            search_radius: 3.0,
            submap_nodes: 10,
            window: 0.4,
            heading_window: 0.05,
            min_matched: 0.6,
            chain_sigma: 0.01,
            chain_heading_sigma: 0.003,
            sigma: 0.02,
            heading_sigma: 0.005,
            range: 30.0,
            online: true,
            submap_scans: 15,
            window_per_metre: 0.03,
            heading_window_per_metre: 0.003,
            max_window: 10.0,
            max_heading_window: 0.8,
            min_score: 0.6,
            max_rival: 0.8,
            max_searches: 3,
            optimize_every: 10,
            max_residual: 10.0,
            open_loop_travel: 10.0,
            relocalise: true,
        }
    }
}

/// What loop closure did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoopClosureReport {
    /// Loop searches made: a processed scan matched against a place passed a loop ago.
    pub candidates: usize,
    /// Matches kept as loop edges.
    pub closures: usize,
    /// Searches that found no match good enough.
    pub rejected: usize,
    /// Matches accepted, then dropped by the graph as inconsistent with the others (online only).
    pub dropped: usize,
    /// Optimisations run (online only).
    pub optimisations: usize,
    /// Stretches of at least `loop_open_travel` metres through places passed a loop ago in which no loop edge
    /// was found (online only): a map with such a stretch may show a place twice.
    pub open_loops: usize,
    /// Searches of a scan against every submap (within a quarter turn of the graph's heading), made after scans
    /// contradicted the map where the graph put them (online only).
    pub relocalisations: usize,
    /// Loop edges those searches kept (also counted in `closures`).
    pub relocalised: usize,
    /// Processed scans judged at the end against the submaps near them passed a loop apart (online only).
    pub judged: usize,
    /// Of those, the scans that see surfaces on a submap's open floor, where the map holds no wall (online only):
    /// the map puts the robot in a place that cannot be where it was, as when loops close into a wrong building.
    pub contradicted: usize,
    /// Largest move of a processed scan's pose by the optimisation, metres.
    pub max_correction: f64,
    /// Gauss-Newton iterations of the optimisation.
    pub iterations: u32,
}

/// Share of the judged scans that must contradict a map for it to be flagged ([`LoopClosureReport::contradicts_itself`]).
pub const CONTRADICTED_SHARE: f64 = 0.05;
/// Judged scans that must contradict a map at least for it to be flagged.
pub const MIN_CONTRADICTED: usize = 5;

impl LoopClosureReport {
    /// Whether the map contradicts itself: at least 5 % of the scans judged (and 5) see walls on its open floor.
    ///
    /// Measured on ACES, FR079 and Intel, with and without their ODOM lines, seeds 0-4: good maps 0-1.7 %; ACES
    /// maps whose loops closed into a wrong building (forced odometry lags): 26-42 %.
    pub fn contradicts_itself(&self) -> bool {
        self.contradicted >= MIN_CONTRADICTED && self.contradicted as f64 >= CONTRADICTED_SHARE * self.judged as f64
    }
}

/// Huber's threshold on a loop edge's Mahalanobis distance.
pub(crate) const LOOP_HUBER: f64 = 3.0;
/// Gauss-Newton iterations at most.
const MAX_ITERATIONS: u32 = 30;
/// Beams of the translation and heading search: every this many (the climb and Gauss-Newton use all).
const SEARCH_STRIDE: usize = 3;

/// Smooths a trajectory (oldest node first) by loop closure with settings `params`, matching with the filter's
/// `matcher` set up for one scan alone on grids and ranges of `map`; returns the new poses, one per node. Poses
/// are unchanged when no loop edge is found.
pub fn close_loops(
    nodes: &[&TrajectoryNode],
    laser: Xyt,
    params: &LoopClosureParams,
    matcher: &MatcherParams,
    map: &MapParams,
) -> (Vec<Xyt>, LoopClosureReport) {
    let mut poses: Vec<Xyt> = nodes.iter().map(|n| n.pose).collect();
    let mut report = LoopClosureReport::default();
    if nodes.len() < 3 {
        return (poses, report);
    }
    let range = map.max_urange.min(params.range);
    let prepared: Vec<PreparedScan> = nodes
        .par_iter()
        .map(|n| PreparedScan::new(&n.scan, map.max_range.min(n.scan.range_max as f64), range, 0))
        .collect();
    // Distance driven up to each node.
    let mut travel = vec![0.0; nodes.len()];
    for k in 1..nodes.len() {
        travel[k] = travel[k - 1] + (poses[k].x - poses[k - 1].x).hypot(poses[k].y - poses[k - 1].y);
    }
    let search = LoopSearch { matcher: loop_matcher(params, matcher, laser), params, delta: map.delta };
    // For each scan, the nearest node passed a loop ago, within the radius.
    let candidates: Vec<(usize, usize)> = (0..nodes.len())
        .filter_map(|j| {
            let p = &poses[j];
            (0..j)
                .filter(|&i| travel[j] - travel[i] >= params.min_travel)
                .map(|i| (i, (poses[i].x - p.x).hypot(poses[i].y - p.y)))
                .filter(|&(_, d)| d <= params.search_radius)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| (i, j))
        })
        .collect();
    report.candidates = candidates.len();
    let loops: Vec<Edge> = candidates
        .par_iter()
        .filter_map(|&(i, j)| {
            let lo = i.saturating_sub(params.submap_nodes);
            let hi = (i + params.submap_nodes).min(j);
            let submap: Vec<usize> = (lo..=hi).filter(|&k| travel[j] - travel[k] >= 0.5 * params.min_travel).collect();
            match_loop(&search, &poses, &prepared, &submap, i, j)
        })
        .collect();
    report.closures = loops.len();
    report.rejected = report.candidates - report.closures;
    if loops.is_empty() {
        return (poses, report);
    }
    let chain_info = Information::from_sigmas(params.chain_sigma, params.chain_heading_sigma);
    let mut edges: Vec<Edge> = (1..nodes.len())
        .map(|k| Edge {
            from: k - 1,
            to: k,
            measured: Xyt::from_pose(&relative(&poses[k - 1].to_pose(), &poses[k].to_pose())),
            information: chain_info,
            huber: f64::INFINITY,
        })
        .collect();
    edges.extend(loops);
    let before = poses.clone();
    if let Some(s) = optimize(&mut poses, &edges, MAX_ITERATIONS) {
        report.iterations = s.iterations;
    }
    report.max_correction = before.iter().zip(&poses).map(|(a, b)| (a.x - b.x).hypot(a.y - b.y)).fold(0.0, f64::max);
    (poses, report)
}

/// What every loop match uses: the matcher, the settings and the grid's cell size.
struct LoopSearch<'a> {
    matcher: ScanMatcher,
    params: &'a LoopClosureParams,
    delta: f64,
}

/// The field matcher the loop search uses: the filter's kernel and reach, no prior, every beam.
fn loop_matcher(params: &LoopClosureParams, matcher: &MatcherParams, laser: Xyt) -> ScanMatcher {
    let p = MatcherParams { heading_search: params.heading_window, motion_prior: 0.0, ..matcher.alone() };
    ScanMatcher::new(p, laser, false)
}

/// Matches node `j`'s scan against the map of the `submap` nodes' scans (at their current poses) around
/// node `i`: a search over translations within `loop_window` and headings within `loop_heading_window` of
/// where the filter put it, then the climb and Gauss-Newton. Returns the loop edge i → j when at least
/// `loop_min_matched` of the beams found a surface there.
fn match_loop(
    search: &LoopSearch,
    poses: &[Xyt],
    prepared: &[PreparedScan],
    submap: &[usize],
    i: usize,
    j: usize,
) -> Option<Edge> {
    let scan = &prepared[j];
    if scan.matched.len() < 10 || submap.is_empty() {
        return None;
    }
    let &LoopSearch { ref matcher, params, delta } = search;
    let mut map = TileMap::new(delta);
    for &k in submap {
        let lp = matcher.laser_pose(&poses[k]);
        let (s, c) = lp.theta.sin_cos();
        for b in &prepared[k].hits {
            let (dx, dy) = (c * b.c - s * b.s, s * b.c + c * b.s);
            map.add_beam_hit(lp.x + b.r * dx, lp.y + b.r * dy, dx, dy).ok()?;
        }
    }
    let init = poses[j];
    let mut scratch = Scratch::default();
    matcher.build_field(&map, &init, scan, &mut scratch.field);
    let f = &scratch.field;
    let sparse: Vec<Beam> = scan.matched.iter().step_by(SEARCH_STRIDE).copied().collect();
    let steps = (params.window / delta).floor() as i32;
    let mut best = (f64::NEG_INFINITY, init);
    for iy in -steps..=steps {
        for ix in -steps..=steps {
            let shifted = Xyt { x: init.x + ix as f64 * delta, y: init.y + iy as f64 * delta, ..init };
            let q = matcher.sweep_heading(&shifted, |q| matcher.field_eval(f, q, &sparse).score);
            let s = matcher.field_eval(f, &q, &sparse).score;
            if s > best.0 {
                best = (s, q);
            }
        }
    }
    let (climbed, _) = matcher.climb(&best.1, |q| matcher.field_eval(f, q, &scan.matched).score);
    let refined = matcher.refine(f, &climbed, &scan.matched, None);
    let (at_climbed, at_refined) =
        (matcher.field_eval(f, &climbed, &scan.matched), matcher.field_eval(f, &refined, &scan.matched));
    let (pose, e) = if at_refined.score >= at_climbed.score { (refined, at_refined) } else { (climbed, at_climbed) };
    if (e.matched as f64) < params.min_matched * scan.matched.len() as f64 {
        return None;
    }
    let h = matcher.scan_information(f, &pose, &scan.matched);
    Some(Edge {
        from: i,
        to: j,
        measured: Xyt::from_pose(&relative(&poses[i].to_pose(), &pose.to_pose())),
        information: loop_information(&h, pose.theta, params),
        huber: LOOP_HUBER,
    })
}

/// A loop edge's information from the scan's information `h` about the robot's pose (map frame): rotated into
/// the robot's frame at heading `theta`, its covariance widened by `loop_sigma` and `loop_heading_sigma` (the
/// matcher's information counts every beam as independent, which they are not).
pub(crate) fn loop_information(h: &Information, theta: f64, params: &LoopClosureParams) -> Information {
    let (s, c) = theta.sin_cos();
    // Rᵀ H R for the translation block, Rᵀ h_tθ for the coupling.
    let m = h.matrix();
    let r = nalgebra::Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    let local = r.transpose() * m * r;
    let eps = 1e-9 * (local[(0, 0)] + local[(1, 1)] + local[(2, 2)]).max(1e-12);
    let cov = (local + nalgebra::Matrix3::identity() * eps).try_inverse().unwrap_or(nalgebra::Matrix3::zeros());
    let floor = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(
        params.sigma * params.sigma,
        params.sigma * params.sigma,
        params.heading_sigma * params.heading_sigma,
    ));
    let info = (cov + floor).try_inverse().unwrap_or(nalgebra::Matrix3::zeros());
    Information::from_matrix(&info)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{error_to, office_keyframes as office_nodes};
    use std::sync::Arc;

    fn nodes(poses: &[Xyt], scans: &[Arc<mrslam_core::LaserScan>]) -> Vec<TrajectoryNode> {
        poses
            .iter()
            .zip(scans)
            .enumerate()
            .map(|(k, (p, s))| TrajectoryNode { stamp: k as f64, pose: *p, scan: s.clone(), parent: None })
            .collect()
    }

    #[test]
    fn a_drifted_lap_is_pulled_back_onto_the_truth() {
        let (truth, scans, laser) = office_nodes();
        // The filter's increments with a heading bias: the lap comes back 0.2-0.3 m off, within the window.
        let mut drifted = vec![Xyt::from_pose(&truth[0])];
        for k in 1..truth.len() {
            let mut z = Xyt::from_pose(&relative(&truth[k - 1], &truth[k]));
            z.theta += 0.0006;
            let p = drifted[k - 1].to_pose() * z.to_pose();
            drifted.push(Xyt::from_pose(&p));
        }
        let (worst_before, end_before) = error_to(&truth, &drifted);
        assert!((0.15..0.4).contains(&end_before), "the lap must end off, within the window: {end_before} m");
        let nodes = nodes(&drifted, &scans);
        let refs: Vec<&TrajectoryNode> = nodes.iter().collect();
        let params = crate::SlamParams::matched();
        let map = MapParams { max_range: 30.0, max_urange: 30.0, ..params.map };
        let (smoothed, report) = close_loops(&refs, laser, &params.loop_closure, &params.matcher, &map);
        let (worst_after, end_after) = error_to(&truth, &smoothed);
        assert!(report.closures >= 3, "{report:?}");
        assert!(end_after < 0.04, "the lap's end {end_after} m from the truth (was {end_before} m), {report:?}");
        assert!(worst_after < 0.4 * worst_before, "worst node {worst_after} m (was {worst_before} m)");
    }

    #[test]
    fn a_true_trajectory_stays_where_it_is_and_short_paths_have_no_loops() {
        let (truth, scans, laser) = office_nodes();
        let poses: Vec<Xyt> = truth.iter().map(Xyt::from_pose).collect();
        let nodes = nodes(&poses, &scans);
        let refs: Vec<&TrajectoryNode> = nodes.iter().collect();
        let params = crate::SlamParams::matched();
        let map = MapParams { max_range: 30.0, max_urange: 30.0, ..params.map };
        let (smoothed, report) = close_loops(&refs, laser, &params.loop_closure, &params.matcher, &map);
        assert!(report.closures >= 3, "{report:?}");
        let (worst, _) = error_to(&truth, &smoothed);
        assert!(worst < 0.03, "the smoothing moved a true pose {worst} m");
        // Fewer metres than `loop_min_travel`: nothing to close.
        let short: Vec<&TrajectoryNode> = refs.iter().take(10).copied().collect();
        let (same, report) = close_loops(&short, laser, &params.loop_closure, &params.matcher, &map);
        assert_eq!(report.closures, 0);
        assert_eq!(same, poses[..10].to_vec());
    }
}
