//! Development aid: the benchmark's filter update (30 particles, 667-beam Hokuyo scan, 20 m of a synthetic
//! corridor mapped) timed many times; prints the minimum and median, robust to a busy machine.
//! `RAYON_NUM_THREADS=1 cargo run --release -p mrslam-dev --bin update_timing -- [name=value ...]`
#![allow(clippy::unwrap_used, reason = "a development aid / test: a failed unwrap names the problem")]

use mrslam_core::pose;
use mrslam_slam::synthetic::{self, Drift, Lidar};
use mrslam_slam::{Rbpf, SlamParams};

fn main() {
    let mut params = SlamParams::hokuyo();
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("name=value");
        params.set(k, v).unwrap();
    }
    let drift = Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 };
    let map = synthetic::corridor_map(52.0);
    let path = synthetic::waypoint_path(&[(1.0, 2.5), (51.0, 2.5)], 0.05, 0.1);
    let run = synthetic::simulate(&map, &path, 0.1, &Lidar::hokuyo(), pose(0.1, 0.0, 0.0), &drift, 1);
    let mut f = Rbpf::new(params, run.laser_offset, 1).unwrap();
    for k in 0..400 {
        f.process(&run.odometry[k], &run.scans[k]).unwrap();
    }
    if std::env::var("SEQ").is_ok() {
        // consecutive updates of one filter, no clone (tiles owned: no copy on write)
        let mut times = Vec::new();
        for k in 400..700 {
            let t = std::time::Instant::now();
            if f.process(&run.odometry[k], &run.scans[k]).unwrap().is_processed() {
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        times.sort_by(f64::total_cmp);
        println!("sequential updates: min {:.2} ms, median {:.2} ms", times[0], times[times.len() / 2]);
        return;
    }
    let k = 405;

    let mut times = Vec::new();
    for _ in 0..60 {
        let mut g = f.clone();
        let t = std::time::Instant::now();
        assert!(g.process(&run.odometry[k], &run.scans[k]).unwrap().is_processed());
        times.push(t.elapsed().as_secs_f64() * 1e3);
        drop(g);
    }
    times.sort_by(f64::total_cmp);
    println!("update: min {:.2} ms, median {:.2} ms", times[0], times[times.len() / 2]);
}
