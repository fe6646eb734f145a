//! The correlative merger's parameters, one struct per stage of the search, and the merger they configure.

use crate::contact::Contact;
use serde::{Deserialize, Serialize};

/// Parameters of the correlative merger, by stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CorrelativeParams {
    /// The global search.
    pub search: SearchParams,
    /// The tolerant second search.
    pub fallback: FallbackParams,
    /// The fine stage.
    pub fine: FineParams,
    /// The checks an answer passes.
    pub answer: AnswerParams,
    /// Search the rotations on rayon's threads.
    pub parallel: bool,
}

impl Default for CorrelativeParams {
    fn default() -> Self {
        CorrelativeParams {
            search: SearchParams::default(),
            fallback: FallbackParams::default(),
            fine: FineParams::default(),
            answer: AnswerParams::default(),
            parallel: true,
        }
    }
}

/// The global search: both maps pooled to search cells, a's score field and its pyramid, branch and bound at the
/// rotations the wall-orientation prior allows, its best distinct answers and rivals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SearchParams {
    /// Cell size of the global search, metres: both maps are pooled to it (never finer than a map's own).
    pub resolution: f64,
    /// Cell size of a first screening of every rotation and translation, metres; its best
    /// [`SearchParams::screen_candidates`] are searched again around themselves at `search_resolution`.
    /// Below 1.5 `search_resolution` (the default, 0), no screening: the whole search runs at
    /// `search_resolution`. Measured at 0.8 m with 64 candidates: 4x faster on the real pairs (both still
    /// found), but 12 instead of 22 of 24 generated pairs merged, so off.
    pub screen_resolution: f64,
    /// Distinct answers of the screening searched again.
    pub screen_candidates: usize,
    /// Blur (Gaussian σ) of a's walls in the global search, search cells.
    pub sigma_cells: f64,
    /// Score of a wall point of b on a free cell of a with no wall near, as a share of a hit (≥ 0, subtracted):
    /// the global search's.
    pub free_penalty: f64,
    /// A free cell of a counts as free space (penalised under b's walls) only when at least this share of the
    /// square of one search cell's extent centred on it is free; fewer leave it unknown (0: every free cell).
    ///
    /// A real robot's map is crossed by single rays that pass through glass, doors and gaps far beyond the
    /// walls: thin lines of free cells. Counted as free space they put the other map's walls "in a room": on
    /// ACES in 4 parts, 99 of b's 513 wall points fell on a's free space at the true pose of a pair with 13
    /// relations, and the pair was refused; at 0.5, 12 did and it merged 0.11 m off. With the two logs in 4, 5, 6
    /// and 9 parts (and `min_acceptance` 0.97): ACES 19 of 39 pairs merged correctly instead of 16, 3 false
    /// instead of 5; FR079 45 of 46 as before; generated plans and willow cuts as before.
    pub dense_free_share: f64,
    /// Search only the rotations near the peaks of the correlation of the maps' wall-orientation histograms
    /// (`correlative::orientation`, after Carpin 2008's Hough spectra); false: every rotation (the search as
    /// Hess et al. describe it).
    pub rotation_prior: bool,
    /// The peaks kept: local maxima scoring at least this share of the highest.
    pub rotation_peak_ratio: f64,
    /// Rotations within this many degrees of a peak (or of it plus a half turn) are searched.
    pub rotation_tolerance_deg: f64,
    /// Levels of the max-pooled pyramid: root blocks of the branch and bound are `2^depth` cells a side.
    pub depth: usize,
    /// Angular step as a multiple of Cartographer's `cell / radius of b's walls` (1: a point at the far
    /// end moves one cell per step).
    pub angle_step_scale: f64,
    /// Most wall points of b in the global search (an even stride over its wall blocks; 0 = all).
    pub max_points: usize,
    /// Distinct answers kept per rotation by the branch and bound.
    pub per_rotation: usize,
    /// Lowest global score, as a share of every point of b on a wall of a.
    pub min_score: f64,
    /// Answers scoring below this share of the best one are dropped; rotations searched later prune with it
    /// (0.7 halves the search time against 0.5 with the same answers on the measured pairs; a rival the gate
    /// must see fits about as well as the best, 0.9 of its walls).
    pub keep_ratio: f64,
    /// Two answers are the same when no wall point of b moves more than this between them, metres.
    pub distinct_m: f64,
    /// The global search's best answers clearly apart from its winner, refined on the fine field beside the
    /// hypotheses: rivals for the significance test, and second chances when the coarse ranking is wrong.
    ///
    /// 8: at 32 the fine ranking also found a 180° flip of a generated 24x18 plan laid on the other half (35 m²
    /// shared, acceptance 0.95, margin 0.24) that passed the gate.
    pub rivals: usize,
    /// Fewest wall points (search blocks) in map b.
    pub min_points: usize,
}

