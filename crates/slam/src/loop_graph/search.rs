//! The loop search: one scan against one submap, over a window of poses around where the graph puts it, by
//! branch and bound on the submap's score pyramid (Olson 2009; Hess et al. 2016), then the field matcher's
//! climb and Gauss-Newton on the submap's own hits.

use super::submap::SubmapGrids;
use crate::loop_closure::{LOOP_HUBER, LoopClosureParams, loop_information};
use crate::scan_matcher::{PreparedScan, ScanMatcher, Scratch};
use mrslam_core::Xyt;
use mrslam_matching::pose_graph::Edge;
use mrslam_matching::{Best, HIT, Window, branch_and_bound};
use rayon::prelude::*;

/// Where a scan is searched for: within ± `linear` metres and ± `angular` radians of a predicted pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchWindow {
    /// Half-width of the translation window, metres.
    pub linear: f64,
    /// Half-width of the heading window, radians.
    pub angular: f64,
}

/// Headings searched at most on each side of the predicted one by a loop search (the step widens beyond).
pub const MAX_HEADING_STEPS: usize = 200;
/// Points of a scan the branch and bound places at most.
const MAX_POINTS: usize = 400;

/// What a search found: the scan's robot pose in the submap's frame and the branch and bound's score (mean
/// field value of its points, 1 on a wall).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Found {
    /// Robot pose, submap (anchor) frame.
    pub pose: Xyt,
    /// Mean score of the scan's points, in (0, 1].
    pub score: f64,
    /// The best score of a pose at least [`AMBIGUITY_SEPARATION`] from this one (any heading), relative to this
    /// one's; 0 when none reached the minimum score. Near 1 along a featureless corridor: the match is ambiguous.
    pub rival: f64,
}

/// Metres apart two answers of the branch and bound must be to be rivals.
pub const AMBIGUITY_SEPARATION: f64 = 1.0;

/// The scan's end points (robot frame) the branch and bound places: one per coarse cell, at most
/// [`MAX_POINTS`] (an even stride).
pub fn search_points(scan: &PreparedScan, matcher: &ScanMatcher, cell: f64) -> Vec<(f64, f64)> {
    let lp = matcher.laser_pose(&Xyt { x: 0.0, y: 0.0, theta: 0.0 });
    let (s, c) = lp.theta.sin_cos();
    let mut cells: Vec<(i64, i64, f64, f64)> = scan
        .hits
        .iter()
        .map(|b| {
            let (x, y) = (lp.x + c * b.x - s * b.y, lp.y + s * b.x + c * b.y);
            ((x / cell).floor() as i64, (y / cell).floor() as i64, x, y)
        })
        .collect();
    cells.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
    let stride = cells.len().div_ceil(MAX_POINTS).max(1);
    cells.iter().step_by(stride).map(|&(_, _, x, y)| (x, y)).collect()
}

