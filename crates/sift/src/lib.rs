//! SIFT keypoints and descriptors on grey f32 images, faithful to Lowe (2004) and OpenCV 4.x
//! (`features2d/src/sift.simd.hpp`, float path).
//!
//! Grey image in (values 0..255 like an 8-bit image), keypoints (OpenCV conventions: pixel centres at
//! integer coordinates, angle in degrees, packed octave) and 128-byte descriptors out. This crate knows
//! nothing of maps.
//!
//! ```
//! use mrslam_sift::{GrayImage, SiftParams, detect_and_compute};
//! let img = GrayImage::new(64, 64, vec![128.0; 64 * 64]).unwrap();
//! let f = detect_and_compute(&img, &SiftParams::default());
//! assert_eq!(f.len(), 0); // a flat image has no keypoint
//! ```

#![deny(missing_docs)]

mod blur;
mod descriptor;
mod dispatch;
mod error;
mod extrema;
mod fastmath;
mod image;
mod keypoint;
mod mask;
mod orientation;
mod params;
mod pyramid;
#[cfg(test)]
mod sparse_tests;
#[cfg(test)]
mod synth;
#[cfg(test)]
mod window_tests;

pub use error::SiftError;
pub use image::GrayImage;
pub use keypoint::{DESCRIPTOR_LEN, Features, Keypoint};
pub use params::SiftParams;

use descriptor::DescScratch;
use extrema::{Candidate, DogRows, DogView, RefineState, Refined, find_candidates, refine};
use orientation::{ORI_HIST_BINS, ORI_RADIUS, ORI_SIG_FCTR, OriScratch, orientation_hist, peak_angles};
use pyramid::Octave;
use rayon::prelude::*;
use std::cmp::Ordering;

/// Largest supported `n_octave_layers` (the layer is packed into 8 bits of `Keypoint::octave`).
pub const MAX_OCTAVE_LAYERS: usize = 250;

/// Detects keypoints and computes their descriptors (one-shot form of [`Sift::detect_and_compute`]).
pub fn detect_and_compute(img: &GrayImage, params: &SiftParams) -> Features {
    Sift::new(params.clone()).detect_and_compute(img)
}

/// A SIFT detector holding its scratch buffers, to be reused across images.
#[derive(Debug)]
pub struct Sift {
    params: SiftParams,
    octave: Octave,
    candidates: Vec<Candidate>,
    dog_rows: DogRows,
    ori: OriScratch,
    desc: DescScratch,
    /// Tests only: the windowed octave's margin and rows instead of the ones the parameters give.
    window: Option<(usize, usize)>,
}

/// A keypoint with its descriptor, before deduplication.
type Found = (Keypoint, [u8; DESCRIPTOR_LEN]);

impl Sift {
    /// A detector with these parameters.
    pub fn new(params: SiftParams) -> Self {
        Self::with_sparse(params, true)
    }

    /// A detector that skips the constant parts of the images (`sparse`) or computes every pixel; the
    /// output is the same either way, bit for bit (the dense form is kept as the reference for tests).
    fn with_sparse(params: SiftParams, sparse: bool) -> Self {
        let mut octave = Octave::default();
        octave.sparse = sparse;
        Self {
            params,
            octave,
            candidates: Vec::new(),
            dog_rows: DogRows::default(),
            ori: OriScratch::default(),
            desc: DescScratch::default(),
            window: None,
        }
    }

    /// The parameters in use.
    pub fn params(&self) -> &SiftParams {
        &self.params
    }

