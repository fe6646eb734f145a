//! Scale space: the initial (optionally doubled) image and the Gaussian octaves.
//!
//! One octave is held at a time; its buffers are sized for the first (largest) octave and reused (never
//! shrunk, so a reused `Sift` does not touch fresh memory). DoG images are not stored: a DoG value is the
//! difference of two Gaussian layers, formed where it is needed (see `extrema`).

use crate::blur::{Kernel, blur, blur_band};
use crate::params::SiftParams;

/// One octave of the scale space: `n_layers + 3` Gaussian images (DoG layer `i` is `gauss[i + 1] - gauss[i]`).
#[derive(Debug, Default)]
pub struct Octave {
    /// Width of this octave's images.
    pub w: usize,
    /// Height of this octave's images.
    pub h: usize,
    /// Gaussian images, increasingly blurred (`sigma * 2^(i / n_layers)` relative to this octave); only
    /// the first `w * h` values of each buffer belong to the octave.
    pub gauss: Vec<Vec<f32>>,
    /// Kernels blurring `gauss[i - 1]` into `gauss[i]` (index 0 unused).
    kernels: Vec<Kernel>,
    /// Spare image buffer (upscaling, next octave's base).
    spare: Vec<f32>,
    /// Row scratch of the blur.
    row_buf: Vec<f32>,
    /// Scratch of the upscaling (horizontally doubled rows).
    up_rows: Vec<f32>,
}

/// Grows `buf` to at least `n` values (never shrinks it).
fn ensure_len(buf: &mut Vec<f32>, n: usize) {
    if buf.len() < n {
        buf.resize(n, 0.0);
    }
}

impl Octave {
    /// Sets up the per-layer kernels for these parameters (OpenCV's incremental sigmas).
    pub fn prepare(&mut self, params: &SiftParams) {
        let n = params.n_octave_layers;
        let sigma = f64::from(params.sigma);
        let k = 2f64.powf(1.0 / n as f64);
        let mut kernels = vec![Kernel { half: vec![1.0] }];
        for i in 1..n + 3 {
            let sig_prev = k.powf((i - 1) as f64) * sigma;
            let sig_total = sig_prev * k;
            kernels.push(Kernel::gaussian((sig_total * sig_total - sig_prev * sig_prev).sqrt()));
        }
        self.kernels = kernels;
        self.gauss.resize_with(n + 3, Vec::new);
    }

    /// Builds the first octave's base image `gauss[0]` from the input (doubling it if asked) and blurs it
    /// from the assumed `init_sigma` to `sigma`.
    pub fn init_base(&mut self, data: &[f32], w: usize, h: usize, params: &SiftParams) {
        let (sigma, init) = (params.sigma, params.init_sigma);
        let (bw, bh, sig_diff) = if params.upscale {
            upscale2x(data, w, h, &mut self.spare, &mut self.up_rows);
            (2 * w, 2 * h, (sigma * sigma - init * init * 4.0).max(0.01).sqrt())
        } else {
            ensure_len(&mut self.spare, w * h);
            self.spare[..w * h].copy_from_slice(data);
            (w, h, (sigma * sigma - init * init).max(0.01).sqrt())
        };
        self.w = bw;
        self.h = bh;
        let base = &mut self.gauss[0];
        ensure_len(base, bw * bh);
        blur(&self.spare, base, bw, bh, &Kernel::gaussian(f64::from(sig_diff)), &mut self.row_buf, params.parallel);
    }

    /// Makes the next octave's base: `gauss[n_layers]` of this octave, every second pixel (OpenCV
    /// `INTER_NEAREST` resize to half size). Returns false when the image would become empty.
    pub fn next_base(&mut self, n_layers: usize) -> bool {
        let (w, h) = (self.w / 2, self.h / 2);
        if w == 0 || h == 0 {
            return false;
        }
        downsample_nearest(&self.gauss[n_layers], self.w, self.h, w, h, &mut self.spare);
        std::mem::swap(&mut self.spare, &mut self.gauss[0]);
        self.w = w;
        self.h = h;
        true
    }

    /// Blurs `gauss[0]` into the remaining layers.
    pub fn build(&mut self, parallel: bool) {
        let n = self.w * self.h;
        for i in 1..self.gauss.len() {
            let (done, rest) = self.gauss.split_at_mut(i);
            let dst = &mut rest[0];
            ensure_len(dst, n);
            blur(&done[i - 1], dst, self.w, self.h, &self.kernels[i], &mut self.row_buf, parallel);
        }
    }

    /// Blurs `gauss[0]` into the remaining layers as a wavefront of row bands, so each layer's rows are
    /// read back (by the next layer's blur and by `scan`) while still in cache. `scan(gauss, r0, r1)` is
    /// called with consecutive row ranges `0..r1` whose Gaussian rows up to `r1` (inclusive) are final in
    /// every layer. Same result as [`Octave::build`] followed by one scan of all rows.
    pub fn build_scan(&mut self, mut scan: impl FnMut(&[Vec<f32>], usize, usize)) {
        const BAND: usize = 16;
        let (w, h) = (self.w, self.h);
        let n = w * h;
        let layers = self.gauss.len();
        for g in &mut self.gauss[1..] {
            ensure_len(g, n);
        }
        let mut avail = vec![0usize; layers];
        avail[0] = h;
        let mut scanned = 0;
        loop {
            for i in 1..layers {
                let r = self.kernels[i].radius();
                let ready = if avail[i - 1] >= h { h } else { avail[i - 1].saturating_sub(r) };
                let target = ready.min(avail[i] + BAND);
                if target > avail[i] {
                    let (done, rest) = self.gauss.split_at_mut(i);
                    blur_band(&done[i - 1], &mut rest[0], w, h, avail[i], target, &self.kernels[i], &mut self.row_buf);
                    avail[i] = target;
                }
            }
            let all = avail.iter().copied().min().unwrap_or(h);
            // Rows whose neighbours (one row below) are final in every layer.
            let upto = if all >= h { h } else { all.saturating_sub(1) };
            if upto > scanned {
                scan(&self.gauss, scanned, upto);
                scanned = upto;
            }
            if all >= h {
                break;
            }
        }
    }

