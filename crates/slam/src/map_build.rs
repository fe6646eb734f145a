//! The output map: the best particle's scans traced along its trajectory into a core [`OccupancyGrid`].
//!
//! Per cell GMapping's `PointAccumulator` counts: `visits` (beams that crossed or ended in the cell) and
//! `hits` (beams that ended in it). As GMapping's ROS node publishes it, a visited cell is occupied when
//! hits/visits > `occ_thresh` and free otherwise; unvisited cells are unknown. The grid holds log-odds
//! ±[`ROS_LOGODDS_LIMIT`] (p ≈ 0.88 / 0.12, beyond core's 0.65 / 0.35 thresholds) and 0 for unknown, so
//! it reads back from map_server files unchanged.
//!
//! With `wall_hits` > 0 (not GMapping) a beam's free-space trace stops at the first cell on its way that at
//! least `wall_hits` beams of the trajectory ended in: beams that passed through glass, or past a wall's
//! edge at a grazing angle, then no longer carve free space behind the wall.

use crate::particle::TrajectoryNode;
use mrslam_core::MAX_CELLS;
use mrslam_core::Xyt;
use mrslam_core::map_io::ROS_LOGODDS_LIMIT;
use mrslam_core::{CellTraversal, LaserScan, OccupancyGrid, pose};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The grid and the ranges of the beams it is built from (the particles' maps and the output map).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MapParams {
    /// `delta`: grid resolution, metres per cell (GMapping 0.05).
    pub delta: f64,
    /// `maxRange`: beams at or beyond this range (metres) are max-range readings: never hits; they clear
    /// free space up to `max_urange` when `clear_max_range` is set (GMapping 80).
    pub max_range: f64,
    /// `maxUrange`: usable range, metres: longer beams are not matched and are clipped here when mapping
    /// free space (GMapping 80).
    pub max_urange: f64,
    /// Whether no-return beams (at or beyond the sensor's / `max_range`) clear free space up to `max_urange`
    /// in the output map. Off by default, as GMapping ignores readings beyond maxRange: on real logs
    /// no-return beams (glass, black surfaces, open doors) would spray free space outside the building.
    /// Beams between `max_urange` and `max_range` always clear up to `max_urange`.
    pub clear_max_range: bool,
    /// `occ_thresh`: a cell of the output map is occupied when hits/visits exceeds this (GMapping 0.25).
    pub occ_thresh: f64,
    /// Not GMapping: `wall_hits`: in the output map a beam's free-space trace stops at the first cell on its
    /// way that at least this many beams ended in (see `map_build`); 0: traces run to the end
    /// point, as GMapping's.
    pub wall_hits: u32,
}

impl Default for MapParams {
    fn default() -> Self {
        MapParams {
            delta: 0.05,
            max_range: 80.0,
            max_urange: 80.0,
            clear_max_range: false,
            occ_thresh: 0.25,
            wall_hits: 0,
        }
    }
}

/// Where a beam ends for mapping, and whether that end is a hit.
fn beam_end(scan: &LaserScan, i: usize, params: &MapParams) -> Option<(f64, bool)> {
    let r = scan.ranges[i] as f64;
    let max_range = params.max_range.min(scan.range_max as f64);
    if scan.is_valid(i) && r < max_range {
        Some((r.min(params.max_urange), r < params.max_urange))
    } else if params.clear_max_range && (scan.is_max_range(i) || (scan.is_valid(i) && r >= max_range)) {
        Some((params.max_urange.min(max_range), false))
    } else {
        None
    }
}

/// Sensor pose (x, y, θ) for a robot pose.
fn sensor(p: &Xyt, laser: &Xyt) -> Xyt {
    let (s, c) = p.theta.sin_cos();
    Xyt { x: p.x + c * laser.x - s * laser.y, y: p.y + s * laser.x + c * laser.y, theta: p.theta + laser.theta }
}

/// The cells a map of some nodes spans, and the counts its cells hold.
///
/// `hits`: with `wall_hits`, the beams that ended in each cell (pass 2, before any trace); else the traced beams
/// that ended there. `visits`: the traced beams that crossed or ended in each cell.
#[derive(Debug, Clone)]
pub(crate) struct Counts {
    pub x0: i64,
    pub y0: i64,
    pub w: usize,
    pub h: usize,
    pub hits: Vec<u32>,
    pub visits: Vec<u32>,
}

