//! The windowed wavefront (the layers hold a sliding window of rows, keypoints made as the rows around them
//! become final) gives exactly the output of whole layers, bit for bit: with the window the parameters give,
//! with windows so small they slide every band and must grow, and with margins so small that refinements
//! step out of the window and wait for another pass down the octave.

use crate::sparse_tests::{assert_agree_on_images, assert_identical};
use crate::{GrayImage, Sift, SiftParams};
use proptest::prelude::*;

/// Detects on every test image with whole layers and windowed with `window` (margin, rows; `None`: the
/// parameters' own), one detector each reused across the images.
fn check(params: SiftParams, window: Option<(usize, usize)>, name: &str) {
    let mut whole = Sift::new(SiftParams { parallel: true, ..params.clone() });
    let mut windowed = Sift::new(params);
    windowed.window = window;
    assert_agree_on_images(&mut windowed, &mut whole, name);
}

#[test]
fn windowed_octaves_equal_whole_ones() {
    check(SiftParams::default(), None, "default");
    check(SiftParams { upscale: false, ..SiftParams::default() }, None, "upscale off");
    check(SiftParams { n_octave_layers: 5, contrast_threshold: 0.005, ..SiftParams::default() }, None, "5 layers");
    check(SiftParams { n_octave_layers: 2, sigma: 3.1, ..SiftParams::default() }, None, "sigma 3.1");
}

#[test]
fn a_window_too_small_slides_and_grows_and_changes_nothing() {
    for rows in [1, 17, 40, 97] {
        check(SiftParams::default(), Some((48, rows)), &format!("{rows} rows"));
    }
}

#[test]
fn refinements_out_of_the_window_resume_in_another_pass_and_keep_their_place() {
    // A margin of 0 or 1 row: most keypoints read rows the window no longer (or does not yet) hold.
    for margin in [0, 1, 3] {
        check(SiftParams::default(), Some((margin, 24)), &format!("margin {margin}"));
        check(SiftParams { upscale: false, ..SiftParams::default() }, Some((margin, 24)), &format!("margin {margin}"));
    }
}

/// A map-like image from a seed: a few constant levels in rectangles (walls, rooms, unknown), with speckle.
fn random_map(w: usize, h: usize, seed: u64) -> GrayImage {
    let mut rng = crate::synth::Lcg(seed);
    let levels = [0.0f32, 205.0, 254.0, 128.0];
    let mut d = vec![levels[rng.int(0, 4)]; w * h];
    for _ in 0..rng.int(1, 12) {
        let (x0, y0) = (rng.int(0, w), rng.int(0, h));
        let (bw, bh) = (rng.int(1, w / 2 + 2), rng.int(1, h / 2 + 2));
        let v = levels[rng.int(0, 4)];
        for y in y0..(y0 + bh).min(h) {
            for x in x0..(x0 + bw).min(w) {
                d[y * w + x] = v;
            }
        }
    }
    for _ in 0..rng.int(0, w * h / 20 + 1) {
        let i = rng.int(0, w * h);
        d[i] = rng.range(0.0, 255.0);
    }
    GrayImage::new(w, h, d).expect("finite")
}

proptest! {
    // About half the cases give keypoints (28 of 48 when written, 147 in all).
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Any image, parameters, window and margin: the windowed build gives the whole octave's output.
    #[test]
    fn any_window_gives_the_whole_octaves_output(w in 8usize..72, h in 8usize..72, seed in any::<u64>(),
                                                 upscale in any::<bool>(), layers in 1usize..5,
                                                 contrast in 0.0f32..0.05, margin in 0usize..60,
                                                 rows in 1usize..160) {
        let img = random_map(w, h, seed);
        let params = SiftParams { upscale, n_octave_layers: layers, contrast_threshold: contrast, ..SiftParams::default() };
        let whole = Sift::new(SiftParams { parallel: true, ..params.clone() }).detect_and_compute(&img);
        let mut windowed = Sift::new(params);
        windowed.window = Some((margin, rows));
        assert_identical(&windowed.detect_and_compute(&img), &whole, &format!("{w}x{h} seed {seed}"));
    }
}
