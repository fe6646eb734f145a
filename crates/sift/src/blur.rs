//! Separable Gaussian blur on contiguous f32 rows, OpenCV's kernel size and `BORDER_REFLECT_101`.
//!
//! Each output row is made in two passes over a small row buffer: a vertical pass that accumulates the
//! kernel's rows (symmetric taps paired, 16 columns at a time in registers), then a horizontal pass over
//! the padded buffer. The loops are written so the compiler vectorises them; on x86-64 CPUs with AVX2 a
//! copy compiled for AVX2 is picked at run time. No fused multiply-add is used, so both copies give
//! bit-identical results.

use rayon::prelude::*;

/// Columns processed together in registers (enough independent accumulators to hide add latency).
const LANES_AVX512: usize = 64;
/// Same for AVX2 and the portable path.
const LANES: usize = 32;

/// A symmetric Gaussian kernel: `half[0]` is the centre weight, `half[i]` the weight at offsets ±i.
#[derive(Debug, Clone, PartialEq)]
pub struct Kernel {
    /// Centre weight first, then the weights of offsets 1, 2, ... (normalised: full kernel sums to 1).
    pub half: Vec<f32>,
}

impl Kernel {
    /// OpenCV's `GaussianBlur(.., Size(), sigma)` kernel for float images: size `round(8 sigma + 1) | 1`.
    pub fn gaussian(sigma: f64) -> Self {
        let ksize = ((sigma * 8.0 + 1.0).round_ties_even().max(1.0) as usize) | 1;
        let r = ksize / 2;
        let scale2 = -0.5 / (sigma * sigma);
        let full: Vec<f64> = (0..ksize)
            .map(|i| {
                let x = i as f64 - r as f64;
                (scale2 * x * x).exp()
            })
            .collect();
        let sum: f64 = full.iter().sum();
        Self { half: full[r..].iter().map(|v| (v / sum) as f32).collect() }
    }

    /// Kernel radius (number of taps on each side of the centre).
    pub fn radius(&self) -> usize {
        self.half.len() - 1
    }
}

/// OpenCV `BORDER_REFLECT_101` index for `i` in a line of `n` (> 0) samples: `-1 -> 1`, `n -> n - 2`.
pub fn reflect101(mut i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    loop {
        if i < 0 {
            i = -i;
        } else if i >= n {
            i = 2 * n - 2 - i;
        } else {
            return i as usize;
        }
    }
}

/// Blurs `src` (`w` x `h`, row-major) into `dst` with `kernel`; `row_buf` is scratch (resized as needed).
/// With `parallel`, bands of rows are spread over the rayon pool (same result).
pub fn blur(src: &[f32], dst: &mut [f32], w: usize, h: usize, kernel: &Kernel, row_buf: &mut Vec<f32>, parallel: bool) {
    let n = w * h;
    if n == 0 {
        return;
    }
    let (src, dst) = (&src[..n], &mut dst[..n]);
    let r = kernel.radius();
    if parallel && h >= 64 {
        let band = h.div_ceil(rayon::current_num_threads().max(1) * 4).max(8);
        dst.par_chunks_mut(band * w).enumerate().for_each(|(b, chunk)| {
            let mut buf = vec![0.0f32; w + 2 * r];
            let y0 = b * band;
            blur_rows(src, chunk, w, h, y0, kernel, &mut buf);
        });
    } else {
        row_buf.resize(w + 2 * r, 0.0);
        blur_rows(src, dst, w, h, 0, kernel, row_buf);
    }
}

/// Blurs rows `y0 .. y1` of `dst` from `src` (both `w x h`); `src` rows up to `min(h, y1 + radius)` (and
/// the first `radius` rows) must be final. Used to run the layers of an octave as a cache-friendly wavefront.
#[allow(clippy::too_many_arguments)]
pub fn blur_band(
    src: &[f32],
    dst: &mut [f32],
    w: usize,
    h: usize,
    y0: usize,
    y1: usize,
    kernel: &Kernel,
    row_buf: &mut Vec<f32>,
) {
    if w == 0 || y0 >= y1 {
        return;
    }
    row_buf.resize(w + 2 * kernel.radius(), 0.0);
    blur_rows(&src[..w * h], &mut dst[y0 * w..y1 * w], w, h, y0, kernel, row_buf);
}

