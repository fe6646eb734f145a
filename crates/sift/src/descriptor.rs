//! The 4x4x8 SIFT descriptor: rotated window, trilinear interpolation into cells and orientation bins,
//! Gaussian weighting, clipping at 0.2, renormalisation, bytes (OpenCV `calcSIFTDescriptor`).

use crate::fastmath::atan2_deg;
use crate::image::Plane;
use crate::keypoint::DESCRIPTOR_LEN;

/// Cells per side of the descriptor window.
pub const DESCR_WIDTH: usize = 4;
/// Orientation bins per cell.
pub const DESCR_HIST_BINS: usize = 8;
/// Cell size relative to the keypoint scale.
pub const DESCR_SCL_FCTR: f32 = 3.0;
/// Clipping threshold on the normalised descriptor's elements.
pub const DESCR_MAG_THR: f32 = 0.2;
/// Factor turning the normalised descriptor into bytes.
pub const INT_DESCR_FCTR: f32 = 512.0;

/// Cells per side of the descriptor grid.
pub const D: usize = DESCR_WIDTH;
const N: usize = DESCR_HIST_BINS;
const HIST_LEN: usize = (D + 2) * (D + 2) * (N + 2);
/// Samples whose histogram shares are computed together.
const BLK: usize = 16;

/// Reusable buffers for descriptors.
#[derive(Debug, Default, Clone)]
pub struct DescScratch {
    dx: Vec<f32>,
    dy: Vec<f32>,
    rbin: Vec<f32>,
    cbin: Vec<f32>,
    w: Vec<f32>,
    ex: Vec<f32>,
    ex_row: Vec<f32>,
}

/// What the samples of one window row depend on besides the column.
#[cfg(target_arch = "x86_64")]
struct RowGeometry {
    ptx: isize,
    radius: isize,
    fi: f32,
    wi: f32,
    cos_t: f32,
    sin_t: f32,
    half: f32,
}

/// The samples of window row `i` at columns `j0 ..= j1` (rows `up`, `mid`, `down` around it), 16 columns
/// at a time, appended from `k` in column order; returns the new count. Same arithmetic as the scalar loop.
///
/// # Safety
/// The CPU has AVX-512F; columns `ptx + j0 - 1 ..= ptx + j1 + 1` are inside the rows; `ex_row` holds
/// `2 radius + 1` weights; each output slice has room for 16 values from any count reached.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::type_complexity)]
unsafe fn window_row_avx512(
    (up, mid, down): (&[f32], &[f32], &[f32]),
    g: &RowGeometry,
    j0: isize,
    j1: isize,
    ex_row: &[f32],
    (sdx, sdy, srb, scb, sw): (&mut [f32], &mut [f32], &mut [f32], &mut [f32], &mut [f32]),
    mut k: usize,
) -> usize {
    use std::arch::x86_64::*;
    let lanes = _mm512_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0);
    let (vcos, vsin) = (_mm512_set1_ps(g.cos_t), _mm512_set1_ps(g.sin_t));
    let (fi_sin, fi_cos) = (_mm512_set1_ps(g.fi * g.sin_t), _mm512_set1_ps(g.fi * g.cos_t));
    let (half, lo, hi) = (_mm512_set1_ps(g.half), _mm512_set1_ps(-1.0), _mm512_set1_ps(D as f32));
    let (zero, wi) = (_mm512_setzero_ps(), _mm512_set1_ps(g.wi));
    let mut j = j0;
    while j <= j1 {
        let n = (j1 - j + 1).min(16) as u32;
        let valid: __mmask16 = if n == 16 { 0xffff } else { ((1u32 << n) - 1) as u16 };
        let c = (g.ptx + j) as usize;
        // SAFETY: lanes past `j1` are masked off, so only in-bounds elements are read; the base
        // pointers are in bounds by the caller's contract.
        let ld = |row: &[f32], at: usize| unsafe { _mm512_maskz_loadu_ps(valid, row.as_ptr().add(at)) };
        let fj = _mm512_add_ps(_mm512_set1_ps(j as f32), lanes);
        let c_rot = _mm512_sub_ps(_mm512_mul_ps(fj, vcos), fi_sin);
        let r_rot = _mm512_add_ps(_mm512_mul_ps(fj, vsin), fi_cos);
        let (rbin, cbin) = (_mm512_add_ps(r_rot, half), _mm512_add_ps(c_rot, half));
        let inside = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(rbin, lo)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(rbin, hi)
            & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cbin, lo)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(cbin, hi);
        let gx = _mm512_sub_ps(ld(mid, c + 1), ld(mid, c - 1));
        let gy = _mm512_sub_ps(ld(up, c), ld(down, c));
        let moving = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(gx, zero) | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(gy, zero);
        let wgt = _mm512_mul_ps(wi, ld(ex_row, (j + g.radius) as usize));
        let keep = valid & inside & moving;
        // SAFETY: each output has room for 16 values from `k` (caller's contract).
        unsafe {
            _mm512_storeu_ps(sdx.as_mut_ptr().add(k), _mm512_maskz_compress_ps(keep, gx));
            _mm512_storeu_ps(sdy.as_mut_ptr().add(k), _mm512_maskz_compress_ps(keep, gy));
            _mm512_storeu_ps(srb.as_mut_ptr().add(k), _mm512_maskz_compress_ps(keep, rbin));
            _mm512_storeu_ps(scb.as_mut_ptr().add(k), _mm512_maskz_compress_ps(keep, cbin));
            _mm512_storeu_ps(sw.as_mut_ptr().add(k), _mm512_maskz_compress_ps(keep, wgt));
        }
        k += keep.count_ones() as usize;
        j += 16;
    }
    k
}

