//! End-to-end merge of two 600×600 maps, single-threaded, and its stages.
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{MergeParams, SiftMerger, merge};
use std::collections::BTreeMap;
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
    // Stage breakdown: median over 11 runs of each stage (more stable than one run on a shared machine).
    let mut stages: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for _ in 0..11 {
        let out = merge(&merger, &pair.a, &pair.b, &params);
        for (k, v) in out.report.timings_ms {
            stages.entry(k).or_default().push(v);
        }
        stages.entry("(whole merge)".into()).or_default().push(out.report.time_ms);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let summary: Vec<String> = stages.iter_mut().map(|(k, v)| format!("{k} {:.2}", median(v))).collect();
    eprintln!("stage medians over 11 runs (ms): {}", summary.join(", "));
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
