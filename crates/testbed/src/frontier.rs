//! Frontiers of an occupancy grid: cells kept clear of walls, reachability from a robot, frontier clusters, and
//! the lone explorer's path to its nearest frontier.
//!
//! A frontier cell is a free cell with at least [`FRONTIER_MIN_UNKNOWN`] unknown cells among its eight
//! neighbours. A robot may stand on a free cell farther than its hard clearance from every occupied cell, or on
//! any cell of its own disc that is not occupied (it stands there, and a lidar does not see under or behind it).
//! Between the hard and the preferred clearance a step costs more, as a navigation stack's inflated costmap
//! makes it: paths keep the preferred distance from walls where there is room, and squeeze through doors where
//! there is not.

use mrslam_core::{CellState, OccupancyGrid, Pose2};
use nalgebra::Point2;
use rayon::prelude::*;

/// Unknown cells among a frontier cell's eight neighbours, at least.
pub const FRONTIER_MIN_UNKNOWN: usize = 3;

/// Clusters of fewer frontier cells than this are dropped by default (see [`frontiers`]).
pub const MIN_CLUSTER_CELLS: usize = 3;

/// Spacing of the points of a planned path, metres (a path is thinned to one cell in this many metres).
pub const PATH_SPACING: f64 = 0.4;

/// Cost of a step between edge neighbours away from walls.
const STEP_COST: u32 = 10;
/// Extra cost of a step onto a cell at the hard clearance; it falls linearly to 0 at the preferred clearance.
const SQUEEZE_COST: f64 = 20.0;
/// Buckets of the search's queue: more than the dearest step's cost ([`STEP_COST`] + [`SQUEEZE_COST`]).
const RING: usize = 32;
const _: () = assert!((STEP_COST as usize + SQUEEZE_COST as usize) < RING);

/// How far a robot keeps from walls, metres: never nearer than `hard` (its half width and a margin, so that it
/// fits through a door), and `preferred` where there is room (its bounding radius and a margin, so that it can
/// turn on the spot and a path follower cutting corners does not touch walls).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearance {
    /// Nearest a planned path comes to an occupied cell, metres.
    pub hard: f64,
    /// Distance from occupied cells beyond which a step costs no more, metres (at least `hard`).
    pub preferred: f64,
}

impl Clearance {
    /// One clearance, hard and preferred alike: every cell nearer a wall is out of bounds, none costs more.
    pub fn uniform(metres: f64) -> Self {
        Clearance { hard: metres, preferred: metres }
    }

    /// The hard and preferred radii in whole cells.
    fn cells(&self, resolution: f64) -> (i64, i64) {
        let hard = radius_cells(self.hard, resolution);
        (hard, radius_cells(self.preferred, resolution).max(hard))
    }
}

/// Squared distance of a cell with no occupied cell on the grid.
const FAR: u32 = u32::MAX;
/// The eight neighbours of a cell.
const AROUND: [(i64, i64); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];
/// Step count of a cell a search did not reach.
const UNREACHED: u32 = u32::MAX;

/// The radius, in whole cells, of a disc of `metres` on a grid of `resolution`.
fn radius_cells(metres: f64, resolution: f64) -> i64 {
    (metres / resolution).ceil() as i64
}

/// True when cell (x, y) is a frontier cell: free, with at least [`FRONTIER_MIN_UNKNOWN`] unknown neighbours.
///
/// Cells beyond the grid are unknown: a map holds only what was seen, so a free cell on its edge borders the
/// unseen (behind a robot whose lidar sees only ahead, above all).
fn is_frontier_cell(map: &OccupancyGrid, x: i64, y: i64) -> bool {
    let state = |x: i64, y: i64| map.get_checked(x, y).map_or(CellState::Unknown, CellState::from_log_odds);
    if !map.contains_cell(x, y) || state(x, y) != CellState::Free {
        return false;
    }
    let unknown = AROUND.iter().filter(|&&(dx, dy)| state(x + dx, y + dy) == CellState::Unknown).count();
    unknown >= FRONTIER_MIN_UNKNOWN
}

