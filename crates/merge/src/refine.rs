//! Refinement of an accepted-looking alignment on the maps themselves: point-to-point ICP between the walls.
//!
//! Features fix the transform to within a few cells; the walls, thousands of cells, fix it to within one.
//! Each iteration pairs every wall cell of b (placed by the current transform) with the nearest wall cell of
//! a within a search radius, and solves the rigid least-squares transform of the pairs (Umeyama/Kabsch).

use crate::estimate::Model;
use crate::estimate::fit;
use mrslam_core::{CellState, OccupancyGrid, Pose2, pose};
use nalgebra::Point2;

/// ICP parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RefineParams {
    /// Run the refinement (false: the estimator's transform as it is, as the paper does).
    pub enabled: bool,
    /// Largest distance of a pair in the first iteration, in cells of map a.
    pub radius_cells: i64,
    /// Iterations (the radius shrinks to one cell over them).
    pub iterations: usize,
    /// Fewest pairs needed to trust an iteration.
    pub min_pairs: usize,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams { enabled: true, radius_cells: 4, iterations: 20, min_pairs: 50 }
    }
}

/// Occupied cell centres of a grid, in its map frame.
pub fn wall_points(g: &OccupancyGrid) -> Vec<Point2<f64>> {
    (0..g.height())
        .flat_map(|iy| (0..g.width()).map(move |ix| (ix, iy)))
        .filter(|&(ix, iy)| g.state(ix, iy) == CellState::Occupied)
        .map(|(ix, iy)| g.cell_center(ix as i64, iy as i64))
        .collect()
}

/// Refines `t_a_b` by ICP of b's walls onto a's walls; returns the input unchanged when too few pairs form.
pub fn refine(a: &OccupancyGrid, walls_b: &[Point2<f64>], t_a_b: &Pose2, p: &RefineParams) -> Pose2 {
    let mut t = *t_a_b;
    if !p.enabled {
        return t;
    }
    let occupied =
        |ix: i64, iy: i64| a.get_checked(ix, iy).is_some_and(|l| CellState::from_log_odds(l) == CellState::Occupied);
    let (mut pa, mut pb) = (Vec::with_capacity(walls_b.len()), Vec::with_capacity(walls_b.len()));
    for k in 0..p.iterations {
        let r = (p.radius_cells - (k as i64 * p.radius_cells) / p.iterations.max(1) as i64).max(1);
        pa.clear();
        pb.clear();
        for q in walls_b {
            let w = t * q;
            let (fx, fy) = a.world_to_cell_f(&w);
            let (cx, cy) = (fx.floor() as i64, fy.floor() as i64);
            let mut best: Option<(f64, i64, i64)> = None;
            for dy in -r..=r {
                for dx in -r..=r {
                    if occupied(cx + dx, cy + dy) {
                        let (ex, ey) = ((cx + dx) as f64 + 0.5 - fx, (cy + dy) as f64 + 0.5 - fy);
                        let d = ex * ex + ey * ey;
                        if best.is_none_or(|b| d < b.0) {
                            best = Some((d, cx + dx, cy + dy));
                        }
                    }
                }
            }
            if let Some((d, x, y)) = best
                && d <= (r * r) as f64
            {
                pa.push(a.cell_center(x, y));
                pb.push(*q);
            }
        }
        if pa.len() < p.min_pairs {
            return *t_a_b;
        }
        let Some(m) = fit(Model::Rigid, &pa, &pb) else { return *t_a_b };
        t = pose(m[(0, 2)], m[(1, 2)], m[(1, 0)].atan2(m[(0, 0)]));
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};

    #[test]
    fn icp_pulls_a_near_miss_onto_the_walls() {
        let map = generate(9, &FloorplanParams::default());
        let walls = wall_points(&map);
        let off = pose(0.12, -0.08, 0.012); // 2-3 cells and 0.7 degrees off
        let fixed = refine(&map, &walls, &off, &RefineParams::default());
        assert!(fixed.translation.vector.norm() < 0.02, "{fixed:?}");
        assert!(fixed.rotation.angle().abs() < 0.002, "{fixed:?}");
        let same = refine(&map, &walls, &off, &RefineParams { enabled: false, ..Default::default() });
        assert_eq!(same, off);
    }
}