    /// Detects keypoints and computes descriptors. Never panics: empty or tiny images and unusable
    /// parameters (no layer, non-positive or non-finite sigma) give no keypoints.
    ///
    /// Output order is OpenCV's after `removeDuplicatedSorted` (x, then y ascending, larger size first,
    /// ...); with `max_features` the strongest responses are kept, strongest first (ties keep that order).
    pub fn detect_and_compute(&mut self, img: &GrayImage) -> Features {
        let p = self.params.clone();
        let (w, h) = (img.width, img.height);
        if w == 0 || h == 0 || img.data.len() != w * h || !params_usable(&p) {
            return Features::default();
        }
        let first_octave: i32 = if p.upscale { -1 } else { 0 };
        let (bw, bh) = if p.upscale { (2 * w, 2 * h) } else { (w, h) };
        let n_octaves = match p.n_octaves {
            Some(n) => n as i64,
            None => (((bw.min(bh) as f64).ln() / 2f64.ln()) - 2.0).round_ties_even() as i64 - i64::from(first_octave),
        };
        if n_octaves <= 0 {
            return Features::default();
        }
        let threshold = p.pre_threshold();
        let windowed = !p.parallel;
        self.octave.prepare(&p);
        self.octave.init_base(&img.data, w, h, &p, windowed);
        let mut found: Vec<Found> = Vec::new();
        for o in 0..n_octaves as usize {
            if o > 0 && !self.octave.next_base(p.n_octave_layers, windowed) {
                break;
            }
            if o >= 31 {
                break;
            }
            self.octave.plan(threshold, p.border);
            self.candidates.clear();
            if p.parallel {
                self.octave_whole(o, threshold, &mut found);
            } else {
                let (ow, oh) = (self.octave.w, self.octave.h);
                let window = self.window.unwrap_or_else(|| {
                    let m = window_margin(&p, ow, oh);
                    (m, window_rows(m))
                });
                self.octave_windowed(&img.data, o, threshold, window, &mut found);
            }
        }
        // Back to input-image coordinates (OpenCV: firstOctave = -1 halves positions and sizes).
        if first_octave < 0 {
            for (kp, _) in &mut found {
                kp.octave = (kp.octave & !255) | ((kp.octave + first_octave) & 255);
                kp.x *= 0.5;
                kp.y *= 0.5;
                kp.size *= 0.5;
            }
        }
        // OpenCV KeyPointsFilter::removeDuplicatedSorted. Sorted as (keypoint, index) pairs (stable, so
        // the same order as sorting the descriptors along), descriptors gathered at the end.
        let mut order: Vec<(Keypoint, usize)> = found.iter().enumerate().map(|(i, f)| (f.0, i)).collect();
        order.sort_by(|a, b| keypoint_order(&a.0, &b.0));
        order.dedup_by(|b, a| a.0.x == b.0.x && a.0.y == b.0.y && a.0.size == b.0.size && a.0.angle == b.0.angle);
        if let Some(max) = p.max_features
            && order.len() > max
        {
            order.sort_by(|a, b| b.0.response.total_cmp(&a.0.response));
            order.truncate(max);
        }
        let mut out = Features {
            keypoints: Vec::with_capacity(order.len()),
            descriptors: Vec::with_capacity(order.len() * DESCRIPTOR_LEN),
        };
        for (kp, i) in order {
            out.keypoints.push(kp);
            out.descriptors.extend_from_slice(&found[i].1);
        }
        out
    }
    /// The keypoints of octave `o`, its layers built whole (blurs and keypoints on the rayon pool).
    fn octave_whole(&mut self, o: usize, threshold: f32, found: &mut Vec<Found>) {
        let p = &self.params;
        let (ow, oh, n_layers) = (self.octave.w, self.octave.h, p.n_octave_layers);
        self.octave.build(true);
        let oct = &self.octave;
        let (ring, cands) = (&mut self.dog_rows, &mut self.candidates);
        find_candidates(&oct.gauss, 0, ow, oh, n_layers, threshold, p.border, 0..oh, oct.scan_mask(), ring, cands);
        let per: Vec<Vec<Found>> = cands
            .par_iter()
            .map_init(
                || (OriScratch::default(), DescScratch::default(), Vec::new()),
                |(ori, desc, angles), &cand| {
                    let mut v = Vec::new();
                    // A whole octave holds every row: no job waits.
                    let _ = process_candidate(oct, o, Job::start(cand), p, ori, desc, angles, &mut v);
                    v
                },
            )
            .collect();
        found.extend(per.into_iter().flatten());
    }

