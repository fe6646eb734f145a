//! Ground truth: the true occupancy grid rasterised from the world's geometry.

use crate::error::{SimError, check_positive};
use crate::world::World;
use mrslam_core::map_io::ROS_LOGODDS_LIMIT;
use mrslam_core::{OccupancyGrid, pose};
use nalgebra::{Point2, Vector2};

impl World {
    /// The true occupancy grid at `resolution` metres per cell, covering the world's bounds plus two
    /// cells: a cell is occupied when any obstacle overlaps it (so thin walls never leave gaps and the
    /// interior of a wall band is occupied), all other cells are free.
    pub fn true_map(&self, resolution: f64) -> Result<OccupancyGrid, SimError> {
        check_positive("true_map resolution", resolution)?;
        let (lo, hi) = self.bounds();
        let margin = 2.0 * resolution;
        let origin = lo - Vector2::new(margin, margin);
        let w = ((hi.x - lo.x + 2.0 * margin) / resolution).ceil() as usize;
        let h = ((hi.y - lo.y + 2.0 * margin) / resolution).ceil() as usize;
        let mut grid = OccupancyGrid::new(w, h, resolution, pose(origin.x, origin.y, 0.0))
            .map_err(|e| crate::error::bad_param("true_map resolution", e.to_string()))?;
        grid.cells_mut().fill(-ROS_LOGODDS_LIMIT);
        for o in self.obstacles() {
            let (a, b) = o.aabb();
            let x0 = (((a.x - origin.x) / resolution).floor().max(0.0) as usize).min(w - 1);
            let x1 = (((b.x - origin.x) / resolution).floor().max(0.0) as usize).min(w - 1);
            let y0 = (((a.y - origin.y) / resolution).floor().max(0.0) as usize).min(h - 1);
            let y1 = (((b.y - origin.y) / resolution).floor().max(0.0) as usize).min(h - 1);
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let i = grid.index(ix, iy);
                    if grid.cells()[i] > 0.0 {
                        continue;
                    }
                    let clo = Point2::new(origin.x + ix as f64 * resolution, origin.y + iy as f64 * resolution);
                    let chi = clo + Vector2::new(resolution, resolution);
                    if o.overlaps_aabb(&clo, &chi) {
                        grid.cells_mut()[i] = ROS_LOGODDS_LIMIT;
                    }
                }
            }
        }
        Ok(grid)
    }
}

#[cfg(test)]
mod tests {
    use crate::world::World;
    use crate::world_file::{CircleSpec, WallSpec, WorldSpec};
    use mrslam_core::CellState;
    use nalgebra::Point2;

    #[test]
    fn rasterises_walls_and_furniture() {
        let spec = WorldSpec {
            walls: vec![WallSpec {
                points: vec![[0.0, 0.0], [5.0, 0.0], [5.0, 4.0], [0.0, 4.0], [0.0, 0.0]],
                thickness: 0.1,
            }],
            circles: vec![CircleSpec { center: [2.5, 2.0], radius: 0.3 }],
            ..WorldSpec::default()
        };
        let w = World::from_spec(&spec).unwrap();
        for res in [0.05, 0.2, 0.5] {
            let g = w.true_map(res).unwrap();
            let at = |x: f64, y: f64| {
                let (ix, iy) = g.world_to_cell(&Point2::new(x, y)).unwrap();
                g.state(ix, iy)
            };
            assert_eq!(at(2.5, 0.0), CellState::Occupied);
            assert_eq!(at(5.0, 2.0), CellState::Occupied);
            assert_eq!(at(2.5, 2.0), CellState::Occupied);
            assert_eq!(at(1.0, 1.0), CellState::Free);
            // a closed wall loop leaves no gap at any resolution: walk along the bottom wall
            let mut x = 0.0;
            while x <= 5.0 {
                assert_eq!(at(x, 0.0), CellState::Occupied, "gap at x={x} res={res}");
                x += res / 3.0;
            }
        }
        let g = w.true_map(0.05).unwrap();
        let (free, occ, unk) = g.state_counts();
        assert_eq!(unk, 0);
        assert!(occ > 0 && free > occ);
        assert!(w.true_map(0.0).is_err());
    }
}
