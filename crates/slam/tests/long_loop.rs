//! A loop of more than 200 m in a building of look-alike corridors, driven with drifting odometry: the default
//! preset (`matched`, loop closure while driving) closes it on every seed, and the map it holds right after the
//! robot is back where it started is already loop-closed: as good as the optimisation at the end of the data
//! makes it; and at the end of the data its map is within 30 cm of the truth where the robot ends and within a metre
//! everywhere, along corridors that look alike.
#![allow(clippy::unwrap_used, reason = "a test: a failed unwrap names the problem")]

use mrslam_core::pose::relative;
use mrslam_core::{Pose2, pose};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use mrslam_slam::{LoopClosureReport, Rbpf, SlamParams};

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

/// What one seed's SLAM made of the loop.
struct Outcome {
    seed: u64,
    /// Error of the pose held back at the start (20 m into the bottom corridor on the second pass), metres.
    back: f64,
    /// Worst error of the trajectory held then, metres.
    worst_back: f64,
    /// Worst error of the trajectory once the end of the data is optimised, metres: what loop closure can make
    /// of this loop (one loop constraint spreads the closing error along it, so its far side keeps some drift).
    worst_last: f64,
    /// Error at the end of the data, metres.
    end: f64,
    report: LoopClosureReport,
}

/// The loop driven once with drifting odometry, and the `matched` preset's SLAM of it on seeds 0-2.
fn outcomes() -> Vec<Outcome> {
    let data = run(7);
    let driven: f64 =
        data.truth.windows(2).map(|w| (w[1].1.translation.vector - w[0].1.translation.vector).norm()).sum();
    assert!(driven > 200.0, "{driven} m");
    // Back at the start: the first scan of the second pass 20 m into the bottom corridor, 10 m before the end (in
    // look-alike corridors one scan's match is ambiguous: the loop is closed once answers agree over 2 m of driving,
    // and the graph optimised once 10 more scans were processed). The top corridor crosses the same x on the way.
    let c = 0.15 + 0.5 * CORRIDOR;
    let half = data.truth.len() / 2;
    let back = (half..data.truth.len())
        .find(|&k| {
            let t = &data.truth[k].1.translation;
            (t.x - (c + 20.0)).abs() < 0.06 && (t.y - c).abs() < 0.5
        })
        .unwrap();
    let odometry_end = error_at(&data, &data.odometry[0].pose, &data.odometry[back].pose, back);
    assert!(odometry_end > 5.0, "the odometry must leave the loop wide open: {odometry_end} m");
    let worst = |trajectory: &[(f64, Pose2)]| {
        trajectory
            .iter()
            .map(|(stamp, p)| error_at(&data, &trajectory[0].1, p, (stamp / 0.1).round() as usize))
            .fold(0.0, f64::max)
    };
    (0..3)
        .map(|seed| {
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
            let report = f.close_loops();
            let o = Outcome {
                seed,
                back: error_at(&data, &first, &pose_back, back),
                worst_back: worst(&trajectory_back),
                worst_last: worst(&f.trajectory()),
                end: error_at(&data, &first, &f.best_pose(), data.truth.len() - 1),
                report,
            };
            eprintln!(
                "seed {seed}: back {:.3} m (worst {:.3} m, at the end {:.3} m), end {:.3} m, {:?}",
                o.back, o.worst_back, o.worst_last, o.end, o.report
            );
            o
        })
        .collect()
}

#[test]
fn a_200_m_loop_is_closed_on_every_seed_while_driving() {
    let mut failed = Vec::new();
    for o in outcomes() {
        let seed = o.seed;
        if !(o.report.closures >= 5 && o.report.open_loops == 0 && !o.report.contradicts_itself()) {
            failed.push(format!("seed {seed}: {:?}", o.report));
        }
        if o.back >= 0.3 {
            failed.push(format!("seed {seed}: back at the start {:.3} m off", o.back));
        }
        // The map held then is the loop-closed one: no worse anywhere than what the end's optimisation makes of
        // the loop (the odometry alone leaves it more than 5 m open).
        if o.worst_back > o.worst_last + 0.1 {
            failed.push(format!(
                "seed {seed}: the map held back at the start is {:.3} m off somewhere, the one at the end {:.3} m",
                o.worst_back, o.worst_last
            ));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// 2026-12-07: seeds 0-2 end 0.14, 0.24, 0.30 m off, worst poses 0.76, 0.76, 0.61 m (before loop edges were held from
/// the submap's node nearest the match: 0.13, 0.36, 0.34 m and 0.85, 1.05, 0.70 m). What is left at the end is the
/// first pass's own drift up to the place the loop closes on, which no loop edge can see.
#[test]
fn a_200_m_loop_of_look_alike_corridors_is_mapped_within_30_cm_at_its_end() {
    let mut failed = Vec::new();
    for o in outcomes() {
        if o.end >= 0.3 || o.worst_last >= 1.0 {
            failed.push(format!("seed {}: the end {:.3} m off, the worst pose {:.3} m", o.seed, o.end, o.worst_last));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