impl Default for SearchParams {
    /// Chosen by measurement on generated 29 m floor-plan pairs (overlap 0.1-0.5, random turns) and the two
    /// real half-log pairs (aces, fr079): a sharp field (σ half a 0.4 m cell) and a free-space penalty of
    /// twice a hit keep b's walls out of a's rooms; blurrier or softer fields prefer laying a half building
    /// over the other (the outer walls coincide), a penalty of 4 made one false merge. The significance test,
    /// the fallback search and the ranking of every answer on the fine field after wall ICP:
    /// benchmarks/runs/2026-12-02-merge-real-significance.md.
    fn default() -> Self {
        SearchParams {
            resolution: 0.4,
            screen_resolution: 0.0,
            screen_candidates: 64,
            sigma_cells: 0.5,
            free_penalty: 2.0,
            dense_free_share: 0.5,
            rotation_prior: true,
            rotation_peak_ratio: 0.3,
            rotation_tolerance_deg: 4.0,
            depth: 6,
            angle_step_scale: 1.0,
            max_points: 800,
            per_rotation: 2,
            min_score: 0.03,
            keep_ratio: 0.7,
            distinct_m: 1.0,
            rivals: 8,
            min_points: 20,
        }
    }
}

/// The second, tolerant global search, run when the first does not settle the pair (or always).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FallbackParams {
    /// [`SearchParams::free_penalty`] of a second global search, run when the first does not settle the
    /// pair (its best is not significant, or no hypothesis shares enough known space), its answers pooled with
    /// the first's and ranked on the same fine field (0: no second search).
    ///
    /// Two robots' maps contradict each other at the right pose: on the ACES log 15-21 % of b's walls over a's
    /// known space lie on a's free space 0.4 m or more from any wall of a (doors, people, furniture), so at
    /// the 0.4 m search cells the true pose scored 0.24 and 0.07 of the best wrong one and was pruned. A
    /// search at 1 finds it; run alone it costs generated floor plans a third of their 10 % overlap merges.
    pub free_penalty: f64,
    /// Least area known in both maps at a pose when the fallback search was needed, m².
    ///
    /// The tolerant search finds coincidences the strict one does not: on generated 18 m x 14 m and 24 m x
    /// 18 m plans cut apart (nothing shared), 180° flips laid wall on wall over 23-36 m² (acceptance 0.95-0.99)
    /// with a margin of 0.13-0.29; ACES's true poses share 270-280 m².
    pub min_overlap_m2: f64,
    /// Run the fallback search even when the first settles the pair, its answers pooled as rivals of the first's
    /// winner (which keeps its own [`AnswerParams::min_overlap_m2`] unless a fallback answer beats it); false:
    /// only when the first does not settle it.
    ///
    /// Small maps of the ACES log (the log cut in 9 parts) made the strict search's winner a 180° flip: at the
    /// true pose more of b's walls fall on a's free space (48 against 31 points of 397), so the truth scored a
    /// tenth of the flip and was pruned; the tolerant search finds it, and on the fine field it leads the flip
    /// or comes within the significance margin of it, so the pair is refused instead of merged 4-18 m off.
    pub always: bool,
    /// [`SearchParams::rivals`] of the fallback search, whose poses need
    /// [`FallbackParams::min_overlap_m2`]: ACES's true pose ranked between its 8th and 32nd answer.
    pub rivals: usize,
}

impl Default for FallbackParams {
    fn default() -> Self {
        FallbackParams { free_penalty: 1.0, min_overlap_m2: 100.0, always: true, rivals: 32 }
    }
}

/// The fine stage: windows at a's own resolution around each global answer, and the polish by wall ICP.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FineParams {
    /// Blur of a's walls in the fine stage, cells of a.
    pub sigma_cells: f64,
    /// [`SearchParams::free_penalty`] of the fine field, which ranks the answers and decides the
    /// significance test (at 1 with the global search at 2, a wrong pose won both ACES pairs that need the fallback).
    pub free_penalty: f64,
    /// Most wall points of b in the fine stage and the evidence (0 = all).
    pub max_points: usize,
    /// Fine stage: angles tried either side of a global answer, over one global step.
    pub angles: usize,
    /// The strongest refined answers polished by wall ICP and scored again at the pose they settle at: they
    /// rank the hypotheses and decide the significance test.
    pub polished: usize,
}

impl Default for FineParams {
    fn default() -> Self {
        FineParams { sigma_cells: 1.5, free_penalty: 2.0, max_points: 6000, angles: 3, polished: 8 }
    }
}

