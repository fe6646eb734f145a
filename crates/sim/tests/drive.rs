//! Driving: goal accuracy without slip, odometry drift growing with distance under slip.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

mod common;

use mrslam_core::pose::relative;
use mrslam_core::{Xyt, pose};
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, Sim, SlipParams, WorldSpec};

#[test]
fn straight_five_metres_without_slip_reaches_goal_and_odometry_agrees() {
    for (model, lidar) in
        [(RobotModel::experia(), LidarModel::hokuyo_urg_04lx()), (RobotModel::prawn(), LidarModel::rplidar_a1())]
    {
        let mut sim = Sim::new(&common::room(8.0, 3.0, 0.1), 7).unwrap();
        let start = pose(1.0, 1.5, 0.0);
        let id = sim.add_robot("r", model.clone(), lidar, SlipParams::none(), EncoderParams::default(), start).unwrap();
        let goal_x = 6.0;
        for _ in 0..3000 {
            let Xyt { x, .. } = Xyt::from_pose(&sim.true_pose(id).unwrap());
            let rem = goal_x - x;
            // slow down so the acceleration limit can stop the robot at the goal
            let v = (rem.signum() * (2.0 * 0.9 * model.max_accel * rem.abs()).sqrt())
                .clamp(-model.max_speed, model.max_speed);
            sim.set_velocity_command(id, if rem.abs() < 2e-4 { 0.0 } else { v }, 0.0).unwrap();
            let ev = sim.step();
            assert!(!ev.robots[0].contact);
        }
        let truth = sim.true_pose(id).unwrap();
        let Xyt { x, y, theta: th } = Xyt::from_pose(&truth);
        assert!(
            (x - goal_x).abs() < 0.01 && (y - 1.5).abs() < 0.01 && th.abs() < 1e-3,
            "{} ended at {x} {y} {th}",
            model.name
        );
        let odo = sim.odometry(id).unwrap();
        let rel = relative(&start, &truth);
        let err = (odo.pose.translation.vector - rel.translation.vector).norm();
        assert!(err < 0.01, "{}: odometry off by {err}", model.name);
        assert!((odo.stamp - sim.time()).abs() < 1e-9);
    }
}

/// Odometry position error after the robot's odometry says it has travelled 2 m and 10 m.
fn drift(seed: u64, slip: SlipParams) -> (f64, f64) {
    let mut sim = Sim::new(&WorldSpec::default(), seed).unwrap();
    let start = pose(0.0, 0.0, 0.0);
    let id = sim
        .add_robot("prawn", RobotModel::prawn(), LidarModel::rplidar_a1(), slip, EncoderParams::default(), start)
        .unwrap();
    sim.set_velocity_command(id, 0.5, 0.0).unwrap();
    let mut at2 = None;
    loop {
        sim.step();
        let odo = sim.odometry(id).unwrap().pose;
        let travelled = odo.translation.vector.norm();
        if travelled >= 2.0 || travelled >= 10.0 {
            let rel = relative(&start, &sim.true_pose(id).unwrap());
            let err = (odo.translation.vector - rel.translation.vector).norm();
            if at2.is_none() {
                at2 = Some(err);
            }
            if travelled >= 10.0 {
                return (at2.unwrap_or(err), err);
            }
        }
        assert!(sim.time() < 60.0, "robot did not get 10 m");
    }
}

#[test]
fn with_slip_odometry_error_grows_with_distance() {
    let runs: Vec<(f64, f64)> = (0..20).map(|s| drift(s, SlipParams::default())).collect();
    let m2 = runs.iter().map(|r| r.0).sum::<f64>() / runs.len() as f64;
    let m10 = runs.iter().map(|r| r.1).sum::<f64>() / runs.len() as f64;
    eprintln!("mean odometry error over 20 seeds: {m2:.4} m at 2 m, {m10:.4} m at 10 m");
    assert!(m2 > 0.0 && m10 > 0.0, "{m2} {m10}");
    assert!(m10 > m2, "mean error at 10 m {m10} <= at 2 m {m2}");
    // and without slip there is no drift at all
    let (a, b) = drift(0, SlipParams::none());
    assert!(a < 1e-3 && b < 1e-3, "{a} {b}");
}

#[test]
fn calibration_error_makes_systematic_drift() {
    let mut sim = Sim::new(&WorldSpec::default(), 1).unwrap();
    let enc = EncoderParams::default().with_calibration_error(0.02, 0.02, 0.0);
    let id = sim
        .add_robot(
            "e",
            RobotModel::experia(),
            LidarModel::hokuyo_urg_04lx(),
            SlipParams::none(),
            enc,
            pose(0.0, 0.0, 0.0),
        )
        .unwrap();
    sim.set_velocity_command(id, 0.5, 0.0).unwrap();
    for _ in 0..1000 {
        sim.step();
    }
    let truth = sim.true_pose(id).unwrap().translation.x;
    let odo = sim.odometry(id).unwrap().pose.translation.x;
    assert!((odo / truth - 1.02).abs() < 2e-3, "{odo} {truth}");
}

#[test]
fn bad_commands_and_ids_are_errors() {
    let mut sim = Sim::new(&WorldSpec::default(), 1).unwrap();
    let id = sim
        .add_robot(
            "e",
            RobotModel::experia(),
            LidarModel::hokuyo_urg_04lx(),
            SlipParams::none(),
            EncoderParams::default(),
            pose(0.0, 0.0, 0.0),
        )
        .unwrap();
    assert!(sim.set_wheel_command(id, f64::NAN, 0.0).is_err());
    assert!(sim.true_pose(mrslam_sim::RobotId(5)).is_err());
    assert!(matches!(
        sim.add_robot(
            "e",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::none(),
            EncoderParams::default(),
            pose(3.0, 0.0, 0.0)
        ),
        Err(mrslam_sim::SimError::DuplicateRobot(_))
    ));
    let bad = RobotModel { wheel_radius: -1.0, ..RobotModel::prawn() };
    assert!(
        sim.add_robot(
            "p",
            bad,
            LidarModel::rplidar_a1(),
            SlipParams::none(),
            EncoderParams::default(),
            pose(3.0, 0.0, 0.0)
        )
        .is_err()
    );
}
