//! The R-map baseline (paper section 2.1, Algorithm 1; Park's map merging with reduced element maps).
//!
//! ```text
//! RMAP(map1), RMAP(map2)               mers::rmap: MER cover of the free space + connections
//! ANGLE(r, c) for each map             orient: edge points from MER sides, RANSAC wall line, mod 90°
//! rotate each map by its angle         resample::resample (skipped when the angle snaps to 0)
//! loop (ratio ≠ 1, at most max_scale_iterations passes):
//!     RMAP of the rotated maps          (re-used when a map was not rotated or rescaled: same result)
//!     TRIANGLE                          triangle: equation (1) over triples of the K largest MERs
//!     Λ_f from the bisector vectors     the nearest quarter turn (maps are axis-aligned by now)
//!     ratio = w_i(map1) / w_i(map2)     width of the apex MER, map 2's turned by Λ_f
//!     rescale map2 by ratio
//! MAP = overlap the triangles' centres  translation = centroid1 − R(Λ_f) · centroid2
//! ```
//!
//! Where the paper is vague, the most literal reading, fixed here (parameters where two are plausible):
//! - **Binary matrix**: 1 for free cells, 0 for occupied *and* unknown ones (a MER never covers unknown).
//! - **R-map**: a greedy cover of the free space by maximal rectangles, by default the greedy set cover
//!   (each next MER integrates the most uncovered free cells), listed in that order ([`CoverRule`],
//!   [`mers`]); small MERs are kept (every free cell is covered) but only the K first take part in
//!   triangles. Taking MERs by area instead fills the top of the list with runs of near-identical MERs
//!   along any staircase boundary, whose centres are collinear (no triangles).
//! - **Connections**: MERs touching or overlapping a MER and sticking out past one of its sides ([`mers`]).
//! - **Edge points** for ANGLE: free-space boundary points walked from MER sides not covered by connected
//!   MERs; only against walls by default ([`OrientParams::edges_at_unknown`]); RANSAC finds the dominant
//!   wall line and its angle modulo 90° ([`orient`]).
//! - **Equation (1)**: apex `i`, base `j k`; areas over the base length in metres, the base angles in
//!   radians, weighted 1; cost = Euclidean norm of the difference ([`triangle`]). Triples are drawn from
//!   the [`RmapParams::k_largest`] largest MERs of each map, so the search is K³·K³/6 pairs at most.
//! - **Line 13**: the bisector is the apex's angle bisector; the bisector angle difference is rounded to
//!   the nearest quarter turn (the maps are axis-aligned after lines 6-7) and pairs too far from a quarter
//!   turn are inadmissible; so is a pair of opposite handedness. This is how the four 90° rotations are
//!   tried. The quarter turn is applied to map 2's R-map exactly instead of re-rasterising map 1 (line 14):
//!   the MERs of a quarter-turned grid are the quarter-turned MERs.
//! - **Lines 15-16**: ratio = width of the apex MER in map 1 over that of its partner (turned) in map 2;
//!   |ratio − 1| ≤ [`RmapParams::ratio_tolerance`] counts as 1. Otherwise map 2 is rescaled about its
//!   frame origin and the loop repeats, at most [`RmapParams::max_scale_iterations`] passes; a ratio outside
//!   [1/max_ratio, max_ratio] or no convergence is a failure. Both maps are first brought to the coarser
//!   of their resolutions, so with equal metric scale the loop ends after one pass.
//! - **Line 18**: the triangles' centres are the centroids of their three MER centres; overlapping them
//!   gives the translation. No refinement beyond the paper.
//!
//! What the merge pipeline sees ([`Alignment`]): `matches` = tentative MER correspondences, the pairs
//! among the [`RmapParams::consistency_mers`] largest MERs of each map whose width and height agree within
//! [`RmapParams::consistency_tol_cells`] once map 2's are turned; `inliers` = the MERs of map 1 with such a
//! partner whose centre the transform also brings within that tolerance. (The number of triangle pairs
//! scored, millions, would make m-explore's confidence `inliers / (8 + 0.3 · matches)` meaningless; it is in
//! [`RmapResult::triangle_pairs`].) Evidence: the centres of those MERs in each map's frame, and the three
//! vertex pairs of the common triangles as inlier pairs.

