//! Separable Gaussian blur on contiguous f32 rows, OpenCV's kernel size and `BORDER_REFLECT_101`.
//!
//! Each output row is made in two passes over a small row buffer: a vertical pass that accumulates the
//! kernel's rows (symmetric taps paired; four output rows at a time whose windows slide down the source,
//! 16 columns in registers), then a horizontal pass over the padded buffer (64 columns of a row at a time).
//! The loops are written so the compiler vectorises them; on x86-64 CPUs with AVX-512 or AVX2 a copy
//! compiled for it is picked at run time. No fused multiply-add is used, so every copy gives bit-identical
//! results.

use crate::image::Plane;
use crate::mask::{CHUNK, ChunkMask, ChunkRuns};
use rayon::prelude::*;

/// A symmetric Gaussian kernel: `half[0]` is the centre weight, `half[i]` the weight at offsets ±i.
#[derive(Debug, Clone, PartialEq)]
pub struct Kernel {
    /// Centre weight first, then the weights of offsets 1, 2, ... (normalised: full kernel sums to 1).
    pub half: Vec<f32>,
}

impl Default for Kernel {
    /// The identity (a single weight 1).
    fn default() -> Self {
        Kernel { half: vec![1.0] }
    }
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

/// Output rows blurred together: the vertical pass of a group runs strip by strip so the input rows it
/// reads stay in the L1 cache.
const GROUP: usize = 16;
/// Columns of one strip of the vertical pass.
const STRIP: usize = 256;

/// Where a blur has to compute (see `mask`): outside `vert` the vertical pass sees one constant down its
/// whole window, outside `out` the horizontal pass does across its window. Both are chunk masks of the
/// output image with offset 0.
#[derive(Debug, Clone, Copy)]
pub struct Sparse<'a> {
    /// Chunks where the vertical pass must compute.
    pub vert: &'a ChunkMask,
    /// Chunks where the output must be computed.
    pub out: &'a ChunkMask,
}

/// Reusable buffers of the blur.
#[derive(Debug, Default, Clone)]
pub struct BlurScratch {
    /// Vertical-pass rows of one group, each padded by the kernel radius on both sides.
    vbuf: Vec<f32>,
    /// Per group row, offsets of the source rows of the vertical window.
    rows: Vec<usize>,
    /// Chunk bits of the rows of one quad.
    spans_u64: Vec<u64>,
}

/// The blur of a constant image `c`: exactly what both passes compute for a constant window
/// (`k0 c`, then `+= k_i (c + c)` for i = 1..r, the same operations in the same order).
#[inline]
pub fn constant(kernel: &Kernel, c: f32) -> f32 {
    let k = &kernel.half[..];
    let mut acc = k[0] * c;
    for &ki in &k[1..] {
        acc += ki * (c + c);
    }
    acc
}

/// Remembers the last few constants blurred (an image has few distinct flat levels).
struct ConstCache<'a> {
    kernel: &'a Kernel,
    keys: [u32; 4],
    vals: [f32; 4],
    len: usize,
    next: usize,
}

impl<'a> ConstCache<'a> {
    fn new(kernel: &'a Kernel) -> Self {
        Self { kernel, keys: [0; 4], vals: [0.0; 4], len: 0, next: 0 }
    }

    #[inline]
    fn get(&mut self, c: f32) -> f32 {
        let b = c.to_bits();
        for i in 0..self.len {
            if self.keys[i] == b {
                return self.vals[i];
            }
        }
        let v = constant(self.kernel, c);
        self.keys[self.next] = b;
        self.vals[self.next] = v;
        self.next = (self.next + 1) % 4;
        self.len = (self.len + 1).min(4);
        v
    }
}

/// Blurs `src` (`w` x `h`, row-major) into `dst` with `kernel`; `scratch` is reused. With `parallel`,
/// bands of rows are spread over the rayon pool; with `sparse`, only the masked chunks are computed and
/// the others are filled with their constant. Same result every way, bit for bit.
pub fn blur(
    src: Plane<'_>,
    dst: &mut [f32],
    kernel: &Kernel,
    scratch: &mut BlurScratch,
    parallel: bool,
    sparse: Option<Sparse<'_>>,
) {
    let (w, h) = (src.w, src.h);
    let n = w * h;
    if n == 0 {
        return;
    }
    let (src, dst) = (Plane::new(&src.data[..n], w, h), &mut dst[..n]);
    if parallel && h >= 64 {
        let band = h.div_ceil(rayon::current_num_threads().max(1) * 4).max(8);
        dst.par_chunks_mut(band * w).enumerate().for_each(|(b, chunk)| {
            let mut s = BlurScratch::default();
            blur_rows(src, chunk, b * band, kernel, &mut s, sparse);
        });
    } else {
        blur_rows(src, dst, 0, kernel, scratch, sparse);
    }
}

