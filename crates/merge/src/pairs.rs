//! Map pairs for evaluation: one map cut in two with a chosen overlap, one half moved by a known transform.

use crate::resample::resample;
use mrslam_core::{CellState, OccupancyGrid, Pose2, pose};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Two maps of one world and the truth about them.
#[derive(Debug, Clone)]
pub struct MapPair {
    /// The first half, in the source map's frame.
    pub a: OccupancyGrid,
    /// The second half, re-rendered axis-aligned in its own moved frame.
    pub b: OccupancyGrid,
    /// True transform taking b's frame into a's frame.
    pub t_a_b: Pose2,
    /// Measured Jaccard overlap of the two halves' known cells (before the move).
    pub overlap: f64,
}

/// How to cut and move.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairSpec {
    /// Jaccard overlap of the halves' known cells, in [0, 1); negative values leave a gap of that
    /// fraction of the known cells between the halves, so they share nothing.
    pub overlap: f64,
    /// Largest translation of the moved half, metres.
    pub max_shift_m: f64,
    /// Rotate the moved half by a random angle (otherwise translate only).
    pub rotate: bool,
}

/// The largest shift of a pair's moved half, metres ([`PairSpec::max_shift_m`]).
pub const MAX_SHIFT_M: f64 = 1000.0;

impl PairSpec {
    /// Refuses an overlap outside [-0.9, 0.95) and a shift that is not a number of metres in
    /// 0..=[`MAX_SHIFT_M`], saying which.
    pub fn validate(&self) -> Result<(), String> {
        if !(-0.9..0.95).contains(&self.overlap) {
            return Err(format!("overlap {}: must lie in [-0.9, 0.95)", self.overlap));
        }
        if !(0.0..=MAX_SHIFT_M).contains(&self.max_shift_m) {
            return Err(format!("max shift {} m: must lie in 0..={MAX_SHIFT_M} m", self.max_shift_m));
        }
        Ok(())
    }
}

impl Default for PairSpec {
    fn default() -> Self {
        PairSpec { overlap: 0.3, max_shift_m: 5.0, rotate: true }
    }
}