/// Blurs output rows `y0 .. y0 + out.len() / w` into `out`.
fn blur_rows(src: &[f32], out: &mut [f32], w: usize, h: usize, y0: usize, kernel: &Kernel, buf: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            unsafe { blur_rows_avx512(src, out, w, h, y0, kernel, buf) };
            return;
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { blur_rows_avx2(src, out, w, h, y0, kernel, buf) };
            return;
        }
    }
    blur_rows_impl::<LANES>(src, out, w, h, y0, kernel, buf);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn blur_rows_avx2(src: &[f32], out: &mut [f32], w: usize, h: usize, y0: usize, kernel: &Kernel, buf: &mut [f32]) {
    blur_rows_impl::<LANES>(src, out, w, h, y0, kernel, buf);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn blur_rows_avx512(src: &[f32], out: &mut [f32], w: usize, h: usize, y0: usize, kernel: &Kernel, buf: &mut [f32]) {
    blur_rows_impl::<LANES_AVX512>(src, out, w, h, y0, kernel, buf);
}

#[inline(always)]
fn blur_rows_impl<const LANES: usize>(
    src: &[f32],
    out: &mut [f32],
    w: usize,
    h: usize,
    y0: usize,
    kernel: &Kernel,
    buf: &mut [f32],
) {
    let k = &kernel.half[..];
    let r = k.len() - 1;
    let k0 = k[0];
    let mut above: Vec<usize> = vec![0; r + 1];
    let mut below: Vec<usize> = vec![0; r + 1];
    for (dy, out_row) in out.chunks_exact_mut(w).enumerate() {
        let y = y0 + dy;
        for i in 1..=r {
            above[i] = reflect101(y as isize - i as isize, h) * w;
            below[i] = reflect101((y + i) as isize, h) * w;
        }
        // Vertical pass into buf[r .. r + w].
        let centre = &src[y * w..y * w + w];
        let inner = &mut buf[r..r + w];
        let mut x = 0;
        while x + LANES <= w {
            let mut acc = [0.0f32; LANES];
            let c = &centre[x..x + LANES];
            for l in 0..LANES {
                acc[l] = k0 * c[l];
            }
            for i in 1..=r {
                let a = &src[above[i] + x..above[i] + x + LANES];
                let b = &src[below[i] + x..below[i] + x + LANES];
                let ki = k[i];
                for l in 0..LANES {
                    acc[l] += ki * (a[l] + b[l]);
                }
            }
            inner[x..x + LANES].copy_from_slice(&acc);
            x += LANES;
        }
        for x in x..w {
            let mut acc = k0 * centre[x];
            for i in 1..=r {
                acc += k[i] * (src[above[i] + x] + src[below[i] + x]);
            }
            inner[x] = acc;
        }
        // Reflect-101 padding of the vertical result.
        for j in 1..=r {
            buf[r - j] = buf[r + reflect101(-(j as isize), w)];
            buf[r + w - 1 + j] = buf[r + reflect101((w - 1 + j) as isize, w)];
        }
        // Horizontal pass.
        let mut x = 0;
        while x + LANES <= w {
            let mut acc = [0.0f32; LANES];
            let c = &buf[r + x..r + x + LANES];
            for l in 0..LANES {
                acc[l] = k0 * c[l];
            }
            for i in 1..=r {
                let a = &buf[r + x - i..r + x - i + LANES];
                let b = &buf[r + x + i..r + x + i + LANES];
                let ki = k[i];
                for l in 0..LANES {
                    acc[l] += ki * (a[l] + b[l]);
                }
            }
            out_row[x..x + LANES].copy_from_slice(&acc);
            x += LANES;
        }
        for x in x..w {
            let mut acc = k0 * buf[r + x];
            for i in 1..=r {
                acc += k[i] * (buf[r + x - i] + buf[r + x + i]);
            }
            out_row[x] = acc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_matches_opencv_size_and_sums_to_one() {
        let k = Kernel::gaussian(1.6);
        assert_eq!(k.radius(), 7); // round(13.8) = 14 | 1 = 15 taps
        let s: f32 = k.half[0] + 2.0 * k.half[1..].iter().sum::<f32>();
        assert!((s - 1.0).abs() < 1e-6);
        assert_eq!(Kernel::gaussian(1.2489996).radius(), 5);
    }

    #[test]
    fn reflect101_works() {
        assert_eq!(reflect101(-1, 5), 1);
        assert_eq!(reflect101(-2, 5), 2);
        assert_eq!(reflect101(5, 5), 3);
        assert_eq!(reflect101(6, 5), 2);
        assert_eq!(reflect101(-7, 3), 1);
        assert_eq!(reflect101(4, 1), 0);
    }

    fn naive(src: &[f32], w: usize, h: usize, k: &Kernel) -> Vec<f32> {
        let r = k.radius() as isize;
        let mut tmp = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for i in -r..=r {
                    s += k.half[i.unsigned_abs()] * src[reflect101(y as isize + i, h) * w + x];
                }
                tmp[y * w + x] = s;
            }
        }
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for i in -r..=r {
                    s += k.half[i.unsigned_abs()] * tmp[y * w + reflect101(x as isize + i, w)];
                }
                out[y * w + x] = s;
            }
        }
        out
    }

    #[test]
    fn blur_matches_naive_and_preserves_constant() {
        for &(w, h) in &[(37usize, 23usize), (3, 2), (1, 1), (40, 5)] {
            let src: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 251) as f32).collect();
            let k = Kernel::gaussian(2.0);
            let mut dst = vec![0.0; w * h];
            let mut buf = Vec::new();
            blur(&src, &mut dst, w, h, &k, &mut buf, false);
            let expect = naive(&src, w, h, &k);
            for (a, b) in dst.iter().zip(&expect) {
                assert!((a - b).abs() < 1e-3, "{a} vs {b}");
            }
            let mut par = vec![0.0; w * h];
            blur(&src, &mut par, w, h, &k, &mut buf, true);
            assert_eq!(par, dst);
        }
        let src = vec![100.0f32; 64 * 70];
        let mut dst = vec![0.0; 64 * 70];
        blur(&src, &mut dst, 64, 70, &Kernel::gaussian(3.0), &mut Vec::new(), true);
        assert!(dst.iter().all(|v| (v - 100.0).abs() < 1e-3));
    }
}
