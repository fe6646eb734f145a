//! Scale-space extrema: 26-neighbour detection, sub-pixel/sub-scale refinement, contrast and edge tests.

use crate::mask::{ChunkMask, ChunkRuns};
use crate::params::SiftParams;

/// A pixel that is a strict-or-equal extremum among its 26 neighbours in a DoG layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Candidate {
    /// Row in the octave image.
    pub r: usize,
    /// Column in the octave image.
    pub c: usize,
    /// DoG layer (1..=n_layers).
    pub layer: usize,
}

/// A refined extremum (OpenCV `adjustLocalExtrema` output, octave-local).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refined {
    /// Integer row after refinement.
    pub r: usize,
    /// Integer column after refinement.
    pub c: usize,
    /// DoG layer after refinement.
    pub layer: usize,
    /// Sub-pixel column offset (|xc| < 0.5).
    pub xc: f32,
    /// Sub-pixel row offset.
    pub xr: f32,
    /// Sub-layer offset.
    pub xi: f32,
    /// Interpolated DoG value on the 0..1 scale.
    pub contr: f32,
}

/// DoG values of one octave, formed on demand from its Gaussian layers: `D_l = G_{l+1} - G_l`.
#[derive(Debug, Clone, Copy)]
pub struct DogView<'a> {
    /// The octave's Gaussian layers, each holding the rows `rows` from its start.
    pub gauss: &'a [Vec<f32>],
    /// Row length.
    pub w: usize,
    /// The first row the layers hold (0 for a whole octave).
    pub y0: usize,
    /// The row after the last the layers hold (final in every layer).
    pub y1: usize,
}

impl DogView<'_> {
    /// DoG layer `l` at row `r`, column `c`.
    #[inline(always)]
    pub fn at(&self, l: usize, r: isize, c: isize) -> f32 {
        let i = ((r - self.y0 as isize) * self.w as isize + c) as usize;
        self.gauss[l + 1][i] - self.gauss[l][i]
    }
}

/// Where a refinement stands: the pixel and layer it is at, the steps it has taken, and once converged, the
/// offsets. A refinement that needs rows its view does not hold (a windowed octave) returns its state, to be
/// resumed, bit for bit the same, where they are held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineState {
    r: isize,
    c: isize,
    layer: isize,
    step: usize,
    /// `(xi, xr, xc)` once converged.
    offsets: Option<[f32; 3]>,
}

impl RefineState {
    /// A refinement about to take its first step at a candidate.
    pub fn start(cand: Candidate) -> Self {
        Self { r: cand.r as isize, c: cand.c as isize, layer: cand.layer as isize, step: 0, offsets: None }
    }

    /// The rows the next step reads.
    pub fn rows(&self) -> std::ops::Range<usize> {
        (self.r - 1).max(0) as usize..(self.r + 2).max(0) as usize
    }
}

/// Columns tested together (the scan mask's chunks).
const CHUNK: usize = crate::mask::CHUNK;

/// Reusable rolling rows (3 per DoG layer): DoG values and their 3-wide horizontal maxima and minima.
#[derive(Debug, Default, Clone)]
pub struct DogRows {
    dog: Vec<f32>,
    hmax: Vec<f32>,
    hmin: Vec<f32>,
}

