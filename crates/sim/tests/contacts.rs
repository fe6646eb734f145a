//! Contacts stop robots at walls; same seed, same trajectories and scans.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

mod common;

use mrslam_core::{Xyt, pose};
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, Sim, SlipParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn a_robot_driven_into_a_wall_stops_and_never_passes_through() {
    // room 6 x 4, east wall's inner face at x = 5.95
    let spec = common::room(6.0, 4.0, 0.1);
    for seed in 0..100u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (model, lidar) = if seed % 2 == 0 {
            (RobotModel::prawn(), LidarModel::rplidar_a1())
        } else {
            (RobotModel::experia(), LidarModel::hokuyo_urg_04lx())
        };
        let reach = model.footprint.bounding_radius();
        let heading = rng.random_range(-0.6..0.6);
        let start = pose(5.95 - reach - 0.8, 2.0 + rng.random_range(-0.5..0.5), heading);
        let mut sim = Sim::new(&spec, seed).unwrap();
        let id =
            sim.add_robot("r", model.clone(), lidar, SlipParams::default(), EncoderParams::default(), start).unwrap();
        sim.set_velocity_command(id, model.max_speed, rng.random_range(-0.1..0.1)).unwrap();
        let mut touched = false;
        for _ in 0..500 {
            let ev = sim.step();
            touched |= ev.robots[0].contact;
            let Xyt { x, y, .. } = Xyt::from_pose(&sim.true_pose(id).unwrap());
            // the footprint's farthest point never crosses the inner face by more than 1 cm
            assert!(x < 5.95 + 0.01, "seed {seed}: centre at x = {x}");
            assert!(y > 0.05 && y < 3.95, "seed {seed}: y = {y}");
            if let mrslam_sim::Footprint::Circle { radius } = model.footprint {
                assert!(x + radius < 5.95 + 0.01, "seed {seed}: disc edge at {}", x + radius);
            }
            assert!(x < 5.95 - 0.5 * reach, "seed {seed}: centre too close to the wall: {x}");
            // the footprint shrunk by 1 cm never overlaps the walls: penetration stays below 1 cm
            let shrunk = match model.footprint {
                mrslam_sim::Footprint::Circle { radius } => mrslam_sim::Footprint::Circle { radius: radius - 0.01 },
                mrslam_sim::Footprint::Box { length, width } => {
                    mrslam_sim::Footprint::Box { length: length - 0.02, width: width - 0.02 }
                }
            };
            assert!(
                !sim.world().footprint_collides(&shrunk, &sim.true_pose(id).unwrap()),
                "seed {seed}: penetrates the wall"
            );
        }
        assert!(touched, "seed {seed}: never touched the wall");
        assert!(sim.contacts(id).unwrap() > 0, "seed {seed}: not resting against the wall");
        // the wheels kept turning against the wall: odometry went further than the robot did
        let odo = sim.odometry(id).unwrap().pose.translation.vector.norm();
        let moved = (sim.true_pose(id).unwrap().translation.vector - start.translation.vector).norm();
        assert!(odo > moved + 0.5, "seed {seed}: odometry {odo} vs moved {moved}");
    }
}

/// True poses, scans and odometry poses of a run.
type Run = (Vec<[f64; 3]>, Vec<Vec<f32>>, Vec<[f64; 3]>);

fn run(seed: u64) -> Run {
    let spec = mrslam_sim::WorldSpec::from_toml_file(common::world_path("two_rooms.toml")).unwrap();
    let mut sim = Sim::new(&spec, seed).unwrap();
    let a = sim
        .add_robot(
            "experia",
            RobotModel::experia(),
            LidarModel::hokuyo_urg_04lx(),
            SlipParams::default(),
            EncoderParams::default(),
            spec.named_pose("start_experia").unwrap(),
        )
        .unwrap();
    let b = sim
        .add_robot(
            "prawn",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::default(),
            EncoderParams::default(),
            spec.named_pose("start_prawn").unwrap(),
        )
        .unwrap();
    let (mut poses, mut scans, mut odos) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..600 {
        let t = k as f64 * 0.01;
        sim.set_velocity_command(a, 0.3, 0.4 * (t * 0.7).sin()).unwrap();
        sim.set_velocity_command(b, 0.25, -0.5 * (t * 0.5).cos()).unwrap();
        sim.step();
        for id in [a, b] {
            let Xyt { x, y, theta: th } = Xyt::from_pose(&sim.true_pose(id).unwrap());
            poses.push([x, y, th]);
            let Xyt { x, y, theta: th } = Xyt::from_pose(&sim.odometry(id).unwrap().pose);
            odos.push([x, y, th]);
            if let Some(s) = sim.take_scan(id).unwrap() {
                scans.push(s.ranges);
            }
        }
    }
    (poses, scans, odos)
}

#[test]
fn same_seed_gives_identical_trajectories_and_scans() {
    let (p1, s1, o1) = run(42);
    let (p2, s2, o2) = run(42);
    assert_eq!(p1, p2);
    assert_eq!(o1, o2);
    assert_eq!(s1.len(), s2.len());
    assert!(!s1.is_empty());
    for (a, b) in s1.iter().zip(&s2) {
        assert_eq!(a.len(), b.len());
        assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
    }
    let (p3, s3, _) = run(43);
    assert_ne!(p1, p3);
    assert!(s1.iter().zip(&s3).any(|(a, b)| a.iter().zip(b).any(|(x, y)| x.to_bits() != y.to_bits())));
}
