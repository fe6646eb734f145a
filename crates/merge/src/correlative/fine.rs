//! The fine stage: every global answer and rival refined by a window search on a's own cells, the strongest
//! polished by wall ICP and scored again; the significance of the best.

use super::bookkeeping::map_with_scratch;
use super::geometry::{angle_gap, max_displacement, to_scan_pose, to_transform};
use super::global::Found;
use super::params::{CorrelativeMerger, CorrelativeParams};
use super::significance::Significance;
use crate::refine::{RefineParams, refine, wall_points};
use crate::timing::ms;
use mrslam_core::{OccupancyGrid, Pose2};
use mrslam_matching::{
    BlockStates, HIT, LocalScratch, LocalWindow, ScanPose, ScoreField, WallScan, WindowField, WindowKey, local_search,
    window_key,
};
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::time::Instant;

/// What the fine stage scores on, built once per pair: b's wall points at its own resolution (thinned to
/// [`crate::FineParams::max_points`] in the scan) and the score field of a at a's resolution.
pub(super) struct FineField {
    /// Every wall point of b (b's frame), for wall ICP.
    pub(super) points: Vec<Point2<f64>>,
    /// The same thinned, about their centroid.
    pub(super) scan: WallScan,
    /// a's fine score field, laid out for the windows.
    pub(super) field: WindowField,
}

