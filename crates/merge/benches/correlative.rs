//! The correlative merger on the 600×600 pair of the SIFT benchmark (`merge.rs`): the whole `merge` pipeline
//! with the rotation search on rayon's threads and on one thread, and the global search alone; the default
//! cascade on a pair the SIFT merger refuses (every stage runs, the correlative one merges), and the correlative
//! search with every rotation (no orientation prior) on the same pair; and the correlative merge by map size
//! (generated buildings of 300², 600², 900² and 1200² cells cut at overlap 0.5).
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{Cascade, CorrelativeMerger, CorrelativeParams, MergeParams, Merger, SearchParams, merge};
use std::hint::black_box;

fn bench_correlative(c: &mut Criterion) {
    // A 29 m × 29 m building at 5 cm with a 0.5 m margin: a 600 × 600 map, cut in two at overlap 0.5.
    let plan = FloorplanParams { width_m: 29.0, height_m: 29.0, ..FloorplanParams::default() };
    let map = generate(7, &plan);
    assert_eq!((map.width(), map.height()), (600, 600));
    let pair = cut_pair(&map, &PairSpec { overlap: 0.5, max_shift_m: 2.0, rotate: true }, 7);
    let params = MergeParams::default();
    let parallel = CorrelativeMerger::default();
    let single = CorrelativeMerger::new(CorrelativeParams { parallel: false, ..CorrelativeParams::default() });
    let out = merge(&parallel, &pair.a, &pair.b, &params);
    eprintln!(
        "correlative: accepted {} {:?}, stages (ms): {:?}",
        out.report.accepted, out.report.reason, out.report.timings_ms
    );
    assert!(out.report.accepted, "the benchmark pair must merge: {:?}", out.report.reason);
    let mut g = c.benchmark_group("correlative_600x600");
    g.bench_function("merge", |b| b.iter(|| merge(&parallel, black_box(&pair.a), black_box(&pair.b), &params)));
    g.bench_function("merge_one_thread", |b| {
        b.iter(|| merge(&single, black_box(&pair.a), black_box(&pair.b), &params))
    });
    g.bench_function("align_one_thread", |b| b.iter(|| single.align(black_box(&pair.a), black_box(&pair.b))));
    g.finish();

    // An 18 m × 14 m plan cut at 15 % overlap (the cascade's unit test, seed 1): SIFT refuses it.
    let plan = FloorplanParams { width_m: 18.0, height_m: 14.0, ..FloorplanParams::default() };
    let pair = cut_pair(&generate(1, &plan), &PairSpec { overlap: 0.15, max_shift_m: 3.0, rotate: true }, 1);
    let cascade = Cascade::default();
    let out = merge(&cascade, &pair.a, &pair.b, &params);
    eprintln!(
        "cascade: accepted {} by {:?}, stages (ms): {:?}",
        out.report.accepted, out.report.stage, out.report.timings_ms
    );
    assert!(out.report.accepted && out.report.stage.as_deref() == Some("correlative"), "{:?}", out.report.reason);
    let every_rotation = CorrelativeMerger::new(CorrelativeParams {
        search: SearchParams { rotation_prior: false, ..SearchParams::default() },
        ..CorrelativeParams::default()
    });
    let mut g = c.benchmark_group("cascade_18x14_low_overlap");
    g.bench_function("cascade", |b| b.iter(|| merge(&cascade, black_box(&pair.a), black_box(&pair.b), &params)));
    g.bench_function("correlative", |b| b.iter(|| merge(&parallel, black_box(&pair.a), black_box(&pair.b), &params)));
    g.bench_function("correlative_every_rotation", |b| {
        b.iter(|| merge(&every_rotation, black_box(&pair.a), black_box(&pair.b), &params))
    });
    g.finish();

    // Time by map size: square buildings at 5 cm (a 0.5 m margin each side), cut at overlap 0.5.
    let mut g = c.benchmark_group("correlative_by_size");
    for side_m in [14.0, 29.0, 44.0, 59.0] {
        let plan = FloorplanParams { width_m: side_m, height_m: side_m, ..FloorplanParams::default() };
        let map = generate(3, &plan);
        let pair = cut_pair(&map, &PairSpec { overlap: 0.5, max_shift_m: 2.0, rotate: true }, 3);
        let out = merge(&parallel, &pair.a, &pair.b, &params);
        eprintln!(
            "correlative {}x{}: accepted {} {:?}, stages (ms): {:?}",
            map.width(),
            map.height(),
            out.report.accepted,
            out.report.reason,
            out.report.timings_ms
        );
        let name = format!("{}x{}", map.width(), map.height());
        g.bench_function(name, |b| b.iter(|| merge(&parallel, black_box(&pair.a), black_box(&pair.b), &params)));
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench_correlative
}
criterion_main!(benches);