/// Squared distance, in cells², from every cell of a grid to its nearest occupied cell: the wall-clearance mask
/// of every clearance at once, computed once per map and shared by every robot planning on it.
///
/// An exact Euclidean distance transform (Felzenszwalb and Huttenlocher's lower envelope of parabolas, one
/// pass down the columns and one along the rows): O(cells) whatever the clearance. A cell is too close to a
/// wall for a clearance of `r` cells when its squared distance is at most `r²`, exactly the cells the discs
/// of radius `r` around the occupied cells cover.
#[derive(Debug, Clone)]
pub struct WallDistance {
    width: usize,
    height: usize,
    d2: Vec<u32>,
}

impl WallDistance {
    /// The distance transform of `map`'s occupied cells.
    pub fn new(map: &OccupancyGrid) -> Self {
        let (w, h) = (map.width(), map.height());
        let cells = map.cells();
        let occupied = |i: usize| CellState::from_log_odds(cells[i]) == CellState::Occupied;
        // Down each column: the distance to the nearest occupied cell of the same column (all columns at
        // once, row after row, to read the grid in memory order).
        let mut g = vec![FAR; w * h];
        let mut last: Vec<Option<usize>> = vec![None; w];
        for y in 0..h {
            for (x, l) in last.iter_mut().enumerate() {
                if occupied(y * w + x) {
                    *l = Some(y);
                }
                if let Some(l) = *l {
                    g[y * w + x] = (y - l) as u32;
                }
            }
        }
        let mut next: Vec<Option<usize>> = vec![None; w];
        for y in (0..h).rev() {
            for (x, n) in next.iter_mut().enumerate() {
                let i = y * w + x;
                if g[i] == 0 {
                    *n = Some(y);
                }
                if let Some(n) = *n {
                    g[i] = g[i].min((n - y) as u32);
                }
            }
        }
        // Along each row: the lower envelope of the parabolas (x - q)² + g(q)²; the rows side by side.
        let mut d2 = vec![FAR; w * h];
        d2.par_chunks_mut(w.max(1))
            .zip(g.par_chunks(w.max(1)))
            .for_each_init(|| (vec![0usize; w], vec![0.0f64; w + 1]), |(v, z), (out, row)| envelope(row, out, v, z));
        WallDistance { width: w, height: h, d2 }
    }

    /// Squared distance from cell (ix, iy) to the nearest occupied cell, cells²; `None` without occupied cells.
    pub fn squared_cells(&self, ix: usize, iy: usize) -> Option<u32> {
        let d = self.d2[iy * self.width + ix];
        (d != FAR).then_some(d)
    }

    /// True when cell `index` (row-major) is within `r` cells of an occupied cell.
    fn blocked(&self, index: usize, r: i64) -> bool {
        (self.d2[index] as i64) <= r * r
    }

    /// True when the transform was computed on a grid of `map`'s size.
    fn fits(&self, map: &OccupancyGrid) -> bool {
        self.width == map.width() && self.height == map.height()
    }
}

/// One row of the distance transform: `out[q]` the least (x - q)² + row[x]² over the columns x (`FAR` columns
/// have no occupied cell in their column and are left out); `v`, `z`: the envelope's scratch (w and w + 1 long).
fn envelope(row: &[u32], out: &mut [u32], v: &mut [usize], z: &mut [f64]) {
    let f = |q: usize| {
        let gq = row[q] as f64;
        gq * gq + (q * q) as f64
    };
    let mut k: Option<usize> = None;
    for q in (0..row.len()).filter(|&q| row[q] != FAR) {
        let Some(mut kk) = k else {
            k = Some(0);
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        };
        let fq = f(q);
        let mut s = (fq - f(v[kk])) / (2.0 * (q - v[kk]) as f64);
        // z[0] is minus infinity: the loop stops at kk = 0 at the latest.
        while s <= z[kk] {
            kk -= 1;
            s = (fq - f(v[kk])) / (2.0 * (q - v[kk]) as f64);
        }
        kk += 1;
        v[kk] = q;
        z[kk] = s;
        z[kk + 1] = f64::INFINITY;
        k = Some(kk);
    }
    if k.is_none() {
        return;
    }
    let mut j = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[j + 1] < q as f64 {
            j += 1;
        }
        let (dx, gy) = (q.abs_diff(v[j]) as u64, row[v[j]] as u64);
        *o = (dx * dx + gy * gy).min(FAR as u64 - 1) as u32;
    }
}

