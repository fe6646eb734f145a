//! Trial identity and seeding: a trial's seed depends on (study seed, overlap index, trial index) only.

/// SplitMix64's finaliser: a well-mixed 64-bit hash of `x`.
pub fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// The seed of repetition `rep` at overlap index `overlap_index` of a study seeded `seed`.
pub fn trial_seed(seed: u64, overlap_index: usize, rep: usize) -> u64 {
    mix(mix(mix(seed) ^ overlap_index as u64) ^ rep as u64)
}

/// One trial of a map-level study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialSpec {
    /// Global index: `overlap_index * trials_per_overlap + rep`.
    pub trial: usize,
    /// Index of the target overlap.
    pub overlap_index: usize,
    /// Repetition at that overlap.
    pub rep: usize,
    /// Target overlap (Jaccard of the halves' known cells).
    pub overlap_target: f64,
    /// Seed of the cut (and of the algorithms' random draws).
    pub seed: u64,
}

/// All trials of a study, in index order.
pub fn trials(seed: u64, overlaps: &[f64], per_overlap: usize) -> Vec<TrialSpec> {
    let mut out = Vec::with_capacity(overlaps.len() * per_overlap);
    for (oi, &o) in overlaps.iter().enumerate() {
        for rep in 0..per_overlap {
            out.push(TrialSpec {
                trial: oi * per_overlap + rep,
                overlap_index: oi,
                rep,
                overlap_target: o,
                seed: trial_seed(seed, oi, rep),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_are_distinct_and_stable() {
        let t = trials(7, &[0.1, 0.2, 0.3], 5);
        assert_eq!(t.len(), 15);
        assert_eq!(t[7].trial, 7);
        assert_eq!((t[7].overlap_index, t[7].rep), (1, 2));
        let mut seeds: Vec<u64> = t.iter().map(|t| t.seed).collect();
        seeds.sort();
        seeds.dedup();
        assert_eq!(seeds.len(), 15);
        assert_eq!(trials(7, &[0.1, 0.2, 0.3], 5), t);
        assert_ne!(trials(8, &[0.1], 1)[0].seed, t[0].seed);
    }
}
