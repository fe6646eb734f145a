//! The goal, not met yet (the test is ignored until it is): a loop of more than 200 m in a building of look-alike corridors, driven with drifting odometry: the default
//! preset (`matched`, loop closure while driving) closes it on every seed, and the map it holds right after the
//! robot is back where it started is already loop-closed.
#![allow(clippy::unwrap_used, reason = "a test: a failed unwrap names the problem")]

use mrslam_core::pose::relative;
use mrslam_core::{Pose2, pose};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use mrslam_slam::{Rbpf, SlamParams};

const W: f64 = 70.0;
const H: f64 = 40.0;
const CORRIDOR: f64 = 3.0;

fn run(seed: u64) -> SyntheticRun {
    let map = synthetic::ring_building(W, H, CORRIDOR, 3);
    let path = synthetic::waypoint_path(&synthetic::ring_loop(W, H, CORRIDOR, 30.0), 0.1, 0.1);
    let drift = Drift { scale: 0.03, heading_per_m: 0.02, sigma_trans: 0.05, sigma_rot: 0.05 };
    synthetic::simulate(&map, &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, seed)
}

/// Distance of the estimated pose at `k` from the truth, both relative to the first pose.
fn error_at(run: &SyntheticRun, first: &Pose2, estimate: &Pose2, k: usize) -> f64 {
    let t = relative(&run.truth[0].1, &run.truth[k].1);
    let e = relative(first, estimate);
    (t.translation.vector - e.translation.vector).norm()
}

#[test]
#[ignore = "fails today (2026-12-06): seed 0 now closes the loop (end 0.13 m; before, an alias on the search window's edge left it 5.8 m off), but the pose it holds 20 m after the return is still 1.5 m off: while driving, the optimisation (4 iterations, loop edges under Huber's loss, weak along the corridor) pulls little; the next step of [slam-general]"]
fn a_200_m_loop_is_closed_on_every_seed_while_driving() {
    let data = run(7);
    let driven: f64 =
        data.truth.windows(2).map(|w| (w[1].1.translation.vector - w[0].1.translation.vector).norm()).sum();
    assert!(driven > 200.0, "{driven} m");
    // Back at the start: the first scan of the second pass 20 m into the bottom corridor, 10 m before the end (in
    // look-alike corridors one scan's match is ambiguous: the loop is closed once answers agree over 2 m of driving,
    // and the graph optimised once 10 more scans were processed).
    let c = 0.15 + 0.5 * CORRIDOR;
    let half = data.truth.len() / 2;
    let back = (half..data.truth.len()).find(|&k| (data.truth[k].1.translation.x - (c + 20.0)).abs() < 0.06).unwrap();
    let odometry_end = error_at(&data, &data.odometry[0].pose, &data.odometry[back].pose, back);
    assert!(odometry_end > 5.0, "the odometry must leave the loop wide open: {odometry_end} m");
    for seed in 0..3 {
        let mut f = Rbpf::new(SlamParams::matched(), data.laser_offset, seed).unwrap();
        let mut at_back = None;
        for (k, (o, s)) in data.odometry.iter().zip(&data.scans).enumerate() {
            f.process(o, s).unwrap();
            if k == back {
                // What the robot holds then: its pose, and the trajectory of the whole loop.
                at_back = Some((f.best_pose(), f.trajectory()));
            }
        }
        let (pose_back, trajectory_back) = at_back.unwrap();
        let first = trajectory_back[0].1;
        let e_back = error_at(&data, &first, &pose_back, back);
        // Every pose the robot held then (one per processed scan), against the truth at its stamp.
        let worst_back = trajectory_back
            .iter()
            .map(|(stamp, p)| error_at(&data, &first, p, (stamp / 0.1).round() as usize))
            .fold(0.0, f64::max);
        let report = f.close_loops();
        let end = data.truth.len() - 1;
        let e_end = error_at(&data, &first, &f.best_pose(), end);
        eprintln!("seed {seed}: back {e_back:.3} m (worst {worst_back:.3} m), end {e_end:.3} m, {report:?}");
        assert!(report.closures >= 5 && report.open_loops == 0, "seed {seed}: {report:?}");
        assert!(
            e_back < 0.3 && worst_back < 0.5,
            "seed {seed}: back at the start {e_back} m off, worst {worst_back} m"
        );
        assert!(e_end < 0.3, "seed {seed}: the end is {e_end} m off");
    }
}
