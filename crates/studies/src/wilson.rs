//! The Wilson score interval of a binomial proportion.

/// z of a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Wilson score interval `(lo, hi)` of `successes` out of `trials` at normal quantile `z`
/// (use [`Z95`] for 95 %). With no trials it is the whole of [0, 1].
pub fn wilson_interval(successes: usize, trials: usize, z: f64) -> (f64, f64) {
    if trials == 0 {
        return (0.0, 1.0);
    }
    let n = trials as f64;
    let p = successes as f64 / n;
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 - b.0).abs() < 5e-4 && (a.1 - b.1).abs() < 5e-4
    }

    #[test]
    fn known_values() {
        assert!(close(wilson_interval(8, 10, Z95), (0.490, 0.943)), "{:?}", wilson_interval(8, 10, Z95));
        assert!(close(wilson_interval(0, 10, Z95), (0.0, 0.2775)), "{:?}", wilson_interval(0, 10, Z95));
        assert!(close(wilson_interval(10, 10, Z95), (0.7225, 1.0)), "{:?}", wilson_interval(10, 10, Z95));
        assert!(close(wilson_interval(50, 100, Z95), (0.4038, 0.5962)), "{:?}", wilson_interval(50, 100, Z95));
        assert_eq!(wilson_interval(0, 0, Z95), (0.0, 1.0));
    }

    #[test]
    fn contains_the_estimate_and_shrinks_with_trials() {
        for (k, n) in [(1, 3), (7, 20), (30, 31)] {
            let (lo, hi) = wilson_interval(k, n, Z95);
            let p = k as f64 / n as f64;
            assert!(lo <= p && p <= hi);
            let (lo2, hi2) = wilson_interval(k * 10, n * 10, Z95);
            assert!(hi2 - lo2 < hi - lo);
        }
    }
}
