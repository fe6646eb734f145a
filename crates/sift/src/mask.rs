//! Activity masks: where a Gaussian layer can differ from a constant, so the blur and the extremum scan
//! can skip the rest (occupancy maps are mostly one grey level).
//!
//! The invariant every mask here keeps, for one image of the pyramid: **two 4-adjacent pixels that are
//! both outside the mask hold the same value, bit for bit, and that value is finite and of magnitude
//! about [`MAX_FLAT`] at most.** It holds for the edge mask of a base image by construction (both pixels
//! of every differing pair, and every non-finite or huge pixel, are in it), and a blur keeps it when the
//! output's mask is the input's mask grown by the kernel radius (vertically for the vertical pass, then
//! horizontally): a pixel outside the vertical mask sees one constant down its whole window, so the
//! vertical pass gives the kernel applied to that constant, and likewise across for the horizontal pass.
//! The constants are computed with the very arithmetic of the blur (see `blur::constant`), so the
//! skipped pixels receive the values the full computation would give. Computing a pixel outside the
//! mask is always allowed (it gets that same value), so masks may be, and are, rounded up.
//!
//! Masks are bitsets, one bit per pixel, rows padded to whole 64-bit words. For the loops they are
//! read at the granularity of [`CHUNK`] columns: a chunk is active when any of its pixels is.

/// Columns handled together by the vector loops (a chunk is active when any of its pixels is).
pub const CHUNK: usize = 16;

/// Pixels of larger magnitude (or not finite) are always active: keeps blurred constants finite.
pub const MAX_FLAT: f32 = 1.8446744e19; // 2^64

/// What an edge mask leaves out: constant pixels of bounded magnitude.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Flat {
    /// Largest magnitude among the finite pixels within [`MAX_FLAT`] (0 when none).
    pub max_abs: f32,
    /// True when every pixel is finite and within [`MAX_FLAT`] (then `max_abs` bounds them all).
    pub all_flat_ok: bool,
    /// True when no pixel has its sign bit set (then any two pixels differ by at most `max_abs`).
    pub non_negative: bool,
    /// Fraction of the pixels in the mask.
    pub density: f64,
}

/// One bit per pixel of a `w x h` image.
#[derive(Debug, Default, Clone)]
pub struct BitMask {
    /// Image width.
    pub w: usize,
    /// Image height.
    pub h: usize,
    /// 64-bit words per row.
    pub wpr: usize,
    /// Row-major words; bits at columns `>= w` are zero.
    pub bits: Vec<u64>,
    /// Scratch of the dilations.
    pre: Vec<u64>,
    suf: Vec<u64>,
}

impl BitMask {
    /// Resizes to `w x h` and clears every bit (keeps the allocation).
    pub fn reset(&mut self, w: usize, h: usize) {
        self.w = w;
        self.h = h;
        self.wpr = w.div_ceil(64);
        self.bits.clear();
        self.bits.resize(self.wpr * h, 0);
    }

    /// Row `y`'s words.
    #[inline]
    pub fn row(&self, y: usize) -> &[u64] {
        &self.bits[y * self.wpr..(y + 1) * self.wpr]
    }

    /// True when pixel (`x`, `y`) is set.
    #[cfg(test)]
    pub fn get(&self, x: usize, y: usize) -> bool {
        self.row(y)[x / 64] >> (x % 64) & 1 == 1
    }

