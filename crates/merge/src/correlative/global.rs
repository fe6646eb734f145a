//! The global search: branch and bound over every translation at each rotation the prior allows, on both maps
//! pooled to the search cell; optionally screened at a coarser cell first.

use super::bookkeeping::{fail, map_with_scratch};
use super::geometry::{angle_gap, to_scan_pose, to_transform};
use super::orientation;
use super::params::{CorrelativeMerger, CorrelativeParams};
use crate::alignment::NoAlignment;
use crate::timing::ms;
use mrslam_core::{OccupancyGrid, Pose2};
use mrslam_matching::{
    Best, BlockStates, Candidate, HIT, LocalScratch, LocalWindow, Pyramid, ScanPose, ScoreField, WallScan, Window,
    WindowField, branch_and_bound, local_search,
};
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::time::Instant;

/// The rounds of the rotation search, as (modulus, remainder) of the rotation index: every 16th first.
const ROUNDS: [(usize, usize); 5] = [(16, 0), (16, 8), (8, 4), (4, 2), (2, 1)];

/// A global answer: rotation index and its best offset.
#[derive(Debug, Clone, Copy)]
pub(super) struct Global {
    pub(super) rotation: usize,
    pub(super) candidate: Candidate,
}

/// What the global search found.
#[derive(Debug, Clone)]
pub(super) struct Found {
    /// The best distinct poses (`T_a_b`), strongest first.
    pub(super) poses: Vec<Pose2>,
    /// The best distinct answers more than [`crate::AnswerParams::rival_distinct_m`] from the first, at most
    /// [`crate::SearchParams::rivals`], strongest first (none scored below the search's pruning floor).
    pub(super) rivals: Vec<Pose2>,
    /// Angular step of the search, radians.
    pub(super) step: f64,
}

/// Both maps pooled to one search resolution, built once per pair and resolution: a's block states and b's wall
/// blocks as a scan (both searches of a pair share them).
pub(super) struct Pooled {
    /// The search cell, metres (a whole number of a's cells).
    pub(super) cell: f64,
    /// a's states on search cells.
    pub(super) blocks: BlockStates,
    /// b's wall blocks, thinned to [`crate::SearchParams::max_points`].
    pub(super) scan: WallScan,
}

impl Pooled {
    /// `cells_a`: a's cells as [`dense_free_cells`] gives them.
    pub(super) fn build(
        a: &OccupancyGrid,
        cells_a: &BlockStates,
        b: &OccupancyGrid,
        resolution: f64,
        max_points: usize,
    ) -> Self {
        let fa = ((resolution / a.resolution()).round() as usize).max(1);
        let fb = ((resolution / b.resolution()).round() as usize).max(1);
        Pooled {
            cell: fa as f64 * a.resolution(),
            blocks: cells_a.pooled(fa),
            scan: WallScan::of_blocks(b, fb, max_points),
        }
    }
}

/// a's cell states with its free cells kept only where at least [`crate::SearchParams::dense_free_share`] of the
/// search cell's extent (made odd) around them is free: what both the global search and the fine field score.
pub(super) fn dense_free_cells(a: &OccupancyGrid, p: &CorrelativeParams) -> BlockStates {
    let fa = ((p.search.resolution / a.resolution()).round() as usize).max(1);
    let mut cells = BlockStates::cells(a);
    cells.keep_dense_free(fa | 1, p.search.dense_free_share);
    cells
}

