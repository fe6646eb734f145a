//! Times N merges of the benchmark's 600x600 pair (for CPU-time measurement with `/usr/bin/time`):
//! `cargo run --release -p mrslam-dev --bin merge_timing -- [N] [up|noup] [paper|robust]`.

use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{MergeParams, SiftMerger, SiftMergerParams, merge};

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(10);
    let upscale = std::env::args().nth(2).is_none_or(|s| s != "noup");
    let plan = FloorplanParams { width_m: 29.0, height_m: 29.0, ..FloorplanParams::default() };
    let map = generate(7, &plan);
    let pair = cut_pair(&map, &PairSpec { overlap: 0.5, max_shift_m: 2.0, rotate: true }, 7);
    let robust = std::env::args().nth(3).is_some_and(|s| s == "robust");
    let mut p = if robust { SiftMergerParams::robust() } else { SiftMergerParams::default() };
    p.sift.upscale = upscale;
    let merger = SiftMerger::new(p);
    let mut stages = std::collections::BTreeMap::<String, f64>::new();
    for _ in 0..n {
        let out = merge(&merger, &pair.a, &pair.b, &MergeParams::default());
        assert!(out.report.accepted);
        for (k, v) in &out.report.timings_ms {
            *stages.entry(k.clone()).or_default() += v / n as f64;
        }
    }
    println!("upscale {upscale}, robust {robust}: mean stage ms {stages:?}");
}
