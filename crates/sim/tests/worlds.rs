//! The shipped worlds load, their named points are free, bad input is reported precisely.

mod common;

use mrslam_core::{CellState, pose};
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, Sim, SimError, SlipParams, World, WorldSpec};

#[test]
fn shipped_worlds_load_with_free_named_points() {
    for (file, area) in [("corridor.toml", (200.0, 300.0)), ("two_rooms.toml", (40.0, 60.0))] {
        let spec = WorldSpec::from_toml_file(common::world_path(file)).unwrap();
        for name in ["start_experia", "start_prawn", "common"] {
            assert!(spec.named_points.contains_key(name), "{file}: no {name}");
        }
        let world = World::from_spec(&spec).unwrap();
        let (lo, hi) = world.bounds();
        let a = (hi.x - lo.x) * (hi.y - lo.y);
        assert!(a > area.0 && a < area.1, "{file}: area {a}");
        let mut sim = Sim::new(&spec, 0).unwrap();
        sim.add_robot(
            "experia",
            RobotModel::experia(),
            LidarModel::hokuyo_urg_04lx(),
            SlipParams::default(),
            EncoderParams::default(),
            spec.named_pose("start_experia").unwrap(),
        )
        .unwrap();
        sim.add_robot(
            "prawn",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::default(),
            EncoderParams::default(),
            spec.named_pose("start_prawn").unwrap(),
        )
        .unwrap();
        // both robots fit at the common point
        assert!(!world.footprint_collides(&RobotModel::experia().footprint, &spec.named_pose("common").unwrap()));
        let map = world.true_map(0.05).unwrap();
        let (free, occ, unknown) = map.state_counts();
        assert!(occ > 0 && free > occ && unknown == 0, "{file}");
    }
}

#[test]
fn corridor_is_feature_rich_for_a_4m_hokuyo() {
    // along the corridor's centre line, every Hokuyo scan sees something that is not a straight wall:
    // count beams whose hit point is off the two main wall faces
    let spec = WorldSpec::from_toml_file(common::world_path("corridor.toml")).unwrap();
    let world = World::from_spec(&spec).unwrap();
    let lidar = LidarModel::hokuyo_urg_04lx();
    let mut x = 2.0;
    while x < 48.0 {
        let mut features = 0;
        for i in 0..lidar.beam_count() {
            let a = lidar.angle_min() + i as f64 * lidar.resolution;
            let o = nalgebra::Point2::new(x, 2.5);
            if let Some(r) = world.cast_ray(&o, a, lidar.range_max) {
                let hy = 2.5 + r * a.sin();
                if (hy - 0.075).abs() > 0.02 && (hy - 4.925).abs() > 0.02 {
                    features += 1;
                }
            }
        }
        assert!(features >= 10, "x = {x}: only {features} feature beams");
        x += 0.5;
    }
}

#[test]
fn start_inside_an_obstacle_is_an_error() {
    let spec = WorldSpec::from_toml_file(common::world_path("two_rooms.toml")).unwrap();
    let mut sim = Sim::new(&spec, 0).unwrap();
    // inside the round table, and straddling the partition wall
    for p in [pose(3.0, 2.2, 0.0), pose(5.6, 3.5, 0.0), pose(0.05, 2.0, 0.0)] {
        let r = sim.add_robot(
            "x",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::none(),
            EncoderParams::default(),
            p,
        );
        assert!(matches!(r, Err(SimError::StartInObstacle { .. })), "{r:?}");
    }
    let ok = sim.add_robot(
        "a",
        RobotModel::prawn(),
        LidarModel::rplidar_a1(),
        SlipParams::none(),
        EncoderParams::default(),
        pose(8.0, 2.5, 0.0),
    );
    assert!(ok.is_ok());
    // on top of another robot
    let r = sim.add_robot(
        "b",
        RobotModel::prawn(),
        LidarModel::rplidar_a1(),
        SlipParams::none(),
        EncoderParams::default(),
        pose(8.1, 2.5, 0.0),
    );
    assert!(matches!(r, Err(SimError::StartInObstacle { .. })));
}

#[test]
fn world_file_errors_name_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let cases = [
        ("[[boxes]]\ncenter = [1, 1]\nsize = [1, 1]\nheight = 2\n", 4, "height"),
        ("[[boxes]]\ncenter = [1, 1]\n\nsize = [1, -1]\n", 4, "boxes[0].size"),
        (
            "[[circles]]\ncenter = [1, 1]\nradius = 0.5\n[[circles]]\ncenter = [1, 1]\nradius = -0.5\n",
            6,
            "circles[1].radius",
        ),
        ("[[polygons]]\npoints = [[0, 0], [1, 1], [2, 2]]\n", 2, "polygons[0].points"),
        ("[[walls]]\npoints = [[0, 0], [1, 0]]\nthickness = 0\n", 3, "walls[0].thickness"),
    ];
    for (text, line, field) in cases {
        std::fs::write(&path, text).unwrap();
        match WorldSpec::from_toml_file(&path) {
            Err(e @ SimError::WorldFile { .. }) => {
                let s = e.to_string();
                let want = format!("{}:{line}: field `{field}`", path.display());
                assert!(s.starts_with(&want), "got `{s}`, want `{want}...`");
            }
            other => panic!("{text}: {other:?}"),
        }
    }
    assert!(matches!(WorldSpec::from_toml_file(dir.path().join("missing.toml")), Err(SimError::Io { .. })));
}

