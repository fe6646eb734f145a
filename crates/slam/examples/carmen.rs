//! Development aid: the filter on a CARMEN log with any parameters (as `mrslam slam --set NAME=VALUE`);
//! writes the best particle's trajectory, `stamp x y theta` per processed scan.
//! `cargo run --release -p mrslam-slam --example carmen -- LOG OUT.txt [preset=gmapping|hokuyo|rplidar]
//! [drift=HEADING_DEG_PER_M,SCALE,SIGMA] [name=value ...]`

use mrslam_core::CarmenLog;
use mrslam_core::pose::pose_xyt;
use mrslam_slam::synthetic::{Drift, inject_drift};
use mrslam_slam::{Rbpf, SlamParams};
use std::fmt::Write as _;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let log = CarmenLog::read(std::path::Path::new(&args[0])).expect("a readable log");
    let mut params = SlamParams::default();
    let mut drift = Drift::none();
    for a in &args[2..] {
        let (k, v) = a.split_once('=').expect("name=value");
        match k {
            "preset" => {
                params = match v {
                    "hokuyo" => SlamParams::hokuyo(),
                    "rplidar" => SlamParams::rplidar(),
                    _ => SlamParams::default(),
                }
            }
            "drift" => {
                let d: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
                drift = Drift { heading_per_m: d[0].to_radians(), scale: d[1], sigma_trans: d[2], sigma_rot: d[2] };
            }
            _ => params.set(k, v).unwrap(),
        }
    }
    let mut odo: Vec<_> = log.scans.iter().map(|r| r.odometry).collect();
    if drift != Drift::none() {
        inject_drift(&mut odo, &drift, 0x5eed_d21f_7000_0001);
    }
    let mut f = Rbpf::new(params, log.scans[0].laser_offset, 0).unwrap();
    let t = std::time::Instant::now();
    for (rec, o) in log.scans.iter().zip(&odo) {
        f.process(o, &rec.scan).unwrap();
    }
    let c = f.counters();
    println!("{} processed, {} resamples, {:.1} s", c.processed, c.resamples, t.elapsed().as_secs_f64());
    let mut text = String::new();
    for (stamp, p) in f.trajectory() {
        let (x, y, th) = pose_xyt(&p);
        let _ = writeln!(text, "{stamp:.6} {x:.6} {y:.6} {th:.6}");
    }
    std::fs::write(&args[1], text).unwrap();
    if let Some(out) = args.get(1).map(|s| s.replace(".txt", ".yaml")) {
        mrslam_core::map_io::write_ros_map(&f.map().unwrap(), std::path::Path::new(&out)).unwrap();
    }
}