    /// The edge mask of `img` (`w x h`): both pixels of every 4-adjacent pair whose bits differ, and every
    /// pixel that is not finite or exceeds [`MAX_FLAT`] in magnitude.
    pub fn edges_of(&mut self, img: &[f32], w: usize, h: usize) -> Flat {
        edges(self, img, w, h)
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn edges_impl<const AVX2: bool>(&mut self, img: &[f32], w: usize, h: usize) -> Flat {
        self.reset(w, h);
        let mut flat = Flat { max_abs: 0.0, all_flat_ok: true, non_negative: true, density: 0.0 };
        if w == 0 || h == 0 {
            return flat;
        }
        let wpr = self.wpr;
        // down[k]: pixels of the previous row that differ from the one below them.
        let mut down = std::mem::take(&mut self.pre);
        down.clear();
        down.resize(wpr, 0);
        for y in 0..h {
            let row = &img[y * w..y * w + w];
            let below = if y + 1 < h { &img[(y + 1) * w..(y + 2) * w] } else { row };
            let mut carry = 0u64;
            for k in 0..wpr {
                let x0 = k * 64;
                let (right, vd, bad, mx, neg) = if x0 + 64 < w {
                    let a: &[f32; 64] = row[x0..x0 + 64].try_into().expect("block");
                    let n: &[f32; 64] = row[x0 + 1..x0 + 65].try_into().expect("block");
                    let b: &[f32; 64] = below[x0..x0 + 64].try_into().expect("block");
                    block_edges::<AVX2>(a, n, b)
                } else {
                    // Last (partial) block: pad with copies so padding never differs.
                    let mut a = [0.0f32; 64];
                    let n_px = w - x0;
                    a[..n_px].copy_from_slice(&row[x0..w]);
                    let fill = a[n_px - 1];
                    a[n_px..].fill(fill);
                    let mut n = [fill; 64];
                    n[..n_px - 1].copy_from_slice(&row[x0 + 1..w]);
                    let mut b = a;
                    b[..n_px].copy_from_slice(&below[x0..w]);
                    let (r, v, bad, mx, neg) = block_edges::<AVX2>(&a, &n, &b);
                    let keep = if n_px == 64 { u64::MAX } else { (1u64 << n_px) - 1 };
                    (r & keep, v & keep, bad & keep, mx, neg)
                };
                flat.non_negative &= !neg;
                if mx > flat.max_abs {
                    flat.max_abs = mx;
                }
                flat.all_flat_ok &= bad == 0;
                self.bits[y * wpr + k] = right | (right << 1) | carry | bad | vd | down[k];
                carry = right >> 63;
                down[k] = vd;
            }
        }
        self.pre = down;
        for row in self.bits.chunks_exact_mut(wpr) {
            clear_tail(row, w);
        }
        flat.density = self.density();
        flat
    }

    /// Fraction of the pixels set.
    pub fn density(&self) -> f64 {
        let n: u64 = self.bits.iter().map(|v| u64::from(v.count_ones())).sum();
        n as f64 / (self.w * self.h).max(1) as f64
    }

    /// `self` = `src` grown by `r` rows up and down (clipped to the image).
    pub fn dilate_vertical(&mut self, src: &BitMask, r: usize) {
        let (w, h, wpr) = (src.w, src.h, src.wpr);
        self.reset(w, h);
        if r == 0 {
            self.bits.copy_from_slice(&src.bits);
            return;
        }
        // Running OR over a sliding window of 2r + 1 rows, by prefix / suffix blocks (van Herk):
        // block length 2r + 1, window [y - r, y + r] = suffix of one block | prefix of the next.
        let k = 2 * r + 1;
        let (mut pre, mut suf) = (std::mem::take(&mut self.pre), std::mem::take(&mut self.suf));
        pre.clear();
        pre.resize(wpr * h, 0);
        suf.clear();
        suf.resize(wpr * h, 0);
        for y in 0..h {
            let s = src.row(y);
            if y % k == 0 {
                pre[y * wpr..(y + 1) * wpr].copy_from_slice(s);
            } else {
                for i in 0..wpr {
                    pre[y * wpr + i] = pre[(y - 1) * wpr + i] | s[i];
                }
            }
        }
        for y in (0..h).rev() {
            let s = src.row(y);
            if y % k == k - 1 || y == h - 1 {
                suf[y * wpr..(y + 1) * wpr].copy_from_slice(s);
            } else {
                for i in 0..wpr {
                    suf[y * wpr + i] = suf[(y + 1) * wpr + i] | s[i];
                }
            }
        }
        for y in 0..h {
            let a = y.saturating_sub(r);
            let b = (y + r).min(h - 1);
            let out = &mut self.bits[y * wpr..(y + 1) * wpr];
            if a / k == b / k {
                // Window inside one block: OR the rows directly (only near the image edges).
                out.fill(0);
                for yy in a..=b {
                    for (o, s) in out.iter_mut().zip(src.row(yy)) {
                        *o |= s;
                    }
                }
            } else {
                for i in 0..wpr {
                    out[i] = suf[a * wpr + i] | pre[b * wpr + i];
                }
            }
        }
        self.pre = pre;
        self.suf = suf;
    }

    /// `self` = `src` grown by `r` columns left and right (clipped to the image).
    pub fn dilate_horizontal(&mut self, src: &BitMask, r: usize) {
        let (w, h, wpr) = (src.w, src.h, src.wpr);
        self.reset(w, h);
        if r < 64 {
            // Grow by shifting: a row grown by t, or-ed with its shifts by s <= t + 1, is grown by t + s.
            // `pad` holds one row between zero words, so every word sees both neighbours (vectorises).
            let mut pad = vec![0u64; wpr + 2];
            for y in 0..h {
                let out = &mut self.bits[y * wpr..(y + 1) * wpr];
                out.copy_from_slice(src.row(y));
                let mut t = 0;
                while t < r {
                    let s = (t + 1).min(r - t) as u32;
                    pad[1..=wpr].copy_from_slice(out);
                    for (o, p) in out.iter_mut().zip(pad.windows(3)) {
                        let (prev, cur, next) = (p[0], p[1], p[2]);
                        *o = cur | (cur << s) | (prev >> (64 - s)) | (cur >> s) | (next << (64 - s));
                    }
                    t += s as usize;
                }
                clear_tail(out, w);
            }
            return;
        }
        for y in 0..h {
            let s = src.row(y);
            let out = &mut self.bits[y * wpr..(y + 1) * wpr];
            // Each run of set bits [a, b) becomes [a - r, b + r).
            let mut x = 0;
            while let Some(a) = next_bit(s, x, w, true) {
                let b = next_bit(s, a, w, false).unwrap_or(w);
                set_range(out, a.saturating_sub(r), (b + r).min(w));
                x = b;
            }
        }
    }

    /// `self` = `src` grown by `r` pixels in every direction (a square of side `2 r + 1`, clipped).
    pub fn dilate_square(&mut self, src: &BitMask, r: usize, tmp: &mut BitMask) {
        tmp.dilate_vertical(src, r);
        self.dilate_horizontal(tmp, r);
    }

    /// The edge mask of the 2x bilinear upscale (see `pyramid::upscale2x`) of an image whose edge mask is
    /// `src`, without looking at the upscaled pixels: an upscaled pixel is marked when an input pixel it
    /// is interpolated from is. Inside, two adjacent unmarked pixels interpolate the same constant `c` with
    /// the same formula, so they are equal. The outer rows and columns copy instead of interpolating in
    /// one direction, which gives `v(c) = 0.75 c + 0.25 c` (f32) instead of `v(v(c))`: equal when
    /// `v(c) == c`, which the caller checks on the input's border pixels; `frame` marks the outer rows and
    /// columns when that check failed.
    pub fn upscaled_edges(&mut self, src: &BitMask, frame: bool) {
        let (w, h) = (2 * src.w, 2 * src.h);
        self.reset(w, h);
        if w == 0 {
            return;
        }
        let wpr = self.wpr;
        let mut merged = vec![0u64; src.wpr];
        for yy in 0..h {
            let out = &mut self.bits[yy * wpr..(yy + 1) * wpr];
            if frame && (yy == 0 || yy + 1 == h) {
                out.fill(u64::MAX);
                clear_tail(out, w);
                continue;
            }
            // Input rows the output row interpolates: 2k -> {k - 1, k}, 2k + 1 -> {k, k + 1} (clamped).
            let k = yy / 2;
            let (r0, r1) = if yy % 2 == 0 { (k.saturating_sub(1), k) } else { (k, (k + 1).min(src.h - 1)) };
            for (m, (a, b)) in merged.iter_mut().zip(src.row(r0).iter().zip(src.row(r1))) {
                *m = a | b;
            }
            // Input column x feeds output columns 2x - 1 ..= 2x + 2.
            for (j, &m) in merged.iter().enumerate() {
                for half in 0..2 {
                    let o = 2 * j + half;
                    if o < wpr {
                        out[o] = spread_bits((m >> (32 * half)) as u32);
                    }
                }
            }
            let mut carry_up = 0u64;
            for i in 0..wpr {
                let d = out[i];
                let next = if i + 1 < wpr { out[i + 1] } else { 0 };
                out[i] = d | (d << 1) | carry_up | (d >> 1) | (next << 63);
                carry_up = d >> 63;
            }
            if frame {
                out[0] |= 1;
                set_range(out, w - 1, w);
            }
            clear_tail(out, w);
        }
    }

    /// `self` = a copy of `src` (keeps the allocation).
    pub fn copy_from(&mut self, src: &BitMask) {
        self.w = src.w;
        self.h = src.h;
        self.wpr = src.wpr;
        self.bits.clear();
        self.bits.extend_from_slice(&src.bits);
    }

    /// `self &= other` (same size).
    pub fn and_with(&mut self, other: &BitMask) {
        for (a, b) in self.bits.iter_mut().zip(&other.bits) {
            *a &= b;
        }
    }
}

crate::cpu_dispatch! {
    /// [`BitMask::edges_of`], its AVX2 copy picked at run time.
    fn edges(mask: &mut BitMask, img: &[f32], w: usize, h: usize) -> Flat;
    "avx2" => edges_avx2 => mask.edges_impl::<true>(img, w, h);
    _ => mask.edges_impl::<false>(img, w, h)
}

/// Bit `j` (0..4) set when any of bits `16 j .. 16 j + 16` of `word` is.
#[inline(always)]
fn chunk_nibble(word: u64) -> u64 {
    let mut t = word;
    t |= t >> 8;
    t |= t >> 4;
    t |= t >> 2;
    t |= t >> 1;
    // Gather bits 0, 16, 32, 48 into bits 60..63 (the products land on distinct bits, no carries).
    (t & 0x0001_0001_0001_0001).wrapping_mul((1 << 60) | (1 << 45) | (1 << 30) | (1 << 15)) >> 60
}

/// Each bit of `x` doubled: bit `i` becomes bits `2 i` and `2 i + 1`.
#[inline]
fn spread_bits(x: u32) -> u64 {
    let mut v = u64::from(x);
    v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
    v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
    v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    v = (v | (v << 2)) & 0x3333_3333_3333_3333;
    v = (v | (v << 1)) & 0x5555_5555_5555_5555;
    v | (v << 1)
}

/// The first column `>= x` (and `< w`) whose bit is `set`.
#[inline]
fn next_bit(row: &[u64], x: usize, w: usize, set: bool) -> Option<usize> {
    let mut k = x / 64;
    if k >= row.len() {
        return None;
    }
    let flip = if set { 0 } else { u64::MAX };
    let mut word = (row[k] ^ flip) & (u64::MAX << (x % 64));
    loop {
        if word != 0 {
            let p = k * 64 + word.trailing_zeros() as usize;
            return (p < w).then_some(p);
        }
        k += 1;
        if k >= row.len() {
            return None;
        }
        word = row[k] ^ flip;
    }
}

/// Sets bits `a .. b` of a row.
#[inline]
fn set_range(row: &mut [u64], a: usize, b: usize) {
    let mut x = a;
    while x < b {
        let (k, o) = (x / 64, x % 64);
        let n = (64 - o).min(b - x);
        row[k] |= if n == 64 { u64::MAX } else { ((1u64 << n) - 1) << o };
        x += n;
    }
}

/// Edge bits of 64 pixels `a` with their right neighbours `n` and the pixels below `b`: (differs from
/// right, differs from below, not finite or too large, largest magnitude of the others).
#[inline(always)]
fn block_edges<const AVX2: bool>(a: &[f32; 64], n: &[f32; 64], b: &[f32; 64]) -> (u64, u64, u64, f32, bool) {
    #[cfg(target_arch = "x86_64")]
    {
        if AVX2 {
            // SAFETY: only instantiated with AVX2 = true from `edges_avx2`, which runs on AVX2 CPUs.
            return unsafe { block_edges_avx2(a, n, b) };
        }
    }
    let mut out = (0u64, 0u64, 0u64, 0.0f32, false);
    for i in 0..64 {
        let v = a[i].to_bits();
        out.4 |= a[i].is_sign_negative();
        out.0 |= u64::from(v != n[i].to_bits()) << i;
        out.1 |= u64::from(v != b[i].to_bits()) << i;
        let m = a[i].abs();
        // `!(m <= MAX_FLAT)` is also true for NaN.
        let ok = m <= MAX_FLAT;
        out.2 |= u64::from(!ok) << i;
        if ok && m > out.3 {
            out.3 = m;
        }
    }
    out
}

/// [`block_edges`] with AVX2: bit patterns compared as integers; magnitudes as the integers of the
/// sign-cleared bits (same order as the floats for non-negative values; NaN and infinity sort above
/// [`MAX_FLAT`]); last: any sign bit set.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn block_edges_avx2(a: &[f32; 64], n: &[f32; 64], b: &[f32; 64]) -> (u64, u64, u64, f32, bool) {
    use std::arch::x86_64::*;
    let abs_mask = _mm256_set1_epi32(0x7fff_ffff);
    let limit = _mm256_set1_epi32(MAX_FLAT.to_bits() as i32);
    let mut best = _mm256_setzero_si256();
    let (mut ne, mut be, mut bad, mut neg) = (0u64, 0u64, 0u64, 0u32);
    for i in (0..64).step_by(8) {
        // SAFETY: `i + 8 <= 64`, so each unaligned 8-lane load stays inside its 64-value array.
        let (va, vn, vb) = unsafe {
            (
                _mm256_loadu_si256(a.as_ptr().add(i).cast()),
                _mm256_loadu_si256(n.as_ptr().add(i).cast()),
                _mm256_loadu_si256(b.as_ptr().add(i).cast()),
            )
        };
        let eq_n = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(va, vn))) as u32;
        let eq_b = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(va, vb))) as u32;
        let mag = _mm256_and_si256(va, abs_mask);
        let over = _mm256_cmpgt_epi32(mag, limit);
        let is_bad = _mm256_movemask_ps(_mm256_castsi256_ps(over)) as u32;
        best = _mm256_max_epi32(best, _mm256_andnot_si256(over, mag));
        neg |= _mm256_movemask_ps(_mm256_castsi256_ps(va)) as u32;
        ne |= u64::from(!eq_n & 0xff) << i;
        be |= u64::from(!eq_b & 0xff) << i;
        bad |= u64::from(is_bad) << i;
    }
    let mut lanes = [0i32; 8];
    // SAFETY: `lanes` holds exactly 8 i32 values (32 bytes).
    unsafe { _mm256_storeu_si256(lanes.as_mut_ptr().cast(), best) };
    let m = lanes.iter().copied().max().unwrap_or(0);
    (ne, be, bad, f32::from_bits(m as u32), neg != 0)
}