crate::cpu_dispatch! {
    /// Appends to `out` the 26-neighbour extrema of DoG layers `1..=n_layers` (OpenCV's test: `|D| > threshold`
    /// and `D >= all neighbours` when positive, `<=` when negative), skipping `border` pixels at the edges.
    ///
    /// DoG rows are formed once each into a small rolling buffer together with their 3-wide running max and
    /// min, so the 3x3x3 maximum (which may include the centre: `D >= max` is the same test) costs 9 loads per
    /// pixel. Chunks of pixels all below the threshold are skipped first; everything runs on whole chunks
    /// (vectorised), with AVX2 / AVX-512 copies picked at run time.
    ///
    /// Only rows `rows` (clamped to `border .. h - border`) are scanned, so a caller can scan an octave in
    /// consecutive row ranges as its layers become available (Gaussian rows up to `rows.end` must be final);
    /// the ranges must start at `border` and follow each other (the rolling buffer carries over).
    ///
    /// With `mask` (chunks of 16 columns from column `border`, one row of chunks per image row), only the
    /// masked chunks are scanned, and DoG rows are formed only where those scans read them; the caller
    /// guarantees that no pixel outside the mask has `|D| > threshold` in any tested layer, so the candidates
    /// (and their order) are those of the full scan.
    #[allow(clippy::too_many_arguments)]
    pub fn find_candidates(
        gauss: &[Vec<f32>],
        y0: usize,
        w: usize,
        h: usize,
        n_layers: usize,
        threshold: f32,
        border: usize,
        rows: std::ops::Range<usize>,
        mask: Option<&ChunkMask>,
        ring: &mut DogRows,
        out: &mut Vec<Candidate>,
    );
    "avx512f" => find_candidates_avx512 =>
        find_candidates_impl(gauss, y0, w, h, n_layers, threshold, border, rows, mask, ring, out);
    "avx2" => find_candidates_avx2 =>
        find_candidates_impl(gauss, y0, w, h, n_layers, threshold, border, rows, mask, ring, out);
    _ => find_candidates_impl(gauss, y0, w, h, n_layers, threshold, border, rows, mask, ring, out)
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn find_candidates_impl(
    gauss: &[Vec<f32>],
    y0: usize,
    w: usize,
    h: usize,
    n_layers: usize,
    threshold: f32,
    border: usize,
    rows: std::ops::Range<usize>,
    mask: Option<&ChunkMask>,
    ring: &mut DogRows,
    out: &mut Vec<Candidate>,
) {
    if border == 0 || w < 2 * border + 1 || h < 2 * border + 1 {
        return;
    }
    let n_dog = n_layers + 2;
    let ring_len = n_dog * 3 * w;
    for v in [&mut ring.dog, &mut ring.hmax, &mut ring.hmin] {
        if v.len() < ring_len {
            v.resize(ring_len, 0.0);
        }
    }
    let (dog, hmax, hmin) = (&mut ring.dog[..ring_len], &mut ring.hmax[..ring_len], &mut ring.hmin[..ring_len]);
    let (r_from, r_to) = (rows.start.max(border), rows.end.min(h - border));
    if r_from >= r_to {
        return;
    }
    let end = w - border;
    // Scan chunks: from column `border`, the last one possibly partial.
    let chunks = (end - border).div_ceil(CHUNK);
    let cwpr = chunks.div_ceil(64);
    let mut union = vec![0u64; cwpr];
    let full: Vec<u64> = (0..cwpr)
        .map(|i| {
            let n = chunks.saturating_sub(i * 64).min(64);
            if n == 64 { u64::MAX } else { (1u64 << n) - 1 }
        })
        .collect();
    // The chunk bits of scan row y (none outside the scanned rows).
    let mask_row = |y: usize| -> Option<&[u64]> {
        if y < border || y >= h - border {
            return None;
        }
        mask.map(|m| m.row(y))
    };
    // Forms DoG row y (with its running max / min) where scans of rows y - 1, y, y + 1 read it.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn fill(
        gauss: &[Vec<f32>],
        y0: usize,
        w: usize,
        n_dog: usize,
        ring: (&mut [f32], &mut [f32], &mut [f32]),
        y: usize,
        masked: bool,
        near: [Option<&[u64]>; 3],
        union: &mut [u64],
        chunks: usize,
        border: usize,
        end: usize,
    ) {
        let (dog, hmax, hmin) = ring;
        if !masked {
            fill_row(gauss, y0, w, n_dog, (dog, hmax, hmin), y, 1, w - 1);
            return;
        }
        union.fill(0);
        for r in near.into_iter().flatten() {
            for (a, b) in union.iter_mut().zip(r) {
                *a |= b;
            }
        }
        for (a, b, on) in ChunkRuns::new(union, chunks) {
            if on {
                let (c0, c1) = (border + a * CHUNK, (border + b * CHUNK).min(end));
                fill_row(gauss, y0, w, n_dog, (&mut *dog, &mut *hmax, &mut *hmin), y, c0, c1);
            }
        }
    }
    let masked = mask.is_some();
    let near = |y: usize| [mask_row(y.wrapping_sub(1)), mask_row(y), mask_row(y + 1)];
    if r_from == border {
        for y in [border - 1, border] {
            let ring = (&mut *dog, &mut *hmax, &mut *hmin);
            fill(gauss, y0, w, n_dog, ring, y, masked, near(y), &mut union, chunks, border, end);
        }
    }
    for r in r_from..r_to {
        let ring = (&mut *dog, &mut *hmax, &mut *hmin);
        fill(gauss, y0, w, n_dog, ring, r + 1, masked, near(r + 1), &mut union, chunks, border, end);
        let (dog, hmax, hmin): (&[f32], &[f32], &[f32]) = (dog, hmax, hmin);
        let row = |l: usize, y: usize| (l * 3 + y % 3) * w;
        let runs = mask_row(r).unwrap_or(&full);
        for layer in 1..=n_layers {
            let cur = &dog[row(layer, r)..row(layer, r) + w];
            let mut maxs: [&[f32]; 9] = [cur; 9];
            let mut mins: [&[f32]; 9] = [cur; 9];
            let mut k = 0;
            for l in layer - 1..=layer + 1 {
                for y in r - 1..=r + 1 {
                    let o = row(l, y);
                    maxs[k] = &hmax[o..o + w];
                    mins[k] = &hmin[o..o + w];
                    k += 1;
                }
            }
            for (a, b, on) in ChunkRuns::new(runs, chunks) {
                if on {
                    let (c0, c1) = (border + a * CHUNK, (border + b * CHUNK).min(end));
                    scan_row(cur, &maxs, &mins, c0, c1, threshold, |c| out.push(Candidate { r, c, layer }));
                }
            }
        }
    }
}

