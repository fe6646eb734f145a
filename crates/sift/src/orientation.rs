//! Dominant orientations: 36-bin gradient histogram, [1 4 6 4 1]/16 smoothing, peaks >= 0.8 of the
//! maximum with parabolic interpolation (OpenCV `calcOrientationHist` and its caller).

use crate::fastmath::{atan2_deg, round_i32};
use crate::image::Plane;

/// Histogram bins.
pub const ORI_HIST_BINS: usize = 36;
/// Gaussian weighting sigma relative to the keypoint scale.
pub const ORI_SIG_FCTR: f32 = 1.5;
/// Window radius relative to the keypoint scale (3 x `ORI_SIG_FCTR`).
pub const ORI_RADIUS: f32 = 3.0 * ORI_SIG_FCTR;
/// A peak must reach this fraction of the maximum to give a keypoint.
pub const ORI_PEAK_RATIO: f32 = 0.8;

/// Reusable buffers for orientation histograms.
#[derive(Debug, Default, Clone)]
pub struct OriScratch {
    dx: Vec<f32>,
    dy: Vec<f32>,
    w: Vec<f32>,
    ex: Vec<f32>,
}

crate::cpu_dispatch! {
    /// Smoothed orientation histogram around integer pixel (`x`, `y`) of Gaussian image `img` (`w` x `h`);
    /// returns its maximum.
    pub fn orientation_hist(
        img: Plane<'_>,
        x: usize,
        y: usize,
        radius: i32,
        sigma: f32,
        hist: &mut [f32; ORI_HIST_BINS],
        s: &mut OriScratch,
    ) -> f32;
    "avx2" => orientation_hist_avx2 => orientation_hist_impl(img, x, y, radius, sigma, hist, s);
    _ => orientation_hist_impl(img, x, y, radius, sigma, hist, s)
}

#[inline(always)]
fn orientation_hist_impl(
    img: Plane<'_>,
    x: usize,
    y: usize,
    radius: i32,
    sigma: f32,
    hist: &mut [f32; ORI_HIST_BINS],
    s: &mut OriScratch,
) -> f32 {
    let Plane { data: img, w, h, y0 } = img;
    let n = ORI_HIST_BINS;
    let expf_scale = -1.0 / (2.0 * sigma * sigma);
    let radius = radius.max(0) as isize;
    s.ex.clear();
    s.ex.extend((0..=radius).map(|i| ((i * i) as f32 * expf_scale).exp()));
    s.dx.clear();
    s.dy.clear();
    s.w.clear();
    let (xi, yi) = (x as isize, y as isize);
    for i in -radius..=radius {
        let yy = yi + i;
        if yy <= 0 || yy >= h as isize - 1 {
            continue;
        }
        let wy = s.ex[i.unsigned_abs()];
        let row = (yy as usize - y0) * w;
        let x0 = (xi - radius).max(1);
        let x1 = (xi + radius).min(w as isize - 2);
        for xx in x0..=x1 {
            let p = row + xx as usize;
            let (gx, gy) = (img[p + 1] - img[p - 1], img[p - w] - img[p + w]);
            // A zero gradient adds `wt * 0 = +0` to a bin (bins are sums of values >= +0): skipping it
            // changes no bit.
            if gx != 0.0 || gy != 0.0 {
                s.dx.push(gx);
                s.dy.push(gy);
                s.w.push(wy * s.ex[(xx - xi).unsigned_abs()]);
            }
        }
    }
    let mut temp = [0.0f32; ORI_HIST_BINS + 4];
    let scale = n as f32 / 360.0;
    // Vectorisable pass: orientation (into dx) and magnitude (into dy).
    for (dx, dy) in s.dx.iter_mut().zip(s.dy.iter_mut()) {
        let (gx, gy) = (*dx, *dy);
        *dx = atan2_deg(gy, gx);
        *dy = (gx * gx + gy * gy).sqrt();
    }
    for ((&ori, &mag), &wt) in s.dx.iter().zip(&s.dy).zip(&s.w) {
        let mut bin = round_i32(scale * ori);
        if bin >= n as i32 {
            bin -= n as i32;
        }
        if bin < 0 {
            bin += n as i32;
        }
        temp[2 + bin as usize] += wt * mag;
    }
    temp[1] = temp[n + 1];
    temp[0] = temp[n];
    temp[n + 2] = temp[2];
    temp[n + 3] = temp[3];
    let mut maxval = f32::MIN;
    for i in 0..n {
        let t = &temp[i..i + 5];
        hist[i] = (t[0] + t[4]) * (1.0 / 16.0) + (t[1] + t[3]) * (4.0 / 16.0) + t[2] * (6.0 / 16.0);
        maxval = maxval.max(hist[i]);
    }
    maxval
}

/// Angles (degrees, OpenCV keypoint convention) of the histogram's peaks reaching `ORI_PEAK_RATIO` of `max`.
pub fn peak_angles(hist: &[f32; ORI_HIST_BINS], max: f32, out: &mut Vec<f32>) {
    let n = ORI_HIST_BINS;
    let mag_thr = max * ORI_PEAK_RATIO;
    for j in 0..n {
        let l = if j > 0 { j - 1 } else { n - 1 };
        let r2 = if j < n - 1 { j + 1 } else { 0 };
        if hist[j] > hist[l] && hist[j] > hist[r2] && hist[j] >= mag_thr {
            let mut bin = j as f32 + 0.5 * (hist[l] - hist[r2]) / (hist[l] - 2.0 * hist[j] + hist[r2]);
            bin = if bin < 0.0 {
                n as f32 + bin
            } else if bin >= n as f32 {
                bin - n as f32
            } else {
                bin
            };
            let mut angle = 360.0 - (360.0 / n as f32) * bin;
            if (angle - 360.0).abs() < f32::EPSILON {
                angle = 0.0;
            }
            out.push(angle);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_gives_one_orientation() {
        // Intensity increasing to the right: gradient along +x, OpenCV angle 0 (or 360 - 0).
        let (w, h) = (32, 32);
        let img: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 3.0).collect();
        let mut hist = [0.0; ORI_HIST_BINS];
        let max = orientation_hist(Plane::new(&img, w, h), 16, 16, 6, 2.0, &mut hist, &mut OriScratch::default());
        let mut angles = Vec::new();
        peak_angles(&hist, max, &mut angles);
        assert_eq!(angles.len(), 1);
        assert!(angles[0] < 1.0 || angles[0] > 359.0, "{angles:?}");
        // Intensity increasing downwards: dy = img[y-1] - img[y+1] < 0, atan -> 270, keypoint angle 90.
        let img: Vec<f32> = (0..w * h).map(|i| (i / w) as f32 * 3.0).collect();
        let max = orientation_hist(Plane::new(&img, w, h), 16, 16, 6, 2.0, &mut hist, &mut OriScratch::default());
        angles.clear();
        peak_angles(&hist, max, &mut angles);
        assert_eq!(angles.len(), 1);
        assert!((angles[0] - 90.0).abs() < 1.0, "{angles:?}");
    }
}
