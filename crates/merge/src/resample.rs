//! Resampling a grid into another frame or resolution (nearest neighbour, states kept sharp).

use mrslam_core::floor_i64;
use mrslam_core::{OccupancyGrid, Pose2, pose};
use nalgebra::Point2;

/// The geometry of a grid: size, resolution and origin, without its cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGeometry {
    /// Width in cells.
    pub width: usize,
    /// Height in cells.
    pub height: usize,
    /// Metres per cell.
    pub resolution: f64,
    /// Pose of cell (0, 0)'s outer corner.
    pub origin: Pose2,
}

impl GridGeometry {
    /// The geometry of an existing grid.
    pub fn of(g: &OccupancyGrid) -> Self {
        GridGeometry { width: g.width(), height: g.height(), resolution: g.resolution(), origin: *g.origin() }
    }
}

/// Calls `f(target_index, source_log_odds)` for every target cell whose centre, taken into the source's
/// frame by `t_target_src⁻¹`, falls on a source cell (nearest neighbour).
///
/// One affine step per cell: no trigonometry or allocation inside the loop.
pub fn sample_cells(target: &GridGeometry, src: &OccupancyGrid, t_target_src: &Pose2, mut f: impl FnMut(usize, f32)) {
    let t_src_target = t_target_src.inverse();
    let res = target.resolution;
    let src_of = |x: f64, y: f64| {
        let p = target.origin * Point2::new(x * res, y * res);
        src.world_to_cell_f(&(t_src_target * p))
    };
    let (ax, ay) = src_of(0.5, 0.5);
    let (bx, by) = src_of(1.5, 0.5);
    let (cx, cy) = src_of(0.5, 1.5);
    let (dux, duy) = (bx - ax, by - ay);
    let (dvx, dvy) = (cx - ax, cy - ay);
    let (sw, sh) = (src.width() as i64, src.height() as i64);
    let cells = src.cells();
    for j in 0..target.height {
        let (mut x, mut y) = (ax + j as f64 * dvx, ay + j as f64 * dvy);
        for i in 0..target.width {
            let (ix, iy) = (floor_i64(x), floor_i64(y));
            if ix >= 0 && iy >= 0 && ix < sw && iy < sh {
                f(j * target.width + i, cells[iy as usize * sw as usize + ix as usize]);
            }
            x += dux;
            y += duy;
        }
    }
}

/// Axis-aligned geometry at `resolution` covering the given map-frame points.
pub fn covering_geometry(points: &[Point2<f64>], resolution: f64) -> GridGeometry {
    let (mut lo, mut hi) = (Point2::new(f64::MAX, f64::MAX), Point2::new(f64::MIN, f64::MIN));
    for c in points {
        lo = lo.inf(c);
        hi = hi.sup(c);
    }
    GridGeometry {
        width: (((hi.x - lo.x) / resolution - 1e-9).ceil() as usize).max(1),
        height: (((hi.y - lo.y) / resolution - 1e-9).ceil() as usize).max(1),
        resolution,
        origin: pose(lo.x, lo.y, 0.0),
    }
}

/// The four outer corners of a grid in its map frame, taken through `t`.
pub fn corners(grid: &OccupancyGrid, t: &Pose2) -> [Point2<f64>; 4] {
    let (w, h) = (grid.width() as f64, grid.height() as f64);
    [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)].map(|(x, y)| t * grid.cell_f_to_world(x, y))
}

/// The four corners of a grid's known part (the whole grid when nothing is known), taken through `t`.
pub fn known_corners(grid: &OccupancyGrid, t: &Pose2) -> [Point2<f64>; 4] {
    let Some((x0, y0, x1, y1)) = grid.known_bounds() else { return corners(grid, t) };
    let (x0, y0, x1, y1) = (x0 as f64, y0 as f64, x1 as f64 + 1.0, y1 as f64 + 1.0);
    [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(x, y)| t * grid.cell_f_to_world(x, y))
}

/// Renders `grid` axis-aligned in a new frame at `resolution`: a cell of the result takes the log-odds of
/// the source cell under its centre. `t_new_old` maps the grid's map frame into the new frame.
pub fn resample(grid: &OccupancyGrid, t_new_old: &Pose2, resolution: f64) -> OccupancyGrid {
    let geo = covering_geometry(&corners(grid, t_new_old), resolution);
    let mut out = OccupancyGrid::new(geo.width, geo.height, resolution, geo.origin)
        .expect("a resampled grid is no larger than its source at a comparable resolution");
    let dst = out.cells_mut();
    sample_cells(&geo, grid, t_new_old, |i, l| dst[i] = l);
    out
}

/// The grid at another resolution, same frame (the result's origin is the source's, yaw dropped into cells).
pub fn to_resolution(grid: &OccupancyGrid, resolution: f64) -> OccupancyGrid {
    if (grid.resolution() - resolution).abs() < 1e-12 && grid.origin().rotation.angle() == 0.0 {
        return grid.clone();
    }
    resample(grid, &Pose2::identity(), resolution)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::CellState;

    #[test]
    fn rotation_by_quarter_turn_moves_cells_exactly() {
        let mut g = OccupancyGrid::new(10, 6, 1.0, pose(0.0, 0.0, 0.0)).unwrap();
        g.set(7, 1, 2.0);
        let t = pose(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let r = resample(&g, &t, 1.0);
        assert_eq!((r.width(), r.height()), (6, 10));
        let p = t * g.cell_center(7, 1);
        let c = r.world_to_cell(&p).unwrap();
        assert_eq!(r.state(c.0, c.1), CellState::Occupied);
        let occupied = r.cells().iter().filter(|&&l| l > 1.0).count();
        assert_eq!(occupied, 1);
    }

    #[test]
    fn halving_resolution_keeps_walls() {
        let mut g = OccupancyGrid::new(40, 40, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for i in 0..40 {
            g.set(i, 20, 2.0);
            g.set(i, 21, 2.0);
        }
        let r = to_resolution(&g, 0.1);
        assert_eq!((r.width(), r.height()), (20, 20));
        assert!((0..20).all(|i| r.state(i, 10) == CellState::Occupied));
    }
}
