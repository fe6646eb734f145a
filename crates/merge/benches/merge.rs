//! End-to-end merge of two 600×600 maps, single-threaded, and its stages.

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{MergeParams, SiftMerger, merge};
use std::hint::black_box;

fn bench_merge(c: &mut Criterion) {
    // A 29 m × 29 m building at 5 cm with a 0.5 m margin: a 600 × 600 map, cut in two at overlap 0.5.
    let plan = FloorplanParams { width_m: 29.0, height_m: 29.0, ..FloorplanParams::default() };
    let map = generate(7, &plan);
    assert_eq!((map.width(), map.height()), (600, 600));
    let pair = cut_pair(&map, &PairSpec { overlap: 0.5, max_shift_m: 2.0, rotate: true }, 7);
    let merger = SiftMerger::default();
    let params = MergeParams::default();
    let out = merge(&merger, &pair.a, &pair.b, &params);
    assert!(out.report.accepted, "the benchmark pair must merge: {:?}", out.report.reason);
    eprintln!("stage breakdown of one run (ms): {:?}", out.report.timings_ms);
    c.bench_function("merge_sift_600x600", |bch| {
        bch.iter(|| merge(&merger, black_box(&pair.a), black_box(&pair.b), &params))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench_merge
}
criterion_main!(benches);
