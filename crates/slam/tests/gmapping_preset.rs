//! The preset a user gets by default and with `--preset gmapping` is GMapping's: set by the names and values
//! GMapping documents (ROS `slam_gmapping`), it stays the same; run on a synthetic log, the filter keeps its 30
//! particles, processes a scan once the odometry moved 1 m or turned 0.5 rad since the last one, and resamples
//! exactly when Neff falls below half the particles.

#![allow(clippy::unwrap_used, reason = "tests: a failed unwrap names the problem")]

use mrslam_core::Xyt;
use mrslam_core::pose;
use mrslam_core::pose::relative;
use mrslam_slam::synthetic::{self, Drift, Lidar};
use mrslam_slam::{Preset, Rbpf, SlamParams};

/// GMapping's documented defaults (slam_gmapping's parameters), by the names `--set` knows them.
const GMAPPING: [(&str, &str); 22] = [
    ("particles", "30"),
    ("linear_update", "1.0"),
    ("angular_update", "0.5"),
    ("temporal_update", "-1.0"),
    ("resample_threshold", "0.5"),
    ("sigma", "0.05"),
    ("lsigma", "0.075"),
    ("ogain", "3.0"),
    ("kernel_size", "1"),
    ("lstep", "0.05"),
    ("astep", "0.05"),
    ("iterations", "5"),
    ("lskip", "0"),
    ("minimum_score", "0.0"),
    ("srr", "0.1"),
    ("srt", "0.2"),
    ("str", "0.1"),
    ("stt", "0.2"),
    ("delta", "0.05"),
    ("max_urange", "80.0"),
    ("max_range", "80.0"),
    ("occ_thresh", "0.25"),
];

#[test]
fn the_default_and_the_gmapping_preset_hold_gmappings_documented_values() {
    let by_name: Preset = "gmapping".parse().unwrap();
    assert_eq!(by_name.params(), SlamParams::default());
    // Starting from another preset, GMapping's values by GMapping's names give the GMapping preset back in
    // everything GMapping has.
    let mut p = SlamParams::hokuyo();
    for (name, value) in GMAPPING {
        p.set(name, value).unwrap();
    }
    let d = SlamParams::default();
    assert_eq!((p.filter, p.motion, p.map), (d.filter, d.motion, d.map));
    let gmappings = |m: &mrslam_slam::MatcherParams| {
        (m.sigma, m.lsigma, m.kernel_size, m.lstep, m.astep, m.iterations, m.lskip, m.minimum_score)
    };
    assert_eq!(gmappings(&p.matcher), gmappings(&d.matcher));
    // The rest are the robot preset's own extensions of GMapping's matcher.
    assert_ne!(p, d);
}

#[test]
fn the_gmapping_filter_keeps_its_particles_updates_after_a_metre_or_half_a_radian_and_resamples_below_half() {
    let map = synthetic::office_map();
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let drift = Drift { scale: 0.02, heading_per_m: 0.01, sigma_trans: 0.01, sigma_rot: 0.01 };
    let run = synthetic::simulate(&map, &path[..700], 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, 3);
    let (mut by_distance, mut by_turn, mut resampled, mut kept) = (0, 0, 0, 0);
    // GMapping's weights on this clean log never fall below the threshold; sharper weights (a smaller `ogain`)
    // make them, and the rule must hold either way.
    for ogain in ["3.0", "0.05"] {
        let mut params: SlamParams = "gmapping".parse::<Preset>().unwrap().params();
        params.set("ogain", ogain).unwrap();
        let mut f = Rbpf::new(params, run.laser_offset, 1).unwrap();
        let (mut moved, mut turned) = (0.0f64, 0.0f64);
        for (k, (o, s)) in run.odometry.iter().zip(&run.scans).enumerate() {
            if k > 0 {
                let d = Xyt::from_pose(&relative(&run.odometry[k - 1].pose, &o.pose));
                moved += d.x.hypot(d.y);
                turned += d.theta.abs();
            }
            let out = f.process(o, s).unwrap();
            assert_eq!(f.particles().count(), 30, "reading {k}");
            let due = k == 0 || moved >= 1.0 || turned >= 0.5;
            assert_eq!(out.is_processed(), due, "reading {k}: moved {moved:.3} m, turned {turned:.3} rad");
            if !out.is_processed() {
                continue;
            }
            if k > 0 {
                if moved >= 1.0 {
                    by_distance += 1;
                } else {
                    by_turn += 1;
                }
            }
            (moved, turned) = (0.0, 0.0);
            let neff = out.neff().unwrap();
            assert_eq!(out.resampled(), neff < 15.0, "reading {k}: Neff {neff}");
            if out.resampled() {
                resampled += 1;
            } else {
                kept += 1;
            }
        }
    }
    // Both triggers and both sides of the resampling threshold were seen.
    assert!(by_distance > 3 && by_turn > 0, "{by_distance} updates by distance, {by_turn} by turning");
    assert!(resampled > 0 && kept > 0, "{resampled} resampled, {kept} kept");
}
