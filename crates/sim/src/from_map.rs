//! A world made from a map (`mrslam world from-map`): the map's occupied cells are the obstacles (the world
//! file's bitmap layer), and start poses are chosen where a robot fits.

use mrslam_core::{CellState, OccupancyGrid, Pose2, Xyt, pose};
use std::collections::VecDeque;
use std::fmt::Write as _;

/// Room a start pose keeps from every cell not known free, metres: the robots' radius (0.2-0.25 m) and a margin.
pub const START_CLEARANCE_M: f64 = 0.4;

/// Chamfer distance weights (3-4): a step to a side neighbour costs 3, to a diagonal one 4; a cell's distance is
/// about a third of its value in cells.
const SIDE: u32 = 3;
const DIAGONAL: u32 = 4;

/// Each cell's distance to the nearest cell that is not free (occupied or unknown; off the map counts as not
/// free), in cells, by the 3-4 chamfer transform (within 8 % of Euclidean).
pub fn clearance_cells(grid: &OccupancyGrid) -> Vec<f64> {
    let (w, h) = (grid.width(), grid.height());
    let mut d: Vec<u32> =
        (0..w * h).map(|i| if grid.state(i % w, i / w) == CellState::Free { u32::MAX / 2 } else { 0 }).collect();
    // The border: outside the map is not free.
    let at = |d: &[u32], x: isize, y: isize| -> u32 {
        if x < 0 || y < 0 || x as usize >= w || y as usize >= h { 0 } else { d[y as usize * w + x as usize] }
    };
    for y in 0..h as isize {
        for x in 0..w as isize {
            let i = y as usize * w + x as usize;
            let v = d[i]
                .min(at(&d, x - 1, y) + SIDE)
                .min(at(&d, x, y - 1) + SIDE)
                .min(at(&d, x - 1, y - 1) + DIAGONAL)
                .min(at(&d, x + 1, y - 1) + DIAGONAL);
            d[i] = v;
        }
    }
    for y in (0..h as isize).rev() {
        for x in (0..w as isize).rev() {
            let i = y as usize * w + x as usize;
            let v = d[i]
                .min(at(&d, x + 1, y) + SIDE)
                .min(at(&d, x, y + 1) + SIDE)
                .min(at(&d, x + 1, y + 1) + DIAGONAL)
                .min(at(&d, x - 1, y + 1) + DIAGONAL);
            d[i] = v;
        }
    }
    d.into_iter().map(|v| v as f64 / SIDE as f64).collect()
}

/// Two start poses in `grid` (map frame, heading 0): the free cell farthest from anything not free, and the cell
/// farthest from it along the way through cells with at least `clearance` metres of room (so a robot can drive
/// from one to the other). `None` when no cell has that much room. Ties go to the lowest row, then column.
pub fn start_poses(grid: &OccupancyGrid, clearance: f64) -> Option<[Pose2; 2]> {
    let (w, h) = (grid.width(), grid.height());
    let room = clearance_cells(grid);
    let need = clearance / grid.resolution();
    let (a, best) =
        room.iter().enumerate().fold((0, f64::MIN), |(bi, bv), (i, &v)| if v > bv { (i, v) } else { (bi, bv) });
    if best < need {
        return None;
    }
    // Breadth-first along cells with room (4-neighbours): the last cell reached is the farthest along the way.
    let mut seen = vec![false; w * h];
    let mut queue = VecDeque::from([a]);
    seen[a] = true;
    let mut last = a;
    while let Some(i) = queue.pop_front() {
        last = i;
        let (x, y) = (i % w, i / w);
        let next =
            [(x > 0).then(|| i - 1), (x + 1 < w).then(|| i + 1), (y > 0).then(|| i - w), (y + 1 < h).then(|| i + w)];
        for j in next.into_iter().flatten() {
            if !seen[j] && room[j] >= need {
                seen[j] = true;
                queue.push_back(j);
            }
        }
    }
    let centre = |i: usize| {
        let p = grid.cell_center((i % w) as i64, (i / w) as i64);
        pose(p.x, p.y, 0.0)
    };
    Some([centre(a), centre(last)])
}

