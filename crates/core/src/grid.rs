//! The log-odds occupancy grid: storage, frames, scan integration and ray casting.

use crate::raycast::CellTraversal;
use crate::scan::LaserScan;
use crate::se2::Pose2;
use nalgebra::Point2;

/// Cells scanned together when looking for a known one (a vectorised test, then the exact position).
const SCAN: usize = 16;

#[inline]
fn is_known(l: f32) -> bool {
    CellState::from_log_odds(l) != CellState::Unknown
}

/// Index of the first known cell of a row.
fn first_known(row: &[f32]) -> Option<usize> {
    let mut chunks = row.chunks_exact(SCAN);
    for (k, c) in (&mut chunks).enumerate() {
        if c.iter().fold(false, |any, &l| any | is_known(l)) {
            return c.iter().position(|&l| is_known(l)).map(|i| k * SCAN + i);
        }
    }
    let base = row.len() - chunks.remainder().len();
    chunks.remainder().iter().position(|&l| is_known(l)).map(|i| base + i)
}

/// Index of the last known cell of a row.
fn last_known(row: &[f32]) -> Option<usize> {
    let mut chunks = row.rchunks_exact(SCAN);
    for (k, c) in (&mut chunks).enumerate() {
        if c.iter().fold(false, |any, &l| any | is_known(l)) {
            return c.iter().rposition(|&l| is_known(l)).map(|i| row.len() - (k + 1) * SCAN + i);
        }
    }
    chunks.remainder().iter().rposition(|&l| is_known(l))
}

/// `x.floor() as i64` (saturating, NaN gives 0), inlined: without SSE4.1, `f64::floor` is a libm call,
/// and cell lookups do one per coordinate.
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x { t.saturating_sub(1) } else { t }
}

/// Largest grid accepted anywhere (cells): 20 000 × 20 000, i.e. 1 km² at 5 cm, 1.6 GB of f32.
///
/// Inputs that claim more are refused before anything is allocated.
pub const MAX_CELLS: usize = 400_000_000;

/// Log-odds above which a cell is occupied: p = 0.65, map_server's default `occupied_thresh`.
pub const OCCUPIED_LOGODDS: f32 = 0.619_039_2;
/// Log-odds below which a cell is free: p = 0.35, the mirror of [`OCCUPIED_LOGODDS`].
pub const FREE_LOGODDS: f32 = -0.619_039_2;

/// Log-odds given to a definitely occupied (+) or free (−) cell read from a ROS map: p ≈ 0.88 / 0.12.
pub const ROS_LOGODDS_LIMIT: f32 = 2.0;

/// What is known of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CellState {
    /// Never observed, or observed without a clear verdict.
    Unknown,
    /// Observed empty.
    Free,
    /// Observed occupied.
    Occupied,
}

impl CellState {
    /// Classifies a log-odds value with [`OCCUPIED_LOGODDS`] and [`FREE_LOGODDS`].
    #[inline]
    pub fn from_log_odds(l: f32) -> Self {
        if l > OCCUPIED_LOGODDS {
            CellState::Occupied
        } else if l < FREE_LOGODDS {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }
}

/// Errors in building or growing a grid.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GridError {
    /// Resolution is zero, negative or not finite.
    #[error("resolution must be a positive finite number of metres per cell, got {0}")]
    BadResolution(f64),
    /// The grid would exceed [`MAX_CELLS`].
    #[error("grid of {width}x{height} cells exceeds the limit of {MAX_CELLS} cells")]
    TooLarge {
        /// Requested width in cells.
        width: usize,
        /// Requested height in cells.
        height: usize,
    },
    /// The cell buffer does not hold width × height values.
    #[error("cell buffer holds {got} values, expected {expected}")]
    BadCellCount {
        /// Values expected.
        expected: usize,
        /// Values given.
        got: usize,
    },
}

/// Inverse sensor model of scan integration, in log-odds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogOddsParams {
    /// Added to the cell a beam ends in (log-odds of p = 0.7).
    pub hit: f32,
    /// Added to each cell a beam passes through before its end (log-odds of p = 0.4).
    pub miss: f32,
    /// Lower clamp, so a cell can change its mind after a few contrary readings.
    pub min: f32,
    /// Upper clamp.
    pub max: f32,
    /// Max-range beams clear the cells along them (without marking a hit).
    pub clear_max_range: bool,
    /// Max-range beams clear at most this far, metres (a sensor's far readings are the least reliable).
    pub max_clear_range: f64,
}