impl CorrelativeMerger {
    /// The global search: the best distinct poses of b's scan in a's grid frame, strongest first.
    pub(super) fn global(
        &self,
        a: &OccupancyGrid,
        pooled: &Pooled,
        keep: usize,
        peaks: &[f64],
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Found, Box<NoAlignment>> {
        let p = &self.params;
        let Pooled { cell, blocks, scan } = pooled;
        let cell = *cell;
        if scan.points.len() < p.search.min_points {
            return Err(fail(
                format!("too few walls in map b: {} blocks (need {})", scan.points.len(), p.search.min_points),
                timings.clone(),
            ));
        }
        let t = Instant::now();
        let penalty = (p.search.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = ScoreField::build(blocks, p.search.sigma_cells, penalty);
        if !field.values.contains(&HIT) {
            return Err(fail("map a has no walls".into(), timings.clone()));
        }
        let pyramid = Pyramid::build(&field, p.search.depth);
        timings.insert("field".into(), ms(t));
        let t = Instant::now();
        let step = (p.search.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let n_rot = (TAU / step).ceil() as usize;
        let step = TAU / n_rot as f64;
        let tolerance = p.search.rotation_tolerance_deg.to_radians().max(step);
        let searched = |j: usize| peaks.is_empty() || orientation::near_a_peak(j as f64 * step, peaks, tolerance);
        let min_floor = (p.search.min_score * f64::from(HIT) * scan.points.len() as f64).ceil() as i64;
        let separation = ((p.search.distinct_m / cell).ceil() as i32).max(1);
        let one = |scratch: &mut (Vec<(i32, i32)>, Vec<Candidate>), j: usize, floor: i64| -> Vec<Global> {
            let (points, roots) = scratch;
            scan.discretize(j as f64 * step, cell, points);
            let (mut x0, mut x1, mut y0, mut y1) = (i32::MAX, i32::MIN, i32::MAX, i32::MIN);
            for &(x, y) in points.iter() {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
            let mut window =
                Window { x0: -x1, x1: field.width as i32 - 1 - x0, y0: -y1, y1: field.height as i32 - 1 - y0 };
            if let Some(c) = self.contact.filter(|c| c.search_within) {
                let [cx0, cx1, cy0, cy1] = c.offsets(a.origin(), &scan.centroid, j as f64 * step, cell);
                window = Window {
                    x0: window.x0.max(cx0),
                    x1: window.x1.min(cx1),
                    y0: window.y0.max(cy0),
                    y1: window.y1.min(cy1),
                };
                if window.x0 > window.x1 || window.y0 > window.y1 {
                    return Vec::new();
                }
            }
            let mut best = Best::new(p.search.per_rotation, separation, floor);
            branch_and_bound(&pyramid, points, window, &mut best, roots);
            best.found.iter().map(|&candidate| Global { rotation: j, candidate }).collect()
        };
        // Rotations in rounds of halving stride (every 16th, then the 8th between them, ...): the best score
        // of the rounds so far sets the floor of the next (keep_ratio of it), so later rounds prune harder.
        // The floor of a round depends only on earlier rounds: the answer does not depend on thread timing.
        let mut all: Vec<Global> = Vec::new();
        let mut floor = min_floor;
        for (modulus, rest) in ROUNDS {
            let js: Vec<usize> = (0..n_rot).filter(|&j| j % modulus == rest && searched(j)).collect();
            let found = map_with_scratch(p.parallel, &js, |s, &j| one(s, j, floor));
            all.extend(found.into_iter().flatten());
            let top = all.iter().map(|g| g.candidate.score).max().unwrap_or(i64::MIN);
            floor = floor.max((p.search.keep_ratio * top as f64).ceil() as i64);
        }
        all.retain(|g| g.candidate.score >= floor);
        all.sort_by(|x, y| {
            y.candidate
                .score
                .cmp(&x.candidate.score)
                .then(x.rotation.cmp(&y.rotation))
                .then(x.candidate.oy.cmp(&y.candidate.oy))
                .then(x.candidate.ox.cmp(&y.candidate.ox))
        });
        timings.insert("search".into(), ms(t));
        let as_pose = |g: &Global| ScanPose {
            theta: g.rotation as f64 * step,
            tx: cell * (f64::from(g.candidate.ox) + 0.5),
            ty: cell * (f64::from(g.candidate.oy) + 0.5),
        };
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut kept: Vec<(ScanPose, i64)> = Vec::new();
        for g in &all {
            let q = as_pose(g);
            if kept.iter().all(|(k, _)| apart(&q, k) > p.search.distinct_m) {
                kept.push((q, g.candidate.score));
                if kept.len() >= keep.max(1) {
                    break;
                }
            }
        }
        if kept.is_empty() {
            return Err(fail(
                format!("no pose scores above {:.0}% of a perfect fit", 100.0 * p.search.min_score),
                timings.clone(),
            ));
        }
        // The best answers clearly apart from the winner: the significance test's rivals.
        let winner = kept[0].0;
        let mut rivals: Vec<ScanPose> = Vec::new();
        for q in all.iter().map(as_pose) {
            if rivals.len() >= p.search.rivals {
                break;
            }
            if apart(&q, &winner) > p.answer.rival_distinct_m
                && rivals.iter().all(|k| apart(&q, k) > p.search.distinct_m)
            {
                rivals.push(q);
            }
        }
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        Ok(Found {
            poses: kept.iter().map(|(q, _)| transform(q)).collect(),
            rivals: rivals.iter().map(transform).collect(),
            step,
        })
    }

    /// The global answers at [`crate::SearchParams::resolution`], strongest first, and the angular step
    /// they were found at; screened first at [`crate::SearchParams::screen_resolution`] when that is coarser.
    pub(super) fn search(
        &self,
        a: &OccupancyGrid,
        cells_a: &BlockStates,
        b: &OccupancyGrid,
        pooled: &Pooled,
        peaks: &[f64],
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Found, Box<NoAlignment>> {
        let p = &self.params;
        if p.search.screen_resolution < 1.5 * p.search.resolution {
            return self.global(a, pooled, p.answer.hypotheses, peaks, timings);
        }
        let t = Instant::now();
        let screen = Pooled::build(a, cells_a, b, p.search.screen_resolution, p.search.max_points);
        timings.insert("pool_screen".into(), ms(t));
        let coarse = self.global(a, &screen, p.search.screen_candidates, peaks, timings)?;
        // Each screened answer searched again around itself at the search resolution.
        let t = Instant::now();
        let Pooled { cell, blocks, scan } = pooled;
        let cell = *cell;
        let penalty = (p.search.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let step = (p.search.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
        let cells = (p.search.screen_resolution / cell).ceil() as i32 + 1;
        let field = WindowField::new(&ScoreField::build(blocks, p.search.sigma_cells, penalty), cells as usize);
        let window = LocalWindow { cells, angles: (coarse.step / step).ceil() as usize, angle_step: step };
        let mut buf = LocalScratch::default();
        let mut found: Vec<(usize, ScanPose, i64)> = coarse
            .poses
            .iter()
            .enumerate()
            .map(|(i, t_a_b)| {
                let start = to_scan_pose(a, &scan.centroid, t_a_b);
                let (q, s) = local_search(&field, cell, scan, start, &window, &mut buf);
                (i, q, s)
            })
            .collect();
        found.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut kept: Vec<(ScanPose, i64)> = Vec::new();
        for (_, q, s) in &found {
            if kept.iter().all(|(k, _)| apart(q, k) > p.search.distinct_m) && kept.len() < p.answer.hypotheses.max(1) {
                kept.push((*q, *s));
            }
        }
        let winner = kept[0].0;
        let rivals: Vec<ScanPose> = found
            .iter()
            .map(|f| f.1)
            .filter(|q| apart(q, &winner) > p.answer.rival_distinct_m)
            .take(p.search.rivals)
            .collect();
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        timings.insert("search_local".into(), ms(t));
        Ok(Found {
            poses: kept.iter().map(|(q, _)| transform(q)).collect(),
            rivals: rivals.iter().map(transform).collect(),
            step,
        })
    }
}