/// Blurs rows `y0 .. y1` of the image into `dst`, which holds the image's rows from `dst_y0` on, from `src` (a
/// view that may hold a window of rows: those the kernel reads around `y0 .. y1`, reflected at the image's
/// edges, must be in it and final). Used to run the layers of an octave as a cache-friendly wavefront.
#[allow(clippy::too_many_arguments)]
pub fn blur_band(
    src: Plane<'_>,
    dst: &mut [f32],
    dst_y0: usize,
    y0: usize,
    y1: usize,
    kernel: &Kernel,
    scratch: &mut BlurScratch,
    sparse: Option<Sparse<'_>>,
) {
    let w = src.w;
    if w == 0 || y0 >= y1 {
        return;
    }
    blur_rows(src, &mut dst[(y0 - dst_y0) * w..(y1 - dst_y0) * w], y0, kernel, scratch, sparse);
}

crate::cpu_dispatch! {
    /// Blurs output rows `y0 .. y0 + out.len() / w` into `out`.
    fn blur_rows(
        src: Plane<'_>,
        out: &mut [f32],
        y0: usize,
        kernel: &Kernel,
        s: &mut BlurScratch,
        sparse: Option<Sparse<'_>>,
    );
    "avx512f" => blur_rows_avx512 => blur_rows_impl(src, out, y0, kernel, s, sparse);
    "avx2" => blur_rows_avx2 => blur_rows_impl(src, out, y0, kernel, s, sparse);
    _ => blur_rows_impl(src, out, y0, kernel, s, sparse)
}

/// Rows computed together: with [`CHUNK`] columns each, enough independent accumulator chains to hide
/// the add latency, whatever the width of the active spans.
const QUAD: usize = 4;

/// Vertical pass of [`CHUNK`] columns at `x` for four consecutive output rows `y .. y + 4`:
/// `k0 c + sum_i k_i (above_i + below_i)` per row. `t[m]` is the offset of source row `y - r + m`
/// (reflected), for `m` in `0 .. 2 r + 4`. The rows above and below slide down the window, so each tap
/// loads two source rows for all four outputs.
///
/// # Safety
/// `t` holds at least `2 k.len() + 2` offsets, and every offset plus `x + CHUNK` is at most `src.len()`.
/// (The loop runs once per tap: bounds checks there would cost as much as the arithmetic.)
#[inline(always)]
#[allow(clippy::needless_range_loop)]
unsafe fn vquad(src: &[f32], t: &[usize], k: &[f32], x: usize) -> [[f32; CHUNK]; QUAD] {
    let r = k.len() - 1;
    let p = src.as_ptr();
    // SAFETY: offsets are in bounds by the caller's contract; `CHUNK` f32 values from
    // an in-bounds offset form a valid `[f32; CHUNK]` (f32 has alignment 4, `p` is a slice pointer).
    let at = |m: usize| unsafe { *(p.add(*t.get_unchecked(m) + x) as *const [f32; CHUNK]) };
    // Row j's taps at distance i: `up[j]` is source row y + j - i, `dn[j]` is y + j + i.
    let mut up: [[f32; CHUNK]; QUAD] = std::array::from_fn(|j| at(r + j));
    let mut dn = up;
    let mut acc = [[0.0f32; CHUNK]; QUAD];
    for j in 0..QUAD {
        for l in 0..CHUNK {
            acc[j][l] = k[0] * up[j][l];
        }
    }
    for i in 1..=r {
        up = [at(r - i), up[0], up[1], up[2]];
        dn = [dn[1], dn[2], dn[3], at(r + QUAD - 1 + i)];
        let ki = k[i];
        for j in 0..QUAD {
            for l in 0..CHUNK {
                acc[j][l] += ki * (up[j][l] + dn[j][l]);
            }
        }
    }
    acc
}

