//! Map b's walls as a point set: occupied cells (or blocks) in b's map frame, thinned evenly, about their
//! centroid, and their cell offsets once rotated.

use crate::field::BlockStates;
use mrslam_core::{CellState, OccupancyGrid};
use nalgebra::{Point2, Rotation2, Vector2};

/// Wall points of map b relative to their centroid.
#[derive(Debug, Clone)]
pub struct WallScan {
    /// Centroid of the points, b's map frame.
    pub centroid: Point2<f64>,
    /// Points minus the centroid, metres.
    pub points: Vec<Vector2<f64>>,
    /// Largest distance of a point from the centroid, metres.
    pub radius: f64,
}

impl WallScan {
    /// Centres of `b`'s occupied blocks of `factor × factor` cells, at most `max_points` (an even stride over
    /// them in row-major order; 0 keeps all).
    pub fn of_blocks(b: &OccupancyGrid, factor: usize, max_points: usize) -> Self {
        let blocks = BlockStates::of(b, factor);
        let f = blocks.factor as f64;
        let all: Vec<Point2<f64>> = (0..blocks.height)
            .flat_map(|y| (0..blocks.width).map(move |x| (x, y)))
            .filter(|&(x, y)| blocks.states[y * blocks.width + x] == CellState::Occupied)
            .map(|(x, y)| b.cell_f_to_world((x as f64 + 0.5) * f, (y as f64 + 0.5) * f))
            .collect();
        Self::of_points(&all, max_points)
    }

    /// `all` thinned to at most `max_points` by an even stride (0 keeps all), about their centroid.
    pub fn of_points(all: &[Point2<f64>], max_points: usize) -> Self {
        let stride = if max_points == 0 { 1 } else { all.len().div_ceil(max_points).max(1) };
        let kept: Vec<Point2<f64>> = all.iter().step_by(stride).copied().collect();
        let n = kept.len().max(1) as f64;
        let centroid = Point2::from(kept.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / n);
        let points: Vec<Vector2<f64>> = kept.iter().map(|p| p - centroid).collect();
        let radius = points.iter().map(|v| v.norm()).fold(0.0, f64::max);
        WallScan { centroid, points, radius }
    }

    /// The points turned by `theta` in cells of `cell` metres, rounded: cell offsets from the cell the
    /// centroid lands in. Written into `out` (cleared first).
    pub fn discretize(&self, theta: f64, cell: f64, out: &mut Vec<(i32, i32)>) {
        let r = Rotation2::new(theta);
        out.clear();
        out.extend(self.points.iter().map(|v| {
            let q = r * v / cell;
            (q.x.round() as i32, q.y.round() as i32)
        }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn points_are_thinned_evenly_and_centred() {
        let all: Vec<Point2<f64>> = (0..100).map(|i| Point2::new(i as f64, 0.0)).collect();
        let s = WallScan::of_points(&all, 10);
        assert_eq!(s.points.len(), 10);
        assert!((s.centroid.x - 45.0).abs() < 1e-9);
        assert!((s.radius - 45.0).abs() < 1e-9);
        let mut cells = Vec::new();
        s.discretize(std::f64::consts::FRAC_PI_2, 10.0, &mut cells);
        assert_eq!(cells[0], (0, -5)); // (-45, 0) turned a quarter: (0, -45), 4.5 cells rounds away from 0
        assert!(cells.iter().all(|c| c.0 == 0));
    }

    #[test]
    fn blocks_are_placed_at_their_centres() {
        let mut g = OccupancyGrid::new(8, 8, 0.1, pose(1.0, 2.0, 0.0)).unwrap();
        g.set(5, 6, 2.0);
        let s = WallScan::of_blocks(&g, 4, 0);
        assert_eq!(s.points.len(), 1);
        assert!((s.centroid - Point2::new(1.6, 2.6)).norm() < 1e-9, "{}", s.centroid);
    }
}