impl Default for LogOddsParams {
    fn default() -> Self {
        LogOddsParams {
            hit: 0.847_297_9,
            miss: -0.405_465_1,
            min: -2.0,
            max: 3.5,
            clear_max_range: true,
            max_clear_range: f64::INFINITY,
        }
    }
}

/// A 2D occupancy grid holding the log-odds of occupancy per cell (0 = unknown).
///
/// Cells are row-major with row 0 at the lowest y of the grid frame, as in ROS's `nav_msgs/OccupancyGrid`.
/// `origin` is the pose, in the map frame, of the outer corner of cell (0, 0); the grid may be rotated.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    resolution: f64,
    origin: Pose2,
    width: usize,
    height: usize,
    cells: Vec<f32>,
}

/// Cells added on each side whenever a grid grows, so that a moving robot does not regrow every scan.
const GROWTH_MARGIN: i64 = 64;

impl OccupancyGrid {
    /// An all-unknown grid of `width × height` cells.
    pub fn new(width: usize, height: usize, resolution: f64, origin: Pose2) -> Result<Self, GridError> {
        check_size(width, height, resolution)?;
        Ok(OccupancyGrid { resolution, origin, width, height, cells: vec![0.0; width * height] })
    }

    /// A grid over the given log-odds cells (row-major, row 0 at the lowest y).
    pub fn from_cells(
        width: usize,
        height: usize,
        resolution: f64,
        origin: Pose2,
        cells: Vec<f32>,
    ) -> Result<Self, GridError> {
        check_size(width, height, resolution)?;
        if cells.len() != width * height {
            return Err(GridError::BadCellCount { expected: width * height, got: cells.len() });
        }
        Ok(OccupancyGrid { resolution, origin, width, height, cells })
    }

    /// Width in cells.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height in cells.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Edge length of a cell, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }
    /// Pose of cell (0, 0)'s outer corner in the map frame.
    pub fn origin(&self) -> &Pose2 {
        &self.origin
    }
    /// Replaces the origin (moves the whole grid in the map frame).
    pub fn set_origin(&mut self, origin: Pose2) {
        self.origin = origin;
    }
    /// Log-odds cells, row-major, row 0 at the lowest y.
    pub fn cells(&self) -> &[f32] {
        &self.cells
    }
    /// Mutable log-odds cells.
    pub fn cells_mut(&mut self) -> &mut [f32] {
        &mut self.cells
    }

    /// Index of cell (ix, iy) in [`Self::cells`].
    #[inline]
    pub fn index(&self, ix: usize, iy: usize) -> usize {
        iy * self.width + ix
    }

    /// True when (ix, iy) lies on the grid.
    #[inline]
    pub fn contains_cell(&self, ix: i64, iy: i64) -> bool {
        ix >= 0 && iy >= 0 && (ix as usize) < self.width && (iy as usize) < self.height
    }

    /// Log-odds of cell (ix, iy); panics off the grid.
    #[inline]
    pub fn get(&self, ix: usize, iy: usize) -> f32 {
        self.cells[self.index(ix, iy)]
    }

    /// Log-odds of cell (ix, iy), or None off the grid.
    #[inline]
    pub fn get_checked(&self, ix: i64, iy: i64) -> Option<f32> {
        self.contains_cell(ix, iy).then(|| self.cells[iy as usize * self.width + ix as usize])
    }

    /// Sets the log-odds of cell (ix, iy); panics off the grid.
    #[inline]
    pub fn set(&mut self, ix: usize, iy: usize, l: f32) {
        let i = self.index(ix, iy);
        self.cells[i] = l;
    }

    /// Occupancy probability of cell (ix, iy).
    pub fn probability(&self, ix: usize, iy: usize) -> f32 {
        probability(self.get(ix, iy))
    }

    /// State of cell (ix, iy).
    pub fn state(&self, ix: usize, iy: usize) -> CellState {
        CellState::from_log_odds(self.get(ix, iy))
    }

    /// The grid as ROS `nav_msgs/OccupancyGrid` data: -1 unknown, else occupancy 0..100.
    ///
    /// Cells at or beyond ±[`ROS_LOGODDS_LIMIT`] (what a read ROS map holds for its
    /// certain cells) become exactly 0 or 100, so ROS data survives a round trip.
    pub fn to_ros_int8(&self) -> Vec<i8> {
        let lim = ROS_LOGODDS_LIMIT;
        self.cells
            .iter()
            .map(|&l| match l {
                0.0 => -1,
                l if l >= lim => 100,
                l if l <= -lim => 0,
                l => (probability(l) * 100.0).round() as i8,
            })
            .collect()
    }

