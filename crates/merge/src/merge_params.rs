//! The parameters of the pipeline around an algorithm: the gate, the wall refinement, the fusion, boundary walls.

use crate::boundary_walls::BoundaryWalls;
use crate::contact::Contact;
use crate::fuse::FusionRule;
use crate::refine::RefineParams;
use crate::verify::VerifyParams;

/// Parameters of the pipeline around an algorithm.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MergeParams {
    /// Thresholds of the verification gate.
    pub verify: VerifyParams,
    /// Apply the gate (false shows the raw algorithm's answer, accepted whatever it is).
    pub verify_enabled: bool,
    /// How aligned cells combine.
    pub fusion: FusionRule,
    /// Wall ICP applied to the algorithm's transform before verification.
    pub refine: RefineParams,
    /// Which maps get walls where their free space meets unknown, for the alignment and the gate
    /// ([`crate::boundary_walls`]): by default those that do not mark their walls (map_server's light-grey walls,
    /// glass); `Off` is the paper's behaviour. The merged map is fused from the maps as given.
    pub boundary_walls: BoundaryWalls,
    /// Where the two maps' robots were when they exchanged them, if they were in contact: the search keeps to
    /// transforms that put them within reach of each other, and the gate refuses any other (None: every
    /// transform, as for two map files).
    #[serde(skip)]
    pub contact: Option<Contact>,
}

impl Default for MergeParams {
    fn default() -> Self {
        MergeParams {
            verify: VerifyParams::default(),
            verify_enabled: true,
            fusion: FusionRule::LogOddsSum,
            refine: RefineParams::default(),
            boundary_walls: BoundaryWalls::Unmarked,
            contact: None,
        }
    }
}
