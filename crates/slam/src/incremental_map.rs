//! The output map kept between calls: when a trajectory only grew since the last map, only its new scans are
//! traced, and the map is the one [`build_map`](crate::map_build::build_map) draws from scratch, cell for cell.
//!
//! The counts are sums over the scans, so the new scans' counts add. With `wall_hits`, a beam's trace stops at
//! the first wall on its way, and the new scans' hits can make walls of cells that old beams crossed: those
//! beams (found by the new wall cells' bearings from each old sensor pose) are traced again, and what they
//! counted past the new wall is taken back. Anything else (a scan moved by loop closure or resampling, the map's
//! bounds grown, many new walls at once) rebuilds from scratch.

use crate::map_build::{Counts, MapParams, beam_cells, cell_bounds, empty_map, sensor_in_cells};
use crate::particle::TrajectoryNode;
use mrslam_core::{LaserScan, OccupancyGrid, Xyt};
use std::f64::consts::TAU;
use std::sync::{Arc, Mutex};

/// What the last map was drawn from, and its counts.
#[derive(Debug, Clone, Default)]
struct Drawn {
    /// The scans and the poses they were drawn at, oldest first.
    nodes: Vec<(Arc<LaserScan>, Xyt)>,
    laser: Option<Xyt>,
    params: Option<MapParams>,
    counts: Option<Counts>,
    /// Calls answered by extending the counts, by rebuilding them, and beams cut at new walls (for the tests).
    extended: usize,
    rebuilt: usize,
    cut: usize,
}

/// An output map that grows with its trajectory (see the module's documentation).
#[derive(Debug, Default)]
pub struct IncrementalMap {
    drawn: Mutex<Drawn>,
}

impl Clone for IncrementalMap {
    fn clone(&self) -> Self {
        IncrementalMap { drawn: Mutex::new(self.lock().clone()) }
    }
}

impl IncrementalMap {
    fn lock(&self) -> std::sync::MutexGuard<'_, Drawn> {
        self.drawn.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The map of `nodes` (oldest first), as [`build_map`](crate::map_build::build_map) draws it; `None` beyond
    /// core's cell limit.
    pub fn map(&self, nodes: &[&TrajectoryNode], laser: &Xyt, params: &MapParams) -> Option<OccupancyGrid> {
        let mut drawn = self.lock();
        let old = drawn.nodes.len();
        let grows = drawn.laser == Some(*laser)
            && drawn.params == Some(*params)
            && old <= nodes.len()
            && drawn.nodes.iter().zip(nodes).all(|((scan, pose), n)| Arc::ptr_eq(scan, &n.scan) && *pose == n.pose);
        let Drawn { counts, cut, .. } = &mut *drawn;
        let added = match (grows, counts.as_mut()) {
            (true, Some(counts)) => add(counts, &nodes[..old], &nodes[old..], laser, params, cut),
            _ => false,
        };
        if added {
            drawn.extended += 1;
        } else {
            drawn.rebuilt += 1;
            drawn.nodes.clear();
            let Ok(counts) = Counts::of(nodes, laser, params) else {
                drawn.counts = None; // beyond the cell limit: nothing kept to extend
                return None;
            };
            drawn.counts = counts;
            drawn.laser = Some(*laser);
            drawn.params = Some(*params);
        }
        let kept = drawn.nodes.len();
        drawn.nodes.extend(nodes[kept..].iter().map(|n| (n.scan.clone(), n.pose)));
        match &drawn.counts {
            Some(c) => c.grid(params),
            None => empty_map(params),
        }
    }
}

