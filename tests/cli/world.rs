//! `mrslam world from-map`: a map's occupied cells become the world's obstacles, exactly; starts where a robot
//! fits; bad maps refused.

use crate::util::{mrslam, p, text};
use mrslam_core::map_io::write_ros_map;
use mrslam_core::{CellState, OccupancyGrid, pose};
use mrslam_sim::{World, WorldSpec};

/// An 8 m × 5 m floor at 0.05 m: outer walls two cells thick, a partition with a door, a pillar, unknown
/// outside.
fn floor() -> OccupancyGrid {
    let (w, h) = (170, 110);
    let mut g = OccupancyGrid::new(w, h, 0.05, pose(-1.5, 2.0, 0.0)).unwrap();
    for y in 5..105 {
        for x in 5..165 {
            let outer = x < 7 || y < 7 || x >= 163 || y >= 103;
            let partition = (90..92).contains(&x) && !(40..60).contains(&y);
            let pillar = (40..44).contains(&x) && (70..74).contains(&y);
            g.set(x, y, if outer || partition || pillar { 3.0 } else { -3.0 });
        }
    }
    g
}

#[test]
fn a_world_from_a_map_has_its_walls_exactly_on_the_occupied_cells() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = floor();
    let map = d.join("maps/floor.yaml");
    std::fs::create_dir_all(map.parent().unwrap()).unwrap();
    write_ros_map(&grid, &map).unwrap();
    let world_path = d.join("floor.toml");
    let o = mrslam(&["world", "from-map", p(&map), "-o", p(&world_path)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("start_a") && out.contains("start_b"), "{out}");
    let file = std::fs::read_to_string(&world_path).unwrap();
    assert!(file.contains("map = \"maps/floor.yaml\""), "the map is named relative to the world: {file}");

    let spec = WorldSpec::from_toml_file(&world_path).unwrap();
    let world = World::from_spec(&spec).unwrap();
    // Every cell's centre is inside an obstacle exactly when the cell is occupied.
    let mut wrong = Vec::new();
    for y in 0..grid.height() {
        for x in 0..grid.width() {
            let c = grid.cell_center(x as i64, y as i64);
            if world.is_occupied(&c) != (grid.state(x, y) == CellState::Occupied) {
                wrong.push((x, y));
            }
        }
    }
    assert!(wrong.is_empty(), "{} cells disagree, first {:?}", wrong.len(), &wrong[..wrong.len().min(5)]);
    // The starts: in free space, every cell centre within 0.4 m free (so the nearest wall cell's centre is at least
    // 0.4 m away), on the two sides of the partition's door.
    for name in ["start_a", "start_b"] {
        let s = world.named_pose(name).unwrap();
        let (x, y) = grid.world_to_cell(&s.translation.vector.into()).unwrap();
        assert_eq!(grid.state(x, y), CellState::Free, "{name}");
        for (dx, dy) in [(7, 0), (0, 7), (-7, 0), (0, -7), (5, 5), (-5, 5), (5, -5), (-5, -5)] {
            let (qx, qy) = ((x as i64 + dx) as usize, (y as i64 + dy) as usize);
            assert_eq!(grid.state(qx, qy), CellState::Free, "{name}: a cell not free within 0.4 m");
        }
    }
    let (a, b) = (world.named_pose("start_a").unwrap(), world.named_pose("start_b").unwrap());
    let partition_x = grid.cell_center(91, 0).x;
    assert!((a.translation.x - partition_x).signum() != (b.translation.x - partition_x).signum(), "{a:?} {b:?}");

    // The map elsewhere: named by its absolute path, and the world still loads.
    let other = tempfile::tempdir().unwrap();
    let far = other.path().join("far.toml");
    let o = mrslam(&["world", "from-map", p(&map), "-o", p(&far)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(WorldSpec::from_toml_file(&far).is_ok());
}

#[test]
fn maps_a_world_cannot_come_from_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("w.toml");
    // No such map: named.
    let missing = d.join("missing.yaml");
    let o = mrslam(&["world", "from-map", p(&missing), "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains(p(&missing)), "{}", text(&o.stderr));
    // A map without walls.
    let mut empty = OccupancyGrid::new(20, 20, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
    for y in 0..20 {
        for x in 0..20 {
            empty.set(x, y, -3.0);
        }
    }
    let map = d.join("empty.yaml");
    write_ros_map(&empty, &map).unwrap();
    let o = mrslam(&["world", "from-map", p(&map), "-o", p(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("no occupied cell"), "{}", text(&o.stderr));
    // A floor too tight for a robot at the clearance asked.
    write_ros_map(&floor(), &map).unwrap();
    let o = mrslam(&["world", "from-map", p(&map), "-o", p(&out), "--clearance", "3"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("no place to start a robot"), "{}", text(&o.stderr));
    // Not a world file name; and nothing was written by any of these.
    let o = mrslam(&["world", "from-map", p(&map), "-o", p(&d.join("w.yaml"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--output"), "{}", text(&o.stderr));
    assert!(!out.exists() && !d.join("w.yaml").exists());
}