/// Where a descriptor is taken: sub-pixel position, orientation and scale in an octave's image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Column, octave pixels.
    pub px: f32,
    /// Row, octave pixels.
    pub py: f32,
    /// Orientation in degrees, gradient convention: `360 - keypoint.angle`.
    pub ori: f32,
    /// Scale, octave pixels.
    pub scl: f32,
}

/// Radius of the window a descriptor at scale `scl` reads in a `w` x `h` image (OpenCV: the rotated
/// histogram's bounding square, at most the image's diagonal).
pub fn radius(scl: f32, w: usize, h: usize) -> usize {
    let r = (DESCR_SCL_FCTR * scl * std::f32::consts::SQRT_2 * (D as f32 + 1.0) * 0.5).round_ties_even() as isize;
    let diag = ((w as f64) * (w as f64) + (h as f64) * (h as f64)).sqrt() as isize;
    r.clamp(0, diag) as usize
}

crate::cpu_dispatch! {
    /// Computes the descriptor of Gaussian image `img` (`w` x `h`) in frame `at`.
    pub fn descriptor(img: Plane<'_>, at: Frame, out: &mut [u8], s: &mut DescScratch);
    "avx512f" => descriptor_avx512 => descriptor_impl::<true>(img, at, out, s);
    "avx2" => descriptor_avx2 => descriptor_impl::<false>(img, at, out, s);
    _ => descriptor_impl::<false>(img, at, out, s)
}

/// The descriptor; with `AVX512` (only when the caller has that target feature), the window's samples
/// are gathered 16 columns at a time (the same values in the same order as the scalar loop).
#[inline(always)]
fn descriptor_impl<const AVX512: bool>(img: Plane<'_>, at: Frame, out: &mut [u8], s: &mut DescScratch) {
    let Plane { data: img, w, h, y0 } = img;
    let Frame { px, py, ori, scl } = at;
    let (ptx, pty) = (px.round_ties_even() as isize, py.round_ties_even() as isize);
    let rad = ori * (std::f32::consts::PI / 180.0);
    let (mut sin_t, mut cos_t) = rad.sin_cos();
    let bins_per_rad = N as f32 / 360.0;
    let exp_scale = -1.0 / (D as f32 * D as f32 * 0.5);
    let hist_width = DESCR_SCL_FCTR * scl;
    let radius = radius(scl, w, h) as isize;
    cos_t /= hist_width;
    sin_t /= hist_width;
    // Gaussian weight exp(-(c_rot^2 + r_rot^2) / (2 (d/2)^2)) is radial, so separable in (i, j).
    let inv_hw2 = 1.0 / (hist_width * hist_width);
    s.ex.clear();
    s.ex.extend((0..=radius).map(|i| ((i * i) as f32 * inv_hw2 * exp_scale).exp()));
    // By column offset j + radius: ex[|j|].
    s.ex_row.clear();
    s.ex_row.extend((-radius..=radius).map(|j| s.ex[j.unsigned_abs()]));
    // Room for a full vector store past the last sample.
    let cap = ((2 * radius + 1) * (2 * radius + 1)) as usize + 16;
    for v in [&mut s.dx, &mut s.dy, &mut s.rbin, &mut s.cbin, &mut s.w] {
        if v.len() < cap {
            v.resize(cap, 0.0);
        }
    }
    let mut k = 0;
    let half = (D / 2) as f32 - 0.5;
    let (sdx, sdy, srb, scb, sw, ex) =
        (&mut s.dx[..cap], &mut s.dy[..cap], &mut s.rbin[..cap], &mut s.cbin[..cap], &mut s.w[..cap], &s.ex[..]);
    let ex_row = &s.ex_row[..];
    for i in -radius..=radius {
        let r = pty + i;
        if r <= 0 || r >= h as isize - 1 {
            continue;
        }
        let row = (r as usize - y0) * w;
        let fi = i as f32;
        let wi = ex[i.unsigned_abs()];
        let (up, mid, down) = (&img[row - w..row], &img[row..row + w], &img[row + w..row + 2 * w]);
        // Columns where the rotated sample can fall inside the window (widened by one; the exact test
        // below decides), and inside the image.
        let (mut j0, mut j1) = (-radius, radius);
        let span = |a: f32, b: f32, j0: &mut isize, j1: &mut isize| {
            // Keep j with a * j + b in (-(D/2 + 1/2)... (D/2 + 1/2)) i.e. bin in (-1, D).
            let lim = half + 1.0;
            if a.abs() > 1e-6 {
                let (p, q) = ((-lim - b) / a, (lim - b) / a);
                let (lo, hi) = if p < q { (p, q) } else { (q, p) };
                *j0 = (*j0).max(lo.floor() as isize - 1);
                *j1 = (*j1).min(hi.ceil() as isize + 1);
            }
        };
        span(sin_t, fi * cos_t, &mut j0, &mut j1);
        span(cos_t, -fi * sin_t, &mut j0, &mut j1);
        j0 = j0.max(1 - ptx);
        j1 = j1.min(w as isize - 2 - ptx);
        #[cfg(target_arch = "x86_64")]
        if AVX512 {
            let geo = RowGeometry { ptx, radius, fi, wi, cos_t, sin_t, half };
            // SAFETY: `AVX512` is only set by `descriptor_avx512`, which has the feature; columns
            // `ptx + j0 - 1 ..= ptx + j1 + 1` lie in the rows (1 <= ptx + j, ptx + j <= w - 2), `ex_row`
            // has 2 radius + 1 entries, and the sample buffers have room for 16 values past any sample.
            k = unsafe { window_row_avx512((up, mid, down), &geo, j0, j1, ex_row, (sdx, sdy, srb, scb, sw), k) };
            continue;
        }
        for j in j0..=j1 {
            let c = ptx + j;
            let fj = j as f32;
            let c_rot = fj * cos_t - fi * sin_t;
            let r_rot = fj * sin_t + fi * cos_t;
            let rbin = r_rot + half;
            let cbin = c_rot + half;
            if rbin > -1.0 && rbin < D as f32 && cbin > -1.0 && cbin < D as f32 {
                let c = c as usize;
                let (gx, gy) = (mid[c + 1] - mid[c - 1], up[c] - down[c]);
                // A zero gradient adds +0 to every share (the histogram's entries are sums of values
                // >= +0, never -0): leaving it out changes no bit. Flat map areas are full of them.
                sdx[k] = gx;
                sdy[k] = gy;
                srb[k] = rbin;
                scb[k] = cbin;
                sw[k] = wi * ex[j.unsigned_abs()];
                k += usize::from(gx != 0.0 || gy != 0.0);
            }
        }
    }
    let len = k;
    // Vectorisable pass: orientation bin and weighted magnitude of every sample (in place in dx, dy).
    for (dx, dy) in s.dx[..len].iter_mut().zip(&mut s.dy[..len]) {
        let (x, y) = (*dx, *dy);
        *dx = (atan2_deg(y, x) - ori) * bins_per_rad;
        *dy = (x * x + y * y).sqrt();
    }
    // Pad to whole blocks with zero-weight samples.
    let padded = len.div_ceil(BLK) * BLK;
    for v in [&mut s.dx, &mut s.dy, &mut s.rbin, &mut s.cbin, &mut s.w] {
        if v.len() < padded {
            v.resize(padded, 0.0);
        }
        v[len..padded].fill(0.0);
    }
    let mut hist = [0.0f32; HIST_LEN];
    let mut k = 0;
    while k < len {
        // Vectorisable: the 8 trilinear shares and the base index of BLK samples.
        let mut vals = [[0.0f32; BLK]; 8];
        let mut idx = [0usize; BLK];
        {
            let mag: &[f32; BLK] = s.dy[k..k + BLK].try_into().expect("block");
            let wgt: &[f32; BLK] = s.w[k..k + BLK].try_into().expect("block");
            let rb: &[f32; BLK] = s.rbin[k..k + BLK].try_into().expect("block");
            let cb: &[f32; BLK] = s.cbin[k..k + BLK].try_into().expect("block");
            let ob: &[f32; BLK] = s.dx[k..k + BLK].try_into().expect("block");
            for l in 0..BLK {
                let mag = mag[l] * wgt[l];
                let (r0, c0, o0f) = (rb[l].floor(), cb[l].floor(), ob[l].floor());
                let (rbin, cbin, obin) = (rb[l] - r0, cb[l] - c0, ob[l] - o0f);
                let mut o0 = o0f as i32;
                o0 = if o0 < 0 { o0 + N as i32 } else { o0 };
                o0 = if o0 >= N as i32 { o0 - N as i32 } else { o0 };
                let v_r1 = mag * rbin;
                let v_r0 = mag - v_r1;
                let v_rc11 = v_r1 * cbin;
                let v_rc10 = v_r1 - v_rc11;
                let v_rc01 = v_r0 * cbin;
                let v_rc00 = v_r0 - v_rc01;
                let v_rco111 = v_rc11 * obin;
                let v_rco101 = v_rc10 * obin;
                let v_rco011 = v_rc01 * obin;
                let v_rco001 = v_rc00 * obin;
                vals[0][l] = v_rc00 - v_rco001;
                vals[1][l] = v_rco001;
                vals[2][l] = v_rc01 - v_rco011;
                vals[3][l] = v_rco011;
                vals[4][l] = v_rc10 - v_rco101;
                vals[5][l] = v_rco101;
                vals[6][l] = v_rc11 - v_rco111;
                vals[7][l] = v_rco111;
                idx[l] = (((r0 as i32 + 1) * (D as i32 + 2) + (c0 as i32 + 1)) * (N as i32 + 2) + o0) as usize;
            }
        }
        // Sequential scatter, in sample order (same sums as OpenCV).
        for l in 0..BLK.min(len - k) {
            let hs = &mut hist[idx[l]..idx[l] + (D + 3) * (N + 2) + 2];
            hs[0] += vals[0][l];
            hs[1] += vals[1][l];
            hs[N + 2] += vals[2][l];
            hs[N + 3] += vals[3][l];
            hs[(D + 2) * (N + 2)] += vals[4][l];
            hs[(D + 2) * (N + 2) + 1] += vals[5][l];
            hs[(D + 3) * (N + 2)] += vals[6][l];
            hs[(D + 3) * (N + 2) + 1] += vals[7][l];
        }
        k += BLK;
    }
    let mut raw = [0.0f32; DESCRIPTOR_LEN];
    for i in 0..D {
        for j in 0..D {
            let idx = ((i + 1) * (D + 2) + (j + 1)) * (N + 2);
            hist[idx] += hist[idx + N];
            hist[idx + 1] += hist[idx + N + 1];
            raw[(i * D + j) * N..(i * D + j + 1) * N].copy_from_slice(&hist[idx..idx + N]);
        }
    }
    let nrm2: f32 = raw.iter().map(|v| v * v).sum();
    let thr = nrm2.sqrt() * DESCR_MAG_THR;
    let mut nrm2 = 0.0f32;
    for v in raw.iter_mut() {
        *v = v.min(thr);
        nrm2 += *v * *v;
    }
    let scale = INT_DESCR_FCTR / nrm2.sqrt().max(f32::EPSILON);
    for (o, v) in out.iter_mut().zip(raw) {
        *o = (v * scale).round_ties_even().clamp(0.0, 255.0) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vector_paths_match_the_scalar_loop_bit_for_bit() {
        // On a CPU with AVX-512 (or AVX2) `descriptor` takes that path; the scalar form is the reference.
        let (w, h) = (97, 83);
        let mut lcg = crate::synth::Lcg(11);
        let mut rnd = || lcg.f32();
        // Flat areas (zero gradients) with steps and a smooth part, like a blurred map.
        let img: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                if x < 30.0 {
                    255.0
                } else if y < 40.0 {
                    (x * 0.21).sin() * 80.0 + y
                } else {
                    17.5
                }
            })
            .collect();
        let (mut a, mut b) = (DescScratch::default(), DescScratch::default());
        for _ in 0..300 {
            let (px, py) = (rnd() * (w as f32 - 1.0), rnd() * (h as f32 - 1.0));
            let (ori, scl) = (rnd() * 360.0, 0.8 + rnd() * 6.0);
            let (mut fast, mut slow) = ([0u8; DESCRIPTOR_LEN], [0u8; DESCRIPTOR_LEN]);
            descriptor(Plane::new(&img, w, h), Frame { px, py, ori, scl }, &mut fast, &mut a);
            descriptor_impl::<false>(Plane::new(&img, w, h), Frame { px, py, ori, scl }, &mut slow, &mut b);
            assert_eq!(fast, slow, "at ({px}, {py}), angle {ori}, scale {scl}");
        }
    }

    #[test]
    fn descriptor_is_normalised_and_rotates_with_the_image() {
        let (w, h) = (64, 64);
        let img: Vec<f32> = (0..w * h).map(|i| ((i % w) as f32 * 0.3).sin() * 50.0 + (i / w) as f32).collect();
        let mut d = [0u8; DESCRIPTOR_LEN];
        descriptor(
            Plane::new(&img, w, h),
            Frame { px: 32.0, py: 32.0, ori: 0.0, scl: 3.0 },
            &mut d,
            &mut DescScratch::default(),
        );
        let n: f32 = d.iter().map(|&v| (v as f32) * (v as f32)).sum::<f32>().sqrt();
        assert!((n - 512.0).abs() < 20.0, "{n}");
        // Transposed image with orientation turned by 90 degrees gives a permuted, similar descriptor.
        let t: Vec<f32> = (0..w * h).map(|i| img[(i % w) * w + i / w]).collect();
        let mut d2 = [0u8; DESCRIPTOR_LEN];
        descriptor(
            Plane::new(&t, w, h),
            Frame { px: 32.0, py: 32.0, ori: 0.0, scl: 3.0 },
            &mut d2,
            &mut DescScratch::default(),
        );
        assert_ne!(d, d2);
        let mut empty = [7u8; DESCRIPTOR_LEN];
        descriptor(
            Plane::new(&[1.0; 9], 3, 3),
            Frame { px: 1.0, py: 1.0, ori: 0.0, scl: 1.0 },
            &mut empty,
            &mut DescScratch::default(),
        );
        assert!(empty.iter().all(|&v| v == 0));
    }
}
