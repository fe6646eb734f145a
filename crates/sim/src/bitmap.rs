//! Bitmap layers: occupied cells of a ROS map merged into few rectangles (greedy row runs, then
//! vertical merging of identical runs), so a real floor plan stays cheap to simulate.

use crate::geometry::Obstacle;
use mrslam_core::{CellState, OccupancyGrid};
use nalgebra::{Point2, Vector2};

/// A rectangle of cells `[x0, x1) × [y0, y1)` in grid indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellRect {
    /// First column.
    pub x0: usize,
    /// One past the last column.
    pub x1: usize,
    /// First row.
    pub y0: usize,
    /// One past the last row.
    pub y1: usize,
}

/// Covers the occupied cells of `grid` exactly with disjoint rectangles.
pub fn merge_occupied(grid: &OccupancyGrid) -> Vec<CellRect> {
    let (w, h) = (grid.width(), grid.height());
    let mut done = Vec::new();
    // Rectangles still open at the previous row, keyed by their run (x0, x1).
    let mut open: Vec<CellRect> = Vec::new();
    for iy in 0..h {
        let mut runs = Vec::new();
        let mut ix = 0;
        while ix < w {
            if grid.state(ix, iy) == CellState::Occupied {
                let x0 = ix;
                while ix < w && grid.state(ix, iy) == CellState::Occupied {
                    ix += 1;
                }
                runs.push((x0, ix));
            } else {
                ix += 1;
            }
        }
        let mut next = Vec::with_capacity(runs.len());
        let mut oi = 0;
        for (x0, x1) in runs {
            // open rectangles are sorted by x0 and disjoint: advance past those left of this run
            while oi < open.len() && open[oi].x0 < x0 {
                done.push(open[oi]);
                oi += 1;
            }
            if oi < open.len() && open[oi].x0 == x0 && open[oi].x1 == x1 {
                let mut r = open[oi];
                r.y1 = iy + 1;
                next.push(r);
                oi += 1;
            } else {
                next.push(CellRect { x0, x1, y0: iy, y1: iy + 1 });
            }
        }
        done.extend_from_slice(&open[oi..]);
        open = next;
    }
    done.extend(open);
    done
}

/// The rectangles of [`merge_occupied`] as obstacles in the map frame.
pub fn occupied_obstacles(grid: &OccupancyGrid) -> Vec<Obstacle> {
    let res = grid.resolution();
    let origin = grid.origin();
    let angle = origin.rotation.angle();
    merge_occupied(grid)
        .into_iter()
        .map(|r| {
            let c = Point2::new(0.5 * (r.x0 + r.x1) as f64 * res, 0.5 * (r.y0 + r.y1) as f64 * res);
            Obstacle::Box {
                center: origin * c,
                half: Vector2::new(0.5 * (r.x1 - r.x0) as f64 * res, 0.5 * (r.y1 - r.y0) as f64 * res),
                angle,
            }
        })
        .collect()
}

/// Frees the occupied cells of `grid` that lie in 8-connected groups of fewer than `min_cells` cells: the specks
/// a SLAM map keeps in open space (a person walking by, a beam's noise) where the map's robot drove freely.
/// Returns the number of cells freed.
pub fn drop_specks(grid: &mut OccupancyGrid, min_cells: usize) -> usize {
    let (w, h) = (grid.width(), grid.height());
    let free = -mrslam_core::map_io::ROS_LOGODDS_LIMIT;
    let occupied: Vec<bool> =
        grid.cells().iter().map(|&l| CellState::from_log_odds(l) == CellState::Occupied).collect();
    let mut seen = vec![false; w * h];
    let (mut group, mut stack, mut freed) = (Vec::new(), Vec::new(), 0);
    for seed in 0..w * h {
        if !occupied[seed] || seen[seed] {
            continue;
        }
        seen[seed] = true;
        group.clear();
        stack.push(seed);
        while let Some(c) = stack.pop() {
            group.push(c);
            let (cx, cy) = ((c % w) as i64, (c / w) as i64);
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (x, y) = (cx + dx, cy + dy);
                    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                        continue;
                    }
                    let n = y as usize * w + x as usize;
                    if occupied[n] && !seen[n] {
                        seen[n] = true;
                        stack.push(n);
                    }
                }
            }
        }
        if group.len() < min_cells {
            let cells = grid.cells_mut();
            for &c in &group {
                cells[c] = free;
            }
            freed += group.len();
        }
    }
    freed
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    fn grid(rows: &[&str]) -> OccupancyGrid {
        let h = rows.len();
        let w = rows[0].len();
        let mut cells = vec![-5.0f32; w * h];
        for (r, row) in rows.iter().enumerate() {
            for (x, ch) in row.chars().enumerate() {
                if ch == '#' {
                    cells[(h - 1 - r) * w + x] = 5.0;
                }
            }
        }
        OccupancyGrid::from_cells(w, h, 0.5, pose(1.0, 2.0, 0.0), cells).unwrap()
    }

    #[test]
    fn rectangles_cover_exactly_the_occupied_cells() {
        let g = grid(&["##########", "#........#", "#..###...#", "#..###...#", "#.....##.#", "##########"]);
        let rects = merge_occupied(&g);
        let mut cover = vec![0u32; g.width() * g.height()];
        for r in &rects {
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    cover[g.index(x, y)] += 1;
                }
            }
        }
        for y in 0..g.height() {
            for x in 0..g.width() {
                let occ = g.state(x, y) == CellState::Occupied;
                assert_eq!(cover[g.index(x, y)], u32::from(occ), "cell {x},{y}");
            }
        }
        // top and bottom rows, two side columns, one 3x2 block, one 2x1 run
        assert_eq!(rects.len(), 6, "{rects:?}");
    }

    #[test]
    fn obstacles_sit_in_the_map_frame() {
        let g = grid(&["#.", ".."]);
        let obs = occupied_obstacles(&g);
        assert_eq!(obs.len(), 1);
        // cell (0, 1) spans x in [1, 1.5], y in [2.5, 3]
        assert!(obs[0].contains(&Point2::new(1.25, 2.75)));
        assert!(!obs[0].contains(&Point2::new(1.75, 2.75)));
    }

    #[test]
    fn specks_are_freed_and_walls_kept() {
        // A 2-cell speck, a lone cell on the border and a 10-cell wall on a 20 x 20 free grid.
        let mut g = OccupancyGrid::new(20, 20, 0.05, mrslam_core::pose(0.0, 0.0, 0.0)).unwrap();
        g.cells_mut().fill(-2.0);
        for (x, y) in [(5, 5), (6, 6), (0, 19)] {
            g.set(x, y, 2.0);
        }
        for x in 5..15 {
            g.set(x, 12, 2.0);
        }
        assert_eq!(drop_specks(&mut g, 4), 3);
        assert_eq!(g.state(5, 5), CellState::Free);
        assert_eq!(g.state(0, 19), CellState::Free);
        assert!((5..15).all(|x| g.state(x, 12) == CellState::Occupied));
        assert_eq!(drop_specks(&mut g, 11), 10, "a group of 10 cells is a speck when 11 are asked for");
    }
}
