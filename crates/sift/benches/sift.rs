//! Criterion benchmark: detect + compute on the 1024x1024 map-like and textured synthetic images.
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_sift::{GrayImage, Sift, SiftParams};
use std::hint::black_box;

#[path = "../src/synth.rs"]
mod synth;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("sift");
    group.sample_size(20);
    for (name, data) in [("map_1024", synth::map_like(1024, 1024, 1)), ("texture_1024", synth::texture(1024, 1024, 2))]
    {
        let img = GrayImage::from_u8(1024, 1024, &data).expect("valid image");
        for parallel in [false, true] {
            let mut sift = Sift::new(SiftParams { parallel, ..Default::default() });
            let id = format!("{name}{}", if parallel { "_parallel" } else { "" });
            group.bench_function(id, |b| b.iter(|| black_box(sift.detect_and_compute(black_box(&img)))));
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
