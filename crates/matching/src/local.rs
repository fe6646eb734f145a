//! The fine stage: the best of a small window of angles and cell offsets around a global answer, on a score
//! field at map a's own resolution, every offset scored.
//!
//! A window is a cross-correlation of the scan's cells with the field over `n × n` offsets: each point adds the
//! `n` field values of a row segment to a row of accumulators, `n` rows per point, contiguous loads the
//! compiler vectorises. On a field blurred over a few cells a max-pooled bound stays above most offsets' scores
//! and branch and bound scores nearly all of them anyway, one gather per point each (8x slower on real maps).

use crate::field::ScoreField;
use crate::scan::WallScan;

/// A score field laid out for window searches: each row with zero cells either side, so a window's row segment
/// that leaves the field reads zeros, as a point off the field scores.
#[derive(Debug, Clone)]
pub struct WindowField {
    /// Cells along x.
    width: usize,
    /// Cells along y.
    height: usize,
    /// Zero cells before and after each row.
    margin: usize,
    /// Row-major values, rows of `width + 2 · margin`.
    values: Vec<i16>,
}

impl WindowField {
    /// `field` ready for windows of up to `max_cells` offsets either side.
    pub fn new(field: &ScoreField, max_cells: usize) -> Self {
        let margin = 2 * max_cells + 1;
        let stride = field.width + 2 * margin;
        let mut values = vec![0i16; stride * field.height];
        if field.width > 0 {
            for (row, out) in field.values.chunks_exact(field.width).zip(values.chunks_exact_mut(stride)) {
                out[margin..margin + field.width].copy_from_slice(row);
            }
        }
        WindowField { width: field.width, height: field.height, margin, values }
    }

    /// The value at cell (`x`, `y`); 0 off the field.
    pub fn get(&self, x: i32, y: i32) -> i16 {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return 0;
        }
        self.values[y as usize * (self.width + 2 * self.margin) + self.margin + x as usize]
    }

    /// Largest window half-width (offsets either side) this layout serves.
    fn max_cells(&self) -> usize {
        (self.margin - 1) / 2
    }
}

/// A pose of b's scan in map a's grid frame: turn `theta` about the scan's centroid, which lands at `t`
/// (metres from a's cell (0, 0) corner, along a's grid axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanPose {
    /// Rotation, radians.
    pub theta: f64,
    /// Where the centroid lands, x, metres.
    pub tx: f64,
    /// Where the centroid lands, y, metres.
    pub ty: f64,
}

/// What the fine window spans around a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalWindow {
    /// Offsets tried either side, cells of the field.
    pub cells: i32,
    /// Angles tried either side of the pose's.
    pub angles: usize,
    /// Angular step, radians.
    pub angle_step: f64,
}

/// Buffers of [`local_search`], kept between calls (no allocation once they have grown).
#[derive(Debug, Default)]
pub struct LocalScratch {
    points: Vec<(i32, i32)>,
    sums: Vec<i32>,
}

/// The best pose within `window` of `start` on `field` (cells of `cell` metres), and its score.
///
/// Every offset of every angle is scored; ties go to the lowest angle, then the lowest offset in y, then in x.
///
/// # Panics
/// When the window is wider than the field was laid out for ([`WindowField::new`]).
pub fn local_search(
    field: &WindowField,
    cell: f64,
    scan: &WallScan,
    start: ScanPose,
    window: &LocalWindow,
    scratch: &mut LocalScratch,
) -> (ScanPose, i64) {
    let c = window.cells.max(0);
    assert!(c as usize <= field.max_cells(), "a window of {c} cells on a field laid out for {}", field.max_cells());
    let (_, cx, cy) = window_key(&start, cell);
    let n = (2 * c + 1) as usize;
    let LocalScratch { points, sums } = scratch;
    let mut best = (start, i64::MIN);
    let k = window.angles as i64;
    for j in -k..=k {
        let theta = start.theta + j as f64 * window.angle_step;
        scan.discretize(theta, cell, points);
        window_sums(field, points, (cx - c, cy - c), n, sums);
        // The first of the highest, row-major: offsets from the lowest y, then x.
        let (at, &score) = sums.iter().enumerate().fold((0, &i32::MIN), |b, (i, s)| if *s > *b.1 { (i, s) } else { b });
        if i64::from(score) > best.1 {
            let (ox, oy) = (cx - c + (at % n) as i32, cy - c + (at / n) as i32);
            let pose = ScanPose { theta, tx: cell * (f64::from(ox) + 0.5), ty: cell * (f64::from(oy) + 0.5) };
            best = (pose, i64::from(score));
        }
    }
    best
}

/// A window by its start's angle (bits) and the cell its centroid falls in.
pub type WindowKey = (u64, i32, i32);

/// What a window's answer depends on besides the field, the scan and its extent: two starts with the same key
/// have the same answer.
pub fn window_key(start: &ScanPose, cell: f64) -> WindowKey {
    (start.theta.to_bits(), (start.tx / cell - 0.5).round() as i32, (start.ty / cell - 0.5).round() as i32)
}

/// The scores of `points` displaced by every offset `(x0 + i, y0 + j)`, `i, j < n`, into `sums[j · n + i]`:
/// the same loop compiled for AVX2 where the processor has it (twice the lanes of the baseline's SSE2).
fn window_sums(field: &WindowField, points: &[(i32, i32)], origin: (i32, i32), n: usize, sums: &mut Vec<i32>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above); the function is plain safe Rust otherwise.
        unsafe { window_sums_avx2(field, points, origin, n, sums) };
        return;
    }
    window_sums_any(field, points, origin, n, sums);
}