/// Clears the bits of columns `>= w` in one row.
fn clear_tail(row: &mut [u64], w: usize) {
    let full = w / 64;
    if full < row.len() {
        let rem = w % 64;
        row[full] &= if rem == 0 { 0 } else { (1u64 << rem) - 1 };
        for v in &mut row[full + 1..] {
            *v = 0;
        }
    }
}

/// Per row, one bit per chunk of [`CHUNK`] columns starting at column `offset` (the last chunk may be
/// partial): set when any pixel of the chunk is set in the pixel mask.
#[derive(Debug, Default, Clone)]
pub struct ChunkMask {
    /// Image width.
    pub w: usize,
    /// Column of the first chunk.
    pub offset: usize,
    /// Number of chunks per row.
    pub chunks: usize,
    /// Words per row.
    pub wpr: usize,
    /// Row-major words.
    pub bits: Vec<u64>,
}

impl ChunkMask {
    /// Chunks of columns `offset .. end` of every row of `m` (empty when `end <= offset`); a chunk may
    /// also be marked for pixels past `end` (harmless: it only computes more).
    pub fn build(&mut self, m: &BitMask, offset: usize, end: usize) {
        let end = end.min(m.w);
        self.w = m.w;
        self.offset = offset;
        self.chunks = end.saturating_sub(offset).div_ceil(CHUNK);
        self.wpr = self.chunks.div_ceil(64);
        self.bits.clear();
        self.bits.resize(self.wpr * m.h, 0);
        if self.chunks == 0 {
            return;
        }
        let (q, b) = (offset / 64, offset % 64);
        let groups = self.chunks.div_ceil(4);
        let mut shifted = vec![0u64; groups];
        for y in 0..m.h {
            let row = m.row(y);
            // Pixel words shifted so that chunk 4k + j starts at bit 16 j of word k.
            for (k, s) in shifted.iter_mut().enumerate() {
                let lo = row.get(k + q).copied().unwrap_or(0);
                *s = if b == 0 { lo } else { (lo >> b) | (row.get(k + q + 1).copied().unwrap_or(0) << (64 - b)) };
            }
            let out = &mut self.bits[y * self.wpr..(y + 1) * self.wpr];
            for (o, words) in out.iter_mut().zip(shifted.chunks(16)) {
                let mut acc = 0u64;
                for (i, &word) in words.iter().enumerate() {
                    acc |= chunk_nibble(word) << (4 * i);
                }
                *o = acc;
            }
            // Chunks past the last one do not exist.
            let rem = self.chunks % 64;
            if rem != 0 {
                out[self.wpr - 1] &= (1u64 << rem) - 1;
            }
        }
    }

