//! The windowed wavefront (the layers hold a sliding window of rows, keypoints made as the rows around them
//! become final) gives exactly the output of whole layers, bit for bit: with the window the parameters give,
//! with windows so small they slide every band and must grow, and with margins so small that refinements
//! step out of the window and wait for another pass down the octave.

use crate::sparse_tests::{assert_identical, images};
use crate::{Sift, SiftParams};

/// Detects on every test image with whole layers and windowed with `window` (margin, rows; `None`: the
/// parameters' own), one detector each reused across the images.
fn check(params: SiftParams, window: Option<(usize, usize)>, name: &str) {
    let mut whole = Sift::new(SiftParams { parallel: true, ..params.clone() });
    let mut windowed = Sift::new(params);
    windowed.window = window;
    for (what, img) in images() {
        let a = windowed.detect_and_compute(&img);
        let b = whole.detect_and_compute(&img);
        assert_identical(&a, &b, &format!("{name}, {what}"));
    }
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