/// Where one robot can drive on a map: a cheapest-path search (Dijkstra; four neighbours, a step costing more
/// between the hard and the preferred clearance) from its pose over the cells it may stand on, with the travel
/// distance along the cheapest path to every reached cell and that path.
///
/// The buffers are two flat arrays of the grid's size; nothing is allocated per cell.
#[derive(Debug, Clone)]
pub struct Reach {
    width: usize,
    resolution: f64,
    start: usize,
    parent: Vec<u32>,
    steps: Vec<u32>,
}

impl Reach {
    /// Searches `map` from `pose` (the map's frame) for a robot keeping `clearance` from walls (`walls`:
    /// [`WallDistance::new`] of the same map); `None` when the pose is off the grid or `walls` is of another
    /// grid.
    pub fn new(map: &OccupancyGrid, walls: &WallDistance, pose: &Pose2, clearance: Clearance) -> Option<Self> {
        Self::search(map, walls, pose, clearance, |_, _| false).map(|(reach, _)| reach)
    }

    /// The search, stopped at the first cell popped for which `stop(x, y)` holds (returned with the search).
    fn search(
        map: &OccupancyGrid,
        walls: &WallDistance,
        pose: &Pose2,
        clearance: Clearance,
        mut stop: impl FnMut(i64, i64) -> bool,
    ) -> Option<(Self, Option<usize>)> {
        if !walls.fits(map) {
            return None;
        }
        let (w, h) = (map.width(), map.height());
        let (r, preferred) = clearance.cells(map.resolution());
        let start = map.world_to_cell(&Point2::new(pose.translation.x, pose.translation.y))?;
        let (sx, sy) = (start.0 as i64, start.1 as i64);
        let on_robot = |x: i64, y: i64| (x - sx).pow(2) + (y - sy).pow(2) <= preferred * preferred;
        // the cost of a step onto cell n: more the nearer a wall within the preferred clearance
        let step_cost = |n: usize| -> u32 {
            let d2 = walls.d2[n] as i64;
            if preferred <= r || d2 >= preferred * preferred {
                return STEP_COST;
            }
            let squeeze = ((preferred as f64 - (d2 as f64).sqrt()) / (preferred - r) as f64).clamp(0.0, 1.0);
            STEP_COST + (SQUEEZE_COST * squeeze).round() as u32
        };
        let cells = map.cells();
        let s = start.1 * w + start.0;
        let mut parent = vec![UNREACHED; w * h];
        let mut steps = vec![UNREACHED; w * h];
        let mut cost = vec![u32::MAX; w * h];
        parent[s] = s as u32;
        steps[s] = 0;
        cost[s] = 0;
        // Cheapest first, the lower index on ties. A step costs at least STEP_COST and less than RING, so the cells
        // queued at cost k are all queued before the search reaches k (Dial's buckets, a ring of them): each bucket is
        // sorted and run in index order, the order a heap of (cost, index) pops them in.
        let mut ring: Vec<Vec<u32>> = vec![Vec::new(); RING];
        ring[0].push(s as u32);
        let (mut k, mut queued) = (0u32, 1usize);
        let mut found = None;
        'search: while queued > 0 {
            let mut bucket = std::mem::take(&mut ring[k as usize % RING]);
            queued -= bucket.len();
            bucket.sort_unstable();
            for &c in &bucket {
                let c = c as usize;
                if k > cost[c] {
                    continue; // queued again since at a lower cost
                }
                let (cx, cy) = ((c % w) as i64, (c / w) as i64);
                if stop(cx, cy) {
                    found = Some(c);
                    break 'search;
                }
                for (dx, dy) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                    let (nx, ny) = (cx + dx, cy + dy);
                    if !map.contains_cell(nx, ny) {
                        continue;
                    }
                    let n = ny as usize * w + nx as usize;
                    let st = CellState::from_log_odds(cells[n]);
                    let passable = if on_robot(nx, ny) {
                        st != CellState::Occupied
                    } else {
                        st == CellState::Free && !walls.blocked(n, r)
                    };
                    let kn = k + step_cost(n);
                    if passable && kn < cost[n] {
                        cost[n] = kn;
                        parent[n] = c as u32;
                        steps[n] = steps[c] + 1;
                        ring[kn as usize % RING].push(n as u32);
                        queued += 1;
                    }
                }
            }
            bucket.clear();
            ring[k as usize % RING] = bucket;
            k += 1;
        }
        Some((Reach { width: w, resolution: map.resolution(), start: s, parent, steps }, found))
    }

    /// The cell the search started from (the robot's).
    pub fn start(&self) -> (usize, usize) {
        (self.start % self.width, self.start / self.width)
    }

    /// Travel distance from the robot to cell (ix, iy), metres (steps between edge neighbours × the
    /// resolution), or `None` when the cell is not reached (or off the grid).
    pub fn distance(&self, ix: usize, iy: usize) -> Option<f64> {
        if ix >= self.width {
            return None;
        }
        let s = *self.steps.get(iy * self.width + ix)?;
        (s != UNREACHED).then_some(s as f64 * self.resolution)
    }

    /// Path (the map's frame) from the robot to cell (ix, iy), thinned to one point every [`PATH_SPACING`] and
    /// ending at the cell's centre; `None` when the cell is not reached. `map` is the searched map.
    pub fn path(&self, map: &OccupancyGrid, ix: usize, iy: usize) -> Option<Vec<Point2<f64>>> {
        self.distance(ix, iy)?;
        Some(self.path_to(map, iy * self.width + ix))
    }

    /// Path to the reached cell `c` (row-major index).
    fn path_to(&self, map: &OccupancyGrid, c: usize) -> Vec<Point2<f64>> {
        let w = self.width;
        let mut cells = vec![c];
        let mut k = c;
        while self.parent[k] as usize != k {
            k = self.parent[k] as usize;
            cells.push(k);
        }
        cells.reverse();
        let step = ((PATH_SPACING / map.resolution()) as usize).max(1);
        let centre = |k: usize| map.cell_center((k % w) as i64, (k / w) as i64);
        let mut path: Vec<Point2<f64>> = cells.iter().step_by(step).map(|&k| centre(k)).collect();
        path.push(centre(c));
        path
    }
}