/// Forms DoG row `y` of every layer into the rolling buffer at columns `c0 - 1 .. c1 + 1` (clipped to the
/// image), and its 3-wide running max / min at columns `c0 .. c1` (`1 <= c0`, `c1 <= w - 1`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn fill_row(
    gauss: &[Vec<f32>],
    y0: usize,
    w: usize,
    n_dog: usize,
    rows: (&mut [f32], &mut [f32], &mut [f32]),
    y: usize,
    c0: usize,
    c1: usize,
) {
    let (dog, hmax, hmin) = rows;
    let (d0, d1) = (c0 - 1, c1 + 1);
    for l in 0..n_dog {
        let slot = (l * 3 + y % 3) * w;
        let d = &mut dog[slot + d0..slot + d1];
        let o = (y - y0) * w;
        let (a, b) = (&gauss[l][o + d0..o + d1], &gauss[l + 1][o + d0..o + d1]);
        for ((o, &x), &z) in d.iter_mut().zip(a).zip(b) {
            *o = z - x;
        }
        let d: &[f32] = d;
        let (mx, mn) = (&mut hmax[slot + c0..slot + c1], &mut hmin[slot + c0..slot + c1]);
        for ((o, p), q) in mx.iter_mut().zip(mn.iter_mut()).zip(d.windows(3)) {
            let m = if q[0] > q[1] { q[0] } else { q[1] };
            *o = if q[2] > m { q[2] } else { m };
            let m = if q[0] < q[1] { q[0] } else { q[1] };
            *p = if q[2] < m { q[2] } else { m };
        }
    }
}