    /// The keypoints of octave `o` on one thread, its layers built as a wavefront through a window of `rows`
    /// rows (`input`: the image, whose rows the first octave doubles as it goes).
    ///
    /// Candidates are refined and described as soon as the rows `margin` below them are final, so the layers
    /// need hold only a window of rows. A refinement that steps to rows the window no longer (or does not yet)
    /// hold waits, and is resumed in another pass down the octave (rare: a step far across a flat region);
    /// keypoints keep their candidate's place in the order.
    fn octave_windowed(
        &mut self,
        input: &[f32],
        o: usize,
        threshold: f32,
        (margin, rows): (usize, usize),
        found: &mut Vec<Found>,
    ) {
        let p = &self.params;
        let (ow, oh, n_layers) = (self.octave.w, self.octave.h, p.n_octave_layers);
        let (cands, ring, ori, desc) = (&mut self.candidates, &mut self.dog_rows, &mut self.ori, &mut self.desc);
        let (mut next, mut angles, mut waiting) = (0, Vec::new(), Vec::new());
        let mut tagged: Vec<(usize, Found)> = Vec::new();
        let mut out = Vec::new();
        self.octave.build_scan(rows, n_layers, input, |oct, r0, r1| {
            let mask = oct.scan_mask();
            find_candidates(&oct.gauss, oct.y0, ow, oh, n_layers, threshold, p.border, r0..r1, mask, ring, cands);
            let last = r1 >= oh;
            while let Some(&cand) = cands.get(next) {
                if !last && cand.r + margin > r1 {
                    break;
                }
                match process_candidate(oct, o, Job::start(cand), p, ori, desc, &mut angles, &mut out) {
                    Ok(()) => tagged.extend(out.drain(..).map(|f| (next, f))),
                    Err(job) => waiting.push((next, Some(job))),
                }
                next += 1;
            }
            cands.get(next).map_or(r1, |c| c.r.min(r1)).saturating_sub(margin)
        });
        let resumed = !waiting.is_empty();
        while !waiting.is_empty() {
            // Another pass: each waiting job runs while the rows it reads are held; a job wanting rows above the
            // window waits for the next pass. Every pass moves every job on (the window keeps the rows a job
            // waits for), and a job takes at most `max_interp_steps` + 2 moves.
            let mut moved = false;
            self.octave.build_scan(rows, n_layers, input, |oct, _, _| {
                let held = oct.held();
                let mut keep = usize::MAX;
                for (i, job) in &mut waiting {
                    while let Some(j) = *job {
                        let need = j.rows(p, ow, oh);
                        if need.start < held.start {
                            break; // the next pass
                        }
                        if need.end > held.end {
                            keep = keep.min(need.start);
                            break;
                        }
                        moved = true;
                        match process_candidate(oct, o, j, p, ori, desc, &mut angles, &mut out) {
                            Ok(()) => {
                                tagged.extend(out.drain(..).map(|f| (*i, f)));
                                *job = None;
                            }
                            Err(left) => *job = Some(left),
                        }
                    }
                }
                keep.min(held.end)
            });
            assert!(moved, "a pass down the octave moves every waiting job on");
            waiting.retain(|(_, job)| job.is_some());
        }
        if resumed {
            tagged.sort_by_key(|t| t.0);
        }
        found.extend(tagged.into_iter().map(|t| t.1));
    }
}

fn params_usable(p: &SiftParams) -> bool {
    let pos = |v: f32| v.is_finite() && v > 0.0;
    (1..=MAX_OCTAVE_LAYERS).contains(&p.n_octave_layers)
        && pos(p.sigma)
        && p.init_sigma.is_finite()
        && p.init_sigma >= 0.0
        && p.contrast_threshold.is_finite()
        && p.edge_threshold.is_finite()
        && p.border >= 1
}

/// OpenCV `KeyPoint_LessThan`: x, y ascending, size descending, angle ascending, response descending,
/// octave descending.
fn keypoint_order(a: &Keypoint, b: &Keypoint) -> Ordering {
    a.x.total_cmp(&b.x)
        .then(a.y.total_cmp(&b.y))
        .then(b.size.total_cmp(&a.size))
        .then(a.angle.total_cmp(&b.angle))
        .then(b.response.total_cmp(&a.response))
        .then(b.octave.cmp(&a.octave))
}

/// Rows a windowed `w` x `h` octave keeps around a candidate: those its orientation histogram and descriptor
/// read at the largest scale a keypoint can have, and a few for its refinement's steps of a pixel or so.
fn window_margin(p: &SiftParams, w: usize, h: usize) -> usize {
    let largest = p.sigma * 2f32.powf((p.n_octave_layers as f32 + 0.5) / p.n_octave_layers as f32);
    describe_reach(largest, w, h) + 8
}

/// Rows of a layer a windowed octave holds: three times what the wavefront keeps at once (the candidates'
/// margin on both sides and the blurs' lag), so a slide moves each row about half a time.
fn window_rows(margin: usize) -> usize {
    margin.saturating_mul(6).saturating_add(256)
}

/// The work left on a candidate of a windowed octave.
#[derive(Debug, Clone, Copy)]
enum Job {
    /// Refining it, from this state.
    Refine(RefineState),
    /// Its orientations and descriptors, refined.
    Describe(Refined),
}

impl Job {
    fn start(cand: Candidate) -> Self {
        Job::Refine(RefineState::start(cand))
    }

    /// The rows the job's next move reads.
    fn rows(&self, p: &SiftParams, w: usize, h: usize) -> std::ops::Range<usize> {
        match self {
            Job::Refine(st) => st.rows(),
            Job::Describe(rf) => {
                let reach = describe_reach(octave_scale(rf, p), w, h);
                rf.r.saturating_sub(reach)..(rf.r + reach + 1).min(h)
            }
        }
    }
}

/// Scale of a refined keypoint in its octave's pixels.
fn octave_scale(rf: &Refined, p: &SiftParams) -> f32 {
    p.sigma * 2f32.powf((rf.layer as f32 + rf.xi) / p.n_octave_layers as f32)
}