/// The cell bounds (x0, y0, x1, y1) of the sensor poses and beam ends of `nodes`; `None` for nothing to map.
pub(crate) fn cell_bounds(nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) -> Option<(i64, i64, i64, i64)> {
    let inv = 1.0 / params.delta;
    let (mut x0, mut y0, mut x1, mut y1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    let mut grow = |x: f64, y: f64| {
        let (cx, cy) = ((x * inv).floor() as i64, (y * inv).floor() as i64);
        x0 = x0.min(cx);
        y0 = y0.min(cy);
        x1 = x1.max(cx);
        y1 = y1.max(cy);
    };
    for n in nodes {
        let lp = sensor(&n.pose, laser);
        grow(lp.x, lp.y);
        for i in 0..n.scan.len() {
            if let Some((r, _)) = beam_end(&n.scan, i, params) {
                let a = lp.theta + n.scan.angle(i);
                grow(lp.x + r * a.cos(), lp.y + r * a.sin());
            }
        }
    }
    (x0 <= x1).then_some((x0, y0, x1, y1))
}

/// A node's sensor in the grid's cell coordinates (x, y) and its heading.
pub(crate) fn sensor_in_cells(n: &TrajectoryNode, laser: &Xyt, params: &MapParams, c: &Counts) -> (f64, f64, f64) {
    let inv = 1.0 / params.delta;
    let lp = sensor(&n.pose, laser);
    (lp.x * inv - c.x0 as f64, lp.y * inv - c.y0 as f64, lp.theta)
}

/// Beam `i` of `n` as the cells it crosses from the sensor (`at`: [`sensor_in_cells`]), and whether it ends in a
/// hit; `None` for a beam that maps nothing.
pub(crate) fn beam_cells(
    n: &TrajectoryNode,
    i: usize,
    at: (f64, f64, f64),
    params: &MapParams,
) -> Option<(CellTraversal, bool)> {
    let inv = 1.0 / params.delta;
    let (sx, sy, theta) = at;
    let (r, hit) = beam_end(&n.scan, i, params)?;
    let a = theta + n.scan.angle(i);
    let (ex, ey) = (sx + r * a.cos() * inv, sy + r * a.sin() * inv);
    Some((CellTraversal::new(sx, sy, ex, ey), hit))
}

impl Counts {
    /// Zero counts over the cells `x0..=x1`, `y0..=y1`; `None` beyond core's cell limit.
    pub(crate) fn zeros((x0, y0, x1, y1): (i64, i64, i64, i64)) -> Option<Counts> {
        let (w, h) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
        if w.checked_mul(h).is_none_or(|c| c > MAX_CELLS) {
            return None;
        }
        Some(Counts { x0, y0, w, h, hits: vec![0; w * h], visits: vec![0; w * h] })
    }

    /// The index of cell (cx, cy), when it is in the grid.
    #[inline]
    pub(crate) fn index(&self, cx: i64, cy: i64) -> Option<usize> {
        (cx >= 0 && cy >= 0 && (cx as usize) < self.w && (cy as usize) < self.h)
            .then(|| cy as usize * self.w + cx as usize)
    }

    /// Pass 2 (with `wall_hits`): the hits of `nodes` added, so that the traces know the walls before they run.
    pub(crate) fn add_hits(&mut self, nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) {
        let inv = 1.0 / params.delta;
        for n in nodes {
            let (sx, sy, theta) = sensor_in_cells(n, laser, params, self);
            for i in 0..n.scan.len() {
                let Some((r, true)) = beam_end(&n.scan, i, params) else {
                    continue;
                };
                let a = theta + n.scan.angle(i);
                let (cx, cy) = ((sx + r * a.cos() * inv).floor() as i64, (sy + r * a.sin() * inv).floor() as i64);
                if let Some(k) = self.index(cx, cy) {
                    self.hits[k] = self.hits[k].saturating_add(1);
                }
            }
        }
    }

    /// Pass 3: the beams of `nodes` traced, in parallel runs of nodes, each counting into its own arrays (the
    /// counts are sums, so they do not depend on the split). With `wall_hits` the traces read the hits and add
    /// none.
    pub(crate) fn add_traces(&mut self, nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) {
        let wall = params.wall_hits;
        let (len, this) = (self.w * self.h, &*self);
        let trace = |run: &[&TrajectoryNode]| -> (Vec<u32>, Vec<u32>) {
            let mut visits = vec![0u32; len];
            let mut ends = if wall == 0 { vec![0u32; len] } else { Vec::new() };
            for n in run {
                let at = sensor_in_cells(n, laser, params, this);
                for i in 0..n.scan.len() {
                    let Some((trav, hit)) = beam_cells(n, i, at, params) else {
                        continue;
                    };
                    let end = trav.end_cell();
                    for (cx, cy) in trav {
                        let Some(k) = this.index(cx, cy) else {
                            continue;
                        };
                        visits[k] = visits[k].saturating_add(1);
                        if (cx, cy) == end {
                            if hit && wall == 0 {
                                ends[k] = ends[k].saturating_add(1);
                            }
                        } else if wall > 0 && this.hits[k] >= wall {
                            // a wall (or glass) that other beams ended on: this beam went through it, so the
                            // space beyond is not known to be free from here
                            break;
                        }
                    }
                }
            }
            (visits, ends)
        };
        let run = nodes.len().div_ceil(rayon::current_num_threads().max(1)).max(1);
        let Some((visits, ends)) = nodes.par_chunks(run).map(trace).reduce_with(|(mut v, mut e), (v2, e2)| {
            add(&mut v, &v2);
            add(&mut e, &e2);
            (v, e)
        }) else {
            return;
        };
        add(&mut self.visits, &visits);
        add(&mut self.hits, &ends);
    }

    /// The grid: a visited cell is occupied when hits/visits exceeds `occ_thresh`, free otherwise.
    pub(crate) fn grid(&self, params: &MapParams) -> Option<OccupancyGrid> {
        let cells: Vec<f32> = self
            .hits
            .iter()
            .zip(&self.visits)
            .map(|(&hi, &v)| {
                if v == 0 {
                    0.0
                } else if hi as f64 > params.occ_thresh * v as f64 {
                    ROS_LOGODDS_LIMIT
                } else {
                    -ROS_LOGODDS_LIMIT
                }
            })
            .collect();
        let origin = pose(self.x0 as f64 * params.delta, self.y0 as f64 * params.delta, 0.0);
        OccupancyGrid::from_cells(self.w, self.h, params.delta, origin, cells).ok()
    }

    /// The counts of `nodes` from nothing; `Ok(None)`: nothing to map; `Err(())`: beyond core's cell limit.
    pub(crate) fn of(nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) -> Result<Option<Counts>, ()> {
        let Some(bounds) = cell_bounds(nodes, laser, params) else {
            return Ok(None);
        };
        let mut c = Counts::zeros(bounds).ok_or(())?;
        if params.wall_hits > 0 {
            c.add_hits(nodes, laser, params);
        }
        c.add_traces(nodes, laser, params);
        Ok(Some(c))
    }
}

/// `into += from`, cell by cell.
fn add(into: &mut [u32], from: &[u32]) {
    into.iter_mut().zip(from).for_each(|(a, b)| *a = a.saturating_add(*b));
}

/// A 1×1 unknown grid: the map of nothing.
pub(crate) fn empty_map(params: &MapParams) -> Option<OccupancyGrid> {
    OccupancyGrid::new(1, 1, params.delta, pose(0.0, 0.0, 0.0)).ok()
}

/// Builds the map of a trajectory from scratch (nodes in any order; order does not change the counts): the
/// reference [`IncrementalMap`](crate::incremental_map::IncrementalMap) is tested against.
///
/// Returns a 1×1 unknown grid when there is nothing to map, and `None` when the map would exceed
/// core's cell limit.
#[cfg(test)]
pub(crate) fn build_map(nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) -> Option<OccupancyGrid> {
    match Counts::of(nodes, laser, params) {
        Ok(Some(c)) => c.grid(params),
        Ok(None) => empty_map(params),
        Err(()) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn with_wall_hits_a_beam_through_a_wall_does_not_clear_the_space_behind_it() {
        // Ten scans from the origin see a wall 2 m ahead (beams at -10°..10°, every 1°); in the last one the
        // straight-ahead beam passes through it (glass) and returns from 6 m.
        let scan = |through: bool| LaserScan {
            stamp: 0.0,
            angle_min: -10f64.to_radians(),
            angle_increment: 1f64.to_radians(),
            range_min: 0.1,
            range_max: 20.0,
            ranges: (0..21)
                .map(|i| {
                    let a = (-10.0 + i as f64).to_radians();
                    if through && i == 10 { 6.0 } else { (2.0 / a.cos()) as f32 }
                })
                .collect(),
        };
        let nodes: Vec<TrajectoryNode> = (0..10)
            .map(|k| TrajectoryNode {
                stamp: k as f64,
                pose: Xyt { x: 0.0, y: 0.0, theta: 0.0 },
                scan: Arc::new(scan(k == 9)),
                parent: None,
            })
            .collect();
        let refs: Vec<&TrajectoryNode> = nodes.iter().collect();
        let laser = Xyt { x: 0.0, y: 0.0, theta: 0.0 };
        let state_at = |params: &MapParams, x: f64| {
            let map = build_map(&refs, &laser, params).unwrap();
            let p = nalgebra::Point2::new(x, 0.0);
            let (cx, cy) = map.world_to_cell(&p).unwrap();
            map.state(cx, cy)
        };
        let gmapping = MapParams::default();
        let walls = MapParams { wall_hits: 2, ..MapParams::default() };
        for params in [&gmapping, &walls] {
            assert_eq!(state_at(params, 2.0 + 0.02), mrslam_core::CellState::Occupied, "the wall stays a wall");
            assert_eq!(state_at(params, 1.0), mrslam_core::CellState::Free);
        }
        assert_eq!(state_at(&gmapping, 4.0), mrslam_core::CellState::Free, "GMapping: cleared behind the wall");
        assert_eq!(state_at(&walls, 4.0), mrslam_core::CellState::Unknown, "wall_hits: not seen behind the wall");
    }
}