/// Horizontal pass of [`CHUNK`] outputs at `x` for four padded rows (`bufs[j]`: column `x` at `r + x`).
///
/// # Safety
/// Every `bufs[j]` holds at least `x + 2 r + CHUNK` values (`r = k.len() - 1`).
#[inline(always)]
#[allow(clippy::needless_range_loop)]
unsafe fn hquad(bufs: [&[f32]; QUAD], k: &[f32], x: usize) -> [[f32; CHUNK]; QUAD] {
    let r = k.len() - 1;
    // SAFETY: offsets up to `x + 2 r` plus `CHUNK` values are in bounds by the caller's contract.
    let at = |j: usize, o: usize| unsafe { &*(bufs[j].as_ptr().add(o) as *const [f32; CHUNK]) };
    let mut acc = [[0.0f32; CHUNK]; QUAD];
    for j in 0..QUAD {
        let c = at(j, r + x);
        for l in 0..CHUNK {
            acc[j][l] = k[0] * c[l];
        }
    }
    for i in 1..=r {
        let ki = k[i];
        for j in 0..QUAD {
            let (a, b) = (at(j, r + x - i), at(j, r + x + i));
            for l in 0..CHUNK {
                acc[j][l] += ki * (a[l] + b[l]);
            }
        }
    }
    acc
}

/// Outputs of one horizontal block: [`QUAD`] adjacent chunks of one row.
const BLOCK: usize = QUAD * CHUNK;

/// Horizontal pass of [`BLOCK`] outputs at `x` of one padded row (column `x` at `r + x`): one base
/// pointer and four independent accumulator chains.
///
/// # Safety
/// `buf` holds at least `x + 2 r + BLOCK` values (`r = k.len() - 1`).
#[inline(always)]
#[allow(clippy::needless_range_loop)]
unsafe fn hblock(buf: &[f32], k: &[f32], x: usize) -> [f32; BLOCK] {
    let r = k.len() - 1;
    // SAFETY: offsets up to `x + 2 r` plus `BLOCK` values are in bounds by the caller's contract.
    let at = |o: usize| unsafe { &*(buf.as_ptr().add(o) as *const [f32; BLOCK]) };
    let c = at(r + x);
    let mut acc = [0.0f32; BLOCK];
    for l in 0..BLOCK {
        acc[l] = k[0] * c[l];
    }
    for i in 1..=r {
        let ki = k[i];
        let (a, b) = (at(r + x - i), at(r + x + i));
        for l in 0..BLOCK {
            acc[l] += ki * (a[l] + b[l]);
        }
    }
    acc
}

/// Vertical pass of one column (narrow images) for row `y + j`, `t` as in [`vquad`].
#[inline(always)]
fn vpixel(src: &[f32], t: &[usize], j: usize, k: &[f32], x: usize) -> f32 {
    let r = k.len() - 1;
    let mut acc = k[0] * src[t[r + j] + x];
    for i in 1..k.len() {
        acc += k[i] * (src[t[r + j - i] + x] + src[t[r + j + i] + x]);
    }
    acc
}

/// Horizontal pass of one output (narrow images).
#[inline(always)]
fn hpixel(buf: &[f32], k: &[f32], x: usize) -> f32 {
    let r = k.len() - 1;
    let mut acc = k[0] * buf[r + x];
    for i in 1..=r {
        acc += k[i] * (buf[r + x - i] + buf[r + x + i]);
    }
    acc
}

/// Column span `[a, b)` of chunks `[ca, cb)` of a row of width `w`.
#[inline]
fn cols(ca: usize, cb: usize, w: usize) -> (usize, usize) {
    (ca * CHUNK, (cb * CHUNK).min(w))
}

/// Column of the block computing chunk `c`: the chunk itself, or for a partial last chunk the last
/// [`CHUNK`] columns of the row (recomputing a few columns gives them their own values again).
#[inline]
fn block_x(c: usize, w: usize) -> usize {
    (c * CHUNK).min(w - CHUNK)
}

/// Row indices (within the group) of quad `q` of a group of `gn` rows; a short last quad repeats its
/// last row (computed twice, same values).
#[inline]
fn quad_rows(q: usize, gn: usize) -> [usize; QUAD] {
    std::array::from_fn(|j| (q * QUAD + j).min(gn - 1))
}

