//! Lidar: beam counts, geometry within the noise bound, range limits, no self-hits, skew, backends.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

mod common;

use mrslam_core::{LaserScan, Pose2, Xyt, pose};
use mrslam_sim::{EncoderParams, LidarModel, RayBackend, RobotModel, Sim, SimConfig, SlipParams};

const T: f64 = 0.1; // wall thickness
const W: f64 = 9.0;
const H: f64 = 5.0;

fn inner(px: f64, py: f64, a: f64) -> f64 {
    common::box_range(px, py, a, T / 2.0, W - T / 2.0, T / 2.0, H - T / 2.0)
}

/// Checks every beam against the room's geometry; returns (valid, max-range, dropout) counts.
fn check_scan(scan: &LaserScan, lidar: &LidarModel, sensor: &Pose2) -> (usize, usize, usize) {
    let Xyt { x: sx, y: sy, theta: st } = Xyt::from_pose(sensor);
    let (mut valid, mut maxr, mut drop) = (0, 0, 0);
    for i in 0..scan.len() {
        let a = st + scan.angle(i);
        let r = inner(sx, sy, a);
        // angular jitter moves the beam: allow the range change of a 4-sigma direction error
        let j = 4.0 * lidar.angular_jitter;
        let dr = (inner(sx, sy, a + j) - r).abs().max((inner(sx, sy, a - j) - r).abs());
        let tol = 4.0 * lidar.range_sigma(r) + dr + 1e-4;
        let m = scan.ranges[i];
        if m.is_nan() {
            drop += 1;
            continue;
        }
        if r > lidar.range_max + tol {
            assert_eq!(m, f32::INFINITY, "beam {i}: true range {r} beyond range_max must read +inf");
            maxr += 1;
        } else if r < lidar.range_max - tol {
            assert!(scan.is_valid(i), "beam {i}: reading {m} for true range {r}");
            assert!((m as f64 - r).abs() <= tol, "beam {i}: {m} vs {r} (tol {tol})");
            valid += 1;
        }
    }
    (valid, maxr, drop)
}

fn sim_with(model: RobotModel, lidar: LidarModel, at: Pose2, backend: RayBackend) -> (Sim, mrslam_sim::RobotId) {
    let cfg = SimConfig { ray_backend: backend, ..SimConfig::default() };
    let mut sim = Sim::with_config(&common::room(W, H, T), 3, cfg).unwrap();
    let id = sim.add_robot("r", model, lidar, SlipParams::none(), EncoderParams::default(), at).unwrap();
    (sim, id)
}

fn first_scan(sim: &mut Sim, id: mrslam_sim::RobotId) -> LaserScan {
    for _ in 0..100 {
        sim.step();
        if let Some(s) = sim.take_scan(id).unwrap() {
            return s;
        }
    }
    panic!("no scan within 1 s");
}

#[test]
fn presets_match_room_geometry_within_noise() {
    for backend in [RayBackend::Grid, RayBackend::Rapier] {
        for (model, lidar, n) in [
            (RobotModel::experia(), LidarModel::hokuyo_urg_04lx(), 667),
            (RobotModel::prawn(), LidarModel::rplidar_a1(), 360),
        ] {
            let at = pose(2.2, 2.1, 0.4);
            let (mut sim, id) = sim_with(model, lidar.clone(), at, backend);
            let scan = first_scan(&mut sim, id);
            assert_eq!(scan.len(), n);
            assert_eq!(scan.stamp, 0.0);
            assert_eq!(scan.range_max as f64, lidar.range_max);
            assert!((scan.angle_increment - lidar.resolution).abs() < 1e-15);
            let (valid, maxr, drop) = check_scan(&scan, &lidar, &(at * lidar.mount));
            assert!(valid > n / 2, "{valid} valid of {n}");
            assert!(maxr > 0, "some beams must exceed range_max in a 9 m room");
            assert!(drop < n / 20, "{drop} dropouts");
        }
    }
}

#[test]
fn scans_are_published_once_per_period() {
    let (mut sim, id) = sim_with(RobotModel::prawn(), LidarModel::rplidar_a1(), pose(3.0, 2.0, 0.0), RayBackend::Grid);
    let mut stamps = Vec::new();
    for _ in 0..100 {
        let ev = sim.step();
        if ev.robots[0].scan_ready {
            stamps.push(sim.take_scan(id).unwrap().unwrap().stamp);
        }
        assert!(sim.take_scan(id).unwrap().is_none());
    }
    // 1 s of 200 ms scans: stamps 0, 0.2, ..., 0.8 (the scan started at 0.8 completes at 1.0)
    assert_eq!(stamps.len(), 5, "{stamps:?}");
    for (k, s) in stamps.iter().enumerate() {
        assert!((s - 0.2 * k as f64).abs() < 1e-9);
    }
}

