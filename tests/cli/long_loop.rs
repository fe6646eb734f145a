//! A loop of more than 200 m through a real building, with exact truth: `mrslam sim log` drives
//! `scenarios/aces_loop.toml` (a Pioneer with the FR079-fitted odometry and a SICK-class lidar round the outer
//! corridors of ACES, `worlds/aces`, 208 m before it sees its start again) and writes the run as a CARMEN log,
//! its true trajectory and the relations the truth implies. The default SLAM (the CLI's `matched` preset, loop
//! closure while driving) must close the loop on every seed, and the map it holds a few metres after the
//! robot is back, before the log ends, must already be loop-closed.

use crate::util::{mrslam, p, root, text};
use mrslam_core::map_io::read_ros_map;
use mrslam_core::relations::{Relation, StampedPose, read_relations, score};
use mrslam_core::{CellState, OccupancyGrid, Pose2};
use mrslam_log::{ReadOptions, read_log};
use mrslam_slam::{Rbpf, SlamBackend, SlamParams, poses_at_every_scan};
use nalgebra::Point2;

/// Loop relations: drawn between scans far apart in time (the local ones span a metre, a few seconds).
fn loop_relations(relations: &[Relation]) -> Vec<Relation> {
    relations.iter().copied().filter(|r| r.t2 - r.t1 > 60.0).collect()
}

/// What the filter holds at one moment: a pose at every scan read so far, and its map.
struct Held {
    trajectory: Vec<StampedPose>,
    map: OccupancyGrid,
}

/// The poses the filter holds now, at every scan read so far (processed scans as the filter has them,
/// the others carried by odometry), as `map_log` gives them at the end.
fn held(filter: &Rbpf, stamps: &[f64], odometry: &[Pose2], processed: &[usize]) -> Held {
    let keyframes = filter.trajectory();
    assert_eq!(keyframes.len(), processed.len());
    let anchors: Vec<(usize, Pose2)> = processed.iter().copied().zip(keyframes.iter().map(|(_, p)| *p)).collect();
    let poses = poses_at_every_scan(stamps, odometry, &anchors).unwrap();
    let trajectory = stamps.iter().zip(poses).map(|(&stamp, pose)| StampedPose { stamp, pose }).collect();
    Held { trajectory, map: filter.map().unwrap() }
}

/// The share of the map's occupied cells that lie within `radius` metres of an obstacle of the world's map,
/// the map placed in the world by the robot's true pose at the first scan. A loop left open draws the corridors
/// where the robot came back a second time beside the first: those walls fall off the building's.
fn walls_on_true_walls(map: &OccupancyGrid, world: &OccupancyGrid, first_true: &Pose2, radius: f64) -> f64 {
    let reach = (radius / world.resolution()).ceil() as i64;
    let (mut on, mut all) = (0usize, 0usize);
    for iy in 0..map.height() {
        for ix in 0..map.width() {
            if map.state(ix, iy) != CellState::Occupied {
                continue;
            }
            all += 1;
            let w = first_true * map.cell_center(ix as i64, iy as i64);
            let (cx, cy) = world.world_to_cell_i(&Point2::new(w.x, w.y));
            let near = (-reach..=reach).any(|dy| {
                (-reach..=reach).any(|dx| {
                    let (x, y) = (cx + dx, cy + dy);
                    x >= 0
                        && y >= 0
                        && (x as usize) < world.width()
                        && (y as usize) < world.height()
                        && world.state(x as usize, y as usize) == CellState::Occupied
                })
            });
            on += usize::from(near);
        }
    }
    on as f64 / all.max(1) as f64
}

