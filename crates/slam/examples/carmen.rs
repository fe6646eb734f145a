//! Development aid: the filter on a CARMEN log with any parameters (as `mrslam slam --set NAME=VALUE`),
//! scored against benchmark relations; builds without the CLI's recording dependencies.
//! `cargo run --release -p mrslam-slam --example carmen -- LOG RELATIONS [seed=S] [preset=NAME]
//! [odometry=interpolated|line] [map=OUT.yaml] [name=value ...]`

use mrslam_core::relations::{self, StampedPose};
use mrslam_core::{CarmenLog, OdometrySource, Pose2, ReadOptions};
use mrslam_slam::{Preset, Rbpf, poses_at_every_scan};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut params = Preset::Gmapping.params();
    let mut seed = 0;
    let mut options = ReadOptions::default();
    let mut map_out = None;
    for a in &args[2..] {
        let (k, v) = a.split_once('=').expect("name=value");
        match k {
            "preset" => params = v.parse::<Preset>().expect("a preset").params(),
            "seed" => seed = v.parse().expect("a seed"),
            "odometry" => options.odometry = v.parse::<OdometrySource>().expect("an odometry source"),
            "map" => map_out = Some(v.to_string()),
            _ => params.set(k, v).expect("a parameter"),
        }
    }
    let log = CarmenLog::read_with(std::path::Path::new(&args[0]), &options).expect("a readable log");
    let rels = relations::read_relations(std::path::Path::new(&args[1])).expect("relations");
    let mut f = Rbpf::new(params, log.scans[0].laser_offset, seed).expect("parameters");
    let t = std::time::Instant::now();
    let mut processed = Vec::new();
    for (i, rec) in log.scans.iter().enumerate() {
        if f.process(&rec.odometry, &rec.scan).expect("a reading").is_processed() {
            processed.push(i);
        }
    }
    let secs = t.elapsed().as_secs_f64();
    let stamps: Vec<f64> = log.scans.iter().map(|r| r.scan.stamp).collect();
    let odometry: Vec<Pose2> = log.scans.iter().map(|r| r.odometry.pose).collect();
    let anchors: Vec<(usize, Pose2)> = processed.iter().copied().zip(f.trajectory().into_iter().map(|k| k.1)).collect();
    let poses = poses_at_every_scan(&stamps, &odometry, &anchors).expect("processed scans");
    let traj: Vec<StampedPose> = stamps.iter().zip(poses).map(|(&stamp, pose)| StampedPose { stamp, pose }).collect();
    let s = relations::score(&traj, &rels, 0.001);
    let c = f.counters();
    let duration = stamps[stamps.len() - 1] - stamps[0];
    println!(
        "seed {seed}: {:.4} ± {:.4} m (max {:.3}), {:.3} ± {:.3} deg (max {:.2}), used {} missing {}, {} processed, {} resamples, {:.1} s = {:.1}x real time",
        s.translation.mean,
        s.translation.std,
        s.translation.max,
        s.rotation.mean.to_degrees(),
        s.rotation.std.to_degrees(),
        s.rotation.max.to_degrees(),
        s.used(),
        s.missing.len(),
        c.processed,
        c.resamples,
        secs,
        duration / secs
    );
    if let Some(out) = map_out {
        mrslam_core::map_io::write_ros_map(&f.map().expect("a map"), std::path::Path::new(&out)).expect("written");
    }
}
