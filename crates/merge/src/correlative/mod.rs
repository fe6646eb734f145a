//! A global correlative merger: the whole of map b's walls matched against a likelihood field of map a's
//! over every translation and the rotations the walls' orientations allow, as Cartographer's loop closure searches
//! a whole submap.
//!
//! ```text
//! pool a and b to search cells (search_resolution)     BlockStates
//! score field of a: blurred walls, penalised free      ScoreField
//! max-pooled pyramid of the field                      Pyramid (Hess et al. 2016)
//! b's wall blocks as points about their centroid       WallScan
//! rotations near the peaks of the wall-orientation     orientation (Carpin 2008's Hough-spectrum idea)
//!     correlation of a and b (± 4°, θ and θ + π)
//! for each such rotation, step = cell / radius (rayon): (Olson 2009; Cartographer's angular step)
//!     branch and bound over all translations           branch_and_bound
//! best distinct (rotation, translation) overall        hypotheses, strongest first, and rivals
//! each: a window at a's resolution (every offset; rayon)   local_search
//! the strongest: wall ICP, scored again, ranked        refine::refine
//! significance: best against the best 2 m or more away Significance (Lowe's ratio test)
//! a second search with a softer penalty, pooled:      fallback_free_penalty (rivals; its own winner
//!     needs fallback_min_overlap_m2)                   fallback_always
//! hypotheses: least shared area and acceptance         verify::agreement
//! the same the other way round (a's walls on b):       cross_check (refused if ambiguous or elsewhere)
//! ```
//!
//! The shared pipeline then refines each answer by wall ICP and puts it through the verification gate.
//!
//! What the pipeline sees ([`Alignment`](crate::Alignment)): the evidence is b's wall cells (at a's resolution, thinned to
//! [`crate::FineParams::max_points`]) placed by the transform. `matches` (and `matched_features`) = those
//! landing on a known cell of a, `inliers` = those of them with a wall of a within one cell: the counts of
//! the gate's wall agreement ([`crate::verify::wall_hits`]). m-explore's confidence
//! `inliers / (8 + 0.3 · matches)` is then above 1 when more than 30 % of b's walls over a's known space meet
//! a's walls (plus 8), and it falls with the share of b's walls that contradict a.
//!
//! The search's map-agnostic pieces (`BlockStates`, `ScoreField`, `Pyramid`, `WallScan`, `branch_and_bound`,
//! `local_search`) live in `mrslam-matching`; this module holds what is about merging two maps: the stages above, their parameters, the
//! significance test and the answer checked the other way round.

mod bookkeeping;
mod fine;
mod geometry;
mod global;
mod merger;
pub mod orientation;
mod params;
mod settle;
mod significance;

pub use params::{AnswerParams, CorrelativeMerger, CorrelativeParams, FallbackParams, FineParams, SearchParams};
pub use settle::{score_near, significance};
pub use significance::Significance;