/// Adds the counts of `new` to those of `old`; false (counts to be rebuilt) when it cannot: the new scans reach
/// beyond the grid, or make so many new walls that tracing everything again is cheaper.
fn add(
    counts: &mut Counts,
    old: &[&TrajectoryNode],
    new: &[&TrajectoryNode],
    laser: &Xyt,
    params: &MapParams,
    cut: &mut usize,
) -> bool {
    if new.is_empty() {
        return true;
    }
    let Some((x0, y0, x1, y1)) = cell_bounds(new, laser, params) else {
        return true; // the new scans map nothing
    };
    let inside =
        x0 >= counts.x0 && y0 >= counts.y0 && x1 < counts.x0 + counts.w as i64 && y1 < counts.y0 + counts.h as i64;
    if !inside {
        return false;
    }
    let wall = params.wall_hits;
    if wall > 0 {
        let before = counts.hits.clone();
        counts.add_hits(new, laser, params);
        let walls: Vec<(i64, i64)> = (0..before.len())
            .filter(|&k| before[k] < wall && counts.hits[k] >= wall)
            .map(|k| ((k % counts.w) as i64, (k / counts.w) as i64))
            .collect();
        // Each new wall costs a few bearings per old scan; past a scan's beams, tracing everything is cheaper.
        let beams = new.iter().map(|n| n.scan.len()).sum::<usize>() / new.len();
        if walls.len() > 2 * beams.max(1) {
            return false; // the caller rebuilds the counts
        }
        if !walls.is_empty() {
            for n in old {
                *cut += cut_at_new_walls(counts, &before, n, &walls, laser, params);
            }
        }
    }
    counts.add_traces(new, laser, params);
    true
}

/// Takes back what the beams of `n` counted beyond the new walls (`walls`, cells whose hits reached `wall_hits`
/// only with the new scans; `before`: the hits without them); how many beams it cut.
fn cut_at_new_walls(
    counts: &mut Counts,
    before: &[u32],
    n: &TrajectoryNode,
    walls: &[(i64, i64)],
    laser: &Xyt,
    params: &MapParams,
) -> usize {
    let wall = params.wall_hits;
    let at = sensor_in_cells(n, laser, params, counts);
    let beams = n.scan.len();
    let mut candidate = vec![false; beams];
    for &(cx, cy) in walls {
        for i in beams_through(n, at, cx, cy) {
            candidate[i] = true;
        }
    }
    let mut cuts = 0;
    for i in (0..beams).filter(|&i| candidate[i]) {
        let Some((trav, _)) = beam_cells(n, i, at, params) else {
            continue;
        };
        let end = trav.end_cell();
        let mut cut = false;
        for (cx, cy) in trav {
            let Some(k) = counts.index(cx, cy) else {
                continue;
            };
            if cut {
                counts.visits[k] = counts.visits[k].saturating_sub(1);
            }
            if (cx, cy) != end {
                if before[k] >= wall {
                    break; // where the beam stopped before
                }
                if counts.hits[k] >= wall && !cut {
                    cut = true; // where it stops now: counted by both, what follows only before
                    cuts += 1;
                }
            }
        }
    }
    cuts
}

/// The beams of `n` (sensor at `at`, cell coordinates) whose bearing lies within the bearings of cell (cx, cy)'s
/// corners, a beam to spare on either side; every beam for a sensor inside the cell or a scan without a steady
/// positive increment.
fn beams_through(n: &TrajectoryNode, at: (f64, f64, f64), cx: i64, cy: i64) -> std::ops::Range<usize> {
    let (sx, sy, theta) = at;
    let beams = n.scan.len();
    let inc = n.scan.angle_increment;
    let inside = sx >= cx as f64 && sx <= (cx + 1) as f64 && sy >= cy as f64 && sy <= (cy + 1) as f64;
    if inside || !(inc > 0.0 && inc.is_finite()) {
        return 0..beams;
    }
    let centre = (cy as f64 + 0.5 - sy).atan2(cx as f64 + 0.5 - sx);
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let d = wrap((cy as f64 + dy - sy).atan2(cx as f64 + dx - sx) - centre);
        lo = lo.min(d);
        hi = hi.max(d);
    }
    // The bearing of the cell's first corner from the scan's first beam, in [0, 2π).
    let from = (centre + lo - theta - n.scan.angle_min).rem_euclid(TAU);
    let span = hi - lo;
    // A scan covers at most a turn or so: the cell's bearings from its first beam, a turn either way.
    let (mut first, mut last) = (usize::MAX, 0usize);
    for turn in [-TAU, 0.0, TAU] {
        let (a, b) = (((from + turn) / inc).floor() - 1.0, ((from + turn + span) / inc).ceil() + 1.0);
        if b < 0.0 || a >= beams as f64 {
            continue;
        }
        first = first.min(a.max(0.0) as usize);
        last = last.max((b as usize).min(beams - 1));
    }
    if first > last { 0..0 } else { first..last + 1 }
}