pub mod mers;
pub mod orient;
pub mod triangle;

pub use mers::{CoverRule, FreeMatrix, Mer, Rmap};
pub use orient::OrientParams;
pub use triangle::{TriangleMatch, TriangleParams};

use crate::alignment::{Alignment, Evidence, NoAlignment};
use crate::merger::Merger;
use crate::resample::{resample, to_resolution};
use crate::timing::ms;
use mrslam_core::{OccupancyGrid, pose};
use nalgebra::{Point2, Rotation2};
use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;
use std::time::Instant;
use triangle::Vertex;

/// Parameters of the R-map merger.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RmapParams {
    /// Which maximal rectangles make the R-map, and their order.
    pub cover: CoverRule,
    /// Orientation alignment (ANGLE).
    pub orient: OrientParams,
    /// Common-triangle search (TRIANGLE, equation 1).
    pub triangle: TriangleParams,
    /// Triangles are formed from this many of each map's largest MERs.
    pub k_largest: usize,
    /// MERs of each map compared for `matches` / `inliers`.
    pub consistency_mers: usize,
    /// Size and position tolerance of a consistent MER pair, cells.
    pub consistency_tol_cells: f64,
    /// Passes of the scale-ratio loop (lines 9-17) before giving up.
    pub max_scale_iterations: usize,
    /// |ratio − 1| below this ends the loop.
    pub ratio_tolerance: f64,
    /// A ratio beyond [1/max_ratio, max_ratio] is taken as a failed match, not rescaled.
    pub max_ratio: f64,
    /// Build the two maps' R-maps on two threads.
    pub parallel: bool,
}

impl Default for RmapParams {
    fn default() -> Self {
        RmapParams {
            cover: CoverRule::GreedyGain,
            orient: OrientParams::default(),
            triangle: TriangleParams::default(),
            k_largest: 16,
            consistency_mers: 40,
            consistency_tol_cells: 2.0,
            max_scale_iterations: 4,
            ratio_tolerance: 0.05,
            max_ratio: 2.0,
            parallel: false,
        }
    }
}

/// Park's R-map merger (the paper's baseline).
#[derive(Debug, Clone, Default)]
pub struct RmapMerger {
    /// Its parameters.
    pub params: RmapParams,
}

/// Everything the R-map merger found, beyond the [`Alignment`].
#[derive(Debug, Clone)]
pub struct RmapResult {
    /// What the pipeline gets.
    pub alignment: Alignment,
    /// Orientation of each map's walls found by ANGLE, radians in [-π/4, π/4).
    pub angles: (f64, f64),
    /// The common triangles (indices into the largest-first MERs of the rotated maps).
    pub triangles: TriangleMatch,
    /// Passes of the scale-ratio loop.
    pub scale_iterations: usize,
    /// Triangle pairs scored with equation (1), over all passes.
    pub triangle_pairs: usize,
    /// MER count of each map's R-map (before rotation).
    pub mer_counts: (usize, usize),
}

/// A map brought into its axis-aligned frame, with its R-map.
struct Oriented {
    grid: OccupancyGrid,
    rmap: Rmap,
}

fn rmap_of(g: &OccupancyGrid, rule: CoverRule) -> (FreeMatrix, Rmap) {
    let m = FreeMatrix::from_grid(g);
    let r = mers::rmap(&m, rule);
    (m, r)
}

/// MER centres (metres, in the grid's map frame) and areas (m²).
fn vertices(g: &OccupancyGrid, r: &Rmap, n: usize) -> Vec<Vertex> {
    let a = g.resolution() * g.resolution();
    r.mers
        .iter()
        .take(n)
        .map(|m| {
            let (cx, cy) = m.center();
            let p = g.cell_f_to_world(cx, cy);
            Vertex { x: p.x, y: p.y, area: m.area() as f64 * a }
        })
        .collect()
}

/// Width and height of a MER after `q` quarter turns.
fn turned(m: &Mer, q: u8) -> (usize, usize) {
    if q % 2 == 1 { (m.h, m.w) } else { (m.w, m.h) }
}

