//! Fusion: one grid in map a's frame holding both maps (paper Alg. 3, line 8).

use crate::resample::{GridGeometry, covering_geometry, known_corners, sample_cells};
use mrslam_core::{CellState, OccupancyGrid, Pose2};

/// How two aligned cells combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FusionRule {
    /// Sum the log-odds (independent evidence), clamped to ±`clamp`.
    LogOddsSum,
    /// m-explore's composition: occupied beats free beats unknown.
    OccupiedFreeUnknown,
}

impl std::str::FromStr for FusionRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "log-odds-sum" | "log_odds_sum" => Ok(FusionRule::LogOddsSum),
            "occupied-free-unknown" | "occupied_free_unknown" => Ok(FusionRule::OccupiedFreeUnknown),
            _ => Err(format!("unknown fusion rule `{s}` (expected log-odds-sum or occupied-free-unknown)")),
        }
    }
}

/// Log-odds clamp of fused cells.
pub const FUSION_CLAMP: f32 = 3.5;

/// Fuses `b`, placed by `t_a_b`, into a grid in a's map frame covering both maps' known cells, at a's
/// resolution.
pub fn fuse(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2, rule: FusionRule) -> OccupancyGrid {
    let mut pts = known_corners(a, &Pose2::identity()).to_vec();
    pts.extend_from_slice(&known_corners(b, t_a_b));
    let geo: GridGeometry = covering_geometry(&pts, a.resolution());
    let mut la = vec![0.0f32; geo.width * geo.height];
    let mut lb = vec![0.0f32; geo.width * geo.height];
    sample_cells(&geo, a, &Pose2::identity(), |i, l| la[i] = l);
    sample_cells(&geo, b, t_a_b, |i, l| lb[i] = l);
    let cells: Vec<f32> = la
        .iter()
        .zip(&lb)
        .map(|(&x, &y)| match rule {
            FusionRule::LogOddsSum => (x + y).clamp(-FUSION_CLAMP, FUSION_CLAMP),
            FusionRule::OccupiedFreeUnknown => {
                // The cell takes the value of whichever map says more (occupied > free > unknown); a wins ties.
                if CellState::from_log_odds(y) > CellState::from_log_odds(x) { y } else { x }
            }
        })
        .collect();
    OccupancyGrid::from_cells(geo.width, geo.height, geo.resolution, geo.origin, cells)
        .expect("fused geometry is valid by construction")
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn fused_grid_covers_both_and_combines() {
        let mut a = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let mut b = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        a.set(5, 5, -2.0);
        b.set(0, 5, 2.0); // lands on a's (5, 5) when b is shifted by 0.5 m
        b.set(9, 9, -2.0);
        let t = pose(0.5, 0.0, 0.0);
        let at = |g: &OccupancyGrid, x: f64, y: f64| {
            let c = g.world_to_cell(&nalgebra::Point2::new(x, y)).expect("on the fused grid");
            g.state(c.0, c.1)
        };
        let sum = fuse(&a, &b, &t, FusionRule::LogOddsSum);
        // the fused grid spans the known cells of both: x 0.5..1.5 m, y 0.5..1.0 m
        assert_eq!((sum.width(), sum.height()), (10, 5));
        assert_eq!(at(&sum, 0.55, 0.55), CellState::Unknown, "-2 + 2 = 0");
        assert_eq!(at(&sum, 1.45, 0.95), CellState::Free);
        let ofu = fuse(&a, &b, &t, FusionRule::OccupiedFreeUnknown);
        assert_eq!(at(&ofu, 0.55, 0.55), CellState::Occupied);
        assert_eq!(at(&ofu, 1.45, 0.95), CellState::Free);
        assert_eq!(at(&ofu, 0.95, 0.75), CellState::Unknown);
    }
}
