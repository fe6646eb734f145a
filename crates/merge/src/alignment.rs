//! What an algorithm answers: the transform between two maps with its evidence, or why it found none.

use mrslam_core::Pose2;
use nalgebra::Point2;
use std::collections::BTreeMap;

/// What an algorithm found: the transform taking map b's frame into map a's, and its evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    /// Rigid transform `T_a_b` (points of b's frame into a's frame).
    pub transform: Pose2,
    /// Scale of the estimated model (1 for rigid).
    pub scale: f64,
    /// Tentative correspondences (feature matches, or candidate triangle pairs).
    pub matches: usize,
    /// Features of map a with at least one correspondence: `matches` when each has one, fewer with k-NN.
    ///
    /// m-explore's confidence divides by the match count of a ratio-tested matcher; k candidates per feature
    /// would inflate it k-fold for the same evidence, so the confidence uses this count.
    pub matched_features: usize,
    /// Correspondences that support the transform.
    pub inliers: usize,
    /// Per-stage wall time, milliseconds.
    pub timings_ms: BTreeMap<String, f64>,
    /// Feature locations and inlier pairs, for drawing.
    pub evidence: Evidence,
    /// Weaker transforms the algorithm also found, strongest first; verification may pick one of them.
    pub alternatives: Vec<Hypothesis>,
    /// The alternatives only challenge the first transform (the gate's rival check) and are never accepted in
    /// its place: an answer that did not lead every other pose of a global search is not significant.
    pub alternatives_are_rivals: bool,
}

/// One candidate transform with its support.
#[derive(Debug, Clone, PartialEq)]
pub struct Hypothesis {
    /// Rigid transform `T_a_b`.
    pub transform: Pose2,
    /// Scale of the estimated model.
    pub scale: f64,
    /// Supporting correspondences.
    pub inliers: usize,
    /// Inlier pairs as (index in points_a, index in points_b).
    pub inlier_pairs: Vec<(usize, usize)>,
}

/// Where an algorithm's evidence lies, in each map's own frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Evidence {
    /// Feature points of map a (map frame, metres).
    pub points_a: Vec<Point2<f64>>,
    /// Feature points of map b (map frame, metres).
    pub points_b: Vec<Point2<f64>>,
    /// Inlier pairs as (index in points_a, index in points_b).
    pub inlier_pairs: Vec<(usize, usize)>,
}

/// Why an algorithm could not produce a transform, with the stage timings spent finding out.
#[derive(Debug, Clone, PartialEq)]
pub struct NoAlignment {
    /// Human-readable reason.
    pub reason: String,
    /// Correspondences found before giving up.
    pub matches: usize,
    /// Per-stage wall time, milliseconds.
    pub timings_ms: BTreeMap<String, f64>,
    /// Evidence gathered before giving up.
    pub evidence: Evidence,
}
