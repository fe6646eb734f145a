//! A rotation prior from the maps' wall orientations: the rotations at which the two maps' histograms of wall
//! orientation agree. Carpin (2008) correlates the maps' Hough spectra for the same purpose; the histogram here
//! is of the walls' local directions (each wall cell's neighbourhood), which a Hough spectrum sums along lines.
//!
//! A wall's orientation is known modulo a half turn, so each peak θ of the correlation stands for θ and θ + π;
//! a building whose walls meet at right angles has its peaks 90° apart, so four rotations survive per peak pair.

use mrslam_core::{CellState, OccupancyGrid};
use std::f64::consts::PI;

/// Bins of an orientation histogram over [0, π): one degree each.
pub const BINS: usize = 180;

/// Radius (cells) of the neighbourhood whose wall cells give a wall cell its direction: a thin wall's staircase
/// of cells reads as one line over 15 cells (at 3, a rotated plan's peak was up to 5° off towards its grid's axes; at 7,
/// below 1°).
const LINE_RADIUS: i32 = 7;

/// Blur (Gaussian σ, bins) of a histogram: one map's walls may lean a degree against the other's.
const HISTOGRAM_BLUR_BINS: f64 = 1.5;

/// The histogram of `g`'s wall directions modulo π: each wall cell votes for the principal axis of the wall cells
/// within [`LINE_RADIUS`] of it, weighted by how line-like they are (1 on a straight wall, 0 on a blob or a
/// corner); blurred over the bins, mean 0, so a rotation's correlation is how much more the two maps agree there
/// than on average.
pub fn orientation_histogram(g: &OccupancyGrid) -> Vec<f64> {
    let (w, h) = (g.width() as i32, g.height() as i32);
    let wall: Vec<bool> = g.cells().iter().map(|&l| CellState::from_log_odds(l) == CellState::Occupied).collect();
    let r = LINE_RADIUS;
    let disc: Vec<(i32, i32)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|(dx, dy)| dx * dx + dy * dy <= r * r)
        .collect();
    let mut hist = vec![0.0f64; BINS];
    for y in 0..h {
        for x in 0..w {
            if !wall[(y * w + x) as usize] {
                continue;
            }
            let (mut n, mut sxx, mut syy, mut sxy) = (0i32, 0i32, 0i32, 0i32);
            for &(dx, dy) in &disc {
                let (xx, yy) = (x + dx, y + dy);
                if xx >= 0 && yy >= 0 && xx < w && yy < h && wall[(yy * w + xx) as usize] {
                    (n, sxx, syy, sxy) = (n + 1, sxx + dx * dx, syy + dy * dy, sxy + dx * dy);
                }
            }
            if n < 3 {
                continue;
            }
            // Second moments about the cell itself: the axis of a line through it.
            let (cxx, cyy, cxy) = (f64::from(sxx), f64::from(syy), f64::from(sxy));
            let spread = cxx + cyy;
            let line = ((cxx - cyy).powi(2) + 4.0 * cxy * cxy).sqrt() / spread;
            let a = (0.5 * (2.0 * cxy).atan2(cxx - cyy)).rem_euclid(PI);
            hist[((a / PI * BINS as f64) as usize).min(BINS - 1)] += line;
        }
    }
    let mut hist = blur_circular(&hist, HISTOGRAM_BLUR_BINS);
    let mean = hist.iter().sum::<f64>() / BINS as f64;
    hist.iter_mut().for_each(|v| *v -= mean);
    hist
}

/// `c[k] = Σ_i a[(i + k) mod n] · b[i]`: how well b's orientations turned by k bins meet a's.
pub fn correlation(a: &[f64], b: &[f64]) -> Vec<f64> {
    let n = a.len();
    (0..n).map(|k| (0..n).map(|i| a[(i + k) % n] * b[i]).sum()).collect()
}

/// The rotations modulo π (radians) at the local maxima of `corr` scoring at least `ratio` of its largest value,
/// strongest first; empty when nothing correlates (no walls).
pub fn peaks(corr: &[f64], ratio: f64) -> Vec<f64> {
    let n = corr.len();
    let top = corr.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if n == 0 || top <= 0.0 {
        return Vec::new();
    }
    let mut found: Vec<(f64, usize)> = (0..n)
        .filter(|&k| {
            let (prev, next) = (corr[(k + n - 1) % n], corr[(k + 1) % n]);
            corr[k] >= ratio * top && corr[k] > prev && corr[k] >= next
        })
        .map(|k| (corr[k], k))
        .collect();
    found.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    found.into_iter().map(|(_, k)| k as f64 * PI / n as f64).collect()
}

/// Whether rotation `theta` lies within `tolerance` (radians) of a peak (modulo π).
pub fn near_a_peak(theta: f64, peaks: &[f64], tolerance: f64) -> bool {
    peaks.iter().any(|&p| {
        let d = (theta - p).rem_euclid(PI);
        d.min(PI - d) <= tolerance
    })
}

/// The rotations of b onto a worth searching: peaks of the correlation of their orientation histograms.
pub fn rotation_peaks(a: &OccupancyGrid, b: &OccupancyGrid, ratio: f64) -> Vec<f64> {
    peaks(&correlation(&orientation_histogram(a), &orientation_histogram(b)), ratio)
}

/// A Gaussian kernel of σ `sigma`, radius 3σ, normalised.
fn kernel(sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as i32;
    let k: Vec<f64> = (-r..=r).map(|i| (-(f64::from(i).powi(2)) / (2.0 * sigma * sigma)).exp()).collect();
    let s: f64 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

/// Blurs a circular histogram.
fn blur_circular(h: &[f64], sigma: f64) -> Vec<f64> {
    let k = kernel(sigma);
    let (n, r) = (h.len() as i64, (k.len() / 2) as i64);
    (0..n).map(|i| k.iter().enumerate().map(|(j, w)| w * h[(i + j as i64 - r).rem_euclid(n) as usize]).sum()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use crate::pairs::{PairSpec, cut_pair};

    #[test]
    fn the_true_rotation_of_a_cut_pair_is_near_a_peak() {
        for seed in 0..6 {
            let plan = generate(seed, &FloorplanParams::default());
            let pair = cut_pair(&plan, &PairSpec { overlap: 0.3, max_shift_m: 3.0, rotate: true }, seed);
            let theta = pair.t_a_b.rotation.angle();
            let peaks = rotation_peaks(&pair.a, &pair.b, 0.5);
            assert!(!peaks.is_empty() && peaks.len() <= 6, "seed {seed}: {peaks:?}");
            assert!(near_a_peak(theta, &peaks, 1.5f64.to_radians()), "seed {seed}: {theta} not near {peaks:?}");
            // The peaks say little about other rotations: most of the turn is not searched.
            let searched = (0..360).filter(|d| near_a_peak(f64::from(*d).to_radians(), &peaks, 4f64.to_radians()));
            assert!(searched.count() < 120, "seed {seed}");
        }
    }

    #[test]
    fn peaks_are_local_maxima_above_the_ratio_strongest_first() {
        let mut c = vec![0.0; 180];
        (c[10], c[11], c[100], c[150]) = (5.0, 4.0, 10.0, 2.0);
        let p = peaks(&c, 0.3);
        assert_eq!(p.len(), 2);
        assert!((p[0] - 100f64.to_radians()).abs() < 1e-9 && (p[1] - 10f64.to_radians()).abs() < 1e-9);
        assert!(peaks(&vec![0.0; 180], 0.3).is_empty());
        assert!(near_a_peak(PI + 100f64.to_radians(), &p, 0.01), "a peak stands for itself plus a half turn");
    }
}