/// An angle in (-π, π].
fn wrap(a: f64) -> f64 {
    let a = a.rem_euclid(TAU);
    if a > std::f64::consts::PI { a - TAU } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_build::build_map;
    use crate::synthetic::office_keyframes;

    /// The office loop's keyframes with their poses turned a little, a different way each (as a filter's
    /// estimate is off): beams then cross walls that other scans ended on.
    fn nodes() -> (Vec<TrajectoryNode>, Xyt) {
        let (truth, scans, laser) = office_keyframes();
        let nodes = truth
            .iter()
            .zip(scans)
            .enumerate()
            .map(|(k, (p, scan))| {
                let mut pose = Xyt::from_pose(p);
                pose.theta += 0.01 * ((k * 7 % 5) as f64 - 2.0);
                pose.x += 0.02 * ((k * 3 % 5) as f64 - 2.0);
                TrajectoryNode { stamp: k as f64, pose, scan, parent: None }
            })
            .collect();
        (nodes, laser)
    }

    fn same(a: &OccupancyGrid, b: &OccupancyGrid) -> bool {
        a.width() == b.width() && a.height() == b.height() && a.origin() == b.origin() && a.cells() == b.cells()
    }

    #[test]
    fn a_growing_trajectory_gets_the_map_drawn_from_scratch_cell_for_cell() {
        let (nodes, laser) = nodes();
        let refs: Vec<&TrajectoryNode> = nodes.iter().collect();
        assert!(refs.len() > 40, "{} keyframes", refs.len());
        for wall_hits in [0, 2] {
            let params = MapParams { wall_hits, max_range: 30.0, max_urange: 30.0, ..MapParams::default() };
            let map = IncrementalMap::default();
            for k in (1..=refs.len()).step_by(3) {
                let (grown, reference) = (map.map(&refs[..k], &laser, &params), build_map(&refs[..k], &laser, &params));
                assert!(same(&grown.unwrap(), &reference.unwrap()), "wall_hits {wall_hits}, {k} scans");
            }
            let drawn = map.lock();
            // The first calls grow the grid's bounds; most later ones extend the counts.
            assert!(drawn.extended > drawn.rebuilt, "{} extended, {} rebuilt", drawn.extended, drawn.rebuilt);
            if wall_hits > 0 {
                assert!(drawn.cut > 0, "no old beam was cut at a new wall: the test does not test that");
            }
        }
    }

    #[test]
    fn a_moved_scan_or_other_parameters_rebuild_the_map() {
        let (mut nodes, laser) = nodes();
        let params = MapParams { wall_hits: 2, ..MapParams::default() };
        let map = IncrementalMap::default();
        let n = nodes.len();
        map.map(&nodes.iter().collect::<Vec<_>>(), &laser, &params);
        // Loop closure moves an old scan: the same call count, the map redrawn.
        nodes[n / 2].pose.x += 0.3;
        let refs: Vec<&TrajectoryNode> = nodes.iter().collect();
        assert!(same(&map.map(&refs, &laser, &params).unwrap(), &build_map(&refs, &laser, &params).unwrap()));
        let gmapping = MapParams::default();
        assert!(same(&map.map(&refs, &laser, &gmapping).unwrap(), &build_map(&refs, &laser, &gmapping).unwrap()));
        // A shorter trajectory (resampling kept another lineage): redrawn too.
        let fewer = &refs[..n / 3];
        assert!(same(&map.map(fewer, &laser, &gmapping).unwrap(), &build_map(fewer, &laser, &gmapping).unwrap()));
        let drawn = map.lock();
        assert_eq!((drawn.extended, drawn.rebuilt), (0, 4));
    }
}