/// Rows on each side of a keypoint at scale `scl` of a `w` x `h` octave its orientation histogram and
/// descriptor read.
fn describe_reach(scl: f32, w: usize, h: usize) -> usize {
    let ori_radius = (ORI_RADIUS * scl).round_ties_even().max(0.0) as usize;
    ori_radius.max(descriptor::radius(scl, w, h)) + 1
}

/// Refines one candidate, assigns its orientations and computes one descriptor per orientation, from `job`
/// on; `Err` with the job left when its next move reads rows the octave does not hold
/// (a windowed octave).
#[allow(clippy::too_many_arguments)]
fn process_candidate(
    oct: &Octave,
    o: usize,
    job: Job,
    p: &SiftParams,
    ori: &mut OriScratch,
    desc: &mut DescScratch,
    angles: &mut Vec<f32>,
    out: &mut Vec<Found>,
) -> Result<(), Job> {
    let (w, h) = (oct.w, oct.h);
    let held = oct.held();
    let rf = match job {
        Job::Describe(rf) => rf,
        Job::Refine(st) => match refine(DogView { gauss: &oct.gauss, w, y0: held.start, y1: held.end }, w, h, st, p) {
            Ok(Some(rf)) => rf,
            Ok(None) => return Ok(()),
            Err(st) => return Err(Job::Refine(st)),
        },
    };
    let need = Job::Describe(rf).rows(p, w, h);
    if need.start < held.start || need.end > held.end {
        return Err(Job::Describe(rf));
    }
    let octv_scale = (1u32 << o) as f32;
    let base = Keypoint {
        x: (rf.c as f32 + rf.xc) * octv_scale,
        y: (rf.r as f32 + rf.xr) * octv_scale,
        size: octave_scale(&rf, p) * octv_scale * 2.0,
        angle: 0.0,
        response: rf.contr.abs(),
        octave: o as i32
            + ((rf.layer as i32) << 8)
            + ((((f64::from(rf.xi) + 0.5) * 255.0).round_ties_even() as i32) << 16),
    };
    // OpenCV's `size * 0.5 / 2^o`: `octave_scale` exactly (powers of two), the scale `describe_reach` was given.
    let scl_octv = base.size * 0.5 / octv_scale;
    let gauss = oct.plane(rf.layer);
    let mut hist = [0.0f32; ORI_HIST_BINS];
    let ori_radius = (ORI_RADIUS * scl_octv).round_ties_even() as i32;
    let omax = orientation_hist(gauss, rf.c, rf.r, ori_radius, ORI_SIG_FCTR * scl_octv, &mut hist, ori);
    angles.clear();
    peak_angles(&hist, omax, angles);
    let (px, py) = (rf.c as f32 + rf.xc, rf.r as f32 + rf.xr);
    for &angle in angles.iter() {
        let kp = Keypoint { angle, ..base };
        let mut d_angle = 360.0 - angle;
        if (d_angle - 360.0).abs() < f32::EPSILON {
            d_angle = 0.0;
        }
        let mut d = [0u8; DESCRIPTOR_LEN];
        let at = descriptor::Frame { px, py, ori: d_angle, scl: scl_octv };
        descriptor::descriptor(gauss, at, &mut d, desc);
        out.push((kp, d));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_and_empty_images_give_nothing() {
        for (w, h) in [(0, 0), (0, 5), (5, 0), (1, 1), (2, 2), (3, 3), (7, 5), (16, 1)] {
            let data: Vec<f32> = (0..w * h).map(|i| (i * 37 % 255) as f32).collect();
            let img = GrayImage::new(w, h, data).unwrap();
            for upscale in [true, false] {
                let f = detect_and_compute(&img, &SiftParams { upscale, ..Default::default() });
                assert!(f.is_empty(), "{w}x{h}");
                assert!(f.descriptors.is_empty());
            }
        }
    }

    #[test]
    fn bad_params_give_nothing() {
        let data: Vec<f32> = (0..64 * 64).map(|i| ((i * 7919) % 255) as f32).collect();
        let img = GrayImage::new(64, 64, data).unwrap();
        for p in [
            SiftParams { n_octave_layers: 0, ..Default::default() },
            SiftParams { sigma: 0.0, ..Default::default() },
            SiftParams { sigma: f32::NAN, ..Default::default() },
            SiftParams { n_octaves: Some(0), ..Default::default() },
        ] {
            assert!(detect_and_compute(&img, &p).is_empty());
        }
        let many = SiftParams { n_octaves: Some(40), ..Default::default() };
        let _ = detect_and_compute(&img, &many);
    }
}
