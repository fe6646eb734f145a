//! Accuracy and speed harness on the synthetic runs of the crate's tests:
//! `cargo run --release -p mrslam-dev --bin office -- [hokuyo|rplidar|corridor|ring] [name=value ...]`.
//!
//! Diagnostics by environment variable: `DRIFT=scale,heading_per_m,sigma_trans,sigma_rot` (odometry model),
//! `SIMSEED=S` (the Hokuyo data's seed, 11 as in the test), `SIMLIKE` (the simulator's lidar noise and
//! mount), `LIDAR_RANGE`, `LIDAR_FOV`, `LIDAR_NOISE`,
//! `LIDAR_NOISE_PER_M`, `LIDAR_DROPOUT` (Hokuyo), `TRACE[=N]` (every N-th pose's error), `INCREMENTS` (per-leg increment errors of SLAM and
//! odometry), `ALL` (every particle's error and log-likelihood), `CLOSE` (the end-of-data loop closure first), `EDGES`
//! (each loop edge's error in the trajectory held), `ORACLE=chain_sigma,chain_heading_sigma` (the trajectory closed
//! by loop edges taken from the truth: what the pose graph's noise model makes of perfect loop edges).
#![allow(clippy::unwrap_used, reason = "a development aid / test: a failed unwrap names the problem")]

use mrslam_core::Xyt;
use mrslam_core::pose::relative;
use mrslam_core::{CellState, OccupancyGrid, Pose2, pose};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use mrslam_slam::{Rbpf, SlamParams};

fn acceptance(map: &OccupancyGrid, truth: &OccupancyGrid, t0: &Pose2) -> f64 {
    let (mut a, mut d) = (0usize, 0usize);
    for iy in 0..map.height() {
        for ix in 0..map.width() {
            let s = map.state(ix, iy);
            if s == CellState::Unknown {
                continue;
            }
            let p = t0 * map.cell_center(ix as i64, iy as i64);
            let Some((tx, ty)) = truth.world_to_cell(&p) else { continue };
            match truth.state(tx, ty) {
                CellState::Unknown => {}
                t if t == s => a += 1,
                _ => d += 1,
            }
        }
    }
    a as f64 / (a + d).max(1) as f64
}

/// The true pose at `stamp` (a stamp of the run's data).
fn truth_at(truth: &[(f64, Pose2)], stamp: f64) -> Pose2 {
    truth[truth.binary_search_by(|(s, _)| s.total_cmp(&stamp)).unwrap()].1
}

