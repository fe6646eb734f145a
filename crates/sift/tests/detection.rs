//! Behaviour on synthetic images: blobs, flat images, bad input, determinism, feature cap.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_sift::{GrayImage, Sift, SiftParams, detect_and_compute};

mod common;
use common::synth;

/// A Gaussian blob of standard deviation `s` (pixels) and amplitude `a` centred at (`cx`, `cy`) on a flat
/// background `bg`.
fn blob(w: usize, h: usize, cx: f32, cy: f32, s: f32, a: f32, bg: f32) -> GrayImage {
    let data = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 - cx, (i / w) as f32 - cy);
            bg + a * (-(x * x + y * y) / (2.0 * s * s)).exp()
        })
        .collect();
    GrayImage::new(w, h, data).unwrap()
}

/// Expected keypoint size for a sampled Gaussian blob of std `s`: the DoG between blurs σ and kσ
/// (k = 2^(1/3)) at the blob's centre is ∝ 1/(a + σ²) - 1/(a + k²σ²) with a = s² - 0.25 (SIFT assumes the
/// input already carries blur 0.5), maximal at σ² = a / k; OpenCV's size is 2σ.
fn expected_size(s: f32) -> f32 {
    let k = 2f32.powf(1.0 / 3.0);
    2.0 * ((s * s - 0.25) / k).sqrt()
}

#[test]
fn gaussian_blob_gives_one_keypoint_at_its_centre_with_matching_size() {
    for &(s, cx, cy, a) in &[(4.0f32, 40.0f32, 36.0f32, 120.0f32), (2.5, 31.0, 33.0, -90.0), (7.0, 60.0, 58.0, 100.0)] {
        let img = blob(120, 110, cx, cy, s, a, 100.0);
        let f = detect_and_compute(&img, &SiftParams::default());
        assert!(!f.is_empty(), "blob s={s}: no keypoint");
        let want = expected_size(s);
        for k in &f.keypoints {
            let d = ((k.x - cx).powi(2) + (k.y - cy).powi(2)).sqrt();
            assert!(d < 0.5, "blob s={s}: keypoint at ({}, {}), {d} px from the centre", k.x, k.y);
            assert!((k.size - want).abs() <= 0.25 * want, "blob s={s}: size {} vs expected {want}", k.size);
        }
        // All keypoints are the same point (possibly several orientations).
        let k0 = f.keypoints[0];
        assert!(f.keypoints.iter().all(|k| k.x == k0.x && k.y == k0.y && k.size == k0.size));
    }
}

#[test]
fn flat_image_gives_nothing() {
    for v in [0.0, 128.0, 255.0] {
        let img = GrayImage::new(200, 150, vec![v; 200 * 150]).unwrap();
        let f = detect_and_compute(&img, &SiftParams::default());
        assert!(f.is_empty());
        assert!(f.descriptors.is_empty());
    }
}

#[test]
fn bad_input_is_handled() {
    for (w, h) in [(0usize, 0usize), (1, 1), (3, 3), (2, 9), (9, 2), (11, 11)] {
        let img = GrayImage::new(w, h, (0..w * h).map(|i| (i * 91 % 256) as f32).collect()).unwrap();
        assert!(detect_and_compute(&img, &SiftParams::default()).is_empty(), "{w}x{h}");
    }
    let mut d = vec![1.0; 16];
    d[5] = f32::NAN;
    assert_eq!(GrayImage::new(4, 4, d).unwrap_err(), mrslam_sift::SiftError::NonFinitePixel { x: 1, y: 1 });
    let mut d = vec![1.0; 16];
    d[15] = f32::NEG_INFINITY;
    assert_eq!(GrayImage::new(4, 4, d).unwrap_err(), mrslam_sift::SiftError::NonFinitePixel { x: 3, y: 3 });
    assert!(GrayImage::new(4, 4, vec![0.0; 15]).is_err());
    // Out-of-range but finite values are accepted and do not panic.
    let img = GrayImage::new(64, 64, (0..64 * 64).map(|i| if i % 7 == 0 { 1e30 } else { -1e30 }).collect()).unwrap();
    let _ = detect_and_compute(&img, &SiftParams::default());
}

#[test]
fn same_image_twice_gives_identical_output() {
    let img = GrayImage::from_u8(200, 180, &synth::texture(200, 180, 7)).unwrap();
    let a = detect_and_compute(&img, &SiftParams::default());
    assert!(a.len() > 20);
    let mut sift = Sift::new(SiftParams::default());
    let b = sift.detect_and_compute(&img);
    // A reused detector (after a larger image) and the parallel mode give the same bytes.
    let big = GrayImage::from_u8(300, 260, &synth::texture(300, 260, 8)).unwrap();
    let _ = sift.detect_and_compute(&big);
    let c = sift.detect_and_compute(&img);
    let d = detect_and_compute(&img, &SiftParams { parallel: true, ..Default::default() });
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(a, d);
    assert_eq!(a.descriptors.len(), a.len() * 128);
}

#[test]
fn max_features_keeps_the_strongest() {
    let img = GrayImage::from_u8(200, 180, &synth::texture(200, 180, 9)).unwrap();
    let all = detect_and_compute(&img, &SiftParams::default());
    let some = detect_and_compute(&img, &SiftParams { max_features: Some(10), ..Default::default() });
    assert_eq!(some.len(), 10);
    let mut resp: Vec<f32> = all.keypoints.iter().map(|k| k.response).collect();
    resp.sort_by(|a, b| b.total_cmp(a));
    let got: Vec<f32> = some.keypoints.iter().map(|k| k.response).collect();
    assert_eq!(got, resp[..10]);
    // Descriptors follow their keypoints.
    for i in 0..some.len() {
        let j = all.keypoints.iter().position(|k| *k == some.keypoints[i]).unwrap();
        assert_eq!(some.descriptor(i), all.descriptor(j));
    }
}

#[test]
fn no_upscale_mode_works() {
    let img = GrayImage::from_u8(200, 180, &synth::texture(200, 180, 3)).unwrap();
    let f = detect_and_compute(&img, &SiftParams { upscale: false, ..Default::default() });
    assert!(!f.is_empty());
    assert!(f.keypoints.iter().all(|k| k.octave_layer().0 >= 0));
}

#[test]
fn random_small_images_never_panic_and_stay_consistent() {
    let mut rng = synth::Lcg(99);
    for _ in 0..60 {
        let (w, h) = (rng.int(0, 48), rng.int(0, 48));
        let scale = rng.range(0.0, 400.0);
        let data: Vec<f32> = (0..w * h).map(|_| rng.range(-scale, scale)).collect();
        let img = GrayImage::new(w, h, data).unwrap();
        let p = SiftParams { upscale: rng.f32() < 0.7, ..Default::default() };
        let f = detect_and_compute(&img, &p);
        assert_eq!(f.descriptors.len(), f.len() * 128);
        for k in &f.keypoints {
            assert!(k.x >= 0.0 && k.y >= 0.0 && k.x <= w as f32 && k.y <= h as f32, "{k:?} in {w}x{h}");
            assert!(k.size > 0.0 && (0.0..360.0).contains(&k.angle) && k.response > 0.0);
        }
    }
}