    /// Gaussian layer `i` of this octave (`w * h` values).
    pub fn layer(&self, i: usize) -> &[f32] {
        &self.gauss[i][..self.w * self.h]
    }
}

/// OpenCV `resize(.., 2x size, INTER_LINEAR)`: half-pixel-centre bilinear doubling, horizontal pass first.
/// `dst` (grown if needed) receives the `2w x 2h` image in its first values; `rows` is scratch.
pub fn upscale2x(src: &[f32], w: usize, h: usize, dst: &mut Vec<f32>, rows: &mut Vec<f32>) {
    let (dw, dh) = (2 * w, 2 * h);
    ensure_len(dst, dw * dh);
    if w == 0 || h == 0 {
        return;
    }
    // Horizontal: every source row doubled.
    ensure_len(rows, dw * h);
    for y in 0..h {
        let s = &src[y * w..y * w + w];
        let d = &mut rows[y * dw..y * dw + dw];
        hdouble(s, d);
    }
    // Vertical.
    for dy in 0..dh {
        let out = &mut dst[dy * dw..dy * dw + dw];
        let (sy, fy) = src_coord(dy, h);
        let r0 = &rows[sy * dw..sy * dw + dw];
        if fy == 0.0 {
            out.copy_from_slice(r0);
        } else {
            let r1 = &rows[(sy + 1) * dw..(sy + 1) * dw + dw];
            let (b0, b1) = (1.0 - fy, fy);
            for ((o, &a), &b) in out.iter_mut().zip(r0).zip(r1) {
                *o = a * b0 + b * b1;
            }
        }
    }
}

/// Source index and fraction for destination index `d` of a 2x bilinear resize of a line of `n` samples.
fn src_coord(d: usize, n: usize) -> (usize, f32) {
    let f = (d as f32 + 0.5) * 0.5 - 0.5;
    let s = f.floor();
    let (mut s, mut f) = (s as isize, f - s);
    if s < 0 {
        s = 0;
        f = 0.0;
    }
    if s as usize >= n - 1 {
        s = n as isize - 1;
        f = 0.0;
    }
    (s as usize, f)
}

/// One row doubled: `d[2k] = 0.25 s[k-1] + 0.75 s[k]`, `d[2k+1] = 0.75 s[k] + 0.25 s[k+1]`, edges copied.
fn hdouble(s: &[f32], d: &mut [f32]) {
    let n = s.len();
    d[0] = s[0];
    d[2 * n - 1] = s[n - 1];
    for (k, pair) in s.windows(2).enumerate() {
        let (a, b) = (pair[0], pair[1]);
        d[2 * k + 1] = a * 0.75 + b * 0.25;
        d[2 * k + 2] = a * 0.25 + b * 0.75;
    }
}

/// OpenCV `resize(.., INTER_NEAREST)` from `w x h` to `dw x dh` (into the first values of `dst`).
pub fn downsample_nearest(src: &[f32], w: usize, h: usize, dw: usize, dh: usize, dst: &mut Vec<f32>) {
    ensure_len(dst, dw * dh);
    let ifx = 1.0 / (dw as f64 / w as f64);
    let ify = 1.0 / (dh as f64 / h as f64);
    let xs: Vec<usize> = (0..dw).map(|x| ((x as f64 * ifx).floor() as usize).min(w - 1)).collect();
    for y in 0..dh {
        let sy = ((y as f64 * ify).floor() as usize).min(h - 1);
        let s = &src[sy * w..sy * w + w];
        for (o, &sx) in dst[y * dw..y * dw + dw].iter_mut().zip(&xs) {
            *o = s[sx];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upscale_matches_opencv_pattern() {
        let src = [0.0, 4.0, 8.0];
        let mut d = Vec::new();
        let mut rows = Vec::new();
        upscale2x(&src, 3, 1, &mut d, &mut rows);
        assert_eq!(d, vec![0.0, 1.0, 3.0, 5.0, 7.0, 8.0, 0.0, 1.0, 3.0, 5.0, 7.0, 8.0]);
        upscale2x(&[5.0], 1, 1, &mut d, &mut rows);
        assert_eq!(d[..4], [5.0; 4]);
    }

    #[test]
    fn downsample_takes_even_pixels() {
        let src: Vec<f32> = (0..16).map(|v| v as f32).collect();
        let mut d = Vec::new();
        downsample_nearest(&src, 4, 4, 2, 2, &mut d);
        assert_eq!(d, vec![0.0, 2.0, 8.0, 10.0]);
    }

    #[test]
    fn octave_layers_have_expected_count() {
        let p = SiftParams::default();
        let mut o = Octave::default();
        o.prepare(&p);
        o.init_base(&vec![10.0; 64], 8, 8, &p);
        o.build(false);
        assert_eq!((o.w, o.h, o.gauss.len()), (16, 16, 6));
        assert!((0..6).all(|i| o.layer(i).iter().all(|v| (v - 10.0).abs() < 1e-3)));
        assert!(o.next_base(3));
        assert_eq!((o.w, o.h), (8, 8));
    }
}