fn errors(est: &[(f64, Pose2)], truth: &[(f64, Pose2)]) -> (f64, f64) {
    let t0 = truth[0].1;
    let (mut sum, mut max) = (0.0, 0.0f64);
    for (stamp, p) in est {
        let t = relative(&t0, &truth_at(truth, *stamp));
        let d = (p.translation.vector - t.translation.vector).norm();
        sum += d * d;
        max = max.max(d);
    }
    ((sum / est.len() as f64).sqrt(), max)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map(String::as_str).unwrap_or("hokuyo");
    let mut drift = Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 };
    // DRIFT=scale,heading_per_m,sigma_trans,sigma_rot overrides the odometry error model (diagnostics)
    if let Ok(v) = std::env::var("DRIFT") {
        let d: Vec<f64> = v.split(',').map(|x| x.trim().parse().expect("DRIFT=a,b,c,d")).collect();
        drift = Drift { scale: d[0], heading_per_m: d[1], sigma_trans: d[2], sigma_rot: d[3] };
    }
    let (run, mut params, seed): (SyntheticRun, SlamParams, u64) = match which {
        "rplidar" => {
            let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.1, 0.2);
            let m = synthetic::office_map();
            (
                synthetic::simulate(&m, &path, 0.2, &Lidar::rplidar(), pose(0.0, 0.0, 0.0), &drift, 3),
                SlamParams::rplidar(),
                9,
            )
        }
        "ring" => {
            // the data of crates/slam/tests/long_loop.rs: a 220 m loop of look-alike corridors, SICK-class lidar
            let (w, h, c) = (70.0, 40.0, 3.0);
            let m = synthetic::ring_building(w, h, c, 3);
            let path = synthetic::waypoint_path(&synthetic::ring_loop(w, h, c, 30.0), 0.1, 0.1);
            let drift = Drift { scale: 0.03, heading_per_m: 0.02, sigma_trans: 0.05, sigma_rot: 0.05 };
            let sim_seed = std::env::var("SIMSEED").ok().and_then(|v| v.parse().ok()).unwrap_or(7);
            (
                synthetic::simulate(&m, &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, sim_seed),
                SlamParams::matched(),
                0,
            )
        }
        "corridor" => {
            let m = synthetic::corridor_map(52.0);
            let path = synthetic::waypoint_path(&[(1.0, 2.5), (51.0, 2.5)], 0.05, 0.1);
            (
                synthetic::simulate(&m, &path, 0.1, &Lidar::hokuyo(), pose(0.1, 0.0, 0.0), &drift, 1),
                SlamParams::hokuyo(),
                1,
            )
        }
        _ => {
            let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
            let m = synthetic::office_map();
            let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
            // SIMLIKE: the simulator's noise model and mount (0.15 m ahead instead of the test's 0.1 m)
            let simlike = std::env::var("SIMLIKE").is_ok();
            let mut lidar = if simlike { Lidar::hokuyo_as_simulated() } else { Lidar::hokuyo() };
            let mount = pose(if simlike { 0.15 } else { 0.1 }, 0.0, 0.0);
            if let Some(r) = env("LIDAR_RANGE") {
                lidar.range_max = r as f32;
            }
            if let Some(f) = env("LIDAR_FOV") {
                lidar.fov = f.to_radians();
                lidar.beams = (f / 0.36).round() as usize;
            }
            if let Some(s) = env("LIDAR_NOISE") {
                lidar.sigma = s;
            }
            if let Some(s) = env("LIDAR_NOISE_PER_M") {
                lidar.sigma_per_m = s;
            }
            if let Some(p) = env("LIDAR_DROPOUT") {
                lidar.dropout = p;
            }
            // SIMSEED: the synthetic data's seed (scan noise, odometry noise), 11 as in the test
            let sim_seed = env("SIMSEED").map_or(11, |s| s as u64);
            (synthetic::simulate(&m, &path, 0.1, &lidar, mount, &drift, sim_seed), SlamParams::hokuyo(), 5)
        }
    };
    let mut seed = seed;
    for a in args.iter().skip(1) {
        let (k, v) = a.split_once('=').expect("name=value");
        if k == "seed" {
            seed = v.parse().unwrap();
            continue;
        }
        params.set(k, v).unwrap();
    }
    let mut f = Rbpf::new(params, run.laser_offset, seed).unwrap();
    let t = std::time::Instant::now();
    let mut times = Vec::new();
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        let t1 = std::time::Instant::now();
        if f.process(o, s).unwrap().is_processed() {
            times.push(t1.elapsed().as_secs_f64() * 1e3);
        }
    }
    if let Ok(v) = std::env::var("ORACLE") {
        oracle(&f.trajectory(), &run.truth, &v);
    }
    if std::env::var("CLOSE").is_ok() {
        println!("{:?}", f.close_loops());
    }
    if std::env::var("EDGES").is_ok() {
        // each loop edge's relative pose in the trajectory held against the truth's (the `to` node's frame)
        let traj = f.trajectory();
        let t_at = |stamp: f64| truth_at(&run.truth, stamp);
        for (a, b) in f.loop_edges() {
            let est = relative(&traj[a].1, &traj[b].1);
            let tru = relative(&t_at(traj[a].0), &t_at(traj[b].0));
            let e = Xyt::from_pose(&(tru.inverse() * est));
            println!("edge {a:3} -> {b:3}: err ({:+.3},{:+.3},{:+.4})", e.x, e.y, e.theta);
        }
    }
    let secs = t.elapsed().as_secs_f64();
    times.sort_by(f64::total_cmp);
    let (rms, max) = errors(&f.trajectory(), &run.truth);
    if std::env::var("TRACE").is_ok() {
        let t0 = run.truth[0].1;
        for (i, (stamp, p)) in f
            .trajectory()
            .iter()
            .enumerate()
            .step_by(std::env::var("TRACE").ok().and_then(|v| v.parse().ok()).unwrap_or(5))
        {
            let true_pose = truth_at(&run.truth, *stamp);
            let e = relative(&t0, &true_pose).inverse() * p;
            let Xyt { x: ex, y: ey, theta: et } = Xyt::from_pose(&e);
            let Xyt { x: tx, y: ty, .. } = Xyt::from_pose(&true_pose);
            println!("{i:4} truth ({tx:5.1},{ty:5.1}) err ({ex:+.3},{ey:+.3},{et:+.4})");
        }
    }
    if std::env::var("INCREMENTS").is_ok() {
        // per-update increment errors of the best trajectory and of odometry (robot frame: along-track,
        // cross-track, heading), summed per leg of the path (legs split where the true heading changes)
        let traj = f.trajectory();
        let t_at = |stamp: f64| truth_at(&run.truth, stamp);
        let o_at = |stamp: f64| run.odometry.iter().find(|o| o.stamp == stamp).unwrap().pose;
        let (mut sum_s, mut sum_o) = ([0.0f64; 3], [0.0f64; 3]);
        let mut leg_start = 0;
        for k in 1..traj.len() {
            let (ta, tb) = (t_at(traj[k - 1].0), t_at(traj[k].0));
            let dt = relative(&ta, &tb);
            let ds = relative(&traj[k - 1].1, &traj[k].1);
            let dodo = relative(&o_at(traj[k - 1].0), &o_at(traj[k].0));
            let es = Xyt::from_pose(&(dt.inverse() * ds));
            let eo = Xyt::from_pose(&(dt.inverse() * dodo));
            for (acc, e) in [(&mut sum_s, es), (&mut sum_o, eo)] {
                acc[0] += e.x;
                acc[1] += e.y;
                acc[2] += e.theta;
            }
            let turn = Xyt::from_pose(&dt).theta.abs() > 1e-6;
            let next_turn = k + 1 < traj.len()
                && Xyt::from_pose(&relative(&t_at(traj[k].0), &t_at(traj[k + 1].0))).theta.abs() > 1e-6;
            if next_turn != turn || k + 1 == traj.len() {
                println!(
                    "updates {leg_start:3}-{k:3} {}: slam sum err ({:+.4},{:+.4},{:+.5}) odo ({:+.4},{:+.4},{:+.5})",
                    if turn { "turn" } else { "leg " },
                    sum_s[0],
                    sum_s[1],
                    sum_s[2],
                    sum_o[0],
                    sum_o[1],
                    sum_o[2]
                );
                (sum_s, sum_o) = ([0.0; 3], [0.0; 3]);
                leg_start = k;
            }
        }
    }
    if std::env::var("ALL").is_ok() {
        let ll = f.lineage_log_likelihoods();
        let mut v: Vec<(f64, f64)> =
            (0..ll.len()).map(|i| (errors(&f.particle_trajectory(i), &run.truth).0, ll[i])).collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        let s: Vec<String> = v.iter().map(|(r, l)| format!("{r:.3}@{l:.0}")).collect();
        println!("particles (rms@loglik, best first): {}", s.join(" "));
    }
    if f.params().filter.odometry_calibration > 0.0 {
        let k = f.odometry_calibration();
        println!("odometry calibration: scale {:+.4} heading {:+.4} rad/m", k[0], k[1]);
    }
    let ai = acceptance(&f.map().unwrap(), &run.truth_map, &run.truth[0].1);
    println!(
        "{which}: rms {rms:.4} max {max:.3} ai {ai:.4} | {} processed, {} resamples, {secs:.1} s, median update {:.1} ms",
        f.counters().processed,
        f.counters().resamples,
        times[times.len() / 2]
    );
}