/// Tests columns `c0 .. c1` of one DoG row: `maxs` / `mins` are the 3-wide running max / min of the 9
/// rows around it (3 layers x 3 rows). Whole chunks are tested together, the rest one by one.
#[inline(always)]
fn scan_row(
    cur: &[f32],
    maxs: &[&[f32]; 9],
    mins: &[&[f32]; 9],
    c0: usize,
    c1: usize,
    thr: f32,
    mut push: impl FnMut(usize),
) {
    let end = c1;
    let mut c = c0;
    while c + CHUNK <= end {
        let v: &[f32; CHUNK] = cur[c..c + CHUNK].try_into().expect("chunk");
        let mut any = false;
        for &x in v {
            any |= x.abs() > thr;
        }
        if any {
            let mut mx = [f32::MIN; CHUNK];
            let mut mn = [f32::MAX; CHUNK];
            for (a, b) in maxs.iter().zip(mins) {
                let a: &[f32; CHUNK] = a[c..c + CHUNK].try_into().expect("chunk");
                let b: &[f32; CHUNK] = b[c..c + CHUNK].try_into().expect("chunk");
                for l in 0..CHUNK {
                    mx[l] = if a[l] > mx[l] { a[l] } else { mx[l] };
                    mn[l] = if b[l] < mn[l] { b[l] } else { mn[l] };
                }
            }
            let mut hit = [false; CHUNK];
            for l in 0..CHUNK {
                let val = v[l];
                hit[l] = (val.abs() > thr) & (((val > 0.0) & (val >= mx[l])) | ((val < 0.0) & (val <= mn[l])));
            }
            // Most chunks hold no extremum: one test for all lanes first.
            if u128::from_ne_bytes(hit.map(u8::from)) != 0 {
                for (l, &h) in hit.iter().enumerate() {
                    if h {
                        push(c + l);
                    }
                }
            }
        }
        c += CHUNK;
    }
    for c in c..end {
        let val = cur[c];
        if val.abs() <= thr {
            continue;
        }
        let mx = maxs.iter().fold(f32::MIN, |m, r| m.max(r[c]));
        let mn = mins.iter().fold(f32::MAX, |m, r| m.min(r[c]));
        if (val > 0.0 && val >= mx) || (val < 0.0 && val <= mn) {
            push(c);
        }
    }
}

#[allow(clippy::needless_range_loop)]
/// Solves `h x = b` by LU with partial pivoting as OpenCV's `hal::LU32f`; `None` when singular.
fn solve3(mut a: [[f32; 3]; 3], mut b: [f32; 3]) -> Option<[f32; 3]> {
    for i in 0..3 {
        let mut k = i;
        for j in i + 1..3 {
            if a[j][i].abs() > a[k][i].abs() {
                k = j;
            }
        }
        if a[k][i].abs() < f32::EPSILON {
            return None;
        }
        if k != i {
            a.swap(i, k);
            b.swap(i, k);
        }
        let d = -1.0 / a[i][i];
        for j in i + 1..3 {
            let alpha = a[j][i] * d;
            for c in i + 1..3 {
                a[j][c] += alpha * a[i][c];
            }
            b[j] += alpha * b[i];
        }
        a[i][i] = -d;
    }
    for i in (0..3).rev() {
        let mut s = b[i];
        for k in i + 1..3 {
            s -= a[i][k] * b[k];
        }
        b[i] = s * a[i][i];
    }
    Some(b)
}

/// DoG values on the 0..1 scale of an 8-bit image (OpenCV's `img_scale` for float input scaled to 0..255).
const IMG_SCALE: f32 = 1.0 / 255.0;

/// The DoG's gradient at pixel (`r`, `c`) of layer `l`: x, y and scale (central differences, OpenCV's scale).
#[inline(always)]
fn gradient(dog: &DogView<'_>, l: usize, r: isize, c: isize) -> [f32; 3] {
    let deriv_scale = IMG_SCALE * 0.5;
    [
        (dog.at(l, r, c + 1) - dog.at(l, r, c - 1)) * deriv_scale,
        (dog.at(l, r + 1, c) - dog.at(l, r - 1, c)) * deriv_scale,
        (dog.at(l + 1, r, c) - dog.at(l - 1, r, c)) * deriv_scale,
    ]
}

