//! Walls for maps that do not mark them. A map stored the map_server way with its walls light grey (between the
//! free and occupied thresholds), or mapped through glass, holds almost no occupied cells: its structure is only the
//! boundary between free and unknown space. Every merger here and the verification gate look at walls, so such a map
//! is given walls where its free space meets unknown, before anything else; a map that marks its walls is left as
//! it is.

use mrslam_core::map_io::ROS_LOGODDS_LIMIT;
use mrslam_core::{CellState, OccupancyGrid};

/// Which maps get walls where their free space meets unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryWalls {
    /// Maps as they are (the paper's merger).
    Off,
    /// Maps that do not mark their walls (fewer occupied cells than [`BOUNDARY_STYLE_RATIO`] of their boundary).
    #[default]
    Unmarked,
    /// Every map, its own walls kept: the boundary of a map that marks only some of its walls completes them.
    ///
    /// A cut's edge and a robot's frontier are boundaries that are no walls, so this is a second try, not the
    /// first ([`crate::Cascade`]): on willow-full-0.05 cuts at 3-5 % overlap it merges 14 and 15 of 15 pairs
    /// against 2 and 7 as stored, on generated plans that mark every wall 8 of 20 at 20 % against 11.
    Always,
}

impl BoundaryWalls {
    /// Every mode, as the command line lists them.
    pub const ALL: [BoundaryWalls; 3] = [BoundaryWalls::Off, BoundaryWalls::Unmarked, BoundaryWalls::Always];

    /// The name: `off`, `unmarked` or `always`.
    pub const fn name(self) -> &'static str {
        match self {
            BoundaryWalls::Off => "off",
            BoundaryWalls::Unmarked => "unmarked",
            BoundaryWalls::Always => "always",
        }
    }
}

impl std::str::FromStr for BoundaryWalls {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        BoundaryWalls::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown boundary-walls mode `{s}` (expected off, unmarked or always)"))
    }
}

/// A map with fewer occupied cells than this fraction of its free/unknown boundary cells does not mark its walls.
/// Measured: a floor plan or FR079's SLAM maps have 0.5-0.9 occupied cells per boundary cell, ACES's SLAM maps only
/// 0.03-0.11 (fans of long rays through its windows end in unknown space), a map with its walls dropped 0.
pub const BOUNDARY_STYLE_RATIO: f64 = 0.01;

/// Unknown cells that touch a free cell (4-neighbourhood): where the walls of a map that does not mark them are.
fn boundary_cells(grid: &OccupancyGrid) -> Vec<(usize, usize)> {
    let (w, h) = (grid.width(), grid.height());
    let free = |x: usize, y: usize| grid.state(x, y) == CellState::Free;
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if grid.state(x, y) != CellState::Unknown {
                continue;
            }
            let touches = (x > 0 && free(x - 1, y))
                || (x + 1 < w && free(x + 1, y))
                || (y > 0 && free(x, y - 1))
                || (y + 1 < h && free(x, y + 1));
            if touches {
                out.push((x, y));
            }
        }
    }
    out
}

/// A map's free/unknown boundary, found once: whether the map marks its walls, and its walls in any mode.
#[derive(Debug, Clone)]
pub struct Boundary {
    /// Unknown cells touching free space.
    cells: Vec<(usize, usize)>,
    /// Occupied cells in the map.
    occupied: usize,
}

impl Boundary {
    /// The boundary of `grid`.
    pub fn of(grid: &OccupancyGrid) -> Self {
        let (_, occupied, _) = grid.state_counts();
        Boundary { cells: boundary_cells(grid), occupied }
    }

    /// Occupied cells in the map.
    pub fn occupied(&self) -> usize {
        self.occupied
    }

    /// Whether the map marks its walls: as many occupied cells as [`BOUNDARY_STYLE_RATIO`] of its boundary cells
    /// (or no boundary at all).
    pub fn marks_its_walls(&self) -> bool {
        self.cells.is_empty() || self.occupied as f64 >= BOUNDARY_STYLE_RATIO * self.cells.len() as f64
    }

    /// `grid` (the map this boundary is of) with walls on the boundary when `mode` asks for them; `None`: use it
    /// as it is.
    pub fn walls(&self, grid: &OccupancyGrid, mode: BoundaryWalls) -> Option<OccupancyGrid> {
        let wanted = match mode {
            BoundaryWalls::Off => false,
            BoundaryWalls::Unmarked => !self.marks_its_walls(),
            BoundaryWalls::Always => !self.cells.is_empty(),
        };
        wanted.then(|| {
            let mut g = grid.clone();
            for &(x, y) in &self.cells {
                g.set(x, y, ROS_LOGODDS_LIMIT);
            }
            g
        })
    }
}

/// Whether `grid` marks its walls ([`Boundary::marks_its_walls`]).
pub fn marks_its_walls(grid: &OccupancyGrid) -> bool {
    Boundary::of(grid).marks_its_walls()
}

