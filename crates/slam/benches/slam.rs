//! Criterion benchmarks: one filter update (30 particles, 667-beam Hokuyo scan); one metre of a SICK-class
//! log (180 and 361 beams, 30 particles: the scans in between and the update at its end) with the GMapping
//! and the matched presets; and the memory of 30 particles after mapping a 50 m corridor (printed, not
//! timed).
//!
//! The update is measured in the state a run is in: each iteration clones the filter and, untimed, processes
//! one update first, so that the particles own the tiles the timed update writes, as they do in the run
//! (which never resamples on this corridor). `rbpf_update_30p_667beams_shared_tiles` times the same update
//! on a clone whose every tile is still shared with another filter, so each tile it writes is copied first:
//! the cost of an update right after a resampling.
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use mrslam_core::pose;
use mrslam_slam::synthetic::{self, Drift, Lidar};
use mrslam_slam::{Rbpf, SlamParams};

fn drift() -> Drift {
    Drift { scale: 0.03, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.01 }
}

fn corridor_filter() -> (Rbpf, synthetic::SyntheticRun, usize) {
    let map = synthetic::corridor_map(52.0);
    let path = synthetic::waypoint_path(&[(1.0, 2.5), (51.0, 2.5)], 0.05, 0.1);
    let run = synthetic::simulate(&map, &path, 0.1, &Lidar::hokuyo(), pose(0.1, 0.0, 0.0), &drift(), 1);
    let mut f = Rbpf::new(SlamParams::hokuyo(), run.laser_offset, 1).expect("valid params");
    // Map the first 20 m; the benchmark then processes one more scan, 0.25 m further on.
    let stop = 400;
    for k in 0..stop {
        f.process(&run.odometry[k], &run.scans[k]).expect("synthetic input is valid");
    }
    (f, run, stop)
}

fn update(c: &mut Criterion) {
    let (f, run, stop) = corridor_filter();
    // 0.25 m per processed update: readings stop+4 and stop+9 are each processed
    let (warm, k) = (stop + 4, stop + 9);
    c.bench_function("rbpf_update_30p_667beams", |b| {
        b.iter_batched(
            || {
                let mut g = f.clone();
                assert!(g.process(&run.odometry[warm], &run.scans[warm]).expect("valid").is_processed());
                g
            },
            |mut f| {
                let out = f.process(&run.odometry[k], &run.scans[k]).expect("valid");
                assert!(out.is_processed());
                f
            },
            BatchSize::SmallInput,
        )
    });
    c.bench_function("rbpf_update_30p_667beams_shared_tiles", |b| {
        b.iter_batched(
            || {
                let mut g = f.clone();
                assert!(g.process(&run.odometry[warm], &run.scans[warm]).expect("valid").is_processed());
                let h = g.clone();
                (g, h)
            },
            |(g, mut h)| {
                // the same update, but every tile it writes is shared with `g` and copied first
                let out = h.process(&run.odometry[k], &run.scans[k]).expect("valid");
                assert!(out.is_processed());
                (g, h)
            },
            BatchSize::SmallInput,
        )
    });
}

/// The office loop seen by a SICK-class lidar of `beams` beams over 180° (80 m), 0.05 m per scan.
fn sick_office(beams: usize) -> synthetic::SyntheticRun {
    let lidar = Lidar { beams, range_max: 80.0, ..Lidar::sick() };
    let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
    synthetic::simulate(&synthetic::office_map(), &path, 0.1, &lidar, pose(0.0, 0.0, 0.0), &drift(), 1)
}

fn metre_of_log(c: &mut Criterion) {
    for beams in [180, 361] {
        let run = sick_office(beams);
        for (name, params) in [("gmapping", SlamParams::default()), ("matched", SlamParams::matched())] {
            let mut f = Rbpf::new(params, run.laser_offset, 1).expect("valid params");
            // 20 m mapped; the benchmark feeds the next metre (20 scans), whose last scan is an update.
            let stop = 400;
            for k in 0..stop {
                f.process(&run.odometry[k], &run.scans[k]).expect("synthetic input is valid");
            }
            c.bench_function(&format!("rbpf_metre_30p_{beams}beams_{name}"), |b| {
                b.iter_batched(
                    || f.clone(),
                    |mut f| {
                        let mut updates = 0;
                        for k in stop..stop + 20 {
                            let out = f.process(&run.odometry[k], &run.scans[k]).expect("valid");
                            updates += usize::from(out.is_processed());
                        }
                        assert!(updates >= 1, "a metre holds an update");
                        f
                    },
                    BatchSize::SmallInput,
                )
            });
        }
    }
}

fn memory(_c: &mut Criterion) {
    let map = synthetic::corridor_map(52.0);
    let path = synthetic::waypoint_path(&[(1.0, 2.5), (51.0, 2.5)], 0.05, 0.1);
    let run = synthetic::simulate(&map, &path, 0.1, &Lidar::hokuyo(), pose(0.1, 0.0, 0.0), &drift(), 1);
    let mut f = Rbpf::new(SlamParams::hokuyo(), run.laser_offset, 1).expect("valid params");
    for (o, s) in run.odometry.iter().zip(&run.scans) {
        f.process(o, s).expect("valid");
    }
    let m = f.memory_stats();
    println!(
        "memory after a 50 m corridor, 30 particles: {} distinct tiles ({:.1} MB) vs {} referenced ({:.1} MB unshared); \
         tile slots {:.2} MB; {} trajectory nodes ({:.2} MB incl. scans); total {:.1} MB; {} resamples",
        m.unique_tiles,
        m.tile_bytes as f64 / 1e6,
        m.referenced_tiles,
        m.unshared_tile_bytes as f64 / 1e6,
        m.slot_bytes as f64 / 1e6,
        m.trajectory_nodes,
        m.trajectory_bytes as f64 / 1e6,
        m.total_bytes() as f64 / 1e6,
        f.counters().resamples
    );
}

criterion_group!(benches, update, metre_of_log, memory);
criterion_main!(benches);