    /// The area the grid knows (free or occupied cells), m².
    pub fn known_area(&self) -> f64 {
        let (free, occupied, _) = self.state_counts();
        (free + occupied) as f64 * self.resolution * self.resolution
    }

    /// Counts of (free, occupied, unknown) cells.
    pub fn state_counts(&self) -> (usize, usize, usize) {
        let (mut f, mut o, mut u) = (0, 0, 0);
        for &l in &self.cells {
            match CellState::from_log_odds(l) {
                CellState::Free => f += 1,
                CellState::Occupied => o += 1,
                CellState::Unknown => u += 1,
            }
        }
        (f, o, u)
    }

    /// Inclusive cell bounds `(min_ix, min_iy, max_ix, max_iy)` of the known (free or occupied) cells.
    pub fn known_bounds(&self) -> Option<(usize, usize, usize, usize)> {
        let mut b: Option<(usize, usize, usize, usize)> = None;
        for iy in 0..self.height {
            let row = &self.cells[iy * self.width..(iy + 1) * self.width];
            if let Some(x0) = first_known(row) {
                let x1 = last_known(row).unwrap_or(x0);
                b = Some(match b {
                    None => (x0, iy, x1, iy),
                    Some((a, by, c, _)) => (a.min(x0), by, c.max(x1), iy),
                });
            }
        }
        b
    }

    /// Continuous cell coordinates of a map-frame point (cell (i, j) covers [i, i+1) × [j, j+1)).
    #[inline]
    pub fn world_to_cell_f(&self, p: &Point2<f64>) -> (f64, f64) {
        let q = self.origin.inverse_transform_point(p);
        (q.x / self.resolution, q.y / self.resolution)
    }

    /// The cell a map-frame point falls in, possibly off the grid.
    #[inline]
    pub fn world_to_cell_i(&self, p: &Point2<f64>) -> (i64, i64) {
        let (x, y) = self.world_to_cell_f(p);
        (floor_i64(x), floor_i64(y))
    }

    /// The cell a map-frame point falls in, or None off the grid.
    pub fn world_to_cell(&self, p: &Point2<f64>) -> Option<(usize, usize)> {
        let (ix, iy) = self.world_to_cell_i(p);
        self.contains_cell(ix, iy).then_some((ix as usize, iy as usize))
    }

    /// Map-frame position of continuous cell coordinates.
    #[inline]
    pub fn cell_f_to_world(&self, x: f64, y: f64) -> Point2<f64> {
        self.origin * Point2::new(x * self.resolution, y * self.resolution)
    }

    /// Map-frame centre of cell (ix, iy).
    #[inline]
    pub fn cell_center(&self, ix: i64, iy: i64) -> Point2<f64> {
        self.cell_f_to_world(ix as f64 + 0.5, iy as f64 + 0.5)
    }

    /// Grows the grid (unknown cells, plus a margin) so that the continuous cell box
    /// `[x0, x1] × [y0, y1]` of the current grid lies on it. Returns the cell shift applied to old indices.
    pub fn grow_to_cells(&mut self, x0: f64, y0: f64, x1: f64, y1: f64) -> Result<(usize, usize), GridError> {
        let (lo_x, lo_y) = (x0.floor() as i64, y0.floor() as i64);
        let (hi_x, hi_y) = (x1.floor() as i64, y1.floor() as i64);
        let (w, h) = (self.width as i64, self.height as i64);
        if lo_x >= 0 && lo_y >= 0 && hi_x < w && hi_y < h {
            return Ok((0, 0));
        }
        let add_left = if lo_x < 0 { -lo_x + GROWTH_MARGIN } else { 0 };
        let add_bottom = if lo_y < 0 { -lo_y + GROWTH_MARGIN } else { 0 };
        let add_right = if hi_x >= w { hi_x - w + 1 + GROWTH_MARGIN } else { 0 };
        let add_top = if hi_y >= h { hi_y - h + 1 + GROWTH_MARGIN } else { 0 };
        let nw = (w + add_left + add_right) as usize;
        let nh = (h + add_bottom + add_top) as usize;
        check_size(nw, nh, self.resolution)?;
        let mut cells = vec![0.0f32; nw * nh];
        let (sx, sy) = (add_left as usize, add_bottom as usize);
        for iy in 0..self.height {
            let src = &self.cells[iy * self.width..(iy + 1) * self.width];
            let dst = (iy + sy) * nw + sx;
            cells[dst..dst + self.width].copy_from_slice(src);
        }
        self.origin *=
            nalgebra::Translation2::new(-(add_left as f64) * self.resolution, -(add_bottom as f64) * self.resolution);
        self.cells = cells;
        self.width = nw;
        self.height = nh;
        Ok((sx, sy))
    }