/// Map 2 rescaled by `ratio` about its frame origin, back at `res`.
fn rescale(g: &OccupancyGrid, ratio: f64, res: f64) -> Option<OccupancyGrid> {
    let o = g.origin();
    let scaled = OccupancyGrid::from_cells(
        g.width(),
        g.height(),
        g.resolution() * ratio,
        pose(o.translation.x * ratio, o.translation.y * ratio, o.rotation.angle()),
        g.cells().to_vec(),
    )
    .ok()?;
    Some(to_resolution(&scaled, res))
}

impl RmapMerger {
    /// A merger with these parameters.
    pub fn new(params: RmapParams) -> Self {
        RmapMerger { params }
    }

    /// Algorithm 1 with all its intermediate results.
    pub fn align_detailed(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<RmapResult, Box<NoAlignment>> {
        let p = &self.params;
        let mut timings = BTreeMap::new();
        let fail = |reason: String, matches: usize, timings: &BTreeMap<String, f64>| {
            Box::new(NoAlignment { reason, matches, timings_ms: timings.clone(), evidence: Evidence::default() })
        };
        let t = Instant::now();
        let res = a.resolution().max(b.resolution());
        let (ga, gb) = (to_resolution(a, res), to_resolution(b, res));
        timings.insert("resample".to_string(), ms(t));
        // Lines 2-3.
        let t = Instant::now();
        let ((ma, ra), (mb, rb)) = if p.parallel {
            rayon::join(|| rmap_of(&ga, p.cover), || rmap_of(&gb, p.cover))
        } else {
            (rmap_of(&ga, p.cover), rmap_of(&gb, p.cover))
        };
        timings.insert("rmap".to_string(), ms(t));
        for (name, m, r) in [("a", &ma, &ra), ("b", &mb, &rb)] {
            if m.free_count() == 0 {
                return Err(fail(format!("map {name} has no free space"), 0, &timings));
            }
            if r.mers.len() < 3 {
                return Err(fail(
                    format!("map {name}'s R-map has only {} MER(s): a triangle needs 3", r.mers.len()),
                    0,
                    &timings,
                ));
            }
        }
        let mer_counts = (ra.mers.len(), rb.mers.len());
        // Lines 4-7.
        let t = Instant::now();
        let angle = |m: &FreeMatrix, r: &Rmap| {
            let pts = orient::edge_points(m, r, p.orient.edges_at_unknown);
            orient::dominant_angle(&pts, &p.orient).map_or(0.0, |(ang, _)| ang)
        };
        let (th_a, th_b) = (angle(&ma, &ra), angle(&mb, &rb));
        timings.insert("angle".to_string(), ms(t));
        let t = Instant::now();
        let orient = |g: OccupancyGrid, r: Rmap, th: f64| {
            if th == 0.0 {
                Oriented { grid: g, rmap: r }
            } else {
                let grid = resample(&g, &pose(0.0, 0.0, -th), res);
                let rmap = rmap_of(&grid, p.cover).1;
                Oriented { grid, rmap }
            }
        };
        let oa = orient(ga, ra, th_a);
        let mut ob = orient(gb, rb, th_b);
        timings.insert("rotate".to_string(), ms(t));
        // Lines 8-17.
        let k = p.k_largest.max(3);
        let t = Instant::now();
        let va = vertices(&oa.grid, &oa.rmap, k);
        let ta = triangle::ordered_triangles(&va, k, &p.triangle);
        let mut scale = 1.0;
        let mut triangle_pairs = 0;
        let mut iterations = 0;
        let found = loop {
            iterations += 1;
            if ob.rmap.mers.len() < 3 {
                return Err(fail("map b's rescaled R-map has fewer than 3 MERs".into(), triangle_pairs, &timings));
            }
            let vb = vertices(&ob.grid, &ob.rmap, k);
            let tb = triangle::unordered_triangles(&vb, k, &p.triangle);
            let (m, scored) = triangle::best_pair(&ta, &tb, &p.triangle);
            triangle_pairs += scored;
            let Some(m) = m else {
                timings.insert("triangles".to_string(), ms(t));
                return Err(fail(
                    format!("no admissible pair of triangles among {} x {} candidates", ta.len(), tb.len()),
                    triangle_pairs,
                    &timings,
                ));
            };
            let wa = oa.rmap.mers[m.a.v[0]].w as f64;
            let wb = turned(&ob.rmap.mers[m.b.v[0]], m.quarter_turns).0 as f64;
            let ratio = wa / wb;
            if (ratio - 1.0).abs() <= p.ratio_tolerance {
                break m;
            }
            let reason = if !(1.0 / p.max_ratio..=p.max_ratio).contains(&ratio) {
                Some(format!("common triangles imply a scale ratio of {ratio:.3}, beyond the allowed {}", p.max_ratio))
            } else if iterations >= p.max_scale_iterations {
                Some(format!("scale ratio still {ratio:.3} after {iterations} passes"))
            } else {
                None
            };
            if let Some(reason) = reason {
                timings.insert("triangles".to_string(), ms(t));
                return Err(fail(reason, triangle_pairs, &timings));
            }
            let Some(grid) = rescale(&ob.grid, ratio, res) else {
                return Err(fail(format!("map b cannot be rescaled by {ratio:.3}"), triangle_pairs, &timings));
            };
            scale *= ratio;
            let rmap = rmap_of(&grid, p.cover).1;
            ob = Oriented { grid, rmap };
        };
        timings.insert("triangles".to_string(), ms(t));
        // Line 18: overlap the triangles' centres.
        let t = Instant::now();
        let vb = vertices(&ob.grid, &ob.rmap, k);
        let centroid = |vs: &[Vertex], tri: &[usize; 3]| {
            let (x, y) = tri.iter().fold((0.0, 0.0), |s, &i| (s.0 + vs[i].x, s.1 + vs[i].y));
            Point2::new(x / 3.0, y / 3.0)
        };
        let q = found.quarter_turns;
        let rq = Rotation2::new(q as f64 * FRAC_PI_2);
        let (ca, cb) = (centroid(&va, &found.a.v), centroid(&vb, &found.b.v));
        let tr = ca - rq * cb;
        // p_ra = R_q p_rb' + tr, p_rb' = s · p_rb, p_ra = R(-θa) p_a, p_rb = R(-θb) p_b.
        let rot_a = Rotation2::new(th_a);
        let t_ab = pose((rot_a * tr).x, (rot_a * tr).y, th_a + q as f64 * FRAC_PI_2 - th_b);
        // Consistency of the MERs with the transform.
        let m_n = p.consistency_mers.max(k);
        let tol = p.consistency_tol_cells;
        let (va_all, vb_all) = (vertices(&oa.grid, &oa.rmap, m_n), vertices(&ob.grid, &ob.rmap, m_n));
        let mut matches = 0;
        let mut inliers = 0;
        for (ia, mer_a) in oa.rmap.mers.iter().take(m_n).enumerate() {
            let mut consistent = false;
            for (ib, mer_b) in ob.rmap.mers.iter().take(m_n).enumerate() {
                let (wb, hb) = turned(mer_b, q);
                if (mer_a.w as f64 - wb as f64).abs() > tol || (mer_a.h as f64 - hb as f64).abs() > tol {
                    continue;
                }
                matches += 1;
                let pb = rq * Point2::new(vb_all[ib].x, vb_all[ib].y) + tr;
                let d = (pb - Point2::new(va_all[ia].x, va_all[ia].y)).norm() / res;
                consistent |= d <= tol;
            }
            inliers += consistent as usize;
        }
        // Evidence in each map's own frame.
        let back_a = Rotation2::new(th_a);
        let back_b = Rotation2::new(th_b);
        let evidence = Evidence {
            points_a: va_all.iter().map(|v| back_a * Point2::new(v.x, v.y)).collect(),
            points_b: vb_all.iter().map(|v| back_b * Point2::new(v.x / scale, v.y / scale)).collect(),
            inlier_pairs: (0..3).map(|i| (found.a.v[i], found.b.v[i])).collect(),
        };
        timings.insert("transform".to_string(), ms(t));
        Ok(RmapResult {
            alignment: Alignment {
                transform: t_ab,
                scale,
                matches,
                matched_features: matches,
                inliers,
                timings_ms: timings,
                evidence,
                alternatives: Vec::new(),
                alternatives_are_rivals: false,
            },
            angles: (th_a, th_b),
            triangles: found,
            scale_iterations: iterations,
            triangle_pairs,
            mer_counts,
        })
    }
}

impl Merger for RmapMerger {
    fn name(&self) -> &'static str {
        crate::Algorithm::Rmap.name()
    }

    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        self.align_detailed(a, b).map(|r| r.alignment)
    }
}
