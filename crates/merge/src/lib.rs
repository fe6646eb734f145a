//! mrslam-merge: occupancy-grid map merging with unknown relative pose.
//!
//! The paper's SIFT merger ([`SiftMerger`], Algorithm 3), its R-map baseline ([`RmapMerger`], Algorithm 1)
//! and a global correlative search ([`CorrelativeMerger`]) behind the [`Merger`] interface, named by [`Algorithm`]
//! and built in one place from plain settings ([`MergerConfig`]), a verification gate that rejects merges the maps
//! themselves contradict (`verify`, `gate`), fusion into one grid (`fuse`), a team's maps as a graph merged
//! incrementally along a spanning tree of the most confident pairs ([`MapGraph`]; [`merge_many`] at once),
//! and the generators evaluation needs: procedural floor plans ([`floorplan`]) and map pairs cut with a
//! known overlap and a known transform ([`pairs`]).
//!
//! Modules are private and their items re-exported here, except the public namespaces [`floorplan`],
//! [`pairs`] and [`resample`]; [`dev`] holds internals public only for tests, benches and the development
//! probes.
//!
//! ```
//! use mrslam_merge::floorplan::{FloorplanParams, generate};
//! use mrslam_merge::pairs::{PairSpec, cut_pair};
//! use mrslam_merge::{MergeParams, SiftMerger, merge};
//!
//! // A generated floor plan cut into two maps that share 40 % of their cells, the second moved at random.
//! let plan = generate(1, &FloorplanParams::default());
//! let pair = cut_pair(&plan, &PairSpec { overlap: 0.4, ..Default::default() }, 3);
//! let out = merge(&SiftMerger::default(), &pair.a, &pair.b, &MergeParams::default());
//! // Accepted by the verification gate, and the estimate is the true transform within a few centimetres.
//! let estimate = out.report.transform.unwrap().to_pose();
//! assert!(out.report.accepted && (estimate.inverse() * pair.t_a_b).translation.vector.norm() < 0.1);
//! ```

#![deny(missing_docs)]

mod algorithm;
mod alignment;
pub mod boundary_walls;
mod cascade;
mod config;
mod contact;
mod correlative;
mod estimate;
pub mod floorplan;
mod fuse;
mod gate;
mod map_image;
mod matching;
mod merge_params;
mod merger;
mod multi;
pub mod pairs;
mod refine;
mod report;
pub mod resample;
mod rmap;
mod sift_merger;
mod team;
mod timing;
mod verify;

pub use algorithm::{Algorithm, UnknownAlgorithm};
pub use alignment::{Alignment, Evidence, Hypothesis, NoAlignment};
pub use boundary_walls::BoundaryWalls;
pub use cascade::{Cascade, Stage};
pub use config::MergerConfig;
pub use contact::Contact;
pub use correlative::{AnswerParams, CorrelativeMerger, CorrelativeParams, FallbackParams, FineParams, SearchParams};
pub use estimate::{Model, RansacParams};
pub use fuse::{FusionRule, fuse as fuse_maps};
pub use map_image::{Encoding, MapEncoding, MapImage};
pub use matching::MatchParams;
pub use merge_params::MergeParams;
pub use merger::{Merger, merge};
pub use multi::{DISAGREE_DEG, DISAGREE_M, Disagreement, MultiOutcome, MultiReport, PairReport, TreeEdge};
pub use refine::RefineParams;
pub use report::{MergeOutcome, MergeReport};
pub use rmap::{CoverRule, OrientParams, RmapMerger, RmapParams, RmapResult, TriangleMatch, TriangleParams};
pub use sift_merger::{SiftMerger, SiftMergerParams};
pub use team::{MapGraph, MapId, UnknownMap, merge_many};
pub use verify::{Agreement, VerifyParams, agreement, agreement_within};

/// Internals public only for the crate's tests and benches and the development probes (`dev/` in the
/// repository): the R-map's maximal empty rectangles, wall ICP, wall hits, descriptor matching. Not part of
/// the crate's API.
pub mod dev {
    pub use crate::correlative::{Significance, score_near, significance};
    pub use crate::matching::{Match, match_features};
    pub use crate::refine::{refine, wall_points};
    pub use crate::rmap::{FreeMatrix, Mer, mers};
    pub use crate::verify::wall_hits;
}
