//! Scale space: the initial (optionally doubled) image and the Gaussian octaves.
//!
//! One octave is held at a time; its buffers are sized for the first (largest) octave and reused (never
//! shrunk, so a reused `Sift` does not touch fresh memory). DoG images are not stored: a DoG value is the
//! difference of two Gaussian layers, formed where it is needed (see `extrema`).
//!
//! The wavefront build ([`Octave::build_scan`]) holds only a window of each layer's rows, sliding down the
//! octave: the doubled first octave of a 1200x950 map is 4.4 Mpx a layer, and touching memory for the first
//! time costs a VM about as much as blurring it (`benchmarks/runs/2026-12-03-sift-row-window.md`).

use crate::blur::{BlurScratch, Kernel, Sparse, blur, blur_band};
use crate::image::Plane;
use crate::mask::{BitMask, ChunkMask, Flat};
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
    /// The image `gauss[0]` is blurred from: the (doubled) input for the first octave, the previous octave's
    /// layer `n_layers` halved for the others.
    spare: Vec<f32>,
    /// The next octave's base, made while a windowed build runs (the layer it comes from is not kept).
    next: Vec<f32>,
    /// The image row the layer buffers start at (0 unless a windowed build slid down).
    pub y0: usize,
    /// Rows `y0 .. held` are final in every layer.
    held: usize,
    /// `next` holds the next octave's base (the last build was [`Octave::build_scan`]).
    next_made: bool,
    /// Scratch of the blur.
    scratch: BlurScratch,
    /// Scratch of the upscaling (two horizontally doubled rows).
    up_rows: Vec<f32>,
    /// The input rows `up_rows` holds (slot `y % 2`).
    up_held: [usize; 2],
    /// Doubling the input is left to [`Octave::build_scan`], row by row as the first layer needs them: `spare`
    /// then holds the doubled rows `spare_rows` only.
    lazy_up: bool,
    spare_rows: std::ops::Range<usize>,
    /// Skip the constant parts of the images (see `mask`); false computes every pixel (same result).
    pub sparse: bool,
    /// This octave uses the masks (`sparse` and its base is mostly constant).
    masked: bool,
    /// Per layer `i >= 1`: chunks where blurring `gauss[i - 1]` into `gauss[i]` must compute (layer 0: blurring
    /// `spare` into it).
    vert: Vec<ChunkMask>,
    out: Vec<ChunkMask>,
    /// Active pixels of the current layer while planning (and of `gauss[0]` after `init_base` / `next_base`).
    level: BitMask,
    /// Edge mask of the image this octave's layers are blurred from (the upscaled input for the first
    /// octave, `gauss[0]` for the others), with what it leaves out.
    base_edges: BitMask,
    base_flat: Flat,
    /// Blur from that image to `gauss[0]` (the initial blur for the first octave, identity for the others).
    base_kernel: Kernel,
    /// Scratch of the planning.
    tmp: BitMask,
    tmp2: BitMask,
    /// Chunks (scan grid) where the extremum scan must look; `None` scans everything.
    scan: Option<ChunkMask>,
    scan_spare: ChunkMask,
}

/// Above this fraction of edge pixels in an octave's base, tracking the constant parts costs more than
/// it saves (textured images): the octave is computed in full.
const MAX_EDGE_DENSITY: f64 = 0.3;

/// Grows `buf` to at least `n` values (never shrinks it).
fn ensure_len(buf: &mut Vec<f32>, n: usize) {
    if buf.len() < n {
        buf.resize(n, 0.0);
    }
}

/// Bound on `|blur(c) / c - 1|` over both passes of `kernel` applied to a constant `c` in f32 arithmetic
/// (weights >= 0: each pass is `S c (1 + t)` with `S` the weights' exact sum and `|t| <= gamma(r + 1)`).
fn constant_drift(kernel: &Kernel) -> f64 {
    let r = kernel.radius() as f64;
    let sum: f64 = f64::from(kernel.half[0]) + 2.0 * kernel.half[1..].iter().map(|&v| f64::from(v)).sum::<f64>();
    let u = f64::powi(2.0, -24);
    let gamma = (r + 1.0) * u / (1.0 - (r + 1.0) * u);
    let hi = (sum * (1.0 + gamma)).powi(2);
    let lo = (sum * (1.0 - gamma)).powi(2);
    (hi - 1.0).max(1.0 - lo) + 1e-12
}