/// A cluster of frontier cells (eight-connected) and the point a robot drives to for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Frontier {
    /// Frontier cells in the cluster.
    pub size: usize,
    /// The target cell: the cluster's cell nearest its centroid.
    pub cell: (usize, usize),
    /// Centre of the target cell (the map's frame).
    pub target: Point2<f64>,
}

/// Frontier cells left out of [`frontiers`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Skip<'a> {
    /// Points (the map's frame) whose surroundings are left out: goals given up on.
    pub avoid: &'a [Point2<f64>],
    /// Frontier cells this close to a point of `avoid` are left out, metres.
    pub avoid_radius: f64,
    /// Robot discs (centre in the map's frame, radius in metres): a lidar does not see under its robot, so
    /// the unknown cells there are no frontier.
    pub footprints: &'a [(Point2<f64>, f64)],
}

/// The frontier clusters of `map` a robot keeping `clearance` from walls may stand on (its hard clearance; `walls`:
/// [`WallDistance::new`] of the same map), in row-major order of their first cell.
///
/// Frontier cells too close to a wall, or left out by `skip`, belong to no cluster; clusters of fewer than
/// `min_cells` cells ([`MIN_CLUSTER_CELLS`] by default) are dropped. Empty when `walls` is of another grid.
pub fn frontiers(
    map: &OccupancyGrid,
    walls: &WallDistance,
    clearance: Clearance,
    skip: &Skip<'_>,
    min_cells: usize,
) -> Vec<Frontier> {
    if !walls.fits(map) {
        return Vec::new();
    }
    let (w, h) = (map.width(), map.height());
    let res = map.resolution();
    let (r, _) = clearance.cells(res);
    let footprints: Vec<(i64, i64, i64)> = skip
        .footprints
        .iter()
        .map(|(p, radius)| {
            let (x, y) = map.world_to_cell_i(p);
            (x, y, radius_cells(*radius, res))
        })
        .collect();
    // Each cell classified once: the frontier test below reads its eight neighbours for every free cell.
    let cells = map.cells();
    let unknown: Vec<bool> = cells.iter().map(|&l| CellState::from_log_odds(l) == CellState::Unknown).collect();
    // Beyond the grid is unknown, as in `is_frontier_cell`.
    let unknown_at = |x: i64, y: i64| !map.contains_cell(x, y) || unknown[y as usize * w + x as usize];
    let mut mark = vec![false; w * h];
    for iy in 0..h {
        for ix in 0..w {
            let (x, y) = (ix as i64, iy as i64);
            let i = iy * w + ix;
            if walls.blocked(i, r) || CellState::from_log_odds(cells[i]) != CellState::Free {
                continue;
            }
            if AROUND.iter().filter(|&&(dx, dy)| unknown_at(x + dx, y + dy)).count() < FRONTIER_MIN_UNKNOWN {
                continue;
            }
            if footprints.iter().any(|&(fx, fy, fr)| (x - fx).pow(2) + (y - fy).pow(2) <= fr * fr) {
                continue;
            }
            let p = map.cell_center(x, y);
            if skip.avoid.iter().any(|q| (p - q).norm() <= skip.avoid_radius) {
                continue;
            }
            mark[i] = true;
        }
    }
    // Eight-connected components, each flood-filled from its first cell in row-major order.
    let mut out = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut members: Vec<usize> = Vec::new();
    for seed in 0..w * h {
        if !mark[seed] {
            continue;
        }
        mark[seed] = false;
        stack.push(seed);
        members.clear();
        while let Some(c) = stack.pop() {
            members.push(c);
            let (cx, cy) = ((c % w) as i64, (c / w) as i64);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (cx + dx, cy + dy);
                    if map.contains_cell(nx, ny) && mark[ny as usize * w + nx as usize] {
                        mark[ny as usize * w + nx as usize] = false;
                        stack.push(ny as usize * w + nx as usize);
                    }
                }
            }
        }
        if members.len() < min_cells.max(1) {
            continue;
        }
        let n = members.len() as f64;
        let (sx, sy) = members.iter().fold((0.0, 0.0), |(sx, sy), &c| (sx + (c % w) as f64, sy + (c / w) as f64));
        let (mx, my) = (sx / n, sy / n);
        let d2 = |c: usize| ((c % w) as f64 - mx).powi(2) + ((c / w) as f64 - my).powi(2);
        let best = members.iter().copied().fold(members[0], |b, c| {
            let (db, dc) = (d2(b), d2(c));
            if dc < db || (dc == db && c < b) { c } else { b }
        });
        let (bx, by) = (best % w, best / w);
        out.push(Frontier { size: members.len(), cell: (bx, by), target: map.cell_center(bx as i64, by as i64) });
    }
    out
}