/// [`window_sums_any`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn window_sums_avx2(field: &WindowField, points: &[(i32, i32)], origin: (i32, i32), n: usize, sums: &mut Vec<i32>) {
    window_sums_any(field, points, origin, n, sums);
}

/// [`window_sums`] for any processor.
#[inline(always)]
fn window_sums_any(field: &WindowField, points: &[(i32, i32)], (x0, y0): (i32, i32), n: usize, sums: &mut Vec<i32>) {
    sums.clear();
    sums.resize(n * n, 0);
    let (w, h, m) = (field.width as i32, field.height as i32, field.margin as i32);
    let stride = field.width + 2 * field.margin;
    let reach = n as i32 - 1;
    for &(px, py) in points {
        let (x, y) = (px + x0, py + y0);
        // The segment [x, x + n) misses the field, or the rows [y, y + n) do.
        if x + reach < 0 || x >= w || y + reach < 0 || y >= h {
            continue;
        }
        // x ≥ -reach ≥ -m and x + reach < w + m: the segment lies in the row and its margins.
        let start = (x + m) as usize;
        let (j0, j1) = ((-y).max(0) as usize, ((h - y) as usize).min(n));
        for j in j0..j1 {
            let row = (y as usize).wrapping_add(j) * stride + start;
            let segment = &field.values[row..row + n];
            for (s, &v) in sums[j * n..(j + 1) * n].iter_mut().zip(segment) {
                *s += i32::from(v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The answer as a plain scan defines it: angles from the lowest, offsets row-major, each point read on the
    /// field (0 off it), a later pose only when strictly better.
    fn plain(field: &ScoreField, scan: &WallScan, start: ScanPose, w: &LocalWindow) -> (ScanPose, i64) {
        let cell = 0.05;
        let (cx, cy) = ((start.tx / cell - 0.5).round() as i32, (start.ty / cell - 0.5).round() as i32);
        let mut best = (start, i64::MIN);
        let mut points = Vec::new();
        for j in -(w.angles as i64)..=w.angles as i64 {
            let theta = start.theta + j as f64 * w.angle_step;
            scan.discretize(theta, cell, &mut points);
            for oy in cy - w.cells..=cy + w.cells {
                for ox in cx - w.cells..=cx + w.cells {
                    let s: i64 = points.iter().map(|&(x, y)| i64::from(field.get(x + ox, y + oy))).sum();
                    if s > best.1 {
                        let tx = cell * (f64::from(ox) + 0.5);
                        best = (ScanPose { theta, tx, ty: cell * (f64::from(oy) + 0.5) }, s);
                    }
                }
            }
        }
        best
    }

    #[test]
    fn the_window_search_is_the_plain_scan_inside_and_across_the_field_edges() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for trial in 0..20 {
            let (w, h) = (60, 50);
            // Few distinct values, so that ties occur and their order is tested too.
            let values = (0..w * h).map(|_| rng.random_range(-2i16..=3) * 10).collect();
            let field = ScoreField { width: w, height: h, values };
            let all: Vec<Point2<f64>> =
                (0..40).map(|_| Point2::new(rng.random_range(0.0..2.0), rng.random_range(0.0..2.0))).collect();
            let scan = WallScan::of_points(&all, 0);
            // Near the middle, then at the corners and past them: part of the scan (or all of it) off the field.
            let (tx, ty) = [(1.5, 1.2), (0.1, 0.1), (2.9, 2.4), (-0.8, 1.0), (3.5, 3.0)][trial % 5];
            let start = ScanPose { theta: 0.3, tx, ty };
            let window = LocalWindow { cells: 1 + trial as i32 % 7, angles: trial % 3, angle_step: 0.05 };
            let laid = WindowField::new(&field, 7);
            let found = local_search(&laid, 0.05, &scan, start, &window, &mut LocalScratch::default());
            assert_eq!(found, plain(&field, &scan, start, &window), "trial {trial}");
        }
    }

    #[test]
    fn the_dispatched_sums_are_the_baseline_sums() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let values = (0..40 * 30).map(|_| rng.random_range(-200i16..=100)).collect();
        let laid = WindowField::new(&ScoreField { width: 40, height: 30, values }, 9);
        let points: Vec<(i32, i32)> =
            (0..300).map(|_| (rng.random_range(-30..60), rng.random_range(-30..50))).collect();
        let (mut fast, mut base) = (Vec::new(), Vec::new());
        for origin in [(-5, -5), (10, 3), (-25, 20)] {
            window_sums(&laid, &points, origin, 19, &mut fast);
            window_sums_any(&laid, &points, origin, 19, &mut base);
            assert_eq!(fast, base, "{origin:?}");
        }
    }

    #[test]
    fn a_laid_out_field_reads_as_the_field() {
        let field = ScoreField { width: 3, height: 2, values: vec![1, 2, 3, 4, 5, 6] };
        let laid = WindowField::new(&field, 2);
        for y in -3..5 {
            for x in -4..7 {
                assert_eq!(laid.get(x, y), field.get(x, y), "({x}, {y})");
            }
        }
    }
}
