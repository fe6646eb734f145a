//! Repeatability and descriptor matching under rotation (30°, 90°) and scaling (0.5, 2) of a textured image.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_sift::{Features, GrayImage, SiftParams, detect_and_compute};

mod common;
use common::synth;

/// Outcome of comparing the keypoints of a reference image with those of a transformed copy.
#[derive(Debug)]
struct Score {
    /// Reference keypoints whose neighbourhood lies inside both images.
    eligible: usize,
    /// Of those, found again in the other image within the tolerance.
    repeated: usize,
    /// Of the repeated, whose nearest descriptor in the other image lies at the right place.
    nn_correct: usize,
}

fn sq_dist(a: &[u8], b: &[u8]) -> u32 {
    a.iter().zip(b).map(|(&x, &y)| (i32::from(x) - i32::from(y)).pow(2) as u32).sum()
}

/// Counts, for reference keypoints `r`, how many are found in `o` within `tol` px (measured in the
/// reference frame) and how many have their descriptor's nearest neighbour in `o` within `nn_tol` px.
/// `r_to_o` / `o_to_r` map points between frames; `o_size` is the other image's size.
#[allow(clippy::too_many_arguments)]
fn score(
    r: &Features,
    r_size: (usize, usize),
    o: &Features,
    o_size: (usize, usize),
    r_to_o: impl Fn(f32, f32) -> (f32, f32),
    o_to_r: impl Fn(f32, f32) -> (f32, f32),
    o_scale: f32,
    tol: f32,
    nn_tol: f32,
) -> Score {
    let o_in_r: Vec<(f32, f32)> = o.keypoints.iter().map(|k| o_to_r(k.x, k.y)).collect();
    let inside = |x: f32, y: f32, (w, h): (usize, usize), m: f32| {
        x >= m && y >= m && x <= w as f32 - 1.0 - m && y <= h as f32 - 1.0 - m
    };
    let mut s = Score { eligible: 0, repeated: 0, nn_correct: 0 };
    for (i, k) in r.keypoints.iter().enumerate() {
        let m = 8.0 + 1.5 * k.size;
        let (ox, oy) = r_to_o(k.x, k.y);
        if !inside(k.x, k.y, r_size, m) || !inside(ox, oy, o_size, m * o_scale) {
            continue;
        }
        s.eligible += 1;
        let near = |&(x, y): &(f32, f32), t: f32| (x - k.x).powi(2) + (y - k.y).powi(2) <= t * t;
        if !o_in_r.iter().any(|p| near(p, tol)) {
            continue;
        }
        s.repeated += 1;
        let d = r.descriptor(i);
        let nn = (0..o.len()).min_by_key(|&j| (sq_dist(d, o.descriptor(j)), j)).expect("non-empty");
        if near(&o_in_r[nn], nn_tol) {
            s.nn_correct += 1;
        }
    }
    s
}

fn texture(w: usize, h: usize) -> Vec<f32> {
    synth::texture(w, h, 42).into_iter().map(f32::from).collect()
}

fn assert_score(name: &str, s: &Score) {
    eprintln!("{name}: {s:?}");
    assert!(s.eligible >= 40, "{name}: too few keypoints to judge: {s:?}");
    let rep = s.repeated as f32 / s.eligible as f32;
    let nn = s.nn_correct as f32 / s.repeated.max(1) as f32;
    assert!(rep >= 0.6, "{name}: repeatability {rep:.2} < 0.6 ({s:?})");
    assert!(nn >= 0.8, "{name}: descriptor NN correct {nn:.2} < 0.8 ({s:?})");
}

fn rotation(deg: f32) {
    let (w, h) = (256usize, 256usize);
    let a = texture(w, h);
    let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
    let (cx, cy) = ((w as f32 - 1.0) / 2.0, (h as f32 - 1.0) / 2.0);
    // Forward: a point q of A appears in B at R (q - c) + c.
    let fwd = move |x: f32, y: f32| (c * (x - cx) - s * (y - cy) + cx, s * (x - cx) + c * (y - cy) + cy);
    let inv = move |x: f32, y: f32| (c * (x - cx) + s * (y - cy) + cx, -s * (x - cx) + c * (y - cy) + cy);
    let b = synth::warp(&a, w, h, w, h, 128.0, inv);
    let p = SiftParams::default();
    let fa = detect_and_compute(&GrayImage::new(w, h, a).unwrap(), &p);
    let fb = detect_and_compute(&GrayImage::new(w, h, b).unwrap(), &p);
    let sc = score(&fa, (w, h), &fb, (w, h), fwd, inv, 1.0, 1.5, 2.0);
    assert_score(&format!("rotation {deg}"), &sc);
}

#[test]
fn rotation_30_degrees() {
    rotation(30.0);
}

#[test]
fn rotation_90_degrees() {
    rotation(90.0);
}

#[test]
fn scale_half() {
    // B = A halved by 2x2 averaging: x_A = 2 x_B + 0.5. Reference: the smaller image B.
    let (w, h) = (384usize, 384usize);
    let a = texture(w, h);
    let b = synth::halve(&a, w, h);
    let p = SiftParams::default();
    let fa = detect_and_compute(&GrayImage::new(w, h, a).unwrap(), &p);
    let fb = detect_and_compute(&GrayImage::new(w / 2, h / 2, b).unwrap(), &p);
    let b_to_a = |x: f32, y: f32| (2.0 * x + 0.5, 2.0 * y + 0.5);
    let a_to_b = |x: f32, y: f32| ((x - 0.5) / 2.0, (y - 0.5) / 2.0);
    let sc = score(&fb, (w / 2, h / 2), &fa, (w, h), b_to_a, a_to_b, 2.0, 1.5, 2.0);
    assert_score("scale 0.5", &sc);
}

#[test]
fn scale_double() {
    // B = A doubled (bilinear, half-pixel centres): x_B = 2 x_A + 0.5. Reference: the smaller image A.
    let (w, h) = (256usize, 256usize);
    let a = texture(w, h);
    let b = synth::warp(&a, w, h, 2 * w, 2 * h, 128.0, |x, y| {
        (((x + 0.5) / 2.0 - 0.5).clamp(0.0, w as f32 - 1.0), ((y + 0.5) / 2.0 - 0.5).clamp(0.0, h as f32 - 1.0))
    });
    let p = SiftParams::default();
    let fa = detect_and_compute(&GrayImage::new(w, h, a).unwrap(), &p);
    let fb = detect_and_compute(&GrayImage::new(2 * w, 2 * h, b).unwrap(), &p);
    let a_to_b = |x: f32, y: f32| (2.0 * x + 0.5, 2.0 * y + 0.5);
    let b_to_a = |x: f32, y: f32| ((x - 0.5) / 2.0, (y - 0.5) / 2.0);
    let sc = score(&fa, (w, h), &fb, (2 * w, 2 * h), a_to_b, b_to_a, 2.0, 1.5, 2.0);
    assert_score("scale 2", &sc);
}
