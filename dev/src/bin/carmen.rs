//! Development aid: the filter on a CARMEN log with any parameters (as `mrslam slam --set NAME=VALUE`),
//! scored against benchmark relations; builds without the CLI's recording dependencies.
//! `cargo run --release -p mrslam-dev --bin carmen -- LOG RELATIONS [seed=S] [preset=NAME]
//! [odometry=interpolated|line] [latency=S] [map=OUT.yaml] [name=value ...]`. Environment: `ODOMETRY_ONLY=1` also
//! scores the filter's odometry alone (scan-matched with `scan_odometry`), `WORST=1` / `WORST_ROT=1` print the
//! worst relations, `DETAIL=1` the long relations off by more than 0.12 m with their error in the first pose's frame,
//! `DEBUG_RANGE=T0,T1` prints raw and filter odometry per scan stamped in [T0, T1].

use mrslam_core::Pose2;
use mrslam_core::Xyt;
use mrslam_core::relations::{self, StampedPose};
use mrslam_log::{OdometrySource, ReadOptions, read_log};
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
            "latency" => options.scan_latency = v.parse().expect("seconds"),
            _ => params.set(k, v).expect("a parameter"),
        }
    }
    let log = read_log(std::path::Path::new(&args[0]), &options).expect("a readable log");
    let rels = relations::read_relations(std::path::Path::new(&args[1])).expect("relations");
    let mut f = Rbpf::new(params, log.scans[0].laser_offset, seed).expect("parameters");
    let t = std::time::Instant::now();
    let mut processed = Vec::new();
    let mut odometry: Vec<Pose2> = Vec::new();
    for (i, rec) in log.scans.iter().enumerate() {
        if f.process(&rec.odometry, &rec.scan).expect("a reading").is_processed() {
            processed.push(i);
        }
        odometry.push(f.odometry_pose().unwrap_or(rec.odometry.pose));
        if let Ok(r) = std::env::var("DEBUG_RANGE") {
            let (a, b) = r.split_once(',').expect("a,b");
            let st = rec.scan.stamp;
            if st >= a.parse::<f64>().expect("a") && st <= b.parse::<f64>().expect("b") {
                let Xyt { x, y, theta: t } = Xyt::from_pose(&rec.odometry.pose);
                let Xyt { x: cx, y: cy, theta: ct } = Xyt::from_pose(odometry.last().expect("pushed"));
                let valid = (0..rec.scan.len()).filter(|&k| rec.scan.is_valid(k)).count();
                println!(
                    "{st:.3} raw {x:.3} {y:.3} {:.2} corrected {cx:.3} {cy:.3} {:.2} valid {valid} {:?}",
                    t.to_degrees(),
                    ct.to_degrees(),
                    f.scan_odometry_counts()
                );
            }
        }
    }
    if f.params().loop_closure.enabled {
        let t = std::time::Instant::now();
        let r = f.close_loops();
        println!("loop closure: {r:?} in {:.2} s", t.elapsed().as_secs_f64());
    }
    let secs = t.elapsed().as_secs_f64();
    let stamps: Vec<f64> = log.scans.iter().map(|r| r.scan.stamp).collect();
    // A pose at every scan from a particle's path (one pose per processed scan).
    let at_every_scan = |path: Vec<(f64, Pose2)>| -> Vec<StampedPose> {
        let anchors: Vec<(usize, Pose2)> = processed.iter().copied().zip(path.into_iter().map(|k| k.1)).collect();
        let poses = poses_at_every_scan(&stamps, &odometry, &anchors).expect("processed scans");
        stamps.iter().zip(poses).map(|(&stamp, pose)| StampedPose { stamp, pose }).collect()
    };
    let s = relations::score(&at_every_scan(f.trajectory()), &rels, 0.001);
    let c = f.counters();
    if std::env::var("ODOMETRY_ONLY").is_ok() {
        let traj: Vec<StampedPose> =
            stamps.iter().zip(&odometry).map(|(&stamp, &pose)| StampedPose { stamp, pose }).collect();
        let s = relations::score(&traj, &rels, 0.001);
        println!("odometry alone: {}, scan odometry {:?}", errors(&s), f.scan_odometry_counts());
        let (ns, ts, rs) = split(&s, false);
        println!("  odometry alone short (<=10 s) {ns}: {ts:.4} m {rs:.3} deg");
    }
    if std::env::var("ALL_PARTICLES").is_ok() {
        // every final particle's trajectory scored: is the chosen one the best, or are they all alike?
        let mut all: Vec<(f64, usize)> = (0..f.particles().count())
            .map(|i| (relations::score(&at_every_scan(f.particle_trajectory(i)), &rels, 0.001).translation.mean, i))
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let best = f.best_index();
        let rank = all.iter().position(|a| a.1 == best).expect("the best is a particle");
        println!(
            "  particles: min {:.4} median {:.4} max {:.4} m; the chosen ranks {rank} of {}",
            all[0].0,
            all[all.len() / 2].0,
            all[all.len() - 1].0,
            all.len()
        );
    }
    let (ns, ts, rs) = split(&s, false);
    let (nl, tl, rl) = split(&s, true);
    println!("  short (<=10 s) {ns}: {ts:.4} m {rs:.3} deg; long {nl}: {tl:.4} m {rl:.3} deg");
    if std::env::var("WORST_ROT").is_ok() {
        let mut v = s.errors.clone();
        v.sort_by(|a, b| b.rotation.total_cmp(&a.rotation));
        for w in v.iter().take(8) {
            println!(
                "  worst rot {:.2}-{:.2} s: {:.3} m {:.2} deg",
                w.t1,
                w.t2,
                w.translation,
                w.rotation.to_degrees()
            );
        }
    }
    if std::env::var("LONG").is_ok() {
        for e in s.errors.iter().filter(|e| (e.t2 - e.t1).abs() > 10.0) {
            println!("  long {:.1}-{:.1} s: {:.3} m {:.2} deg", e.t1, e.t2, e.translation, e.rotation.to_degrees());
        }
    }
    if std::env::var("DETAIL").is_ok() {
        // the worst long relations' errors in the first pose's frame, and the nearest processed scans
        let traj = at_every_scan(f.trajectory());
        let at =
            |t: f64| traj.iter().min_by(|a, b| (a.stamp - t).abs().total_cmp(&(b.stamp - t).abs())).expect("poses");
        for r in &rels {
            let (a, b) = (at(r.t1), at(r.t2));
            let est = Xyt::from_pose(&a.pose.inv_mul(&b.pose));
            let tru = Xyt::from_pose(&r.delta);
            let (ex, ey) = (est.x - tru.x, est.y - tru.y);
            if ex.hypot(ey) > 0.12 && (r.t2 - r.t1).abs() > 10.0 {
                println!(
                    "  rel {:.1}-{:.1}: true ({:.2}, {:.2}, {:.1} deg) error ({:+.3}, {:+.3}, {:+.2} deg)",
                    r.t1,
                    r.t2,
                    tru.x,
                    tru.y,
                    tru.theta.to_degrees(),
                    ex,
                    ey,
                    (est.theta - tru.theta).to_degrees()
                );
            }
        }
    }
    if std::env::var("WORST").is_ok() {
        for w in s.worst(8) {
            println!("  worst {:.1}-{:.1} s: {:.3} m {:.2} deg", w.t1, w.t2, w.translation, w.rotation.to_degrees());
        }
    }
    let duration = stamps[stamps.len() - 1] - stamps[0];
    println!(
        "seed {seed}: {}, used {} missing {}, {} processed, {} resamples, {:.1} s = {:.1}x real time",
        errors(&s),
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

/// Mean ± std and max of a score's translational and rotational errors.
fn errors(s: &relations::RelationsScore) -> String {
    format!(
        "{:.4} ± {:.4} m (max {:.3}), {:.3} ± {:.3} deg (max {:.2})",
        s.translation.mean,
        s.translation.std,
        s.translation.max,
        s.rotation.mean.to_degrees(),
        s.rotation.std.to_degrees(),
        s.rotation.max.to_degrees()
    )
}

/// Relations of at most (`long` false) or more than (true) 10 s: count, mean translation (m) and rotation (deg).
fn split(s: &relations::RelationsScore, long: bool) -> (usize, f64, f64) {
    let e: Vec<_> = s.errors.iter().filter(|e| ((e.t2 - e.t1).abs() > 10.0) == long).collect();
    let n = e.len().max(1) as f64;
    (
        e.len(),
        e.iter().map(|e| e.translation).sum::<f64>() / n,
        e.iter().map(|e| e.rotation).sum::<f64>().to_degrees() / n,
    )
}