/// Generates the ACES loop with `seed`, maps `north`'s log with the default preset and checks the loop relations
/// a few metres after the robot is back at its start and at the end, and the map then against the world.
fn the_aces_loop_is_closed(seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("logs");
    let scenario = root().join("scenarios/aces_loop.toml");
    let seed_text = seed.to_string();
    let o = mrslam(&["sim", "log", p(&scenario), "--out", p(&out), "--seed", &seed_text, "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("log.json")).unwrap()).unwrap();
    let north = &summary["robots"][0];
    assert_eq!(north["name"], "north");
    assert!(north["longest_loop_m"].as_f64().unwrap() > 200.0, "seed {seed}: {north}");

    let relations = read_relations(&out.join("north.relations")).unwrap();
    let loops = loop_relations(&relations);
    assert!(!loops.is_empty(), "seed {seed}: the truth draws no loop relation");
    // A few metres after the robot is back where it started.
    let back = loops.iter().map(|r| r.t2).fold(f64::INFINITY, f64::min) + 10.0;
    let truth = mrslam_core::relations::read_trajectory(&out.join("north.truth")).unwrap();
    let world = read_ros_map(&root().join("worlds/aces/aces.yaml")).unwrap();

    let log = read_log(&out.join("north.clf"), &ReadOptions::default()).unwrap();
    let mut filter = Rbpf::new(SlamParams::matched(), log.scans[0].laser_offset, seed).unwrap();
    let (mut stamps, mut odometry, mut processed) = (Vec::new(), Vec::new(), Vec::new());
    let mut at_back = None;
    for (k, record) in log.scans.iter().enumerate() {
        if at_back.is_none() && record.scan.stamp > back {
            at_back = Some(held(&filter, &stamps, &odometry, &processed));
        }
        let outcome = filter.process(&record.odometry, &record.scan).unwrap();
        stamps.push(record.scan.stamp);
        odometry.push(filter.odometry_pose().unwrap_or(record.odometry.pose));
        if outcome.is_processed() {
            processed.push(k);
        }
    }
    let at_back = at_back.unwrap();
    let report = filter.finish();
    let at_end = held(&filter, &stamps, &odometry, &processed);

    // The odometry alone leaves the loop open: closing it is the SLAM's work.
    let dead_reckoning: Vec<StampedPose> =
        log.scans.iter().map(|r| StampedPose { stamp: r.scan.stamp, pose: r.odometry.pose }).collect();
    let open = score(&dead_reckoning, &loops, 1e-3).errors.iter().map(|e| e.translation).fold(0.0, f64::max);
    assert!(open > 1.0, "seed {seed}: the odometry alone is only {open:.2} m off across the loop");
    eprintln!("seed {seed}: the odometry alone {open:.2} m off across the loop");
    let first_true = truth[0].pose;
    for (when, held, relations) in [
        ("back at the start", &at_back, loops.iter().copied().filter(|r| r.t2 <= back).collect::<Vec<_>>()),
        ("at the end", &at_end, loops.clone()),
    ] {
        let s = score(&held.trajectory, &relations, 1e-3);
        assert_eq!(s.used(), relations.len(), "seed {seed}, {when}: every loop relation scored");
        let worst = s.errors.iter().map(|e| e.translation).fold(0.0, f64::max);
        let worst_rot = s.errors.iter().map(|e| e.rotation.to_degrees()).fold(0.0, f64::max);
        let on_walls = walls_on_true_walls(&held.map, &world, &first_true, 0.25);

        eprintln!(
            "seed {seed}, {when}: loop relations {} worst {worst:.3} m {worst_rot:.2} deg; walls on true walls {on_walls:.3}",
            s.used()
        );
        assert!(
            worst < 0.15 && worst_rot < 1.0,
            "seed {seed}, {when}: the loop is open: {worst:.3} m, {worst_rot:.2} deg"
        );
        assert!(on_walls > 0.95, "seed {seed}, {when}: {on_walls:.3} of the map's walls on the building's walls");
    }
    let report = report.unwrap();
    assert_eq!(report.open_loops, 0, "seed {seed}: {report:?}");
    assert!(report.judged > 0 && !report.contradicts_itself(), "seed {seed}: {report:?}");
}

#[test]
fn the_aces_loop_is_closed_on_seed_0() {
    the_aces_loop_is_closed(0);
}

#[test]
fn the_aces_loop_is_closed_on_seed_1() {
    the_aces_loop_is_closed(1);
}

#[test]
fn the_aces_loop_is_closed_on_seed_2() {
    the_aces_loop_is_closed(2);
}
