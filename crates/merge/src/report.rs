//! The merge report: what `--report` writes, laid out in ARCHITECTURE.md, "Merge report".

use crate::alignment::Evidence;
use crate::timing::ms;
use mrslam_core::{OccupancyGrid, Xyt};
use std::collections::BTreeMap;
use std::time::Instant;

/// Result of one merge, accepted or not. `transform` maps points of b's frame into a's frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MergeReport {
    /// Whether the merge passed verification (and a merged map was produced).
    pub accepted: bool,
    /// Algorithm name.
    pub algorithm: String,
    /// The stage of a cascade that decided (the one accepted, else the last refusing); absent for one algorithm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    /// Estimated `T_a_b`, when the algorithm produced one (also when rejected).
    pub transform: Option<Xyt>,
    /// Scale of the estimated model.
    pub scale: Option<f64>,
    /// Tentative correspondences.
    pub matches: usize,
    /// Supporting correspondences.
    pub inliers: usize,
    /// m-explore confidence inliers / (8 + 0.3 · matches).
    pub confidence: f64,
    /// Carpin's acceptance index of the aligned maps.
    pub acceptance_index: Option<f64>,
    /// Cells known in both aligned maps.
    pub common_cells: usize,
    /// Share of b's walls meeting a wall of a after alignment.
    pub wall_agreement: Option<f64>,
    /// Best share of those wall matches kept when b slides 1 m (near 1: not pinned down); computed only when
    /// every other check passed.
    pub ambiguity: Option<f64>,
    /// Why the merge was rejected.
    pub reason: Option<String>,
    /// Wall time of the merge itself (file loading excluded), milliseconds.
    pub time_ms: f64,
    /// Per-stage wall time, milliseconds.
    pub timings_ms: BTreeMap<String, f64>,
}

/// Everything a merge produced.
#[derive(Debug, Clone)]
pub struct MergeOutcome {
    /// The report (also the JSON written by `--report`).
    pub report: MergeReport,
    /// The merged grid in a's frame, when accepted.
    pub merged: Option<OccupancyGrid>,
    /// The algorithm's evidence (present whether accepted or not).
    pub evidence: Evidence,
}

/// The outcome of a merge refused before the gate: no transform, no merged map.
pub(crate) fn refused(
    algorithm: &str,
    reason: String,
    matches: usize,
    timings_ms: BTreeMap<String, f64>,
    start: Instant,
) -> MergeOutcome {
    let report = MergeReport {
        accepted: false,
        algorithm: algorithm.to_string(),
        stage: None,
        transform: None,
        scale: None,
        matches,
        inliers: 0,
        confidence: 0.0,
        acceptance_index: None,
        common_cells: 0,
        wall_agreement: None,
        ambiguity: None,
        reason: Some(reason),
        time_ms: ms(start),
        timings_ms,
    };
    MergeOutcome { report, merged: None, evidence: Evidence::default() }
}