/// The DoG's spatial second derivatives `(dxx, dyy, dxy)` at pixel (`r`, `c`) of layer `l`.
#[inline(always)]
fn hessian_xy(dog: &DogView<'_>, l: usize, r: isize, c: isize) -> (f32, f32, f32) {
    let v2 = dog.at(l, r, c) * 2.0;
    let dxx = (dog.at(l, r, c + 1) + dog.at(l, r, c - 1) - v2) * IMG_SCALE;
    let dyy = (dog.at(l, r + 1, c) + dog.at(l, r - 1, c) - v2) * IMG_SCALE;
    let dxy = (dog.at(l, r + 1, c + 1) - dog.at(l, r + 1, c - 1) - dog.at(l, r - 1, c + 1) + dog.at(l, r - 1, c - 1))
        * (IMG_SCALE * 0.25);
    (dxx, dyy, dxy)
}

/// Refines a candidate to sub-pixel and sub-scale accuracy (Lowe 2004 §4, OpenCV `adjustLocalExtrema`)
/// and applies the contrast and edge tests, from `state` on. `Ok(None)` when rejected; `Err` with the state
/// reached when the next step reads rows the view does not hold.
pub fn refine(
    dog: DogView<'_>,
    w: usize,
    h: usize,
    state: RefineState,
    params: &SiftParams,
) -> Result<Option<Refined>, RefineState> {
    // Every read is at rows r - 1 ..= r + 1.
    let inside = |r: isize| r > dog.y0 as isize && r + 1 < dog.y1 as isize;
    let (second_deriv_scale, cross_deriv_scale) = (IMG_SCALE, IMG_SCALE * 0.25);
    let n_layers = params.n_octave_layers;
    let border = params.border as isize;
    let RefineState { mut r, mut c, mut layer, step, mut offsets } = state;
    let wi = w as isize;
    if offsets.is_none() {
        for step in step..params.max_interp_steps {
            if !inside(r) {
                return Err(RefineState { r, c, layer, step, offsets });
            }
            let (img, prev, next) = (layer as usize, layer as usize - 1, layer as usize + 1);
            let at = |l: usize, rr: isize, cc: isize| dog.at(l, rr, cc);
            let d_d = gradient(&dog, img, r, c);
            let v2 = at(img, r, c) * 2.0;
            let (dxx, dyy, dxy) = hessian_xy(&dog, img, r, c);
            let dss = (at(next, r, c) + at(prev, r, c) - v2) * second_deriv_scale;
            let dxs =
                (at(next, r, c + 1) - at(next, r, c - 1) - at(prev, r, c + 1) + at(prev, r, c - 1)) * cross_deriv_scale;
            let dys =
                (at(next, r + 1, c) - at(next, r - 1, c) - at(prev, r + 1, c) + at(prev, r - 1, c)) * cross_deriv_scale;
            let x = solve3([[dxx, dxy, dxs], [dxy, dyy, dys], [dxs, dys, dss]], d_d).unwrap_or([0.0; 3]);
            let (xi, xr, xc) = (-x[2], -x[1], -x[0]);
            if xi.abs() < 0.5 && xr.abs() < 0.5 && xc.abs() < 0.5 {
                offsets = Some([xi, xr, xc]);
                break;
            }
            let lim = (i32::MAX / 3) as f32;
            if !(xi.abs() <= lim && xr.abs() <= lim && xc.abs() <= lim) {
                return Ok(None);
            }
            c += xc.round_ties_even() as isize;
            r += xr.round_ties_even() as isize;
            layer += xi.round_ties_even() as isize;
            if layer < 1
                || layer > n_layers as isize
                || c < border
                || c >= wi - border
                || r < border
                || r >= h as isize - border
            {
                return Ok(None);
            }
        }
    }
    let Some([xi, xr, xc]) = offsets else {
        return Ok(None);
    };
    if !inside(r) {
        let step = params.max_interp_steps;
        return Err(RefineState { r, c, layer, step, offsets });
    }
    let img = layer as usize;
    let d_d = gradient(&dog, img, r, c);
    let t = d_d[0] * xc + d_d[1] * xr + d_d[2] * xi;
    let contr = dog.at(img, r, c) * IMG_SCALE + t * 0.5;
    if contr.abs() * (n_layers as f32) < params.contrast_threshold {
        return Ok(None);
    }
    let (dxx, dyy, dxy) = hessian_xy(&dog, img, r, c);
    let tr = dxx + dyy;
    let det = dxx * dyy - dxy * dxy;
    let et = params.edge_threshold;
    if det <= 0.0 || tr * tr * et >= (et + 1.0) * (et + 1.0) * det {
        return Ok(None);
    }
    Ok(Some(Refined { r: r as usize, c: c as usize, layer: layer as usize, xc, xr, xi, contr }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve3_solves() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = solve3(a, [1.0, 2.0, 3.0]).unwrap();
        for (row, want) in a.iter().zip([1.0, 2.0, 3.0]) {
            let got: f32 = row.iter().zip(&x).map(|(p, q)| p * q).sum();
            assert!((got - want).abs() < 1e-5);
        }
        assert!(solve3([[0.0; 3]; 3], [1.0; 3]).is_none());
    }

    #[test]
    fn a_refinement_stopped_at_the_window_resumes_to_the_same_answer() {
        // DoG layer 1 is a bowl peaking at row 18.4, column 20.2: from the candidate at row 15 the first step
        // moves three rows down, the second converges.
        let (w, h) = (40, 40);
        let dog = |l: usize, r: usize, c: usize| {
            let (dr, dc, dl) = (r as f32 - 18.4, c as f32 - 20.2, l as f32 - 1.0);
            100.0 - 2.0 * dr * dr - 2.0 * dc * dc - 8.0 * dl * dl
        };
        let mut g = vec![vec![0.0f32; w * h]; 4];
        for l in 0..3 {
            let (below, above) = g.split_at_mut(l + 1);
            for (i, (up, &down)) in above[0].iter_mut().zip(&below[l]).enumerate() {
                *up = down + dog(l, i / w, i % w);
            }
        }
        let p = SiftParams { n_octave_layers: 1, ..SiftParams::default() };
        let start = RefineState::start(Candidate { r: 15, c: 20, layer: 1 });
        let whole = DogView { gauss: &g, w, y0: 0, y1: h };
        let want = refine(whole, w, h, start, &p).expect("all rows held").expect("kept");
        assert_eq!((want.r, want.c, want.layer), (18, 20, 1));
        // Rows 13..17 only: the first step runs, the second needs rows 17..20.
        let window: Vec<Vec<f32>> = g.iter().map(|l| l[13 * w..17 * w].to_vec()).collect();
        let stopped = refine(DogView { gauss: &window, w, y0: 13, y1: 17 }, w, h, start, &p).unwrap_err();
        assert_eq!(stopped.rows(), 17..20);
        assert_eq!(refine(whole, w, h, stopped, &p), Ok(Some(want)));
    }

    #[test]
    fn isolated_peaks_are_candidates() {
        // Gaussian layers whose DoG layer 1 has a maximum at (8, 8) and a minimum at (20, 30).
        let (w, h) = (40, 32);
        let mut g = vec![vec![0.0f32; w * h]; 4];
        g[2][8 * w + 8] = 5.0;
        g[2][8 * w + 9] = 2.0;
        g[2][20 * w + 30] = -3.0;
        g[2][20 * w + 31] = -3.0; // equal neighbour: still an extremum (>= test), both found
        let mut out = Vec::new();
        let mut ring = DogRows::default();
        find_candidates(&g, 0, w, h, 1, 1.0, 5, 0..h, None, &mut ring, &mut out);
        let mut split = Vec::new();
        find_candidates(&g, 0, w, h, 1, 1.0, 5, 0..13, None, &mut ring, &mut split);
        find_candidates(&g, 0, w, h, 1, 1.0, 5, 13..h, None, &mut ring, &mut split);
        assert_eq!(out, split);
        out.sort_by_key(|c| (c.r, c.c));
        assert_eq!(
            out,
            vec![
                Candidate { r: 8, c: 8, layer: 1 },
                Candidate { r: 20, c: 30, layer: 1 },
                Candidate { r: 20, c: 31, layer: 1 }
            ]
        );
        out.clear();
        find_candidates(&g, 0, 10, 10, 1, 1.0, 5, 0..10, None, &mut ring, &mut out);
        assert!(out.is_empty());
    }
}