/// `gamma(n) = n u / (1 - n u)`, the relative error bound of `n` rounded f32 operations.
fn gamma(n: f64) -> f64 {
    let u = f64::powi(2.0, -24);
    n * u / (1.0 - n * u)
}

/// The smallest `d >= 1` such that every DoG value of layers `1..=n_layers` at a pixel whose Chebyshev
/// distance to the nearest edge pixel of the base image is `>= d` has magnitude `<= threshold`, as
/// computed in f32; `None` when no distance guarantees it.
///
/// Why: with `K_l` the 2-D kernel taking the base `U` to layer `l` (the composition of the blurs, exact
/// arithmetic, f32 weights), `D_l = (K_{l+1} - K_l) * U`. Within distance `d - 1` of such a pixel `p`
/// the base is one constant `c = U(p)` (adjacent non-edge pixels are equal; reflect-101 borders mirror
/// pixels of that same square), so `D_l(p) = c sum(K_{l+1} - K_l) + sum_{|q|_inf >= d} (K_{l+1} -
/// K_l)(q) (U(p - q) - c)`, at most `M |S_{l+1} - S_l| + X T(d)` in magnitude, where `M` bounds `|U|`,
/// `X` (`spread`) bounds `|U(q) - U(p)|`, `S` is a kernel's sum and `T(d)` the mass of `|K_{l+1} - K_l|`
/// outside the square of radius `d - 1`. The f32 results differ from the exact ones by at most
/// `err_l + err_{l+1}`.
pub fn dog_reach(
    base: &Kernel,
    kernels: &[Kernel],
    n_layers: usize,
    max_abs: f64,
    spread: f64,
    threshold: f32,
) -> Option<usize> {
    let full = |k: &Kernel| -> Vec<f64> {
        let r = k.radius();
        (0..2 * r + 1).map(|i| f64::from(k.half[i.abs_diff(r)])).collect()
    };
    let conv = |a: &[f64], b: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; a.len() + b.len() - 1];
        for (i, &x) in a.iter().enumerate() {
            for (j, &y) in b.iter().enumerate() {
                out[i + j] += x * y;
            }
        }
        out
    };
    // Per layer: the 1-D composite kernel, the f32 error bound and the magnitude bound.
    let sum = |k: &Kernel| f64::from(k.half[0]) + 2.0 * k.half[1..].iter().map(|&v| f64::from(v)).sum::<f64>();
    let step = |k: &Kernel, err: f64, m: f64| {
        let (s, g) = (sum(k), gamma(k.radius() as f64 + 3.0));
        if k.radius() == 0 && k.half[0] == 1.0 {
            return (err, m); // identity: no arithmetic
        }
        (s * s * (1.0 + g) * (1.0 + g) * err + 2.5 * g * s * s * m, s * s * (1.0 + g) * (1.0 + g) * m)
    };
    let mut comp = vec![full(base)];
    let (mut err, mut m) = step(base, 0.0, max_abs);
    let mut errs = vec![err];
    for k in &kernels[1..=n_layers + 1] {
        let next = conv(comp.last().expect("base layer"), &full(k));
        comp.push(next);
        (err, m) = step(k, err, m);
        errs.push(err);
    }
    // T(d) = sum of |K_{l+1} - K_l| over the 2-D offsets q with |q|_inf >= d, from the separable
    // composites (K(x, y) = k(x) k(y)), bucketed by Chebyshev radius; f64 rounding is covered by a slack.
    let tails = |a: &[f64], b: &[f64]| -> Vec<f64> {
        let (ra, rb) = (a.len() / 2, b.len() / 2);
        let r = ra.max(rb);
        let at = |k: &[f64], rk: usize, x: usize| if x + rk >= r && x < r + rk + 1 { k[x + rk - r] } else { 0.0 };
        let mut bucket = vec![0.0f64; r + 2];
        for y in 0..=2 * r {
            for x in 0..=2 * r {
                let d = (at(b, rb, x) * at(b, rb, y) - at(a, ra, x) * at(a, ra, y)).abs();
                bucket[x.abs_diff(r).max(y.abs_diff(r))] += d;
            }
        }
        // Suffix sums: tail[d] = mass at radius >= d.
        for d in (0..=r).rev() {
            bucket[d] += bucket[d + 1];
        }
        bucket
    };
    let max_r = comp.iter().map(|k| k.len() / 2).max().unwrap_or(0);
    let thr = f64::from(threshold);
    let mut reach = 1;
    for l in 1..=n_layers {
        let (a, b) = (&comp[l], &comp[l + 1]);
        let (sa, sb): (f64, f64) = (a.iter().sum(), b.iter().sum());
        let fixed = max_abs * (sb * sb - sa * sa).abs() + errs[l] + errs[l + 1];
        let tail = tails(a, b);
        let ok = |d: usize| {
            let t = tail.get(d).copied().unwrap_or(0.0) + 1e-10;
            let bound = fixed + spread * t;
            bound * (1.0 + 1e-9) + 1e-30 < thr
        };
        let d = (1..=max_r + 1).find(|&d| ok(d))?;
        reach = reach.max(d);
    }
    Some(reach)
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
        self.vert.resize_with(n + 3, ChunkMask::default);
        self.out.resize_with(n + 3, ChunkMask::default);
    }

    /// Prepares the first octave's base from the input (doubling it if asked): the image `gauss[0]` is blurred
    /// from and the blur from the assumed `init_sigma` to `sigma`. Unless `windowed` (then
    /// [`Octave::build_scan`] makes it row by row), `gauss[0]` is blurred here.
    pub fn init_base(&mut self, data: &[f32], w: usize, h: usize, params: &SiftParams, windowed: bool) {
        let (sigma, init) = (params.sigma, params.init_sigma);
        // A windowed build doubles the rows as it needs them (unless the edge mask must be taken from the
        // doubled image itself, below).
        self.lazy_up = windowed && params.upscale && (2 * w).max(2 * h) <= 1 << 22;
        (self.spare_rows, self.up_held) = (0..0, [usize::MAX; 2]);
        let (bw, bh, sig_diff) = if params.upscale {
            if !self.lazy_up {
                upscale2x(data, w, h, &mut self.spare, &mut self.up_rows);
            }
            (2 * w, 2 * h, (sigma * sigma - init * init * 4.0).max(0.01).sqrt())
        } else {
            ensure_len(&mut self.spare, w * h);
            self.spare[..w * h].copy_from_slice(data);
            (w, h, (sigma * sigma - init * init).max(0.01).sqrt())
        };
        self.w = bw;
        self.h = bh;
        let kernel = Kernel::gaussian(f64::from(sig_diff));
        self.masked = false;
        if self.sparse {
            // Upscaled pixels only repeat constants where the input does: derive their edge mask from the
            // input's (4x fewer pixels to look at) while f32 holds the interpolation fractions exactly.
            self.base_flat = if params.upscale && bw.max(bh) <= 1 << 22 {
                let flat = self.tmp.edges_of(data, w, h);
                self.base_edges.upscaled_edges(&self.tmp, !border_interpolates_exactly(data, w, h));
                Flat { max_abs: flat.max_abs * (1.0 + 1e-6), ..flat }
            } else {
                self.base_edges.edges_of(&self.spare[..bw * bh], bw, bh)
            };
            self.masked = self.base_flat.density <= MAX_EDGE_DENSITY;
        }
        if self.masked {
            self.level.copy_from(&self.base_edges);
            grow(&mut self.tmp, &mut self.level, kernel.radius(), &mut self.vert[0], &mut self.out[0]);
        }
        self.base_kernel = kernel;
        if !windowed {
            self.base_whole(params.parallel);
        }
    }

    /// Makes `gauss[0]` whole from `spare`, the layer buffers holding the whole octave.
    fn base_whole(&mut self, parallel: bool) {
        let n = self.w * self.h;
        self.y0 = 0;
        ensure_len(&mut self.gauss[0], n);
        if self.base_kernel.radius() == 0 {
            self.gauss[0][..n].copy_from_slice(&self.spare[..n]);
        } else {
            let sp = self.masked.then(|| Sparse { vert: &self.vert[0], out: &self.out[0] });
            let src = Plane::new(&self.spare, self.w, self.h);
            blur(src, &mut self.gauss[0], &self.base_kernel, &mut self.scratch, parallel, sp);
        }
    }

    /// Makes the next octave's base: `gauss[n_layers]` of this octave, every second pixel (OpenCV
    /// `INTER_NEAREST` resize to half size; a windowed build made it already). Unless `windowed`, `gauss[0]` is
    /// made here. Returns false when the image would become empty.
    pub fn next_base(&mut self, n_layers: usize, windowed: bool) -> bool {
        let (w, h) = (self.w / 2, self.h / 2);
        if w == 0 || h == 0 {
            return false;
        }
        self.lazy_up = false;
        if self.next_made {
            // The wavefront halved the layer as it went (a window of it is all that is left).
            std::mem::swap(&mut self.spare, &mut self.next);
        } else {
            downsample_nearest(&self.gauss[n_layers], self.w, self.h, w, h, &mut self.spare);
        }
        self.w = w;
        self.h = h;
        self.masked = false;
        if self.sparse {
            self.base_flat = self.base_edges.edges_of(&self.spare[..w * h], w, h);
            self.masked = self.base_flat.density <= MAX_EDGE_DENSITY;
            self.level.copy_from(&self.base_edges);
        }
        self.base_kernel = Kernel { half: vec![1.0] };
        if !windowed {
            self.base_whole(false);
        }
        true
    }

    /// Plans the octave (after `init_base` or `next_base`): which chunks each layer's blur must compute
    /// and which chunks the extremum scan must look at (scan grid from column `border`): only where a DoG
    /// value of a tested layer may exceed `threshold` (see [`dog_reach`]).
    pub fn plan(&mut self, threshold: f32, border: usize) {
        if let Some(m) = self.scan.take() {
            self.scan_spare = m;
        }
        if !self.masked {
            return;
        }
        let n_layers = self.gauss.len() - 3;
        // Constant pixels drift by a few ulps per blur: |D| <= drift_{l+1} * max|G_l| there.
        let mut flat = f64::from(self.base_flat.max_abs) * (1.0 + constant_drift(&self.base_kernel));
        let mut worst = 0.0f64;
        let mut constant_ok = false;
        for i in 1..self.gauss.len() {
            let drift = constant_drift(&self.kernels[i]);
            grow(&mut self.tmp, &mut self.level, self.kernels[i].radius(), &mut self.vert[i], &mut self.out[i]);
            if (2..=n_layers + 1).contains(&i) {
                worst = worst.max(drift * flat);
            }
            flat *= 1.0 + drift;
            if i == n_layers + 1 {
                constant_ok = worst * (1.0 + 1e-6) + 1e-30 < f64::from(threshold);
                if constant_ok {
                    // Pixels outside this mask are constant in every DoG layer the scan tests.
                    self.tmp2.copy_from(&self.level);
                }
            }
        }
        let reach = if self.base_flat.all_flat_ok {
            let m = f64::from(self.base_flat.max_abs);
            let spread = if self.base_flat.non_negative { m } else { 2.0 * m };
            dog_reach(&self.base_kernel, &self.kernels, n_layers, m, spread, threshold)
        } else {
            None
        };
        if let Some(d) = reach {
            // Pixels farther than `d - 1` from every edge of the base cannot pass the threshold.
            self.level.dilate_square(&self.base_edges, d - 1, &mut self.tmp);
            if constant_ok {
                self.level.and_with(&self.tmp2);
            }
        } else if constant_ok {
            std::mem::swap(&mut self.level, &mut self.tmp2);
        } else {
            return;
        }
        let mut m = std::mem::take(&mut self.scan_spare);
        m.build(&self.level, border, self.w.saturating_sub(border));
        self.scan = Some(m);
    }

    /// The scan mask of the planned octave (`None`: scan everything).
    pub fn scan_mask(&self) -> Option<&ChunkMask> {
        self.scan.as_ref()
    }

    /// Blurs `gauss[0]` into the remaining layers, whole.
    pub fn build(&mut self, parallel: bool) {
        let n = self.w * self.h;
        for i in 1..self.gauss.len() {
            let (done, rest) = self.gauss.split_at_mut(i);
            let dst = &mut rest[0];
            ensure_len(dst, n);
            let sp = self.masked.then(|| Sparse { vert: &self.vert[i], out: &self.out[i] });
            blur(Plane::new(&done[i - 1], self.w, self.h), dst, &self.kernels[i], &mut self.scratch, parallel, sp);
        }
        (self.y0, self.held, self.next_made) = (0, self.h, false);
    }

    /// Makes the layers as a wavefront of row bands, so each layer's rows are read back (by the next layer's
    /// blur and by `step`) while still in cache, holding at most about `window` rows of each layer (all of
    /// them when the octave is shorter): the window slides down the octave. `step(octave, r0, r1)` is called
    /// with consecutive row ranges `0..r1` whose rows up to `r1` (inclusive) are final in every layer, and
    /// returns the lowest row it will still read; [`Octave::held`] says which rows it may read now. Also
    /// makes the next octave's base. `input` is the image given to [`Octave::init_base`] (the first octave
    /// doubles its rows here). Same values as [`Octave::build`], bit for bit.
    pub fn build_scan(
        &mut self,
        window: usize,
        n_layers: usize,
        input: &[f32],
        mut step: impl FnMut(&Octave, usize, usize) -> usize,
    ) {
        const BAND: usize = 16;
        let (w, h) = (self.w, self.h);
        let layers = self.gauss.len();
        if w == 0 || h == 0 {
            return;
        }
        let radii: Vec<usize> =
            (0..layers).map(|i| if i == 0 { self.base_kernel.radius() } else { self.kernels[i].radius() }).collect();
        let mut cap = window.clamp(BAND, h.max(BAND)).min(h);
        for g in &mut self.gauss {
            ensure_len(g, cap * w);
        }
        (self.y0, self.held, self.next_made) = (0, 0, true);
        let (nw, nh) = (w / 2, h / 2);
        let (xs, ys) = (nearest_indices(w, nw), nearest_indices(h, nh));
        ensure_len(&mut self.next, nw * nh);
        let mut next_done = 0;
        let mut avail = vec![0usize; layers];
        let (mut scanned, mut keep) = (0usize, 0usize);
        loop {
            for i in 0..layers {
                let src_avail = if i == 0 { h } else { avail[i - 1] };
                let ready = if src_avail >= h { h } else { src_avail.saturating_sub(radii[i]) };
                let target = ready.min(avail[i] + BAND);
                if target <= avail[i] {
                    continue;
                }
                if target > self.y0 + cap {
                    // Slide: drop the rows nobody reads any more (the step, the blurs of the next layers, the
                    // next octave's base), then grow the window if that was not enough.
                    let mut from = keep.min(scanned.saturating_sub(1));
                    if let Some(&y) = ys.get(next_done) {
                        from = from.min(y);
                    }
                    for j in 1..layers {
                        from = from.min(avail[j].saturating_sub(radii[j]));
                    }
                    if from > self.y0 {
                        let shift = (from - self.y0) * w;
                        for (g, &a) in self.gauss.iter_mut().zip(&avail) {
                            g.copy_within(shift..(a - self.y0) * w, 0);
                        }
                        self.y0 = from;
                    }
                    if target > self.y0 + cap {
                        cap = (2 * cap).max(target - self.y0).min(h);
                        for g in &mut self.gauss {
                            ensure_len(g, cap * w);
                        }
                    }
                }
                if i == 0 {
                    self.base_rows(avail[0], target, input);
                } else {
                    let (done, rest) = self.gauss.split_at_mut(i);
                    let sp = self.masked.then(|| Sparse { vert: &self.vert[i], out: &self.out[i] });
                    let src = Plane::window(&done[i - 1], w, h, self.y0);
                    let (k, sc) = (&self.kernels[i], &mut self.scratch);
                    blur_band(src, &mut rest[0], self.y0, avail[i], target, k, sc, sp);
                }
                avail[i] = target;
            }
            while let Some(&sy) = ys.get(next_done) {
                if sy >= avail[n_layers] {
                    break;
                }
                let row = &self.gauss[n_layers][(sy - self.y0) * w..(sy - self.y0 + 1) * w];
                for (o, &sx) in self.next[next_done * nw..(next_done + 1) * nw].iter_mut().zip(&xs) {
                    *o = row[sx];
                }
                next_done += 1;
            }
            let all = avail.iter().copied().min().unwrap_or(h);
            self.held = all;
            // Rows whose neighbours (one row below) are final in every layer.
            let upto = if all >= h { h } else { all.saturating_sub(1) };
            if upto > scanned {
                keep = step(self, scanned, upto);
                scanned = upto;
            }
            if all >= h {
                break;
            }
        }
    }

    /// Rows `y0 .. y1` of `gauss[0]` (window from `self.y0`), from `spare`.
    fn base_rows(&mut self, y0: usize, y1: usize, input: &[f32]) {
        let (w, h, o) = (self.w, self.h, self.y0);
        if self.base_kernel.radius() == 0 {
            self.gauss[0][(y0 - o) * w..(y1 - o) * w].copy_from_slice(&self.spare[y0 * w..y1 * w]);
            return;
        }
        let sp = self.masked.then(|| Sparse { vert: &self.vert[0], out: &self.out[0] });
        let src = if self.lazy_up {
            // The doubled rows the kernel reads (reflected rows at the top are among the first `r`).
            let r = self.base_kernel.radius();
            let (lo, hi) = (y0.saturating_sub(r), (y1 + r).min(h));
            let held = &mut self.spare_rows;
            if held.start < lo && lo < held.end {
                self.spare.copy_within((lo - held.start) * w..(held.end - held.start) * w, 0);
                *held = lo..held.end;
            } else if !(held.start <= lo && lo < held.end) {
                *held = lo..lo;
            }
            ensure_len(&mut self.spare, (hi - held.start) * w);
            for dy in held.end..hi {
                let out = &mut self.spare[(dy - held.start) * w..(dy - held.start + 1) * w];
                upscale_row(input, w / 2, h / 2, dy, out, &mut self.up_rows, &mut self.up_held);
            }
            held.end = held.end.max(hi);
            Plane::window(&self.spare, w, h, held.start)
        } else {
            Plane::new(&self.spare[..w * h], w, h)
        };
        blur_band(src, &mut self.gauss[0], o, y0, y1, &self.base_kernel, &mut self.scratch, sp);
    }

    /// The rows final in every layer, held from the start of the layer buffers at row [`Octave::y0`].
    pub fn held(&self) -> std::ops::Range<usize> {
        self.y0..self.held
    }

    /// Gaussian layer `i` of this octave: the rows [`Octave::held`] from its start.
    pub fn layer(&self, i: usize) -> &[f32] {
        &self.gauss[i][..(self.held - self.y0) * self.w]
    }

    /// Gaussian layer `i` as a view of the rows [`Octave::held`].
    pub fn plane(&self, i: usize) -> Plane<'_> {
        Plane::window(self.layer(i), self.w, self.h, self.y0)
    }
}

