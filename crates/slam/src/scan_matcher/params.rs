//! The scan matcher's parameters and which matcher scores poses: the part of the filter's parameters the
//! matcher owns.

use serde::{Deserialize, Serialize};

/// Which scan matcher scores poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MatcherKind {
    /// GMapping's: per beam and pose, a (2k+1)² kernel search for the nearest cell mean with a free cell
    /// behind it; hill climbing.
    #[default]
    Gmapping,
    /// A likelihood field of surfels built once per particle and update (`field`): one table read
    /// per beam; hill climbing on it, then Gauss-Newton refinement (`refine_iterations`).
    Field,
}

impl std::str::FromStr for MatcherKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "gmapping" => Ok(MatcherKind::Gmapping),
            "field" => Ok(MatcherKind::Field),
            other => Err(format!("unknown matcher '{other}' (expected gmapping or field)")),
        }
    }
}

impl std::fmt::Display for MatcherKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            MatcherKind::Gmapping => "gmapping",
            MatcherKind::Field => "field",
        })
    }
}

/// The scan matcher's settings, named and defaulted as GMapping's where GMapping has them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MatcherParams {
    /// Not GMapping: `matcher`, the scan matcher: `gmapping` (the default: GMapping's kernel search per beam
    /// and pose) or `field` (a likelihood field of surface segments built once per particle and update, one
    /// table read per beam, then Gauss-Newton refinement; see `field`).
    pub kind: MatcherKind,
    /// `sigma`: the scan matcher's endpoint-match sigma: score += exp(-d²/sigma), d in metres (GMapping 0.05).
    pub sigma: f64,
    /// `lsigma`: the likelihood's sigma: log-likelihood += -d²/lsigma per beam (GMapping 0.075).
    pub lsigma: f64,
    /// `kernelSize`: half-width in cells of the window searched for an occupied cell around each beam
    /// end point (GMapping 1, i.e. 3×3).
    pub kernel_size: i32,
    /// `lstep`: initial linear step of the hill-climbing optimiser, metres (GMapping 0.05).
    pub lstep: f64,
    /// `astep`: initial angular step of the hill-climbing optimiser, radians (GMapping 0.05).
    pub astep: f64,
    /// `iterations`: number of step halvings of the optimiser (GMapping 5).
    pub iterations: u32,
    /// `lskip`: the matcher uses every (lskip+1)-th beam (GMapping 0: all beams).
    pub lskip: usize,
    /// `minimumScore`: the matched pose replaces the motion-model pose only when the match score exceeds
    /// this (GMapping 0).
    pub minimum_score: f64,
    /// Not GMapping: match only the beams whose end point finds an occupied cell at the motion-model pose
    /// (the "frontier guard"; see [`crate::scan_matcher::ScanMatcher::beams_in_map`]). Off by default.
    pub frontier_guard: bool,
    /// Not GMapping: metres of each beam before its end point, and as far behind it, marked as seen
    /// ("known") in every particle's map; 0 (the default) keeps GMapping's hits-only matching.
    /// When positive, a beam whose window finds no occupied cell and whose end point lies in never-seen
    /// space scores `unknown_score` and costs no likelihood, instead of scoring 0 and costing
    /// `nullLikelihood`: GMapping's score otherwise rewards poses that pull beams ending beyond the mapped
    /// region back onto it, which drags the pose backwards whenever the robot drives into new space.
    pub seen_band: f64,
    /// Score of a beam ending in never-seen space when `seen_band` is on, as a fraction of a perfect match.
    pub unknown_score: f64,
    /// Not GMapping: `field_reach`, cells: how far from a surface the `field` matcher still finds it (a beam
    /// ending farther from every surface is unmatched). GMapping's kernel reaches `kernel_size` + ½ cell.
    pub field_reach: i32,
    /// Not GMapping: `field_lines`: the `field` matcher measures a beam's distance to the line through the
    /// cell means around the nearest occupied cell (a segment one cell long), where they lie on a line;
    /// off: to the nearest cell mean, as GMapping.
    pub field_lines: bool,
    /// Not GMapping: `refine_iterations`: Gauss-Newton iterations refining the `field` matcher's hill-climbed
    /// pose (0: none).
    pub refine_iterations: u32,
    /// Not GMapping: `weight_all_beams`: the likelihood that weighs particles uses every beam within the
    /// usable range; off: the matched beams only (every `lskip`+1-th), as GMapping.
    pub weight_all_beams: bool,
    /// Not GMapping: `heading_search`, radians: before hill climbing, the `field` matcher tries the
    /// motion-model pose turned by every multiple of `heading_step` within ±this and climbs from the best
    /// (0: off). The narrow kernel of the presets has a narrow basin: a heading error of 0.05 rad (one
    /// sigma of GMapping's `srt` over 0.25 m) moves end points 4 m away by 20 cm, beyond the field's reach.
    pub heading_search: f64,
    /// Not GMapping: `heading_step`, radians: the heading search's step.
    pub heading_step: f64,
    /// Not GMapping: `motion_prior`: the `field` matcher maximises the scan score plus the log of the
    /// motion model's density around the particle's sample (GMapping's noise model, `srr`..`stt`, over the
    /// odometry since the last processed scan), scaled by this weight; 0: the scan score alone, as
    /// GMapping. Without it, a direction the scan does not observe (along a corridor whose walls have no
    /// features within range) is free to drift with the matcher's small model errors.
    pub motion_prior: f64,
    /// Not GMapping: `kernel_likelihood`: with the `field` matcher, weigh each particle by GMapping's kernel
    /// likelihood (`kernel_size`, `lsigma`) at its matched pose rather than by the field's distances: the
    /// field finds the pose, GMapping's likelihood tells the particles apart.
    pub kernel_likelihood: bool,
}

impl Default for MatcherParams {
    fn default() -> Self {
        MatcherParams {
            kind: MatcherKind::Gmapping,
            sigma: 0.05,
            lsigma: 0.075,
            kernel_size: 1,
            lstep: 0.05,
            astep: 0.05,
            iterations: 5,
            lskip: 0,
            minimum_score: 0.0,
            frontier_guard: false,
            seen_band: 0.0,
            unknown_score: 0.5,
            field_reach: 3,
            field_lines: true,
            refine_iterations: 0,
            weight_all_beams: false,
            heading_search: 0.0,
            heading_step: 0.01,
            motion_prior: 0.0,
            kernel_likelihood: false,
        }
    }
}

impl MatcherParams {
    /// These parameters with the `field` matcher set up to match one scan on its own: every beam, no seen band,
    /// a short climb and Gauss-Newton, none of the filter's options (minimum score, frontier guard, all-beam or
    /// kernel weighting). What the scan odometry and the loop closure start from.
    pub(crate) fn alone(&self) -> Self {
        MatcherParams {
            kind: MatcherKind::Field,
            lskip: 0,
            seen_band: 0.0,
            iterations: 2,
            refine_iterations: 10,
            heading_step: 0.01,
            minimum_score: 0.0,
            frontier_guard: false,
            weight_all_beams: false,
            kernel_likelihood: false,
            ..*self
        }
    }
}