/// Branch and bound of `points` (robot frame) on `grids` over `window` around `predicted` (submap frame), at
/// most `max_steps` headings on each side: the best pose whose mean score reaches `min_score`, or `None`.
pub fn branch_and_bound_pose(
    grids: &SubmapGrids,
    points: &[(f64, f64)],
    predicted: &Xyt,
    window: SearchWindow,
    min_score: f64,
    max_steps: usize,
) -> Option<Found> {
    if points.is_empty() {
        return None;
    }
    let cell = grids.cell;
    let reach = points.iter().map(|&(x, y)| x.hypot(y)).fold(cell, f64::max);
    // The heading step that moves the farthest point by about a cell.
    let fine = (1.0 - cell * cell / (2.0 * reach * reach)).clamp(-1.0, 1.0).acos().max(1e-4);
    let steps = ((window.angular / fine).ceil() as usize).min(max_steps);
    let step = if steps > 0 { window.angular / steps as f64 } else { 0.0 };
    let (cx, cy) = ((predicted.x - grids.origin.0) / cell, (predicted.y - grids.origin.1) / cell);
    let half = (window.linear / cell).ceil() as i32;
    let win = Window {
        x0: cx.floor() as i32 - half,
        x1: cx.floor() as i32 + half,
        y0: cy.floor() as i32 - half,
        y1: cy.floor() as i32 + half,
    };
    let floor = (min_score * HIT as f64 * points.len() as f64).ceil() as i64;
    let separation = (AMBIGUITY_SEPARATION / cell).ceil() as i32;
    let headings: Vec<i32> = (-(steps as i32)..=steps as i32).collect();
    // The two best distinct offsets of every heading, best first overall.
    let mut found: Vec<(i64, i32, i32, i32)> =
        headings
            .par_iter()
            .map_init(
                || (Vec::new(), Vec::new()),
                |(cells, scratch), &k| {
                    let theta = predicted.theta + k as f64 * step;
                    let (s, c) = theta.sin_cos();
                    cells.clear();
                    cells.extend(points.iter().map(|&(x, y)| {
                        (((c * x - s * y) / cell).floor() as i32, ((s * x + c * y) / cell).floor() as i32)
                    }));
                    let mut best = Best::new(2, separation, floor);
                    branch_and_bound(&grids.pyramid, cells, win, &mut best, scratch);
                    best.found.iter().map(|f| (f.score, k, f.ox, f.oy)).collect::<Vec<_>>()
                },
            )
            .flatten()
            .collect();
    found.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.abs().cmp(&b.1.abs())).then(a.1.cmp(&b.1)));
    let &(score, k, ox, oy) = found.first()?;
    // An answer on the window's edge is the best inside it, not a peak: the true pose (or a better one) may lie
    // beyond, so the match is not kept.
    let on_edge = ox <= win.x0 || ox >= win.x1 || oy <= win.y0 || oy >= win.y1;
    if on_edge {
        return None;
    }
    let rival = found
        .iter()
        .find(|r| (r.2 - ox).abs() >= separation || (r.3 - oy).abs() >= separation)
        .map_or(0.0, |r| r.0 as f64 / score as f64);
    Some(Found {
        pose: Xyt {
            x: grids.origin.0 + (ox as f64 + 0.5) * cell,
            y: grids.origin.1 + (oy as f64 + 0.5) * cell,
            theta: predicted.theta + k as f64 * step,
        },
        score: score as f64 / (HIT as f64 * points.len() as f64),
        rival,
    })
}

/// Refines a branch and bound answer with the field matcher on the submap's hits and makes it a loop edge
/// `anchor → node` (the pose is the node's in the anchor's frame), when at least `min_matched` of the scan's
/// beams found a surface there.
pub fn refine_to_edge(
    grids: &SubmapGrids,
    matcher: &ScanMatcher,
    scan: &PreparedScan,
    found: &Found,
    params: &LoopClosureParams,
    (anchor, node): (usize, usize),
) -> Option<Edge> {
    let mut scratch = Scratch::default();
    matcher.build_field(&grids.tiles, &found.pose, scan, &mut scratch.field);
    let f = &scratch.field;
    let (climbed, _) = matcher.climb(&found.pose, |q| matcher.field_eval(f, q, &scan.matched).score);
    let refined = matcher.refine(f, &climbed, &scan.matched, None);
    let (at_climbed, at_refined) =
        (matcher.field_eval(f, &climbed, &scan.matched), matcher.field_eval(f, &refined, &scan.matched));
    let (pose, e) = if at_refined.score >= at_climbed.score { (refined, at_refined) } else { (climbed, at_climbed) };
    if scan.matched.is_empty() || (e.matched as f64) < params.min_matched * scan.matched.len() as f64 {
        return None;
    }
    let h = matcher.scan_information(f, &pose, &scan.matched);
    Some(Edge {
        from: anchor,
        to: node,
        measured: pose,
        information: loop_information(&h, pose.theta, params),
        huber: LOOP_HUBER,
    })
}
