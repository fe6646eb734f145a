//! Runs the filter on the synthetic office loop and prints per-update errors (a development aid).

use mrslam_core::pose;
use mrslam_core::pose::{pose_xyt, relative};
use mrslam_slam::synthetic::{self, Drift, Lidar};
use mrslam_slam::{Rbpf, SlamParams, UpdateOutcome};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(11);
    let rp = std::env::var("RP").is_ok();
    let lidar = if rp { Lidar::rplidar() } else { Lidar::hokuyo() };
    let map = synthetic::office_map();
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let envd = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let drift = Drift { scale: envd("DS", 0.03), heading_per_m: envd("DH", 0.01), sigma_trans: 0.02, sigma_rot: 0.01 };
    let run = synthetic::simulate(&map, &path, 0.1, &lidar, pose(0.1, 0.0, 0.0), &drift, seed);
    let env = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let base = if rp { SlamParams::rplidar() } else { SlamParams::hokuyo() };
    let params = SlamParams {
        sigma: env("SIGMA", base.sigma),
        lsigma: env("LSIGMA", base.lsigma),
        lskip: env("LSKIP", base.lskip as f64) as usize,
        linear_update: env("LU", base.linear_update),
        particles: env("N", base.particles as f64) as usize,
        kernel_size: env("KS", base.kernel_size as f64) as i32,
        ogain: env("OGAIN", base.ogain),
        ..base
    };
    let mut f = Rbpf::new(params, run.laser_offset, 5).unwrap();
    let t0 = run.truth[0].1;
    let start = std::time::Instant::now();
    let mut sum = 0.0;
    let mut n = 0;
    for (k, (o, s)) in run.odometry.iter().zip(&run.scans).enumerate() {
        let t = std::time::Instant::now();
        let out = f.process(o, s).unwrap();
        if let UpdateOutcome::Processed(st) = out {
            let truth = relative(&t0, &run.truth[k].1);
            let est = f.best_pose();
            let (ex, ey, et) = pose_xyt(&relative(&truth, &est));
            sum += ex * ex + ey * ey;
            n += 1;
            if std::env::var("V").is_ok() && (n % 10 == 0 || ex.hypot(ey) > 0.1) {
                println!(
                    "{k:5} err ({ex:+.3},{ey:+.3},{et:+.4}) neff {:5.1} res {} score {:6.1}/{} ms {:.1}",
                    st.neff,
                    st.resampled as u8,
                    st.mean_score,
                    st.beams_matched,
                    t.elapsed().as_secs_f64() * 1e3
                );
            }
        }
    }
    println!("online rms {:.4}, {:.2} s, {:?}", (sum / n as f64).sqrt(), start.elapsed().as_secs_f64(), f.counters());
    println!("{:?}", f.memory_stats());
    let traj = f.trajectory();
    let mut s2 = 0.0;
    for (st, p) in &traj {
        let k = run.truth.iter().position(|(s, _)| s == st).unwrap();
        let t = relative(&t0, &run.truth[k].1);
        s2 += (p.translation.vector - t.translation.vector).norm_squared();
    }
    println!("final trajectory rms {:.4}", (s2 / traj.len() as f64).sqrt());
    let mut o2 = 0.0;
    for (st, _) in &traj {
        let k = run.truth.iter().position(|(s, _)| s == st).unwrap();
        let t = relative(&t0, &run.truth[k].1);
        let o = relative(&run.odometry[0].pose, &run.odometry[k].pose);
        o2 += (o.translation.vector - t.translation.vector).norm_squared();
    }
    println!("odometry rms {:.4}", (o2 / traj.len() as f64).sqrt());
}
