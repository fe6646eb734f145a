//! A pair settled: the strict search, the tolerant fallback pooled with it, and the shared-area check; the
//! probes' views of them.

use super::fine::{Candidates, FineCache, FineField};
use super::geometry::{to_scan_pose, to_transform};
use super::global::{Pooled, dense_free_cells};
use super::orientation;
use super::params::{CorrelativeMerger, CorrelativeParams, SearchParams};
use super::significance::Significance;
use crate::alignment::NoAlignment;
use crate::timing::ms;
use crate::verify::agreement;
use mrslam_core::{OccupancyGrid, Pose2};
use mrslam_matching::{HIT, LocalScratch, LocalWindow, ScoreField, WallScan, WindowField, local_search, window_key};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::time::Instant;

/// The significance of the correlative merger's answer for a pair (its best answer against its best clearly
/// different one, both on the fine field). Public (through the crate's `dev` module) only for the development
/// probes.
pub fn significance(merger: &CorrelativeMerger, a: &OccupancyGrid, b: &OccupancyGrid) -> Option<Significance> {
    merger.settled(a, b, &mut BTreeMap::new()).ok().map(|c| c.significance)
}

/// The global score of `t_a_b` (the best within two search cells and two angular steps of it), and how many
/// of b's search points land on a wall's blur, on penalised free space and elsewhere there.
/// Public (through the crate's `dev` module) only for the development probes.
pub fn score_near(
    merger: &CorrelativeMerger,
    a: &OccupancyGrid,
    b: &OccupancyGrid,
    t_a_b: &Pose2,
) -> (i64, [usize; 3], Pose2) {
    let p = &merger.params;
    let fa = ((p.search.resolution / a.resolution()).round() as usize).max(1);
    let fb = ((p.search.resolution / b.resolution()).round() as usize).max(1);
    let cell = fa as f64 * a.resolution();
    let scan = WallScan::of_blocks(b, fb, p.search.max_points);
    let penalty = (p.search.free_penalty.max(0.0) * f64::from(HIT)).round() as i16;
    let field = ScoreField::build(&dense_free_cells(a, p).pooled(fa), p.search.sigma_cells, penalty);
    let grid = WindowField::new(&field, 2);
    let step = (p.search.angle_step_scale * cell / scan.radius.max(cell)).min(PI / 2.0);
    let window = LocalWindow { cells: 2, angles: 2, angle_step: step };
    let start = to_scan_pose(a, &scan.centroid, t_a_b);
    let mut pts = Vec::new();
    let (q, s) = local_search(&grid, cell, &scan, start, &window, &mut LocalScratch::default());
    scan.discretize(q.theta, cell, &mut pts);
    let (_, cx, cy) = window_key(&q, cell);
    let mut counts = [0usize; 3];
    for &(x, y) in &pts {
        let v = grid.get(x + cx, y + cy);
        counts[if v > 0 {
            0
        } else if v < 0 {
            1
        } else {
            2
        }] += 1;
    }
    (s, counts, to_transform(a, &scan.centroid, &q))
}

impl CorrelativeMerger {
    /// The candidates of the search with [`crate::SearchParams::free_penalty`]; when they do not settle the pair
    /// (the best is not significant, or no hypothesis shares enough known space at the acceptance asked for),
    /// pooled with those of a second search with [`crate::FallbackParams::free_penalty`].
    pub(super) fn settled(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        timings: &mut BTreeMap<String, f64>,
    ) -> Result<Candidates, Box<NoAlignment>> {
        let p = &self.params;
        let t = Instant::now();
        let cells_a = dense_free_cells(a, p);
        let pooled = Pooled::build(a, &cells_a, b, p.search.resolution, p.search.max_points);
        timings.insert("pool".into(), ms(t));
        let t = Instant::now();
        let peaks = if p.search.rotation_prior {
            orientation::rotation_peaks(a, b, p.search.rotation_peak_ratio)
        } else {
            Vec::new()
        };
        timings.insert("orientation".into(), ms(t));
        let strict = self.search(a, &cells_a, b, &pooled, &peaks, timings)?;
        let t = Instant::now();
        let fine = FineField::build(a, &cells_a, b, p);
        timings.insert("fine_field".into(), ms(t));
        let mut cache = FineCache::default();
        let first = self.candidates(a, &fine, &[&strict], &mut cache, timings);
        let settles = |c: &Candidates| {
            c.significance.refusal(p.answer.min_margin).is_none()
                && !self.shared(a, b, &c.refined, c.min_overlap_m2).0.is_empty()
        };
        let first_settles = settles(&first);
        if p.fallback.free_penalty <= 0.0
            || p.fallback.free_penalty == p.search.free_penalty
            || (first_settles && !p.fallback.always)
        {
            return Ok(first);
        }
        let tolerant = CorrelativeMerger {
            params: CorrelativeParams {
                search: SearchParams { free_penalty: p.fallback.free_penalty, rivals: p.fallback.rivals, ..p.search },
                ..*p
            },
            contact: self.contact,
        };
        let mut more = BTreeMap::new();
        let Ok(second) = tolerant.search(a, &cells_a, b, &pooled, &peaks, &mut more) else {
            return Ok(first);
        };
        for (k, v) in more {
            timings.insert(format!("fallback_{k}"), v);
        }
        let mut pooled = self.candidates(a, &fine, &[&strict, &second], &mut cache, timings);
        // A pose only the tolerant search found needs the larger shared area; the first search's settled answer,
        // now tested against the tolerant search's rivals too, keeps its own.
        if !first_settles || !pooled.best_from_first {
            pooled.min_overlap_m2 = p.answer.min_overlap_m2.max(p.fallback.min_overlap_m2);
        }
        Ok(pooled)
    }

    /// The first [`crate::AnswerParams::hypotheses`] of `refined` that share `min_m2` of known space at an
    /// acceptance index of [`crate::AnswerParams::min_acceptance`] (none unless the first does, with the
    /// significance test on), and what each tried had.
    ///
    /// A pose found by trying every pose needs a shared area of some size to count: a small patch where the walls
    /// coincide by chance (a building corner on another) is expected somewhere. Checked after wall ICP: a pose a
    /// cell off lays thin walls on free space, which the acceptance index would count against it.
    pub(super) fn shared(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        refined: &[(Pose2, i64)],
        min_m2: f64,
    ) -> (Vec<Pose2>, Vec<String>) {
        let p = &self.params;
        let cell_m2 = a.resolution() * a.resolution();
        let mut tried = Vec::new();
        let mut poses = Vec::new();
        for (t, _) in refined.iter().take(p.answer.hypotheses.max(1)) {
            let agr = agreement(a, b, t);
            let (m2, acc) = (agr.common() as f64 * cell_m2, agr.acceptance_index());
            tried.push(format!("{m2:.1} m² at {acc:.3}"));
            if m2 >= min_m2 && acc >= p.answer.min_acceptance {
                poses.push(*t);
            }
        }
        // With the significance test on, only the best may be accepted: a weaker answer led nothing.
        if p.answer.min_margin > 0.0 && poses.first() != refined.first().map(|r| &r.0) {
            poses.clear();
        }
        (poses, tried)
    }
}