/// True when every border pixel `c` of the image satisfies `0.75 c + 0.25 c == c` in f32 (as the
/// upscaling computes it), so the copied outer rows and columns of the upscaled image equal their
/// interpolated neighbours where the image is constant.
fn border_interpolates_exactly(data: &[f32], w: usize, h: usize) -> bool {
    let ok = |c: f32| (c * 0.75 + c * 0.25).to_bits() == c.to_bits();
    let rows = data[..w].iter().chain(&data[(h - 1) * w..h * w]);
    let cols = (0..h).flat_map(|y| [data[y * w], data[y * w + w - 1]]);
    rows.copied().chain(cols).all(ok)
}

/// One blur step of the activity masks: `level` (active pixels of the input) becomes the active pixels
/// of the output of a kernel of radius `r`; `vert` / `out` receive the chunks the blur must compute.
fn grow(tmp: &mut BitMask, level: &mut BitMask, r: usize, vert: &mut ChunkMask, out: &mut ChunkMask) {
    tmp.dilate_vertical(level, r);
    vert.build(tmp, 0, tmp.w);
    level.dilate_horizontal(tmp, r);
    out.build(level, 0, level.w);
}

/// OpenCV `resize(.., 2x size, INTER_LINEAR)`: half-pixel-centre bilinear doubling, horizontal pass first.
/// `dst` (grown if needed) receives the `2w x 2h` image in its first values; `rows` is scratch (two doubled
/// source rows).
pub fn upscale2x(src: &[f32], w: usize, h: usize, dst: &mut Vec<f32>, rows: &mut Vec<f32>) {
    let (dw, dh) = (2 * w, 2 * h);
    ensure_len(dst, dw * dh);
    let mut held = [usize::MAX; 2];
    for dy in 0..dh {
        upscale_row(src, w, h, dy, &mut dst[dy * dw..(dy + 1) * dw], rows, &mut held);
    }
}