    /// Grows the grid so that every given map-frame point lies on it.
    pub fn grow_to_points(&mut self, points: &[Point2<f64>]) -> Result<(), GridError> {
        if points.is_empty() {
            return Ok(());
        }
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in points {
            let (x, y) = self.world_to_cell_f(p);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
        self.grow_to_cells(x0, y0, x1, y1).map(|_| ())
    }

    /// Integrates one scan taken with the sensor at `sensor_pose` (map frame), growing the grid as needed.
    ///
    /// Each valid beam lowers the log-odds of the cells it crosses and raises the cell it ends in; a max-range
    /// beam (when `params.clear_max_range`) lowers the cells up to `min(range_max, max_clear_range)` and marks
    /// nothing. Invalid beams (NaN, below range_min, negative) are ignored.
    pub fn integrate_scan(
        &mut self,
        scan: &LaserScan,
        sensor_pose: &Pose2,
        params: &LogOddsParams,
    ) -> Result<(), GridError> {
        let clear_range = (scan.range_max as f64).min(params.max_clear_range);
        let beam_end = |i: usize| -> Option<(f64, bool)> {
            if scan.is_valid(i) {
                Some((scan.ranges[i] as f64, true))
            } else if params.clear_max_range && scan.is_max_range(i) && clear_range > 0.0 {
                Some((clear_range, false))
            } else {
                None
            }
        };
        // Grow once for the whole scan.
        let sensor = Point2::new(sensor_pose.translation.x, sensor_pose.translation.y);
        let (sx, sy) = self.world_to_cell_f(&sensor);
        let (mut x0, mut y0, mut x1, mut y1) = (sx, sy, sx, sy);
        for i in 0..scan.len() {
            if let Some((r, _)) = beam_end(i) {
                let (x, y) = self.world_to_cell_f(&scan.point_at(sensor_pose, i, r));
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x);
                y1 = y1.max(y);
            }
        }
        self.grow_to_cells(x0, y0, x1, y1)?;
        let (sx, sy) = self.world_to_cell_f(&sensor);
        let (lo, hi) = (params.min, params.max);
        for i in 0..scan.len() {
            let Some((r, hit)) = beam_end(i) else {
                continue;
            };
            let (ex, ey) = self.world_to_cell_f(&scan.point_at(sensor_pose, i, r));
            let trav = CellTraversal::new(sx, sy, ex, ey);
            let end = trav.end_cell();
            for (cx, cy) in trav {
                let idx = cy as usize * self.width + cx as usize;
                let delta = if (cx, cy) == end { if hit { params.hit } else { params.miss } } else { params.miss };
                self.cells[idx] = (self.cells[idx] + delta).clamp(lo, hi);
            }
        }
        Ok(())
    }

    /// Expected range of a beam from `from` (map frame) at map-frame angle `angle`: the distance to where it
    /// enters the first occupied cell, or None when nothing occupied lies within `max_range`.
    pub fn cast_ray(&self, from: &Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
        let (x0, y0) = self.world_to_cell_f(from);
        let local = angle - self.origin.rotation.angle();
        let (dx, dy) = (local.cos() * max_range / self.resolution, local.sin() * max_range / self.resolution);
        let (x1, y1) = (x0 + dx, y0 + dy);
        let (w, h) = (self.width as i64, self.height as i64);
        for (cx, cy) in CellTraversal::new(x0, y0, x1, y1) {
            if cx < 0 || cy < 0 || cx >= w || cy >= h {
                // Left the grid for good, or not yet on it: skip either way.
                continue;
            }
            if self.cells[cy as usize * self.width + cx as usize] > OCCUPIED_LOGODDS {
                let t = entry_parameter(x0, y0, dx, dy, cx, cy);
                return Some(t * max_range);
            }
        }
        None
    }
}

