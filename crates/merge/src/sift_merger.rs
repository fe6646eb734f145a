//! The paper's merger (Algorithm 3): maps → images → SIFT → ratio-test matches → robust transform.

use crate::alignment::{Alignment, Evidence, Hypothesis, NoAlignment};
use crate::estimate::{Estimate, Model, RansacParams, estimate_many};
use crate::map_image::{MapEncoding, MapImage};
use crate::matching::{MatchParams, match_features};
use crate::merger::Merger;
use crate::resample::to_resolution;
use crate::timing::ms;
use mrslam_core::OccupancyGrid;
use mrslam_sift::{Features, GrayImage, Sift, SiftParams};
use nalgebra::Point2;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::time::Instant;

/// Parameters of the SIFT merger.
#[derive(Debug, Clone, PartialEq)]
pub struct SiftMergerParams {
    /// Grey levels of the map states.
    pub encoding: MapEncoding,
    /// SIFT detector parameters (OpenCV's defaults).
    pub sift: SiftParams,
    /// Descriptor matching.
    pub matching: MatchParams,
    /// Transform family.
    pub model: Model,
    /// Robust estimator.
    pub ransac: RansacParams,
    /// Unknown margin kept around each map's known part when it becomes an image, cells.
    pub image_padding: usize,
    /// Occupied cells are grown by this many cells before SIFT (0 = the map as it is, as the paper does).
    pub wall_dilation: usize,
    /// Detect features of the two maps on two threads.
    pub parallel: bool,
    /// Transforms handed to verification (sequential RANSAC); 1 is the paper's single answer.
    pub hypotheses: usize,
}

impl Default for SiftMergerParams {
    fn default() -> Self {
        SiftMergerParams {
            encoding: MapEncoding::default(),
            sift: SiftParams::default(),
            matching: MatchParams::default(),
            model: Model::Rigid,
            ransac: RansacParams::default(),
            image_padding: 8,
            wall_dilation: 0,
            parallel: false,
            hypotheses: 1,
        }
    }
}

impl SiftMergerParams {
    /// The setting for SLAM maps of different lidars: walls grown one cell, the 6 nearest descriptors per
    /// feature instead of the ratio test, and 4 sequential-RANSAC hypotheses for verification to choose from.
    ///
    /// Measured on the paper corridor, where the default (the paper's) finds no true match: see BENCHMARKS.md.
    pub fn robust() -> Self {
        SiftMergerParams {
            wall_dilation: 1,
            matching: MatchParams { candidates: 6, ..MatchParams::default() },
            hypotheses: 4,
            ..SiftMergerParams::default()
        }
    }
}

/// The SIFT map merger of the paper.
#[derive(Debug, Clone, Default)]
pub struct SiftMerger {
    /// Its parameters.
    pub params: SiftMergerParams,
}

impl SiftMerger {
    /// A merger with these parameters.
    pub fn new(params: SiftMergerParams) -> Self {
        SiftMerger { params }
    }
}

thread_local! {
    /// One detector per thread, kept between merges: its scratch buffers are the costly part of a call.
    static DETECTOR: RefCell<Option<Sift>> = const { RefCell::new(None) };
}

/// Runs SIFT with this thread's cached detector (rebuilt when the parameters change).
fn detect(img: &GrayImage, params: &SiftParams) -> Features {
    DETECTOR.with(|cell| {
        let mut slot = cell.borrow_mut();
        if slot.as_ref().is_none_or(|s| s.params() != params) {
            *slot = Some(Sift::new(params.clone()));
        }
        slot.as_mut().map_or_else(Features::default, |s| s.detect_and_compute(img))
    })
}

/// Features of one map with their map-frame positions.
fn map_features(grid: &OccupancyGrid, p: &SiftMergerParams) -> (Features, Vec<Point2<f64>>) {
    let img = MapImage::render_dilated(grid, &p.encoding, p.image_padding, p.wall_dilation);
    let features = match GrayImage::new(img.width, img.height, img.pixels) {
        Ok(g) => detect(&g, &p.sift),
        Err(_) => Features::default(), // only an empty image can fail here: no features
    };
    // OpenCV's image doubling shifts reported positions by +0.25 px; undo it so map positions are unbiased.
    let bias = if p.sift.upscale { 0.25 } else { 0.0 };
    let view = MapImage { pixels: Vec::new(), ..img };
    let points =
        features.keypoints.iter().map(|k| view.pixel_to_map(grid, k.x as f64 - bias, k.y as f64 - bias)).collect();
    (features, points)
}

impl Merger for SiftMerger {
    fn name(&self) -> &'static str {
        crate::Algorithm::Sift.name()
    }

    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        let p = &self.params;
        let mut timings = BTreeMap::new();
        // One resolution for both: the coarser, so neither map's detail is invented.
        let t = Instant::now();
        let res = a.resolution().max(b.resolution());
        let (ra, rb) = (to_resolution(a, res), to_resolution(b, res));
        timings.insert("resample".to_string(), ms(t));
        let t = Instant::now();
        let ((fa, pa), (fb, pb)) = if p.parallel {
            rayon::join(|| map_features(&ra, p), || map_features(&rb, p))
        } else {
            (map_features(&ra, p), map_features(&rb, p))
        };
        timings.insert("features".to_string(), ms(t));
        let mut evidence = Evidence { points_a: pa.clone(), points_b: pb.clone(), inlier_pairs: Vec::new() };
        let fail = |reason: String, matches: usize, timings: BTreeMap<String, f64>, evidence: Evidence| {
            Box::new(NoAlignment { reason, matches, timings_ms: timings, evidence })
        };
        let k = p.model.sample_size();
        if fa.len() < k || fb.len() < k {
            return Err(fail(
                format!("too few features to match: {} in map a, {} in map b", fa.len(), fb.len()),
                0,
                timings,
                evidence,
            ));
        }
        let t = Instant::now();
        let matches = match_features(&fa, &fb, &p.matching);
        timings.insert("match".to_string(), ms(t));
        if matches.len() < k {
            return Err(fail(
                format!("only {} matches pass the ratio test (need {k})", matches.len()),
                matches.len(),
                timings,
                evidence,
            ));
        }
        let t = Instant::now();
        let (ma, mb): (Vec<_>, Vec<_>) = matches.iter().map(|m| (pa[m.a], pb[m.b])).unzip();
        let ransac = RansacParams { threshold: p.ransac.threshold.max(2.0 * res), ..p.ransac };
        let mut found = estimate_many(p.model, &ma, &mb, &ransac, p.hypotheses.max(1)).into_iter();
        timings.insert("estimate".to_string(), ms(t));
        let Some(est) = found.next() else {
            return Err(fail("no transform has consensus among the matches".into(), matches.len(), timings, evidence));
        };
        let pairs = |e: &Estimate| e.inliers.iter().map(|&i| (matches[i].a, matches[i].b)).collect::<Vec<_>>();
        evidence.inlier_pairs = pairs(&est);
        let alternatives = found
            .map(|e| Hypothesis {
                transform: e.rigid(),
                scale: e.scale(),
                inliers: e.inliers.len(),
                inlier_pairs: pairs(&e),
            })
            .collect();
        Ok(Alignment {
            transform: est.rigid(),
            scale: est.scale(),
            matches: matches.len(),
            matched_features: {
                let mut seen: Vec<usize> = matches.iter().map(|m| m.a).collect();
                seen.dedup(); // matches come ordered by feature of a
                seen.len()
            },
            inliers: est.inliers.len(),
            timings_ms: timings,
            evidence,
            alternatives,
            alternatives_are_rivals: false,
        })
    }
}