/// Cuts `map` along a random direction into two halves with the given overlap, then rotates and shifts the
/// second half at random. Deterministic in `seed`. A spec [`PairSpec::validate`] refuses does not panic: a
/// shift that is not a non-negative number moves nothing.
pub fn cut_pair(map: &OccupancyGrid, spec: &PairSpec, seed: u64) -> MapPair {
    cut_pair_with(map, spec, seed, |rng| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
}

/// As [`cut_pair`], but the second half turns by a random multiple of 90° (when `spec.rotate`), so an
/// axis-aligned map stays axis-aligned.
pub fn cut_pair_quarter(map: &OccupancyGrid, spec: &PairSpec, seed: u64) -> MapPair {
    cut_pair_with(map, spec, seed, |rng| rng.random_range(0..4u8) as f64 * std::f64::consts::FRAC_PI_2)
}

fn cut_pair_with(
    map: &OccupancyGrid,
    spec: &PairSpec,
    seed: u64,
    draw_angle: impl FnOnce(&mut ChaCha8Rng) -> f64,
) -> MapPair {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dir = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let (dx, dy) = (dir.cos(), dir.sin());
    // Rank the known cells along the cut direction.
    let w = map.width();
    let mut known: Vec<(f64, usize)> = map
        .cells()
        .iter()
        .enumerate()
        .filter(|(_, l)| CellState::from_log_odds(**l) != CellState::Unknown)
        .map(|(i, _)| (((i % w) as f64) * dx + ((i / w) as f64) * dy, i))
        .collect();
    known.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let n = known.len();
    let mid = rng.random_range(0.4..0.6);
    let half = spec.overlap / 2.0;
    let end_a = ((mid + half).clamp(0.0, 1.0) * n as f64) as usize;
    let start_b = ((mid - half).clamp(0.0, 1.0) * n as f64) as usize;
    let mut in_a = vec![false; map.cells().len()];
    let mut in_b = vec![false; map.cells().len()];
    for (k, &(_, i)) in known.iter().enumerate() {
        in_a[i] = k < end_a;
        in_b[i] = k >= start_b;
    }
    let both = in_a.iter().zip(&in_b).filter(|(a, b)| **a && **b).count();
    let either = in_a.iter().zip(&in_b).filter(|(a, b)| **a || **b).count();
    let keep = |mask: &[bool]| {
        let mut g = map.clone();
        for (l, &m) in g.cells_mut().iter_mut().zip(mask) {
            if !m {
                *l = 0.0;
            }
        }
        g
    };
    let a = keep(&in_a);
    let b_cut = keep(&in_b);
    let theta = if spec.rotate { draw_angle(&mut rng) } else { 0.0 };
    let s = if spec.max_shift_m.is_finite() { spec.max_shift_m.max(0.0) } else { 0.0 };
    let t_b_a = pose(rng.random_range(-s..=s), rng.random_range(-s..=s), theta);
    let b = resample(&b_cut, &t_b_a, map.resolution());
    MapPair { a, b, t_a_b: t_b_a.inverse(), overlap: if either == 0 { 0.0 } else { both as f64 / either as f64 } }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::floorplan::{FloorplanParams, generate};
    use crate::verify::agreement;

    #[test]
    fn a_bad_shift_is_refused_by_validate_and_does_not_panic() {
        let map = generate(3, &FloorplanParams::default());
        for shift in [-5.0, f64::NAN, 1e9] {
            let spec = PairSpec { max_shift_m: shift, ..PairSpec::default() };
            assert!(spec.validate().unwrap_err().contains("max shift"), "{shift}");
            let pair = cut_pair(&map, &spec, 1);
            assert!(pair.t_a_b.translation.vector.norm() < 1e9, "{shift}");
        }
        assert!(PairSpec { overlap: 0.99, ..PairSpec::default() }.validate().unwrap_err().contains("overlap"));
        assert_eq!(PairSpec::default().validate(), Ok(()));
    }

    #[test]
    fn overlap_is_as_asked_and_truth_aligns_the_halves() {
        let map = generate(3, &FloorplanParams::default());
        for (seed, want) in [(1, 0.1), (2, 0.3), (3, 0.6)] {
            let pair = cut_pair(&map, &PairSpec { overlap: want, ..Default::default() }, seed);
            assert!((pair.overlap - want).abs() < 0.01, "asked {want}, got {}", pair.overlap);
            let agr = agreement(&pair.a, &pair.b, &pair.t_a_b);
            // nearest-neighbour rotation of thin walls costs a little agreement, not much
            assert!(agr.acceptance_index() > 0.97, "{agr:?}");
            assert!(agr.common() > 1000);
        }
    }

    #[test]
    fn quarter_pairs_turn_by_quarter_turns_and_align() {
        let map = generate(3, &FloorplanParams::default());
        let spec = PairSpec { overlap: 0.6, ..Default::default() };
        for seed in 0..4 {
            let pair = cut_pair_quarter(&map, &spec, seed);
            let q = pair.t_a_b.rotation.angle() / std::f64::consts::FRAC_PI_2;
            assert!((q - q.round()).abs() < 1e-9, "{q}");
            assert!(agreement(&pair.a, &pair.b, &pair.t_a_b).acceptance_index() > 0.99);
        }
    }

    #[test]
    fn gap_pairs_share_nothing() {
        let map = generate(4, &FloorplanParams::default());
        let pair = cut_pair(&map, &PairSpec { overlap: -0.1, ..Default::default() }, 9);
        assert_eq!(pair.overlap, 0.0);
        assert_eq!(agreement(&pair.a, &pair.b, &pair.t_a_b).common(), 0);
    }
}
