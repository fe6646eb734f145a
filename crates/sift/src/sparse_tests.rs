//! The sparse path (constant parts skipped, see `mask`) gives exactly the dense path's output, bit for
//! bit, on map-like, textured, random and adversarial images, for several parameter sets, with one
//! detector reused across images of different sizes (stale buffers and masks).

use crate::{Features, GrayImage, Sift, SiftParams};

use crate::synth;

/// Panics with the first difference between two feature sets.
pub(crate) fn assert_identical(sparse: &Features, dense: &Features, what: &str) {
    assert_eq!(sparse.keypoints.len(), dense.keypoints.len(), "{what}: keypoint count");
    for (i, (a, b)) in sparse.keypoints.iter().zip(&dense.keypoints).enumerate() {
        let bits = |k: &crate::Keypoint| {
            (k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.angle.to_bits(), k.response.to_bits(), k.octave)
        };
        assert_eq!(bits(a), bits(b), "{what}: keypoint {i}: {a:?} vs {b:?}");
    }
    assert!(sparse.descriptors == dense.descriptors, "{what}: descriptors differ");
}

/// Images with large constant areas, textures, noise and awkward values.
pub(crate) fn images() -> Vec<(String, GrayImage)> {
    let mut out = Vec::new();
    let u8_img = |w: usize, h: usize, d: Vec<u8>| GrayImage::from_u8(w, h, &d).expect("valid image");
    for (w, h, seed) in [(300usize, 240usize, 1u64), (181, 317, 2), (96, 70, 3)] {
        out.push((format!("map {w}x{h}"), u8_img(w, h, synth::map_like(w, h, seed))));
    }
    // Walls-only look: one light level for free and unknown, black walls.
    let walls: Vec<u8> = synth::map_like(256, 200, 4).into_iter().map(|v| if v == 0 { 0 } else { 255 }).collect();
    out.push(("walls 256x200".into(), u8_img(256, 200, walls)));
    out.push(("texture 160x144".into(), u8_img(160, 144, synth::texture(160, 144, 5))));
    let mut rng = synth::Lcg(99);
    let noise: Vec<u8> = (0..123 * 77).map(|_| (rng.next_u32() % 256) as u8).collect();
    out.push(("noise 123x77".into(), u8_img(123, 77, noise)));
    // Constant background with scattered boxes of random levels, fractional and negative values.
    let (w, h) = (210, 150);
    let mut d = vec![37.3f32; w * h];
    for _ in 0..25 {
        let (x0, y0) = (rng.int(0, w), rng.int(0, h));
        let (bw, bh) = (rng.int(1, 14), rng.int(1, 14));
        let v = rng.range(-300.0, 300.0);
        for y in y0..(y0 + bh).min(h) {
            for x in x0..(x0 + bw).min(w) {
                d[y * w + x] = v;
            }
        }
    }
    out.push(("boxes 210x150".into(), GrayImage::new(w, h, d).expect("finite")));
    // Four constant quadrants (borders whose upscaled copies differ from the interpolated inside:
    // 0.75 c + 0.25 c != c for these levels), -0.0 next to +0.0, a tiny subnormal patch.
    let (w, h) = (140, 110);
    let levels = [0.1f32, 200.7, -0.0, 0.0];
    let mut d: Vec<f32> = (0..w * h).map(|i| levels[(i % w) * 2 / w + 2 * ((i / w) * 2 / h)]).collect();
    for y in 40..44 {
        for x in 10..14 {
            d[y * w + x] = 1e-42;
        }
    }
    out.push(("quadrants 140x110".into(), GrayImage::new(w, h, d).expect("finite")));
    // Not finite pixels (possible through the public fields) in a flat image.
    let (w, h) = (90, 80);
    let mut d = vec![128.0f32; w * h];
    d[30 * w + 30] = f32::INFINITY;
    d[50 * w + 60] = f32::NAN;
    d[10 * w + 70] = 3e38;
    out.push(("non-finite 90x80".into(), GrayImage { width: w, height: h, data: d }));
    // Filled discs and squares on a flat background: blob extrema at their centres, far from any
    // non-constant pixel (the scan's reach bound decides whether they are looked at).
    let (w, h) = (400, 300);
    let mut d = vec![250.0f32; w * h];
    let mut cx = 20.0f32;
    for (i, r) in [3.0f32, 5.0, 7.0, 9.0, 12.0, 15.0, 19.0, 24.0, 30.0].into_iter().enumerate() {
        let cy = if i % 2 == 0 { 75.0 } else { 220.0 };
        cx += r + 12.0;
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f32 - cx, y as f32 - cy);
                let inside = if i % 3 == 2 { dx.abs() <= r && dy.abs() <= r } else { dx * dx + dy * dy <= r * r };
                if inside {
                    d[y * w + x] = if i % 2 == 0 { 5.0 } else { 140.0 };
                }
            }
        }
        cx += r;
    }
    out.push(("discs 400x300".into(), GrayImage::new(w, h, d).expect("finite")));
    out.push(("flat 64x48".into(), GrayImage::new(64, 48, vec![254.0; 64 * 48]).expect("finite")));
    out
}

/// Detects on every test image with both detectors (each reused across the images) and asserts the same output.
pub(crate) fn assert_agree_on_images(a: &mut Sift, b: &mut Sift, name: &str) {
    for (what, img) in images() {
        assert_identical(&a.detect_and_compute(&img), &b.detect_and_compute(&img), &format!("{name}, {what}"));
    }
}

fn check(params: SiftParams, name: &str) {
    let mut sparse = Sift::with_sparse(params.clone(), true);
    assert_agree_on_images(&mut sparse, &mut Sift::with_sparse(params, false), name);
}

#[test]
fn sparse_equals_dense_default_params() {
    check(SiftParams::default(), "default");
}

#[test]
fn sparse_equals_dense_without_upscaling() {
    check(SiftParams { upscale: false, ..SiftParams::default() }, "upscale off");
}

#[test]
fn sparse_equals_dense_other_params() {
    // More layers and a tiny threshold; fewer layers and a large sigma; a threshold of zero (every
    // non-zero DoG passes: no scan skipping can be proven); parallel blurs.
    check(SiftParams { n_octave_layers: 5, contrast_threshold: 0.005, border: 2, ..SiftParams::default() }, "5 layers");
    check(SiftParams { n_octave_layers: 2, sigma: 3.1, edge_threshold: 20.0, ..SiftParams::default() }, "sigma 3.1");
    check(SiftParams { contrast_threshold: 0.0, upscale: false, ..SiftParams::default() }, "threshold 0");
    check(SiftParams { parallel: true, ..SiftParams::default() }, "parallel");
}

#[test]
fn sparse_path_finds_the_map_keypoints() {
    // Not vacuous: the map images give keypoints, and most of them lie on constant-free ground.
    let img = GrayImage::from_u8(300, 240, &synth::map_like(300, 240, 1)).expect("valid image");
    let f = Sift::new(SiftParams::default()).detect_and_compute(&img);
    assert!(f.len() > 20, "{} keypoints", f.len());
}