/// What an answer must pass before the pipeline's gate sees it: shared area, acceptance index, the significance
/// test, the search the other way round; and the gate's wall agreement asked of it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AnswerParams {
    /// Hypotheses handed to verification: the best and this many minus one alternatives.
    pub hypotheses: usize,
    /// Least area known in both maps (cells of a) at a pose for it to be handed to verification, m².
    ///
    /// Trying every pose finds a small patch where walls coincide by chance (a building's corner on
    /// another's); the gate's common-cell floor, set for feature matches, is too low for such a search.
    pub min_overlap_m2: f64,
    /// Lowest acceptance index (Carpin's, [`crate::verify::Agreement::acceptance_index`]) of a pose before
    /// it is handed to verification.
    ///
    /// Stricter than the gate's: the best of every pose is a far stronger coincidence than a feature
    /// consensus, so its maps must contradict each other less for the same trust. 0.97 (not 0.95):
    /// the logs' correct merges scored 0.975-0.988 (FR079 and ACES in 2-9 parts), the two false
    /// ones of 0.95 scored 0.957 and 0.966 (22 and 32 m off); on generated 18 m x 14 m plans it cost one of 120
    /// merges (at 10 % overlap).
    pub min_acceptance: f64,
    /// The verification gate's wall agreement asked of this search's answers, when lower than the gate's own
    /// ([`crate::VerifyParams::min_wall_agreement`], 0.6).
    ///
    /// 0.4: the search's answers already passed stricter checks (acceptance index, shared area, significance,
    /// the search the other way round), and two robots' maps have doubled and bent walls. On the logs every answer
    /// this gate refused at 0.6 was right (ACES in 4-6 parts: 5 pairs at 53-59 %, 0.03-0.06 m off), and at 0.5
    /// one more: ACES in 2 parts mapped from the scan lines' own odometry (the log without its ODOM lines), 49 %,
    /// 0.21 m and 0.61° off. Correct answers on the logs score 49-97 %, the false ones 60-70 %: wall agreement
    /// does not tell them apart there. The map-level studies and 400 further generated pairs at overlap 0 and 0.05
    /// gave the same answers at 0.4, 0.5 and 0.6, and 180 29 m plan pairs at 0-0.1 at 0.4 and 0.5
    /// (benchmarks/runs/2026-12-04-merge-real-unsettled-check.md).
    pub min_wall_agreement: f64,
    /// The significance test: the best answer's fine score (after wall ICP) must exceed that of every answer
    /// more than [`AnswerParams::rival_distinct_m`] away by this share of itself (`rival ≤ (1 - min_margin)
    /// · best`, Lowe's ratio test, Olson's ambiguity test); else the pair is refused as ambiguous, naming the
    /// rival. 0 turns the test off.
    ///
    /// 0.15: on 360 generated pairs the three wrong answers the gate let through led by 0.04-0.09, the
    /// correct ones by 0-1 (a few below 0.15 lost); every correct answer on the real logs by 1.
    pub min_margin: f64,
    /// A rival of the significance test is a pose that moves some wall point of b more than this, metres.
    pub rival_distinct_m: f64,
    /// Merge the maps the other way round too (a's walls on b's field) and refuse when that is ambiguous (the
    /// significance test) or gives another answer (one that, inverted, moves some wall point of b more than
    /// [`SearchParams::distinct_m`]); when nothing settles the other way round, the answer stands (false:
    /// one way only). A left-right consistency check, as stereo matching makes.
    ///
    /// On the logs it refused the three 180° flips of ACES in 6 and 9 parts (the other way round a pose 180° away
    /// scored 87-89 % of the best) and no correct merge of ACES and FR079 in 2-9 parts, with other SLAM seeds, log
    /// stretches and drifted odometry (135 correct of 156 pairs either way); the map-level studies gave the same
    /// answers. Refusing also when nothing settles the other way round lost 9 of those correct merges: the fine
    /// field's penalty for free space under a wall is one-sided, and a's walls often find no pose scoring above 0
    /// on b's. It doubles the search's time on the pairs it accepts
    /// (benchmarks/runs/2026-12-03-merge-real-robustness.md).
    pub cross_check: bool,
}

impl Default for AnswerParams {
    fn default() -> Self {
        AnswerParams {
            hypotheses: 4,
            min_overlap_m2: 10.0,
            min_acceptance: 0.97,
            min_wall_agreement: 0.4,
            min_margin: 0.15,
            rival_distinct_m: 2.0,
            cross_check: true,
        }
    }
}

/// The global correlative merger.
#[derive(Debug, Clone, Default)]
pub struct CorrelativeMerger {
    /// Its parameters.
    pub params: CorrelativeParams,
    /// The robots' contact, when the maps come from robots in contact ([`crate::Merger::align_near`]): with
    /// [`crate::Contact::search_within`], the searches keep to the translations that put them within reach.
    pub contact: Option<Contact>,
}

impl CorrelativeMerger {
    /// A merger with these parameters.
    pub fn new(params: CorrelativeParams) -> Self {
        CorrelativeMerger { params, contact: None }
    }
}