/// Parameter in [0, 1] at which the segment `p + t·d` enters cell (cx, cy).
fn entry_parameter(x0: f64, y0: f64, dx: f64, dy: f64, cx: i64, cy: i64) -> f64 {
    let mut t: f64 = 0.0;
    for (p, d, lo) in [(x0, dx, cx as f64), (y0, dy, cy as f64)] {
        if d != 0.0 {
            let (a, b) = ((lo - p) / d, (lo + 1.0 - p) / d);
            t = t.max(a.min(b));
        }
    }
    t.clamp(0.0, 1.0)
}

/// Occupancy probability of a log-odds value.
#[inline]
pub fn probability(l: f32) -> f32 {
    1.0 - 1.0 / (1.0 + l.exp())
}

/// Log-odds of a probability in (0, 1).
#[inline]
pub fn log_odds(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

fn check_size(width: usize, height: usize, resolution: f64) -> Result<(), GridError> {
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(GridError::BadResolution(resolution));
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(GridError::TooLarge { width, height });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_and_last_known_cells_of_rows() {
        for n in [0usize, 1, 5, 16, 17, 40] {
            for a in 0..n {
                for b in a..n {
                    let mut row = vec![0.0f32; n];
                    row[a] = 2.0;
                    row[b] = -2.0;
                    assert_eq!((first_known(&row), last_known(&row)), (Some(a), Some(b)), "{n} {a} {b}");
                }
            }
            assert_eq!((first_known(&vec![0.1; n]), last_known(&vec![f32::NAN; n])), (None, None));
        }
    }

    #[test]
    fn floor_i64_is_floor_as_i64() {
        for x in [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.999_999, -2.000_001, 1e300, -1e300, 9.3e18, -9.3e18, f64::NAN] {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
        for x in [f64::INFINITY, f64::NEG_INFINITY, f64::MIN_POSITIVE, -f64::MIN_POSITIVE, 4503599627370495.5] {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }
    use crate::se2::pose;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    fn box_room(width_m: f64, height_m: f64, res: f64) -> OccupancyGrid {
        let w = (width_m / res).round() as usize;
        let h = (height_m / res).round() as usize;
        let mut g = OccupancyGrid::new(w, h, res, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..h {
            for ix in 0..w {
                let wall = ix == 0 || iy == 0 || ix == w - 1 || iy == h - 1;
                g.set(ix, iy, if wall { 3.0 } else { -2.0 });
            }
        }
        g
    }

    #[test]
    fn thresholds_match_probabilities() {
        assert!((probability(OCCUPIED_LOGODDS) - 0.65).abs() < 1e-5);
        assert!((log_odds(0.7) - LogOddsParams::default().hit).abs() < 1e-5);
        assert!((log_odds(0.4) - LogOddsParams::default().miss).abs() < 1e-5);
    }

    #[test]
    fn refuses_bad_sizes() {
        assert_eq!(OccupancyGrid::new(10, 10, 0.0, pose(0.0, 0.0, 0.0)), Err(GridError::BadResolution(0.0)));
        assert!(matches!(
            OccupancyGrid::new(100_000, 100_000, 0.05, pose(0.0, 0.0, 0.0)),
            Err(GridError::TooLarge { .. })
        ));
    }

    #[test]
    fn ros_view_marks_unknown() {
        let mut g = OccupancyGrid::new(3, 1, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        g.set(1, 0, 10.0);
        g.set(2, 0, -10.0);
        assert_eq!(g.to_ros_int8(), vec![-1, 100, 0]);
    }

    #[test]
    fn cast_ray_measures_distance_to_wall() {
        let g = box_room(4.0, 3.0, 0.05);
        let from = Point2::new(1.0, 1.5);
        // East wall's inner face is at x = 4.0 - 0.05.
        let r = g.cast_ray(&from, 0.0, 10.0).unwrap();
        assert!((r - 2.95).abs() < 1e-9, "{r}");
        let r = g.cast_ray(&from, PI / 2.0, 10.0).unwrap();
        assert!((r - 1.45).abs() < 1e-9, "{r}");
        assert_eq!(g.cast_ray(&from, 0.0, 1.0), None);
    }

    #[test]
    fn cast_ray_respects_rotated_origin() {
        let mut g = box_room(4.0, 3.0, 0.05);
        g.set_origin(pose(10.0, 0.0, PI / 2.0));
        // The grid's +x axis now points along the map's +y axis.
        let from = g.cell_f_to_world(20.0, 30.0);
        let r = g.cast_ray(&from, PI / 2.0, 10.0).unwrap();
        assert!((r - (3.95 - 1.0)).abs() < 1e-9, "{r}");
    }

    #[test]
    fn integrate_scan_grows_and_marks() {
        let mut g = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let scan = LaserScan {
            stamp: 0.0,
            angle_min: 0.0,
            angle_increment: PI / 2.0,
            range_min: 0.05,
            range_max: 4.0,
            ranges: vec![2.0, 4.0, f32::NAN],
        };
        g.integrate_scan(&scan, &pose(0.55, 0.55, 0.0), &LogOddsParams::default()).unwrap();
        assert!(g.width() > 20, "grid grew to hold the 2 m beam");
        let hit = g.world_to_cell(&Point2::new(2.55, 0.55)).unwrap();
        assert_eq!(g.state(hit.0, hit.1), CellState::Occupied, "one hit gives p = 0.7 > 0.65");
        assert!(g.get(hit.0, hit.1) > 0.8);
        let free = g.world_to_cell(&Point2::new(1.5, 0.55)).unwrap();
        assert!(g.get(free.0, free.1) < 0.0);
        // the max-range beam cleared upwards but marked nothing
        let up = g.world_to_cell(&Point2::new(0.55, 4.5)).unwrap();
        let up_end = g.world_to_cell(&Point2::new(0.55, 4.54)).unwrap();
        assert!(g.get(up.0, up.1) < 0.0 && g.get(up_end.0, up_end.1) <= 0.0);
    }

    #[test]
    fn growth_preserves_world_positions() {
        let mut g = OccupancyGrid::new(4, 4, 0.5, pose(1.0, 2.0, 0.3)).unwrap();
        g.set(1, 2, 2.0);
        let p = g.cell_center(1, 2);
        g.grow_to_points(&[Point2::new(-10.0, -10.0), Point2::new(10.0, 10.0)]).unwrap();
        let c = g.world_to_cell(&p).unwrap();
        assert_eq!(g.get(c.0, c.1), 2.0);
        assert!(g.world_to_cell(&Point2::new(-10.0, -10.0)).is_some());
        assert!(g.world_to_cell(&Point2::new(10.0, 10.0)).is_some());
    }

    proptest! {
        #[test]
        fn world_cell_world_within_half_cell(x in -50.0f64..50.0, y in -50.0f64..50.0,
                                             ox in -5.0f64..5.0, oy in -5.0f64..5.0, oth in -3.1f64..3.1,
                                             res in 0.01f64..0.5) {
            let g = OccupancyGrid::new(10, 10, res, pose(ox, oy, oth)).unwrap();
            let p = Point2::new(x, y);
            let (ix, iy) = g.world_to_cell_i(&p);
            let c = g.cell_center(ix, iy);
            // in the grid frame the offset is at most half a cell on each axis
            let q = g.origin().inverse_transform_point(&p) - g.origin().inverse_transform_point(&c);
            prop_assert!(q.x.abs() <= res / 2.0 + 1e-9 && q.y.abs() <= res / 2.0 + 1e-9);
        }

        /// A single beam changes nothing beyond its hit: cells behind it are never made free.
        #[test]
        fn integration_never_frees_behind_hit(sx in 1.0f64..3.0, sy in 1.0f64..3.0, a in -PI..PI,
                                              r in 0.2f64..1.9) {
            let mut g = OccupancyGrid::new(80, 80, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
            let scan = LaserScan { stamp: 0.0, angle_min: a, angle_increment: 0.0, range_min: 0.05,
                                   range_max: 10.0, ranges: vec![r as f32] };
            g.integrate_scan(&scan, &pose(sx, sy, 0.0), &LogOddsParams::default()).unwrap();
            let hit = Point2::new(sx + r * a.cos(), sy + r * a.sin());
            let hit_cell = g.world_to_cell_i(&hit);
            prop_assert!(g.get(hit_cell.0 as usize, hit_cell.1 as usize) > 0.0);
            for k in 1..40 {
                let d = r + k as f64 * 0.025;
                let p = Point2::new(sx + d * a.cos(), sy + d * a.sin());
                let c = g.world_to_cell_i(&p);
                if c == hit_cell { continue; }
                if let Some(l) = g.get_checked(c.0, c.1) {
                    prop_assert!(l >= 0.0, "cell {:?} behind the hit at {} m was freed", c, d);
                }
            }
        }
    }
}
