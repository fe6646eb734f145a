//! One merger construction: the settings a user chooses, as plain data, and the one place a merger is built from them.

use crate::algorithm::Algorithm;
use crate::cascade::Cascade;
use crate::correlative::{CorrelativeMerger, CorrelativeParams};
use crate::estimate::Model;
use crate::map_image::Encoding;
use crate::matching::MatchParams;
use crate::merger::Merger;
use crate::rmap::{RmapMerger, RmapParams};
use crate::sift_merger::{SiftMerger, SiftMergerParams};

/// What a merger is: the algorithm, the settings a user sets, and one seed for every random draw.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct MergerConfig {
    /// The algorithm.
    pub algorithm: Algorithm,
    /// The SIFT merger's transform family.
    pub model: Model,
    /// The SIFT merger's map-to-image encoding.
    pub encoding: Encoding,
    /// Lowe's ratio of the descriptor matching.
    pub ratio: f32,
    /// Candidates per feature: 1 = nearest neighbour with the ratio test; k > 1 = the k nearest.
    pub candidates: usize,
    /// Keep only mutual nearest-neighbour matches.
    pub mutual: bool,
    /// Transforms the SIFT merger hands to verification (sequential RANSAC).
    pub hypotheses: usize,
    /// Occupied cells grown by this many cells before SIFT.
    pub wall_dilation: usize,
    /// SIFT doubles each map image before its pyramid (OpenCV's `firstOctave = -1`, Lowe's recommendation for
    /// photographs); false starts at the map's own cells, for SLAM maps whose finest scale is the walls' jitter.
    pub upscale: bool,
    /// Detect and match the two maps' features on two threads (one merge with the machine to itself).
    pub parallel: bool,
    /// A cascade runs `sift+boundary` beside `sift` ([`Cascade::side_by_side`]: for robots' maps, which `sift`
    /// rarely settles).
    pub side_by_side: bool,
    /// The correlative search's significance margin ([`AnswerParams::min_margin`](crate::AnswerParams::min_margin)).
    pub min_margin: f64,
    /// The correlative answer checked by the same search the other way round ([`AnswerParams::cross_check`](crate::AnswerParams::cross_check)).
    pub cross_check: bool,
    /// Seed of every random draw (the SIFT merger's RANSAC, the R-map's orientation RANSAC).
    pub seed: u64,
}

impl Default for MergerConfig {
    /// The cascade with every algorithm's defaults, seed 0.
    fn default() -> Self {
        let sift = SiftMergerParams::default();
        let correlative = CorrelativeParams::default();
        MergerConfig {
            algorithm: Algorithm::Cascade,
            model: sift.model,
            encoding: Encoding::default(),
            ratio: sift.matching.ratio,
            candidates: sift.matching.candidates,
            mutual: sift.matching.mutual,
            hypotheses: sift.hypotheses,
            wall_dilation: sift.wall_dilation,
            upscale: sift.sift.upscale,
            parallel: sift.parallel,
            side_by_side: false,
            min_margin: correlative.answer.min_margin,
            cross_check: correlative.answer.cross_check,
            seed: 0,
        }
    }
}

impl MergerConfig {
    /// The default settings for `algorithm`, seeded `seed`.
    pub fn new(algorithm: Algorithm, seed: u64) -> Self {
        MergerConfig { algorithm, seed, ..MergerConfig::default() }
    }

    /// The SIFT merger's parameters (also a cascade's SIFT stages').
    pub fn sift(&self) -> SiftMergerParams {
        let mut p = SiftMergerParams {
            model: self.model,
            encoding: self.encoding.levels(),
            matching: MatchParams {
                ratio: self.ratio,
                mutual: self.mutual,
                parallel: self.parallel,
                candidates: self.candidates,
            },
            hypotheses: self.hypotheses,
            wall_dilation: self.wall_dilation,
            parallel: self.parallel,
            ..SiftMergerParams::default()
        };
        p.ransac.seed = self.seed;
        p.sift.upscale = self.upscale;
        p
    }

    /// The correlative search's parameters (also a cascade's last stage's).
    pub fn correlative(&self) -> CorrelativeParams {
        let mut p = CorrelativeParams::default();
        p.answer.min_margin = self.min_margin;
        p.answer.cross_check = self.cross_check;
        p
    }

    /// The R-map merger's parameters.
    pub fn rmap(&self) -> RmapParams {
        let mut p = RmapParams::default();
        p.orient.seed = self.seed;
        p
    }

    /// The merger: the one place one is built.
    pub fn build(&self) -> Box<dyn Merger> {
        match self.algorithm {
            Algorithm::Sift => Box::new(SiftMerger::new(self.sift())),
            Algorithm::Rmap => Box::new(RmapMerger::new(self.rmap())),
            Algorithm::Correlative => Box::new(CorrelativeMerger::new(self.correlative())),
            Algorithm::Cascade if self.side_by_side => {
                Box::new(Cascade::new(self.sift(), self.correlative()).side_by_side())
            }
            Algorithm::Cascade => Box::new(Cascade::new(self.sift(), self.correlative())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use crate::pairs::{PairSpec, cut_pair};
    use crate::{MergeParams, merge};

    /// A generated pair of modest overlap, small enough for every algorithm.
    fn pair() -> crate::pairs::MapPair {
        let plan = generate(2, &FloorplanParams { width_m: 16.0, height_m: 12.0, ..FloorplanParams::default() });
        cut_pair(&plan, &PairSpec { overlap: 0.4, max_shift_m: 2.0, rotate: true }, 5)
    }

    /// The parts of a report that do not depend on wall time.
    fn outcome(c: &MergerConfig, p: &crate::pairs::MapPair) -> String {
        let mut r = merge(c.build().as_ref(), &p.a, &p.b, &MergeParams::default()).report;
        r.time_ms = 0.0;
        r.timings_ms.clear();
        format!("{r:?}")
    }

    #[test]
    fn a_config_built_twice_merges_alike_and_every_algorithm_gets_its_own_merger() {
        let p = pair();
        for a in Algorithm::ALL {
            let c = MergerConfig::new(a, 11);
            assert_eq!(c.build().name(), a.name());
            assert_eq!(outcome(&c, &p), outcome(&c, &p), "{a}");
        }
    }

    #[test]
    fn the_seed_reaches_every_random_draw() {
        // The R-map's orientation RANSAC and the SIFT merger's RANSAC both follow the config's seed.
        let c = MergerConfig::new(Algorithm::Rmap, 9);
        assert_eq!(c.rmap().orient.seed, 9);
        assert_eq!(c.sift().ransac.seed, 9);
        let p = pair();
        let rmap = |seed| outcome(&MergerConfig::new(Algorithm::Rmap, seed), &p);
        assert!((0..6).map(rmap).collect::<std::collections::BTreeSet<_>>().len() > 1, "R-map draws ignore the seed");
    }
}
