//! The particle filter through the back-end interface: what code that drives any SLAM sees of it.
#![allow(clippy::unwrap_used, reason = "a test: a failed unwrap names the problem")]

use mrslam_core::{Pose2, pose};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use mrslam_slam::{Rbpf, SlamBackend, SlamParams};

/// The office loop with the SICK-class lidar and odometry that drifts a metre per lap (a loop to close).
fn sick_office_run(seed: u64) -> SyntheticRun {
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let drift = Drift { scale: 0.03, heading_per_m: 0.02, sigma_trans: 0.05, sigma_rot: 0.05 };
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, seed)
}

#[test]
fn a_loop_closure_reports_the_poses_it_moved_once() {
    let run = sick_office_run(5);
    let mut filter: Box<dyn SlamBackend> = Box::new(Rbpf::new(SlamParams::matched(), run.laser_offset, 0).unwrap());
    // The matched preset closes loops while it drives: after every reading, the poses moved since the last one.
    let (mut reported, mut moved_total) = (0, 0);
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        let before = filter.trajectory();
        filter.process(o, s).unwrap();
        let after = filter.trajectory();
        let corrections = filter.take_corrections();
        assert!(filter.take_corrections().is_empty(), "each correction is reported once");
        // Each correction names a pose of the path before the reading and the one the trajectory holds now.
        for c in &corrections {
            let k = before.iter().position(|(s, _)| *s == c.stamp).expect("a trajectory stamp");
            assert_eq!((before[k].1, after[k].1), (c.before, c.after));
        }
        let moved = before.iter().zip(&after).filter(|(b, a)| b.1 != a.1).count();
        assert_eq!(moved, corrections.len(), "every moved pose is reported");
        (reported, moved_total) = (reported + corrections.len(), moved_total + moved);
    }
    let before = filter.trajectory();
    let report = filter.finish().expect("the matched preset closes loops");
    assert!(report.closures >= 1, "{report:?}");
    let corrections = filter.take_corrections();
    let after = filter.trajectory();
    for c in &corrections {
        let k = before.iter().position(|(s, _)| *s == c.stamp).expect("a trajectory stamp");
        assert_eq!((before[k].1, after[k].1), (c.before, c.after));
    }
    assert!(reported + corrections.len() > 0, "a closed loop moves poses");
    assert_eq!(reported, moved_total);
}

#[test]
fn the_filter_shows_its_particles_as_hypotheses_and_reports_no_correction_without_loop_closure() {
    let run = sick_office_run(5);
    let mut params = SlamParams::hokuyo();
    params.filter.particles = 8;
    let mut filter = Rbpf::new(params, run.laser_offset, 3).unwrap();
    let n = 80;
    for (o, s) in run.odometry.iter().zip(&run.scans).take(n) {
        SlamBackend::process(&mut filter, o, s).unwrap();
        assert!(filter.take_corrections().is_empty());
    }
    let h = filter.hypotheses();
    assert_eq!(h.poses.len(), 8);
    assert_eq!(h.effective, Some(filter.neff()));
    let total: f64 = h.poses.iter().map(|(_, w)| w).sum();
    assert!((total - 1.0).abs() < 1e-9, "normalised weights: {total}");
    let best: Pose2 = SlamBackend::best_pose(&filter);
    assert_eq!(best, filter.best_pose());
    assert!(filter.finish().is_none(), "loop closure is off in the preset");
    assert_eq!(SlamBackend::counters(&filter).readings, n);
}