/// Path (the map's frame) to the nearest reachable frontier cell, thinned to one point every [`PATH_SPACING`]:
/// the lone explorer's rule.
///
/// A frontier cell is a free cell with at least [`FRONTIER_MIN_UNKNOWN`] unknown cells among its eight
/// neighbours (the edge of unexplored space, not a one-cell hole between two far beams), outside the robot's
/// own disc and farther than `avoid_radius` from every point of `avoid`. The disc of the preferred clearance around
/// the robot is passable wherever it is not occupied: the robot stands there, and a lidar does not see the
/// cells under and behind the robot.
pub fn frontier_path(
    map: &OccupancyGrid,
    pose: &Pose2,
    clearance: Clearance,
    avoid: &[Point2<f64>],
    avoid_radius: f64,
) -> Option<Vec<Point2<f64>>> {
    let walls = WallDistance::new(map);
    let (_, r) = clearance.cells(map.resolution());
    let (sx, sy) = map.world_to_cell_i(&Point2::new(pose.translation.x, pose.translation.y));
    let on_robot = |x: i64, y: i64| (x - sx).pow(2) + (y - sy).pow(2) <= r * r;
    let is_goal = |x: i64, y: i64| {
        is_frontier_cell(map, x, y) && !on_robot(x, y) && {
            let p = map.cell_center(x, y);
            !avoid.iter().any(|q| (p - q).norm() <= avoid_radius)
        }
    };
    let (reach, found) = Reach::search(map, &walls, pose, clearance, is_goal)?;
    found.map(|c| reach.path_to(map, c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    /// A `w x h` grid at 5 cm, all unknown.
    fn grid(w: usize, h: usize) -> OccupancyGrid {
        OccupancyGrid::new(w, h, 0.05, pose(0.0, 0.0, 0.0)).unwrap()
    }

    /// A grid of `w x h` cells whose first `room_w` columns are a known room, walled, with a door in its east
    /// wall over rows `door`; unknown beyond.
    fn room_with_east_door(w: usize, h: usize, room_w: usize, door: std::ops::Range<usize>) -> OccupancyGrid {
        let mut g = grid(w, h);
        for iy in 0..h {
            for ix in 0..room_w {
                let wall = ix == 0 || iy == 0 || iy == h - 1 || (ix == room_w - 1 && !door.contains(&iy));
                g.set(ix, iy, if wall { 2.0 } else { -2.0 });
            }
        }
        g
    }

    #[test]
    fn frontier_is_found_through_the_door() {
        // A 4 m x 2 m known room, walled, with a gap in the east wall; unknown beyond.
        let mut g = room_with_east_door(120, 40, 80, 15..25);
        let path = frontier_path(&g, &pose(1.0, 1.0, 0.0), Clearance::uniform(0.15), &[], 0.0).expect("a frontier");
        let end = path.last().unwrap();
        assert!(end.x > 3.9 && end.y > 0.7 && end.y < 1.3, "{end:?}");
        for iy in 15..25 {
            g.set(79, iy, 2.0);
        }
        assert!(
            frontier_path(&g, &pose(1.0, 1.0, 0.0), Clearance::uniform(0.15), &[], 0.0).is_none(),
            "closed door: nothing to explore"
        );
    }

    #[test]
    fn a_door_narrower_than_the_preferred_clearance_is_passed_through_its_middle() {
        // A 4 m x 3 m known room, walled, with a 0.8 m door in the east wall (y 1.1 to 1.9); unknown beyond. The
        // Pioneer's clearances: hard 0.3 m (half its width and a margin), preferred 0.51 m (its bounding radius
        // and a margin), which the door does not leave.
        let g = room_with_east_door(120, 60, 80, 22..38);
        let start = pose(1.0, 0.6, 0.0);
        let pioneer = Clearance { hard: 0.3, preferred: 0.51 };
        assert!(frontier_path(&g, &start, Clearance::uniform(0.51), &[], 0.0).is_none(), "one clearance: blocked");
        let path = frontier_path(&g, &start, pioneer, &[], 0.0).expect("through the door");
        let end = path.last().unwrap();
        assert!(end.x > 3.9 && (end.y - 1.5).abs() < 0.1, "the frontier in the door's middle: {end:?}");
        // Away from the door the path keeps the preferred clearance: it leaves the wall the robot starts 0.6 m from
        // no nearer, and crosses the room at least 0.51 m from every wall.
        let walls = WallDistance::new(&g);
        for p in path.iter().filter(|p| p.x > 0.6 && p.x < 3.4) {
            let (ix, iy) = g.world_to_cell(p).unwrap();
            let d = f64::from(walls.squared_cells(ix, iy).unwrap()).sqrt() * 0.05;
            assert!(d >= 0.5, "{p:?} is {d:.2} m from a wall");
        }
        // And the travel distance is that of the path, not its cost.
        let reach = Reach::new(&g, &walls, &start, pioneer).unwrap();
        let (ex, ey) = g.world_to_cell(end).unwrap();
        let metres = reach.distance(ex, ey).unwrap();
        assert!((3.4..4.5).contains(&metres), "{metres} m");
    }

    #[test]
    fn a_robot_that_cannot_see_behind_itself_still_finds_its_frontier() {
        // A walled 4 m x 2 m room seen by a forward-looking lidar mounted ahead of the axle at (1.05, 1): the
        // robot's own cell and everything behind it are unknown, and so is a one-cell hole far ahead.
        let mut g = grid(80, 40);
        for iy in 0..40 {
            for ix in 0..80 {
                let wall = ix == 0 || iy == 0 || iy == 39 || ix == 79;
                let seen = ix > 22;
                if wall {
                    g.set(ix, iy, 2.0);
                } else if seen && (ix, iy) != (60, 20) {
                    g.set(ix, iy, -2.0);
                }
            }
        }
        let path = frontier_path(&g, &pose(1.05, 1.0, 0.0), Clearance::uniform(0.3), &[], 0.0)
            .expect("the unseen space behind the robot");
        let end = path.last().unwrap();
        assert!(end.x < 1.3, "it drives to the edge of the unseen space, not to the hole: {end:?}");
        // Once the space behind is seen, only the hole is left, and a hole is no frontier.
        for iy in 1..39 {
            for ix in 1..23 {
                g.set(ix, iy, -2.0);
            }
        }
        assert!(frontier_path(&g, &pose(1.05, 1.0, 0.0), Clearance::uniform(0.3), &[], 0.0).is_none());
    }

    #[test]
    fn a_map_that_ends_behind_the_robot_has_its_frontier_on_the_edge() {
        // A SLAM map holds only what was seen: a robot with a forward-looking lidar facing a dead end (a 2 m
        // corridor closed 3 m ahead) stands on the grid's west edge, and the corridor behind it is off the grid.
        let mut g = grid(60, 40);
        for iy in 0..40 {
            for ix in 0..60 {
                let wall = iy == 0 || iy == 39 || ix == 59;
                g.set(ix, iy, if wall { 2.0 } else { -2.0 });
            }
        }
        let path = frontier_path(&g, &pose(0.02, 1.0, 0.0), Clearance::uniform(0.3), &[], 0.0)
            .expect("the corridor behind the robot");
        let end = path.last().unwrap();
        assert!(end.x < 0.1, "the goal is on the west edge: {end:?}");
        let walls = WallDistance::new(&g);
        let clusters = frontiers(&g, &walls, Clearance::uniform(0.3), &Skip::default(), MIN_CLUSTER_CELLS);
        assert_eq!(clusters.len(), 1, "{clusters:?}");
        assert!(clusters[0].target.x < 0.1, "{clusters:?}");
    }

    #[test]
    fn the_distance_transform_marks_the_cells_the_wall_discs_cover() {
        // Scattered walls and posts, one wall cell on the border: the transform against the brute-force discs.
        let mut g = grid(61, 37);
        for (ix, iy) in [(0, 5), (10, 10), (11, 10), (12, 10), (30, 20), (45, 3), (60, 36), (20, 30), (21, 31)] {
            g.set(ix, iy, 2.0);
        }
        for iy in 15..30 {
            g.set(50, iy, 2.0);
        }
        let walls = WallDistance::new(&g);
        let occupied: Vec<(i64, i64)> = (0..37)
            .flat_map(|y| (0..61).map(move |x| (x, y)))
            .filter(|&(x, y)| g.state(x as usize, y as usize) == CellState::Occupied)
            .collect();
        for iy in 0..37usize {
            for ix in 0..61usize {
                let brute =
                    occupied.iter().map(|&(x, y)| (x - ix as i64).pow(2) + (y - iy as i64).pow(2)).min().unwrap();
                assert_eq!(walls.squared_cells(ix, iy), Some(brute as u32), "cell ({ix}, {iy})");
            }
        }
        assert_eq!(WallDistance::new(&grid(5, 4)).squared_cells(2, 2), None, "no wall anywhere");
    }

    #[test]
    fn reach_measures_the_way_round_a_wall_and_stops_at_it() {
        // A known 3 m x 2 m room split by a wall from the south edge up to cell row 29 at cell column 30.
        let mut g = grid(60, 40);
        for iy in 0..40 {
            for ix in 0..60 {
                let wall = ix == 0 || iy == 0 || ix == 59 || iy == 39 || (ix == 30 && iy < 30);
                g.set(ix, iy, if wall { 2.0 } else { -2.0 });
            }
        }
        let walls = WallDistance::new(&g);
        // 0.12 m: three cells kept from walls, so the wall is passed at row 33 at the lowest.
        let reach = Reach::new(&g, &walls, &pose(0.525, 0.525, 0.0), Clearance::uniform(0.12)).unwrap();
        assert_eq!(reach.start(), (10, 10));
        // To cell (40, 10): 20 cells east and 23 north to (30, 33), then 10 east and 23 south: 76 steps.
        let d = reach.distance(40, 10).unwrap();
        assert!((d - 76.0 * 0.05).abs() < 1e-9, "{d}");
        assert_eq!(reach.distance(30, 10), None, "the wall itself");
        assert_eq!(reach.distance(30, 32), None, "too close to the wall's end");
        assert_eq!(reach.distance(2, 20), None, "too close to the west wall");
        assert!(reach.distance(30, 33).is_some());
        let path = reach.path(&g, 40, 10).unwrap();
        assert_eq!(path.first().copied(), Some(g.cell_center(10, 10)));
        assert_eq!(path.last().copied(), Some(g.cell_center(40, 10)));
        assert!(path.iter().any(|p| p.y > 1.6), "the path goes round the wall: {path:?}");
        for w in path.windows(2) {
            assert!((w[1] - w[0]).norm() <= 0.4 + 1e-9, "thinned to 0.4 m at most: {path:?}");
        }
        assert!(Reach::new(&g, &walls, &pose(-1.0, 0.5, 0.0), Clearance::uniform(0.12)).is_none(), "off the grid");
        assert!(
            Reach::new(&g, &WallDistance::new(&grid(3, 3)), &pose(0.5, 0.5, 0.0), Clearance::uniform(0.12)).is_none(),
            "other grid"
        );
    }

    #[test]
    fn frontiers_are_clustered_and_small_or_avoided_ones_dropped() {
        // A known 4 m x 2 m room, walled north and south, open (unknown beyond) east and west, with a 3 x 3 cell
        // unknown hole in its middle (one lone frontier cell on each of its sides).
        let mut g = grid(100, 40);
        for iy in 0..40 {
            for ix in 10..90 {
                let hole = (40..43).contains(&ix) && (18..21).contains(&iy);
                if !hole {
                    g.set(ix, iy, if iy == 0 || iy == 39 { 2.0 } else { -2.0 });
                }
            }
        }
        let walls = WallDistance::new(&g);
        let all = frontiers(&g, &walls, Clearance::uniform(0.12), &Skip::default(), 1);
        assert_eq!(all.len(), 6, "west, east, and the hole's four sides: {all:?}");
        let west = &all[0];
        assert_eq!(west.size, 32, "rows 4 to 35: farther than three cells from the walls");
        assert_eq!(west.cell, (10, 19), "the middle (of two, the first)");
        assert_eq!(west.target, g.cell_center(10, 19));
        assert_eq!(all[1].cell, (89, 19));
        assert!(all[2..].iter().all(|f| f.size == 1), "{all:?}");
        let kept = frontiers(&g, &walls, Clearance::uniform(0.12), &Skip::default(), MIN_CLUSTER_CELLS);
        assert_eq!(kept, all[..2].to_vec(), "the hole's single cells are dropped");
        let avoid = [Point2::new(0.5, 1.0)];
        let skip = Skip { avoid: &avoid, avoid_radius: 1.0, footprints: &[] };
        let east_only = frontiers(&g, &walls, Clearance::uniform(0.12), &skip, MIN_CLUSTER_CELLS);
        assert_eq!(east_only, all[1..2].to_vec());
        // A robot's disc of 0.3 m (six cells) round cell (88, 20) takes rows 15 to 25 off the east frontier.
        let robot = [(Point2::new(4.4, 1.0), 0.3)];
        let skip = Skip { footprints: &robot, ..Skip::default() };
        let beside = frontiers(&g, &walls, Clearance::uniform(0.12), &skip, MIN_CLUSTER_CELLS);
        let sizes: Vec<usize> = beside.iter().map(|f| f.size).collect();
        assert_eq!(sizes, [32, 11, 10], "{beside:?}");
    }
}