impl FineField {
    /// `cells_a`: a's cells as [`dense_free_cells`] gives them.
    pub(super) fn build(a: &OccupancyGrid, cells_a: &BlockStates, b: &OccupancyGrid, p: &CorrelativeParams) -> Self {
        let points = wall_points(b);
        let scan = WallScan::of_points(&points, p.fine.max_points);
        let penalty = (p.fine.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
        let field = ScoreField::build(cells_a, p.fine.sigma_cells, penalty);
        FineField { points, scan, field: WindowField::new(&field, fine_window_cells(a, p) as usize) }
    }
}

/// The fine stage's work on one pair kept between its calls, for one window extent: each window's answer, and
/// each start's polish by its index among the starts.
#[derive(Debug, Default)]
pub(super) struct FineCache {
    pub(super) window: Option<LocalWindow>,
    pub(super) windows: BTreeMap<WindowKey, (ScanPose, i64)>,
    pub(super) polished: BTreeMap<usize, (Pose2, i64)>,
}

/// Offsets the fine windows search either side of a global answer, cells of a: a search cell and one more.
pub(super) fn fine_window_cells(a: &OccupancyGrid, p: &CorrelativeParams) -> i32 {
    ((p.search.resolution / a.resolution()).round() as i32).max(1) + 1
}

/// The global search's answers refined on the fine field, strongest first, and the significance of the first.
pub(super) struct Candidates {
    /// Polished poses `T_a_b` and their fine scores, strongest first.
    pub(super) refined: Vec<(Pose2, i64)>,
    pub(super) significance: Significance,
    /// The fine scan's points (thinned), b's frame.
    pub(super) scan_points: Vec<Point2<f64>>,
    /// Least shared area a hypothesis needs, m²: more when the fallback search was needed.
    pub(super) min_overlap_m2: f64,
    /// The best polished answer came from the first of the searches pooled.
    pub(super) best_from_first: bool,
}

impl CorrelativeMerger {
    /// The global answers and the significance test's rivals, each refined by a search of a small window on the
    /// fine field (a's resolution); the refined answers strongest first.
    ///
    /// `cache` keeps each window's answer, and each start's polish by its index among the starts: a second call
    /// whose searches begin with the first call's (the fallback pooled with the strict search) reuses them.
    pub(super) fn candidates(
        &self,
        a: &OccupancyGrid,
        fine_field: &FineField,
        searches: &[&Found],
        cache: &mut FineCache,
        timings: &mut BTreeMap<String, f64>,
    ) -> Candidates {
        let p = &self.params;
        let t = Instant::now();
        let FineField { points: fine_points, scan, field: fine } = fine_field;
        let window = LocalWindow {
            cells: fine_window_cells(a, p),
            angles: p.fine.angles,
            angle_step: searches.iter().map(|f| f.step).fold(f64::INFINITY, f64::min) / p.fine.angles.max(1) as f64,
        };
        if cache.window != Some(window) {
            *cache = FineCache { window: Some(window), ..FineCache::default() };
        }
        let one = |buf: &mut LocalScratch, &(key, start): &(WindowKey, ScanPose)| {
            (key, local_search(fine, a.resolution(), scan, start, &window, buf))
        };
        // Every global answer and rival refined: the fine field ranks them (the coarse search only screens).
        // Starts of the same window (the strict and tolerant searches often agree) are searched once.
        let starts: Vec<(WindowKey, ScanPose)> = searches
            .iter()
            .flat_map(|f| f.poses.iter().chain(&f.rivals))
            .map(|t_a_b| to_scan_pose(a, &scan.centroid, t_a_b))
            .map(|start| (window_key(&start, a.resolution()), start))
            .collect();
        let mut todo: Vec<(WindowKey, ScanPose)> = Vec::new();
        for s in &starts {
            if !cache.windows.contains_key(&s.0) && todo.iter().all(|t| t.0 != s.0) {
                todo.push(*s);
            }
        }
        cache.windows.extend(map_with_scratch(p.parallel, &todo, one));
        let mut refined: Vec<(usize, ScanPose, i64)> = starts
            .iter()
            .enumerate()
            .map(|(i, (key, _))| {
                let (q, score) = cache.windows[key];
                (i, q, score)
            })
            .collect();
        refined.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let apart =
            |q: &ScanPose, k: &ScanPose| (q.tx - k.tx).hypot(q.ty - k.ty) + scan.radius * angle_gap(q.theta, k.theta);
        let mut distinct: Vec<(usize, ScanPose, i64)> = Vec::new();
        for r in refined {
            if distinct.iter().all(|k| apart(&r.1, &k.1) > p.search.distinct_m) {
                distinct.push(r);
            }
        }
        // The strongest polished by wall ICP and scored again where they settle: the fine window's steps (a
        // third of the global angular step) leave a few per cent of the score to chance, as much as a rival's
        // lead can be.
        let icp = RefineParams::default();
        let window0 = LocalWindow { cells: 0, angles: 0, angle_step: 0.0 };
        let transform = |q: &ScanPose| to_transform(a, &scan.centroid, q);
        let top: Vec<(usize, ScanPose)> =
            distinct.iter().take(p.fine.polished.max(1)).map(|&(i, q, _)| (i, q)).collect();
        let polish = |buf: &mut LocalScratch, &(i, q): &(usize, ScanPose)| {
            let t = refine(a, fine_points, &transform(&q), &icp);
            let start = to_scan_pose(a, &scan.centroid, &t);
            (i, (t, local_search(fine, a.resolution(), scan, start, &window0, buf).1))
        };
        let todo: Vec<(usize, ScanPose)> =
            top.iter().filter(|(i, _)| !cache.polished.contains_key(i)).copied().collect();
        cache.polished.extend(map_with_scratch(p.parallel, &todo, polish));
        let mut polished: Vec<(usize, Pose2, i64)> = top
            .iter()
            .map(|&(i, _)| {
                let (t, score) = cache.polished[&i];
                (i, t, score)
            })
            .collect();
        polished.sort_by(|x, y| y.2.cmp(&x.2).then(x.0.cmp(&y.0)));
        let from_first = searches.first().map_or(0, |f| f.poses.len() + f.rivals.len());
        let best_from_first = polished[0].0 < from_first;
        // The significance test: the best polished answer against every one clearly apart from it.
        let moved = |t: &Pose2, u: &Pose2| max_displacement(scan, t, u);
        let (best, best_score) = (polished[0].1, polished[0].2);
        let rival = polished[1..].iter().find(|r| moved(&r.1, &best) > p.answer.rival_distinct_m);
        let significance =
            Significance { best, best_score, rival: rival.map(|r| r.1), rival_score: rival.map_or(0, |r| r.2) };
        *timings.entry("fine".into()).or_insert(0.0) += ms(t);
        Candidates {
            refined: polished.iter().map(|(_, t, s)| (*t, *s)).collect(),
            significance,
            scan_points: scan.points.iter().map(|v| scan.centroid + v).collect(),
            min_overlap_m2: p.answer.min_overlap_m2,
            best_from_first,
        }
    }
}
