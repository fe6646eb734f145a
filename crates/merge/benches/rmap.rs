//! The R-map baseline (paper Alg. 1) beside the SIFT merger (Alg. 3) on the same 300×300 pair, both
//! single-threaded through the full `merge` pipeline; and the R-map of a 600×600 map alone.
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_merge::CoverRule;
use mrslam_merge::dev::{FreeMatrix, mers};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair_quarter};
use mrslam_merge::{MergeParams, Merger, RmapMerger, SiftMerger, merge};
use std::hint::black_box;

fn bench_rmap(c: &mut Criterion) {
    // A 14 m × 14 m building at 5 cm with a 0.5 m margin: a 300 × 300 map, cut in two at overlap 0.6,
    // the second half turned by a multiple of 90 degrees (the R-map merger's home ground).
    let plan = FloorplanParams { width_m: 14.0, height_m: 14.0, ..FloorplanParams::default() };
    let map = generate(3, &plan);
    assert_eq!((map.width(), map.height()), (300, 300));
    let pair = cut_pair_quarter(&map, &PairSpec { overlap: 0.6, max_shift_m: 2.0, rotate: true }, 3);
    let params = MergeParams::default();
    let rmap = RmapMerger::default();
    let sift = SiftMerger::default();
    for m in [&rmap as &dyn Merger, &sift] {
        let out = merge(m, &pair.a, &pair.b, &params);
        eprintln!(
            "{}: accepted {} {:?}, stages (ms): {:?}",
            m.name(),
            out.report.accepted,
            out.report.reason,
            out.report.timings_ms
        );
        assert!(out.report.accepted, "the benchmark pair must merge with {}", m.name());
    }
    let mut g = c.benchmark_group("merge_300x300");
    g.bench_function("rmap", |b| b.iter(|| merge(&rmap, black_box(&pair.a), black_box(&pair.b), &params)));
    g.bench_function("sift", |b| b.iter(|| merge(&sift, black_box(&pair.a), black_box(&pair.b), &params)));
    g.finish();
    // RMAP alone on a 600 × 600 map (MER enumeration, greedy cover, connections).
    let big = generate(7, &FloorplanParams { width_m: 29.0, height_m: 29.0, ..FloorplanParams::default() });
    assert_eq!((big.width(), big.height()), (600, 600));
    let m = FreeMatrix::from_grid(&big);
    c.bench_function("rmap_build_600x600", |b| b.iter(|| mers::rmap(black_box(&m), CoverRule::GreedyGain)));
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench_rmap
}
criterion_main!(benches);