#[test]
fn range_limits_are_honoured() {
    let lidar = LidarModel { range_min: 1.0, range_max: 2.0, ..LidarModel::hokuyo_urg_04lx().noiseless() };
    // close to the south-west corner: some walls within range_min, some beyond range_max
    let at = pose(0.75, 0.75, -2.3);
    let (mut sim, id) = sim_with(RobotModel::prawn(), lidar.clone(), at, RayBackend::Grid);
    let scan = first_scan(&mut sim, id);
    let sensor = at * lidar.mount;
    let Xyt { x: sx, y: sy, theta: st } = Xyt::from_pose(&sensor);
    let (mut close, mut far, mut ok) = (0, 0, 0);
    for i in 0..scan.len() {
        let r = inner(sx, sy, st + scan.angle(i));
        let m = scan.ranges[i];
        if r < 1.0 - 1e-6 {
            assert_eq!(m, f32::NEG_INFINITY);
            close += 1;
        } else if r > 2.0 + 1e-6 {
            assert_eq!(m, f32::INFINITY);
            assert!(scan.is_max_range(i));
            far += 1;
        } else if r > 1.0 + 1e-6 && r < 2.0 - 1e-6 {
            assert!((m as f64 - r).abs() < 1e-4);
            ok += 1;
        }
    }
    assert!(close > 0 && far > 0 && ok > 0, "{close} {far} {ok}");
}

#[test]
fn beams_never_hit_their_own_robot() {
    for backend in [RayBackend::Grid, RayBackend::Rapier] {
        // mount the lidar at the back of Experia's box so half the beams cross its own footprint
        let lidar = LidarModel { mount: pose(-0.2, 0.0, 0.0), ..LidarModel::rplidar_a1().noiseless() };
        let at = pose(3.5, 2.5, 0.0);
        let (mut sim, id) =
            sim_with(RobotModel::experia(), LidarModel { range_min: 0.0, ..lidar.clone() }, at, backend);
        let scan = first_scan(&mut sim, id);
        for i in 0..scan.len() {
            assert!(scan.ranges[i] > 1.0, "beam {i} hit something at {}", scan.ranges[i]);
        }
    }
}

#[test]
fn other_robots_are_seen() {
    for backend in [RayBackend::Grid, RayBackend::Rapier] {
        let lidar = LidarModel::rplidar_a1().noiseless();
        let (mut sim, id) = sim_with(RobotModel::prawn(), lidar.clone(), pose(2.0, 2.5, 0.0), backend);
        sim.add_robot(
            "other",
            RobotModel::prawn(),
            lidar,
            SlipParams::none(),
            EncoderParams::default(),
            pose(3.0, 2.5, 0.0),
        )
        .unwrap();
        let scan = first_scan(&mut sim, id);
        // the beam straight ahead (index 180 at angle 0) hits the other robot's disc at 1.0 - 0.15
        assert!((scan.angle(180)).abs() < 1e-12);
        assert!((scan.ranges[180] - 0.85).abs() < 1e-3, "{}", scan.ranges[180]);
    }
}

#[test]
fn backends_agree() {
    let lidar = LidarModel::hokuyo_urg_04lx().noiseless();
    let at = pose(4.1, 1.3, 2.0);
    let a =
        first_scan(&mut sim_with(RobotModel::experia(), lidar.clone(), at, RayBackend::Grid).0, mrslam_sim::RobotId(0));
    let b = first_scan(&mut sim_with(RobotModel::experia(), lidar, at, RayBackend::Rapier).0, mrslam_sim::RobotId(0));
    for i in 0..a.len() {
        let (x, y) = (a.ranges[i], b.ranges[i]);
        assert!(x == y || (x - y).abs() < 2e-4, "beam {i}: {x} vs {y}");
    }
}

#[test]
fn a_turning_rplidar_scan_is_skewed() {
    // turning in place at 1.5 rad/s: the last beam of a 200 ms scan is taken ~0.3 rad later than the first
    let run = |skew: bool| {
        let lidar = LidarModel { skew, ..LidarModel::rplidar_a1().noiseless() };
        let (mut sim, id) = sim_with(RobotModel::prawn(), lidar, pose(3.5, 2.5, 0.0), RayBackend::Grid);
        sim.set_velocity_command(id, 0.0, 1.5).unwrap();
        let mut scans = Vec::new();
        for _ in 0..200 {
            sim.step();
            if let Some(s) = sim.take_scan(id).unwrap() {
                let truth = sim.true_pose(id).unwrap();
                scans.push((s, truth));
            }
        }
        scans
    };
    let skewed = run(true);
    let plain = run(false);
    // compare a late scan (constant turn rate): the skewed one differs from the unskewed one
    let (a, b) = (&skewed[6].0, &plain[6].0);
    let diff: f32 = a
        .ranges
        .iter()
        .zip(&b.ranges)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (x - y).abs())
        .sum();
    assert!(diff > 10.0, "skewed and unskewed scans agree too well ({diff})");
    assert!(a.ranges.iter().filter(|r| r.is_finite()).count() > 300);
}

#[test]
fn scan_now_works_before_the_first_step() {
    for backend in [RayBackend::Grid, RayBackend::Rapier] {
        let lidar = LidarModel::rplidar_a1().noiseless();
        let (mut sim, id) = sim_with(RobotModel::prawn(), lidar, pose(3.0, 2.0, 0.0), backend);
        let s = sim.scan_now(id).unwrap();
        assert_eq!(s.len(), 360);
        assert!(s.valid_count() > 300, "{backend:?}: {} valid", s.valid_count());
    }
}
