//! mrslam-merge: occupancy-grid map merging with unknown relative pose.
//!
//! The paper's SIFT merger ([`SiftMerger`], Algorithm 3), its R-map baseline ([`RmapMerger`], Algorithm 1)
//! and a global correlative search ([`CorrelativeMerger`]) behind the [`Merger`] interface, named by [`Algorithm`], a verification
//! gate that rejects merges the maps themselves contradict ([`verify`]), fusion into one grid ([`fuse`]),
//! N maps at once along a spanning tree of the most confident pairs ([`multi`]),
//! and the generators evaluation needs: procedural floor plans ([`floorplan`]) and map pairs cut with a
//! known overlap and a known transform ([`pairs`]).

mod algorithm;
pub mod correlative;
pub mod estimate;
pub mod floorplan;
pub mod fuse;
pub mod map_image;
pub mod matching;
pub mod merger;
pub mod multi;
pub mod pairs;
pub mod refine;
pub mod report;
pub mod resample;
pub mod rmap;
pub mod sift_merger;
pub mod verify;

pub use algorithm::{Algorithm, UnknownAlgorithm};
pub use correlative::{CorrelativeMerger, CorrelativeParams};
pub use estimate::{Model, RansacParams};
pub use fuse::FusionRule;
pub use map_image::MapEncoding;
pub use matching::MatchParams;
pub use merger::{Alignment, Evidence, MergeOutcome, MergeParams, Merger, NoAlignment, merge};
pub use multi::{MultiOutcome, MultiReport, PairReport, TreeEdge, merge_many};
pub use refine::RefineParams;
pub use report::MergeReport;
pub use rmap::{RmapMerger, RmapParams};
pub use sift_merger::{SiftMerger, SiftMergerParams};
pub use verify::VerifyParams;