/// The filter's trajectory as a pose graph (its increments, `loop_chain_*` information) closed by loop edges taken
/// from the truth (each node of a later pass to the nearest node passed 20+ m of driving earlier, within 1 m):
/// what the graph's noise model makes of perfect loop edges. `spec` = "chain_sigma,chain_heading_sigma".
fn oracle(traj: &[(f64, Pose2)], truth: &[(f64, Pose2)], spec: &str) {
    use mrslam_matching::Information;
    use mrslam_matching::pose_graph::{Edge, optimize};
    let v: Vec<f64> = spec.split(',').map(|x| x.parse().unwrap()).collect();
    let tr: Vec<Pose2> = traj.iter().map(|(s, _)| truth_at(truth, *s)).collect();
    let mut poses: Vec<Xyt> = traj.iter().map(|(_, p)| Xyt::from_pose(p)).collect();
    let mut edges = Vec::new();
    let mut travel = vec![0.0];
    for k in 1..traj.len() {
        let d = (tr[k].translation.vector - tr[k - 1].translation.vector).norm();
        travel.push(travel[k - 1] + d);
        edges.push(Edge {
            from: k - 1,
            to: k,
            measured: Xyt::from_pose(&relative(&traj[k - 1].1, &traj[k].1)),
            information: Information::from_sigmas(v[0], v[1]),
            huber: f64::INFINITY,
        });
    }
    // Loop edges as sure as the loop closure's floor on its matches (`loop_sigma`, `loop_heading_sigma`).
    let lc = mrslam_slam::LoopClosureParams::default();
    let mut loops = 0;
    for k in 0..traj.len() {
        let best = (0..k)
            .filter(|&j| travel[k] - travel[j] > 20.0)
            .map(|j| (j, (tr[k].translation.vector - tr[j].translation.vector).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, d)) = best
            && d < 1.0
        {
            loops += 1;
            edges.push(Edge {
                from: j,
                to: k,
                measured: Xyt::from_pose(&relative(&tr[j], &tr[k])),
                information: Information::from_sigmas(lc.sigma, lc.heading_sigma),
                huber: f64::INFINITY,
            });
        }
    }
    let s = optimize(&mut poses, &edges, 100).unwrap();
    let est: Vec<(f64, Pose2)> = traj.iter().zip(&poses).map(|((st, _), p)| (*st, p.to_pose())).collect();
    let (rms, max) = errors(&est, truth);
    println!("oracle ({loops} loop edges, {} iterations): rms {rms:.4} max {max:.3}", s.iterations);
}
