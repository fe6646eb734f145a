//! Simulator benchmarks: one Hokuyo scan in the corridor (grid caster vs rapier's query pipeline),
//! and world steps per second with two robots.
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mrslam_sim::{EncoderParams, LidarModel, RayBackend, RobotModel, Sim, SimConfig, SlipParams, WorldSpec};
use std::hint::black_box;

fn corridor() -> WorldSpec {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../worlds/corridor.toml");
    WorldSpec::from_toml_file(p).expect("corridor world")
}

fn two_robot_sim(spec: &WorldSpec, backend: RayBackend) -> Sim {
    let cfg = SimConfig { ray_backend: backend, ..SimConfig::default() };
    let mut sim = Sim::with_config(spec, 1, cfg).expect("sim");
    let a = sim
        .add_robot(
            "experia",
            RobotModel::experia(),
            LidarModel::hokuyo_urg_04lx(),
            SlipParams::default(),
            EncoderParams::default(),
            mrslam_core::pose(10.5, 2.5, 0.0),
        )
        .expect("experia");
    let b = sim
        .add_robot(
            "prawn",
            RobotModel::prawn(),
            LidarModel::rplidar_a1(),
            SlipParams::default(),
            EncoderParams::default(),
            mrslam_core::pose(12.0, 2.0, 0.3),
        )
        .expect("prawn");
    sim.set_velocity_command(a, 0.3, 0.05).expect("cmd");
    sim.set_velocity_command(b, 0.2, -0.1).expect("cmd");
    sim
}

fn scan(c: &mut Criterion) {
    let spec = corridor();
    let mut g = c.benchmark_group("hokuyo_scan_corridor");
    g.throughput(Throughput::Elements(667));
    for (name, backend) in [("grid", RayBackend::Grid), ("rapier", RayBackend::Rapier)] {
        let mut sim = two_robot_sim(&spec, backend);
        sim.step();
        let id = sim.robot_id("experia").expect("id");
        g.bench_function(name, |b| b.iter(|| black_box(sim.scan_now(id).expect("scan"))));
    }
    g.finish();
}

fn steps(c: &mut Criterion) {
    let spec = corridor();
    let mut g = c.benchmark_group("world_step_two_robots");
    g.throughput(Throughput::Elements(100));
    for (name, backend) in [("grid", RayBackend::Grid), ("rapier", RayBackend::Rapier)] {
        g.bench_function(name, |b| {
            b.iter_batched_ref(
                || two_robot_sim(&spec, backend),
                |sim| {
                    for _ in 0..100 {
                        black_box(sim.step());
                    }
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, scan, steps);
criterion_main!(benches);