/// Row `dy` of the doubled `w x h` image `src` (see [`upscale2x`]) into `out`. `rows` holds the doubled
/// source rows `held` says (slot `y % 2`); start with `[usize::MAX; 2]`.
fn upscale_row(
    src: &[f32],
    w: usize,
    h: usize,
    dy: usize,
    out: &mut [f32],
    rows: &mut Vec<f32>,
    held: &mut [usize; 2],
) {
    let dw = 2 * w;
    if w == 0 || h == 0 {
        return;
    }
    ensure_len(rows, 2 * dw);
    let (sy, fy) = src_coord(dy, h);
    let last = if fy == 0.0 { sy } else { sy + 1 };
    for y in sy..=last {
        if held[y % 2] != y {
            hdouble(&src[y * w..y * w + w], &mut rows[(y % 2) * dw..(y % 2 + 1) * dw]);
            held[y % 2] = y;
        }
    }
    let r0 = &rows[(sy % 2) * dw..(sy % 2 + 1) * dw];
    if fy == 0.0 {
        out.copy_from_slice(r0);
    } else {
        let r1 = &rows[((sy + 1) % 2) * dw..((sy + 1) % 2 + 1) * dw];
        let (b0, b1) = (1.0 - fy, fy);
        for ((o, &a), &b) in out.iter_mut().zip(r0).zip(r1) {
            *o = a * b0 + b * b1;
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
    let xs = nearest_indices(w, dw);
    for (y, sy) in nearest_indices(h, dh).into_iter().enumerate() {
        let s = &src[sy * w..sy * w + w];
        for (o, &sx) in dst[y * dw..y * dw + dw].iter_mut().zip(&xs) {
            *o = s[sx];
        }
    }
}

/// Source index of each of `dn` samples resizing a line of `n` with `INTER_NEAREST`.
fn nearest_indices(n: usize, dn: usize) -> Vec<usize> {
    let inv = 1.0 / (dn as f64 / n as f64);
    (0..dn).map(|d| ((d as f64 * inv).floor() as usize).min(n.saturating_sub(1))).collect()
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
        o.init_base(&vec![10.0; 64], 8, 8, &p, false);
        o.plan(1.0, 5);
        o.build(false);
        assert_eq!((o.w, o.h, o.gauss.len()), (16, 16, 6));
        assert!((0..6).all(|i| o.layer(i).iter().all(|v| (v - 10.0).abs() < 1e-3)));
        assert!(o.next_base(3, false));
        assert_eq!((o.w, o.h), (8, 8));
    }
}