    /// Row `y`'s words.
    #[inline]
    pub fn row(&self, y: usize) -> &[u64] {
        &self.bits[y * self.wpr..(y + 1) * self.wpr]
    }
}

/// The maximal runs of equal chunk bits of one row, in order, covering chunks `0 .. chunks`:
/// `(start_chunk, end_chunk, active)`.
#[derive(Debug, Clone)]
pub struct ChunkRuns<'a> {
    row: &'a [u64],
    chunks: usize,
    c: usize,
}

impl<'a> ChunkRuns<'a> {
    /// Runs of the first `chunks` bits of `row`.
    #[inline(always)]
    pub fn new(row: &'a [u64], chunks: usize) -> Self {
        Self { row, chunks, c: 0 }
    }
}

impl Iterator for ChunkRuns<'_> {
    type Item = (usize, usize, bool);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, usize, bool)> {
        let c = self.c;
        if c >= self.chunks {
            return None;
        }
        let active = self.row[c / 64] >> (c % 64) & 1 == 1;
        // The first chunk >= c whose bit differs.
        let mut e = c;
        loop {
            let k = e / 64;
            if k >= self.row.len() {
                break;
            }
            let word = if active { !self.row[k] } else { self.row[k] } >> (e % 64);
            if word == 0 {
                e = (k + 1) * 64;
            } else {
                e += word.trailing_zeros() as usize;
                break;
            }
        }
        let e = e.min(self.chunks);
        self.c = e;
        Some((c, e, active))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive_dilate(m: &BitMask, rx: usize, ry: usize) -> Vec<bool> {
        let (w, h) = (m.w, m.h);
        let mut out = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                let (y0, y1) = (y.saturating_sub(ry), (y + ry).min(h - 1));
                let (x0, x1) = (x.saturating_sub(rx), (x + rx).min(w - 1));
                out[y * w + x] = (y0..=y1).any(|yy| (x0..=x1).any(|xx| m.get(xx, yy)));
            }
        }
        out
    }

    #[test]
    fn dilations_match_naive() {
        let mut lcg = crate::synth::Lcg(12345);
        let mut rnd = || (lcg.next_u32() >> 1) as usize;
        for &(w, h) in &[(1usize, 1usize), (5, 3), (64, 7), (65, 20), (130, 41), (200, 3), (3, 90)] {
            for &r in &[0usize, 1, 2, 5, 13, 63, 64, 70] {
                let mut m = BitMask::default();
                m.reset(w, h);
                for _ in 0..(w * h / 97 + 1) {
                    let (x, y) = (rnd() % w, rnd() % h);
                    m.bits[y * m.wpr + x / 64] |= 1 << (x % 64);
                }
                let mut v = BitMask::default();
                v.dilate_vertical(&m, r);
                let mut a = BitMask::default();
                a.dilate_horizontal(&v, r);
                let want_v = naive_dilate(&m, 0, r);
                let want_a = naive_dilate(&m, r, r);
                for y in 0..h {
                    for x in 0..w {
                        assert_eq!(v.get(x, y), want_v[y * w + x], "v {w}x{h} r={r} ({x},{y})");
                        assert_eq!(a.get(x, y), want_a[y * w + x], "a {w}x{h} r={r} ({x},{y})");
                    }
                    // No stray bits past the width.
                    let row = a.row(y);
                    assert_eq!(
                        row.iter().map(|v| v.count_ones() as usize).sum::<usize>(),
                        (0..w).filter(|&x| a.get(x, y)).count()
                    );
                }
            }
        }
    }

    #[test]
    fn edges_mark_both_pixels_of_differing_pairs() {
        let (w, h) = (70, 4);
        let mut img = vec![5.0f32; w * h];
        img[w + 63] = 6.0; // differs from its 4 neighbours
        img[3 * w + 69] = f32::NAN;
        img[2] = -0.0;
        img[3] = 0.0; // -0 and +0 differ in bits
        img[4] = 0.0;
        let mut m = BitMask::default();
        let flat = m.edges_of(&img, w, h);
        assert_eq!((flat.max_abs, flat.all_flat_ok, flat.non_negative), (6.0, false, false));
        let set: Vec<(usize, usize)> =
            (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| m.get(x, y)).collect();
        let mut want = vec![(63, 0), (62, 1), (63, 1), (64, 1), (63, 2), (69, 2), (68, 3), (69, 3)];
        want.extend([(1, 0), (2, 0), (3, 0), (4, 0), (5, 0), (2, 1), (3, 1), (4, 1)]);
        want.sort_by_key(|&(x, y)| (y, x));
        assert_eq!(set, want);
    }

    #[test]
    fn chunk_runs_cover_the_row() {
        let mut m = BitMask::default();
        m.reset(300, 1);
        for x in [0usize, 40, 41, 150, 299] {
            m.bits[x / 64] |= 1 << (x % 64);
        }
        let mut c = ChunkMask::default();
        c.build(&m, 5, 295);
        assert_eq!(c.chunks, 19);
        let runs: Vec<_> = ChunkRuns::new(c.row(0), c.chunks).collect();
        // chunks of 16 from column 5: 40, 41 -> chunk 2; 150 -> chunk 9; 299 -> chunk 18 (partly past the
        // end, marked anyway: it only computes more).
        assert_eq!(
            runs,
            vec![(0, 2, false), (2, 3, true), (3, 9, false), (9, 10, true), (10, 18, false), (18, 19, true)]
        );
    }
}