/// `grid` with walls where its free space meets unknown, when it does not mark its walls (fewer occupied cells than
/// [`BOUNDARY_STYLE_RATIO`] of its boundary cells); `None` when it does (use it as it is).
pub fn walls_from_boundary(grid: &OccupancyGrid) -> Option<OccupancyGrid> {
    Boundary::of(grid).walls(grid, BoundaryWalls::Unmarked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use crate::pairs::{PairSpec, cut_pair};
    use crate::{MergeParams, SiftMerger, SiftMergerParams, merge};

    fn drop_walls(g: &OccupancyGrid) -> OccupancyGrid {
        let mut bare = g.clone();
        for y in 0..bare.height() {
            for x in 0..bare.width() {
                if bare.state(x, y) == CellState::Occupied {
                    bare.set(x, y, 0.0);
                }
            }
        }
        bare
    }

    fn count(g: &OccupancyGrid, s: CellState) -> usize {
        (0..g.height()).flat_map(|y| (0..g.width()).map(move |x| (x, y))).filter(|&(x, y)| g.state(x, y) == s).count()
    }

    #[test]
    fn a_plan_with_walls_is_left_alone_and_without_them_gets_them_back() {
        let plan = generate(5, &FloorplanParams { width_m: 12.0, height_m: 9.0, ..FloorplanParams::default() });
        assert!(walls_from_boundary(&plan).is_none(), "a floor plan marks its walls");
        // The same plan with its walls dropped to unknown: walls come back around the free space.
        let bare = drop_walls(&plan);
        let walled = walls_from_boundary(&bare).expect("a map without walls");
        assert_eq!(count(&walled, CellState::Free), count(&plan, CellState::Free), "free space untouched");
        // Every new wall lies where a wall of the plan was (the plan's walls bound its free space).
        let (mut on, mut all) = (0, 0);
        for y in 0..walled.height() {
            for x in 0..walled.width() {
                if walled.state(x, y) == CellState::Occupied {
                    all += 1;
                    on += (plan.state(x, y) == CellState::Occupied) as usize;
                }
            }
        }
        assert!(all > 100 && on as f64 > 0.95 * all as f64, "{on} of {all} new walls on the plan's walls");
    }

    #[test]
    fn a_pair_without_walls_merges_with_the_defaults_and_not_without_boundary_walls() {
        let plan = generate(7, &FloorplanParams { width_m: 24.0, height_m: 18.0, ..FloorplanParams::default() });
        let pair = cut_pair(&plan, &PairSpec { overlap: 0.5, max_shift_m: 3.0, rotate: true }, 7);
        let (a, b) = (drop_walls(&pair.a), drop_walls(&pair.b));
        let merger = SiftMerger::new(SiftMergerParams::default());
        let out = merge(&merger, &a, &b, &MergeParams::default());
        assert!(out.report.accepted, "{:?}", out.report.reason);
        let t = out.report.transform.unwrap().to_pose();
        let err = t.inv_mul(&pair.t_a_b);
        assert!(err.translation.vector.norm() < 0.1 && err.rotation.angle().abs() < 0.02, "{err:?}");
        let merged = out.merged.unwrap();
        assert_eq!(count(&merged, CellState::Occupied), 0, "the merged map is fused from the maps as given");
        let off = MergeParams { boundary_walls: BoundaryWalls::Off, ..MergeParams::default() };
        assert!(!merge(&merger, &a, &b, &off).report.accepted, "the maps as they are have nothing to merge on");
    }

    #[test]
    fn a_map_whose_rays_fan_into_unknown_keeps_its_own_walls() {
        // A 6 m room with walls, and 40 rays of free space 8 m long through a window into unknown (as ACES's
        // windows leave them): few occupied cells against many boundary cells, but walls all the same.
        let mut g = OccupancyGrid::new(400, 400, 0.05, mrslam_core::pose(0.0, 0.0, 0.0)).unwrap();
        for y in 100..220 {
            for x in 100..220 {
                let wall = x == 100 || y == 100 || x == 219 || y == 219;
                g.set(x, y, if wall { 3.0 } else { -3.0 });
            }
        }
        for k in 0..40 {
            let a = -0.6 + 1.2 * k as f64 / 39.0;
            for s in 0..160 {
                let (x, y) = (220.0 + s as f64 * a.cos(), 160.0 + s as f64 * a.sin());
                g.set(x as usize, y as usize, -3.0);
            }
        }
        let boundary = boundary_cells(&g).len();
        let occupied = count(&g, CellState::Occupied);
        assert!((occupied as f64) < 0.5 * boundary as f64, "{occupied} occupied, {boundary} boundary");
        assert!(walls_from_boundary(&g).is_none(), "a map with walls of its own is left alone");
    }
}