#[test]
fn bitmap_layer_becomes_merged_obstacles() {
    let dir = tempfile::tempdir().unwrap();
    // a 40 x 30 cell map at 0.1 m: a border wall and one 5 x 5 block
    let (w, h) = (40usize, 30usize);
    let mut cells = vec![-2.0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            if x == 0 || y == 0 || x == w - 1 || y == h - 1 || ((20..25).contains(&x) && (10..15).contains(&y)) {
                cells[y * w + x] = 2.0;
            }
        }
    }
    let grid = mrslam_core::OccupancyGrid::from_cells(w, h, 0.1, pose(-1.0, -1.0, 0.0), cells).unwrap();
    mrslam_core::map_io::write_ros_map(&grid, &dir.path().join("floor.yaml")).unwrap();
    let world_file = dir.path().join("w.toml");
    std::fs::write(
        &world_file,
        "name = \"bitmap\"\n[bitmap]\nmap = \"floor.yaml\"\n[named_points]\ns = { x = 0, y = 0 }\n",
    )
    .unwrap();
    let spec = WorldSpec::from_toml_file(&world_file).unwrap();
    let world = World::from_spec(&spec).unwrap();
    // 2 full rows, 2 side columns, 1 block
    assert_eq!(world.obstacles().len(), 5);
    assert!(world.is_occupied(&nalgebra::Point2::new(1.25, 0.25)));
    assert!(!world.is_occupied(&nalgebra::Point2::new(0.0, 0.0)));
    let r = world.cast_ray(&nalgebra::Point2::new(0.0, 0.25), 0.0, 10.0).unwrap();
    assert!((r - 1.0).abs() < 1e-9, "{r}");
    // the true map reproduces the bitmap's occupied cells
    let truth = world.true_map(0.1).unwrap();
    let (ix, iy) = truth.world_to_cell(&nalgebra::Point2::new(1.25, 0.25)).unwrap();
    assert_eq!(truth.state(ix, iy), CellState::Occupied);
    // a robot in the open space runs
    let mut sim = Sim::new(&spec, 0).unwrap();
    let id = sim
        .add_robot(
            "p",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::none(),
            EncoderParams::default(),
            pose(0.0, 0.0, 0.0),
        )
        .unwrap();
    sim.set_velocity_command(id, 0.5, 0.0).unwrap();
    for _ in 0..300 {
        sim.step();
    }
    assert!(sim.true_pose(id).unwrap().translation.x < 1.0 - 0.15 + 0.01);
}

#[test]
fn a_bitmaps_unknown_cells_may_be_walls_so_the_building_is_closed() {
    let dir = tempfile::tempdir().unwrap();
    // A 30 x 20 cell map at 0.1 m: a free room of 10 x 10 cells in the middle, unknown around it, no wall.
    let (w, h) = (30usize, 20usize);
    let cells: Vec<f32> = (0..w * h)
        .map(|i| if (10..20).contains(&(i % w)) && (5..15).contains(&(i / w)) { -2.0 } else { 0.0 })
        .collect();
    let grid = mrslam_core::OccupancyGrid::from_cells(w, h, 0.1, pose(0.0, 0.0, 0.0), cells).unwrap();
    mrslam_core::map_io::write_ros_map(&grid, &dir.path().join("floor.yaml")).unwrap();
    let world_at = |unknown: &str| {
        let file = dir.path().join("w.toml");
        std::fs::write(&file, format!("name = \"room\"\n[bitmap]\nmap = \"floor.yaml\"\n{unknown}\n")).unwrap();
        WorldSpec::from_toml_file(&file).map(|spec| World::from_spec(&spec).unwrap())
    };
    let open = world_at("").unwrap();
    let closed = world_at("unknown = \"occupied\"").unwrap();
    let (inside, outside) = (nalgebra::Point2::new(1.5, 1.0), nalgebra::Point2::new(0.5, 1.0));
    assert!(!open.is_occupied(&outside) && !open.is_occupied(&inside));
    assert!(closed.is_occupied(&outside) && !closed.is_occupied(&inside));
    // A beam east from the room's middle stops at the room's edge (x = 2.0 m) in the closed world only.
    let r = closed.cast_ray(&inside, 0.0, 10.0).unwrap();
    assert!((r - 0.5).abs() < 1e-9, "{r}");
    assert!(open.cast_ray(&inside, 0.0, 10.0).is_none());
    // Anything else names the field and the line.
    let e = world_at("unknown = \"walls\"").unwrap_err().to_string();
    assert!(e.contains("w.toml:2: field `bitmap.unknown`: expected \"free\" or \"occupied\""), "{e}");
}
