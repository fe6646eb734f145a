//! Development aid: scan-matcher accuracy against a map built from true poses.
#![allow(clippy::unwrap_used, reason = "a development aid / test: a failed unwrap names the problem")]

use mrslam_core::Xyt;
use mrslam_core::pose;
use mrslam_slam::dev::TileMap;
use mrslam_slam::dev::{PreparedScan, ScanMatcher};
use mrslam_slam::synthetic::{self, Drift, Lidar};

fn main() {
    let env = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let map = synthetic::office_map();
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let run = synthetic::simulate(&map, &path, 0.1, &Lidar::hokuyo(), pose(0.0, 0.0, 0.0), &Drift::none(), 1);
    let params = mrslam_slam::MatcherParams { sigma: env("SIGMA", 0.05), ..Default::default() };
    let m = ScanMatcher::new(params, Xyt { x: 0.0, y: 0.0, theta: 0.0 }, false);
    // map from the first 150 true scans
    let mut tm = TileMap::new(0.05);
    let upto = env("UPTO", 150.0) as usize;
    for k in 0..env("MAPN", upto as f64) as usize {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&run.truth[k].1);
        let ps = PreparedScan::new(&run.scans[k], 4.0, 4.0, 0);
        for b in &ps.hits {
            let (s, c) = t.sin_cos();
            tm.add_hit(x + b.r * (c * b.c - s * b.s), y + b.r * (s * b.c + c * b.s)).unwrap();
        }
    }
    let (mut ex, mut ey, mut et) = (0.0, 0.0, 0.0);
    let mut n = 0.0;
    for k in (upto..upto + 60).step_by(3) {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&run.truth[k].1);
        let ps = PreparedScan::new(&run.scans[k], 4.0, 4.0, 1);
        for (dx, dy, dt) in [(0.04, 0.0, 0.0), (-0.03, 0.02, 0.01), (0.0, 0.0, -0.02), (0.02, -0.03, 0.015)] {
            let init = Xyt { x: x + dx, y: y + dy, theta: t + dt };
            let sel = if std::env::var("GUARD").is_ok() {
                m.beams_in_map(&tm, &init, &ps.matched)
            } else {
                ps.matched.clone()
            };
            let (p, _) = m.optimize(&tm, &init, &sel);
            ex += (p.x - x).abs();
            ey += (p.y - y).abs();
            et += (p.theta - t).abs();
            n += 1.0;
        }
    }
    println!("mean abs err x {:.4} y {:.4} t {:.4}", ex / n, ey / n, et / n);
}