#[inline(always)]
fn blur_rows_impl(
    src: Plane<'_>,
    out: &mut [f32],
    y0: usize,
    kernel: &Kernel,
    s: &mut BlurScratch,
    sparse: Option<Sparse<'_>>,
) {
    let held = src.rows();
    let Plane { data: src, w, h, y0: sy0 } = src;
    let k = &kernel.half[..];
    let r = k.len() - 1;
    let stride = w + 2 * r;
    let n_rows = out.len() / w;
    // Source rows of a quad's vertical windows (see `vquad`).
    let taps = 2 * r + QUAD;
    let chunks = w.div_ceil(CHUNK);
    let cwpr = chunks.div_ceil(64);
    // The unchecked reads of `vquad` rely on these (and on the window check of each source row below).
    assert!(src.len() >= held.len() * w && (y0 + n_rows) <= h, "blur: image smaller than its size");
    if s.vbuf.len() < GROUP * stride {
        s.vbuf.resize(GROUP * stride, 0.0);
    }
    if s.rows.len() < GROUP.div_ceil(QUAD) * taps {
        s.rows.resize(GROUP.div_ceil(QUAD) * taps, 0);
    }
    let full: Vec<u64> = (0..cwpr)
        .map(|i| {
            let n = chunks.saturating_sub(i * 64).min(64);
            if n == 64 { u64::MAX } else { (1u64 << n) - 1 }
        })
        .collect();
    // Union of the chunk masks of a quad's rows (`None`: every chunk).
    let union = |m: Option<&ChunkMask>, y: [usize; QUAD], u: &mut Vec<u64>| {
        u.clear();
        match m {
            None => u.extend_from_slice(&full),
            Some(m) => {
                u.resize(cwpr, 0);
                for &yy in &y {
                    for (a, b) in u.iter_mut().zip(m.row(yy)) {
                        *a |= b;
                    }
                }
            }
        }
    };
    let mut consts = ConstCache::new(kernel);
    let mut u = std::mem::take(&mut s.spans_u64);
    let mut gy = 0;
    while gy < n_rows {
        let gn = (n_rows - gy).min(GROUP);
        let quads = gn.div_ceil(QUAD);
        for q in 0..quads {
            let yq = (y0 + gy + q * QUAD) as isize;
            // A short last quad also computes rows past the group (dropped): their extra taps read the last
            // needed source row, so a window of source rows need not hold more.
            let needed = 2 * r + (gn - q * QUAD).min(QUAD);
            for (m, t) in s.rows[q * taps..(q + 1) * taps].iter_mut().enumerate() {
                let row = reflect101(yq - r as isize + m.min(needed - 1) as isize, h);
                assert!(held.contains(&row), "blur: source row {row} outside the rows held {held:?}");
                *t = (row - sy0) * w;
            }
        }
        // Vertical pass, strip by strip (the source rows of a strip stay in L1), four rows at a time.
        if w >= CHUNK {
            // The quads' chunk masks, then strips outermost.
            u.clear();
            for q in 0..quads {
                let qr = quad_rows(q, gn).map(|j| y0 + gy + j);
                let at = u.len();
                match sparse {
                    None => u.extend_from_slice(&full),
                    Some(m) => {
                        u.resize(at + cwpr, 0);
                        for &yy in &qr {
                            for (a, b) in u[at..].iter_mut().zip(m.vert.row(yy)) {
                                *a |= b;
                            }
                        }
                    }
                }
            }
            let strip_chunks = STRIP / CHUNK;
            for cs in (0..chunks).step_by(strip_chunks) {
                let ce = (cs + strip_chunks).min(chunks);
                for q in 0..quads {
                    let t = &s.rows[q * taps..(q + 1) * taps];
                    let valid = (gn - q * QUAD).min(QUAD);
                    for (a, b, on) in ChunkRuns::new(&u[q * cwpr..(q + 1) * cwpr], ce) {
                        if !on || b <= cs {
                            continue;
                        }
                        for c in a.max(cs)..b {
                            let x = block_x(c, w);
                            // SAFETY: `t` has `2 r + 4` offsets, each `row * w` with `row < h`, and
                            // `x + CHUNK <= w`, so every read ends within `h * w <= src.len()`.
                            let acc = unsafe { vquad(src, t, k, x) };
                            // A short last quad computed rows past the group: dropped.
                            for (jq, v) in acc.iter().enumerate().take(valid) {
                                let o = (q * QUAD + jq) * stride + r + x;
                                s.vbuf[o..o + CHUNK].copy_from_slice(v);
                            }
                        }
                    }
                }
            }
        } else {
            for j in 0..gn {
                let (q, jq) = (j / QUAD, j % QUAD);
                let t = &s.rows[q * taps..(q + 1) * taps];
                for x in 0..w {
                    s.vbuf[j * stride + r + x] = vpixel(src, t, jq, k, x);
                }
            }
        }
        for j in 0..gn {
            let y = y0 + gy + j;
            let buf = &mut s.vbuf[j * stride..(j + 1) * stride];
            if let Some(m) = sparse {
                // Columns the vertical pass skipped see one constant: the source pixel's.
                let row = &src[(y - sy0) * w..(y - sy0) * w + w];
                for (a, b, on) in ChunkRuns::new(m.vert.row(y), m.vert.chunks) {
                    if !on {
                        let (a, b) = cols(a, b, w);
                        let v = consts.get(row[a]);
                        buf[r + a..r + b].fill(v);
                    }
                }
            }
            // Reflect-101 padding of the vertical result.
            for q in 1..=r {
                buf[r - q] = buf[r + reflect101(-(q as isize), w)];
                buf[r + w - 1 + q] = buf[r + reflect101((w - 1 + q) as isize, w)];
            }
        }
        // Horizontal pass, a block of four chunks at a time (rows wide enough) or four rows at a time, then
        // the constant outputs. A block may cover inactive chunks: their windows hold one constant, so they
        // get the constant's blur, the value the fill below writes too.
        if w >= BLOCK {
            for j in 0..gn {
                let y = y0 + gy + j;
                let buf = &s.vbuf[j * stride..(j + 1) * stride];
                let runs: &[u64] = match sparse {
                    Some(m) => m.out.row(y),
                    None => &full,
                };
                let mut done = 0; // chunks below this one are computed
                for (a, b, on) in ChunkRuns::new(runs, chunks) {
                    let mut c = a.max(done);
                    while on && c < b {
                        let x = (c * CHUNK).min(w - BLOCK);
                        // SAFETY: the buffer holds `w + 2 r` values and `x + BLOCK <= w`.
                        let acc = unsafe { hblock(buf, k, x) };
                        let o = (gy + j) * w + x;
                        out[o..o + BLOCK].copy_from_slice(&acc);
                        c = if x + BLOCK >= w { chunks } else { (x + BLOCK) / CHUNK };
                        done = c;
                    }
                }
            }
        } else if w >= CHUNK {
            for q in 0..quads {
                let qr = quad_rows(q, gn);
                union(sparse.map(|m| m.out), qr.map(|j| y0 + gy + j), &mut u);
                let bufs = qr.map(|j| &s.vbuf[j * stride..(j + 1) * stride]);
                for (a, b, on) in ChunkRuns::new(&u, chunks) {
                    if !on {
                        continue;
                    }
                    for c in a..b {
                        let x = block_x(c, w);
                        // SAFETY: each buffer holds `w + 2 r` values and `x + CHUNK <= w`.
                        let acc = unsafe { hquad(bufs, k, x) };
                        for (j, v) in qr.iter().zip(&acc) {
                            let o = (gy + j) * w + x;
                            out[o..o + CHUNK].copy_from_slice(v);
                        }
                    }
                }
            }
        } else {
            for j in 0..gn {
                let buf = &s.vbuf[j * stride..(j + 1) * stride];
                for x in 0..w {
                    out[(gy + j) * w + x] = hpixel(buf, k, x);
                }
            }
        }
        if let Some(m) = sparse {
            for j in 0..gn {
                let y = y0 + gy + j;
                let buf = &s.vbuf[j * stride..(j + 1) * stride];
                let out_row = &mut out[(gy + j) * w..(gy + j + 1) * w];
                for (a, b, on) in ChunkRuns::new(m.out.row(y), m.out.chunks) {
                    if !on {
                        let (a, b) = cols(a, b, w);
                        out_row[a..b].fill(consts.get(buf[r + a]));
                    }
                }
            }
        }
        gy += gn;
    }
    s.spans_u64 = u;
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
            let mut buf = BlurScratch::default();
            blur(Plane::new(&src, w, h), &mut dst, &k, &mut buf, false, None);
            let expect = naive(&src, w, h, &k);
            for (a, b) in dst.iter().zip(&expect) {
                assert!((a - b).abs() < 1e-3, "{a} vs {b}");
            }
            let mut par = vec![0.0; w * h];
            blur(Plane::new(&src, w, h), &mut par, &k, &mut buf, true, None);
            assert_eq!(par, dst);
        }
        let src = vec![100.0f32; 64 * 70];
        let mut dst = vec![0.0; 64 * 70];
        blur(Plane::new(&src, 64, 70), &mut dst, &Kernel::gaussian(3.0), &mut BlurScratch::default(), true, None);
        assert!(dst.iter().all(|v| (v - 100.0).abs() < 1e-3));
    }

    /// The blur in the order of the implementation, one pixel at a time: vertical `k0 c + sum k_i (a + b)`,
    /// then the same across the reflect-101 padded row.
    fn paired(src: &[f32], w: usize, h: usize, k: &Kernel) -> Vec<f32> {
        let r = k.radius();
        let mut tmp = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = k.half[0] * src[y * w + x];
                for i in 1..=r {
                    let (a, b) = (reflect101(y as isize - i as isize, h), reflect101((y + i) as isize, h));
                    acc += k.half[i] * (src[a * w + x] + src[b * w + x]);
                }
                tmp[y * w + x] = acc;
            }
        }
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = k.half[0] * tmp[y * w + x];
                for i in 1..=r {
                    let (a, b) = (reflect101(x as isize - i as isize, w), reflect101((x + i) as isize, w));
                    acc += k.half[i] * (tmp[y * w + a] + tmp[y * w + b]);
                }
                out[y * w + x] = acc;
            }
        }
        out
    }

    #[test]
    fn blur_is_bitwise_the_paired_formula_dense_and_sparse() {
        use crate::mask::BitMask;
        let mut lcg = crate::synth::Lcg(7);
        let mut rnd = || (lcg.next_u32() >> 1) as usize;
        let mut exercised = false;
        for &(w, h) in &[(200usize, 90usize), (37, 41), (15, 9), (64, 3), (1, 20), (130, 1)] {
            // Flat areas of three levels with random boxes (some fractional, some negative).
            let mut src: Vec<f32> = (0..w * h).map(|i| [255.0, 0.3, -7.5][(i % w) * 3 / w]).collect();
            for _ in 0..(w * h / 300 + 2) {
                let (x0, y0, v) = (rnd() % w, rnd() % h, (rnd() % 5000) as f32 * 0.37 - 900.0);
                for y in y0..(y0 + 1 + rnd() % 6).min(h) {
                    for x in x0..(x0 + 1 + rnd() % 6).min(w) {
                        src[y * w + x] = v;
                    }
                }
            }
            for sigma in [0.8, 1.2262735, 3.0900155, 6.0] {
                let k = Kernel::gaussian(sigma);
                let want = paired(&src, w, h, &k);
                let mut s = BlurScratch::default();
                let mut dense = vec![0.0; w * h];
                blur(Plane::new(&src, w, h), &mut dense, &k, &mut s, false, None);
                // Sparse: masks from the source's edges grown by the radius (as the pyramid does).
                let (mut edges, mut vm, mut am) = (BitMask::default(), BitMask::default(), BitMask::default());
                edges.edges_of(&src, w, h);
                vm.dilate_vertical(&edges, k.radius());
                am.dilate_horizontal(&vm, k.radius());
                let (mut vert, mut out) = (ChunkMask::default(), ChunkMask::default());
                vert.build(&vm, 0, w);
                out.build(&am, 0, w);
                let mut sparse = vec![f32::NAN; w * h];
                blur(Plane::new(&src, w, h), &mut sparse, &k, &mut s, false, Some(Sparse { vert: &vert, out: &out }));
                for i in 0..w * h {
                    assert_eq!(dense[i].to_bits(), want[i].to_bits(), "dense {w}x{h} sigma {sigma} at {i}");
                    assert_eq!(sparse[i].to_bits(), want[i].to_bits(), "sparse {w}x{h} sigma {sigma} at {i}");
                }
                exercised |= am.density() < 0.8;
            }
        }
        assert!(exercised, "some blur skipped constant parts");
    }
}