/// The text of a world file whose obstacles are the occupied cells of the map at `map_ref` (as the file will
/// name it: relative to the world file, or absolute), with `named_points`.
pub fn world_toml(name: &str, description: &str, map_ref: &str, named_points: &[(String, Pose2)]) -> String {
    let quote = |s: &str| toml::Value::String(s.to_string()).to_string();
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# Made by `mrslam world from-map`: the obstacles are the occupied cells of the bitmap layer's map."
    );
    let _ = writeln!(t, "name = {}", quote(name));
    let _ = writeln!(t, "description = {}", quote(description));
    let _ = writeln!(t, "\n[bitmap]\nmap = {}", quote(map_ref));
    if !named_points.is_empty() {
        let _ = writeln!(t, "\n[named_points]");
        for (n, p) in named_points {
            let Xyt { x, y, theta } = Xyt::from_pose(p);
            let bare = !n.is_empty() && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            let key = if bare { n.clone() } else { quote(n) };
            let _ = writeln!(t, "{key} = {{ x = {x:.3}, y = {y:.3}, theta = {theta:.4} }}");
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 m × 2 m room at 0.1 m: walls on the border cells, unknown outside, a pillar at (1.0, 1.0).
    fn room() -> OccupancyGrid {
        let mut g = OccupancyGrid::new(32, 22, 0.1, pose(-0.1, -0.1, 0.0)).unwrap();
        for y in 1..21 {
            for x in 1..31 {
                let wall = x == 1 || y == 1 || x == 30 || y == 20 || (x == 11 && y == 11);
                g.set(x, y, if wall { 5.0 } else { -5.0 });
            }
        }
        g
    }

    #[test]
    fn clearance_is_the_distance_to_the_nearest_cell_not_free() {
        let g = room();
        let c = clearance_cells(&g);
        let at = |x: usize, y: usize| c[y * g.width() + x];
        assert_eq!(at(1, 1), 0.0, "a wall");
        assert_eq!(at(2, 5), 1.0, "next to the west wall");
        assert_eq!(at(5, 5), 4.0);
        assert_eq!(at(12, 11), 1.0, "next to the pillar");
        assert!((at(12, 12) - 4.0 / 3.0).abs() < 1e-9, "a diagonal step from the pillar: {}", at(12, 12));
    }

    #[test]
    fn starts_lie_in_the_open_and_far_apart() {
        let g = room();
        let [a, b] = start_poses(&g, 0.4).unwrap();
        let c = clearance_cells(&g);
        for p in [a, b] {
            let (x, y) = g.world_to_cell(&p.translation.vector.into()).unwrap();
            assert!(c[y * g.width() + x] * g.resolution() >= 0.4, "{p:?}");
        }
        let gap = (a.translation.vector - b.translation.vector).norm();
        assert!(gap > 1.0, "the second start is far along the room: {gap} m");
        assert!(start_poses(&g, 1.5).is_none(), "no cell has 1.5 m of room in a 2 m wide room");
    }

    #[test]
    fn the_world_text_names_the_map_and_the_points() {
        let points = [("start_a".into(), pose(1.0, 2.0, 0.5)), ("door 2".into(), pose(0.0, 0.0, 0.0))];
        let t = world_toml("lab \"7\"", "from lab.yaml", "maps/lab.yaml", &points);
        assert!(t.contains("\nstart_a = {"), "{t}");
        let v: toml::Value = toml::from_str(&t).unwrap();
        assert_eq!(v["name"].as_str(), Some("lab \"7\""));
        assert_eq!(v["bitmap"]["map"].as_str(), Some("maps/lab.yaml"));
        assert_eq!(v["named_points"]["start_a"]["theta"].as_float(), Some(0.5));
        assert_eq!(v["named_points"]["door 2"]["x"].as_float(), Some(0.0));
    }
}
