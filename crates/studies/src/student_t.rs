//! Student's t: the mean of a small sample with its two-sided 95 % confidence interval, `mean ± t · s / √n`
//! (`s` the sample standard deviation, `t` the 97.5 % quantile of Student's t with n − 1 degrees of freedom).

/// Two-sided probability `P(|T| <= t)` of Student's t with `df` (at least 1) degrees of freedom, exact for whole
/// degrees of freedom (Abramowitz & Stegun 26.7.3 and 26.7.4: finite sums in cos² of `atan(t / √df)`).
fn central_probability(t: f64, df: u32) -> f64 {
    let theta = (t.abs() / f64::from(df).sqrt()).atan();
    let (s, c) = theta.sin_cos();
    let c2 = c * c;
    if df.is_multiple_of(2) {
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..df / 2 {
            term *= c2 * f64::from(2 * k - 1) / f64::from(2 * k);
            sum += term;
        }
        s * sum
    } else {
        let mut sum = 0.0;
        if df > 1 {
            let mut term = 1.0;
            sum = 1.0;
            for k in 1..(df - 1) / 2 {
                term *= c2 * f64::from(2 * k) / f64::from(2 * k + 1);
                sum += term;
            }
        }
        std::f64::consts::FRAC_2_PI * (theta + s * c * sum)
    }
}

/// Above this many degrees of freedom the quantile comes from the Cornish–Fisher expansion around the normal's
/// (error below 1e-7 there) instead of the exact sums, whose length grows with the degrees of freedom.
const EXPANSION_DF: u32 = 1000;

/// The quantile `q` of Student's t with `df` (at least 1) degrees of freedom such that `P(|T| <= q) = level`
/// (`level` in (0, 1); 0.95 gives the 97.5 % quantile of a two-sided 95 % interval).
pub fn t_quantile(level: f64, df: u32) -> f64 {
    assert!(level > 0.0 && level < 1.0 && df >= 1, "t_quantile({level}, {df}): level in (0, 1), df >= 1");
    if df > EXPANSION_DF {
        let z = normal_quantile(0.5 + level / 2.0);
        let n = f64::from(df);
        let (z3, z5) = (z.powi(3), z.powi(5));
        return z + (z3 + z) / (4.0 * n) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n);
    }
    let mut hi = 1.0;
    while central_probability(hi, df) < level {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if central_probability(mid, df) < level {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The standard normal's quantile at `p` in (0, 1) (Acklam's rational approximation: relative error below
/// 1.2e-9).
fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] =
        [7.784_695_709_041_462e-3, 3.224_671_290_700_398e-1, 2.445_134_137_142_996, 3.754_408_661_907_416];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// A sample's mean and its two-sided 95 % Student t interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanCi {
    /// Values in the sample.
    pub n: usize,
    /// Their mean (NaN without values).
    pub mean: f64,
    /// Lower end of the interval (NaN with fewer than two values: no spread to estimate).
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl MeanCi {
    /// The interval intersected with `[min, max]` (a share cannot leave [0, 1], a time cannot be negative).
    pub fn clamped(self, min: f64, max: f64) -> MeanCi {
        let c = |v: f64| if v.is_nan() { v } else { v.clamp(min, max) };
        MeanCi { lo: c(self.lo), hi: c(self.hi), ..self }
    }
}

/// The mean of `values` with its 95 % Student t interval (n − 1 degrees of freedom).
pub fn mean_ci(values: &[f64]) -> MeanCi {
    let n = values.len();
    if n == 0 {
        return MeanCi { n, mean: f64::NAN, lo: f64::NAN, hi: f64::NAN };
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return MeanCi { n, mean, lo: f64::NAN, hi: f64::NAN };
    }
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
    let df = u32::try_from(n - 1).unwrap_or(u32::MAX);
    let half = t_quantile(0.95, df) * (var / n as f64).sqrt();
    MeanCi { n, mean, lo: mean - half, hi: mean + half }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_the_tables() {
        // t(0.975, df) from the standard tables.
        for (df, t) in [(1, 12.7062), (2, 4.3027), (3, 3.1824), (4, 2.7764), (9, 2.2622), (30, 2.0423), (100, 1.9840)] {
            assert!((t_quantile(0.95, df) - t).abs() < 1e-4, "df {df}: {} vs {t}", t_quantile(0.95, df));
        }
        // Across the switch to the expansion, and towards the normal's 1.959964.
        assert!((t_quantile(0.95, 1000) - 1.962_339).abs() < 1e-5, "{}", t_quantile(0.95, 1000));
        assert!((t_quantile(0.95, 1001) - t_quantile(0.95, 1000)).abs() < 1e-5);
        assert!((t_quantile(0.95, 1_000_000) - 1.959_966).abs() < 1e-5);
        assert!((t_quantile(0.90, 5) - 2.0150).abs() < 1e-4);
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-6);
    }

    #[test]
    fn the_interval_of_a_known_sample() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, s = 2.138090, t(0.975, 7) = 2.364624.
        let ci = mean_ci(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!((ci.n, ci.mean), (8, 5.0));
        let half = 2.364_624 * 2.138_090 / 8f64.sqrt();
        assert!((ci.lo - (5.0 - half)).abs() < 1e-5 && (ci.hi - (5.0 + half)).abs() < 1e-5, "{ci:?}");
        // One value: a mean, no interval; none: nothing.
        let one = mean_ci(&[3.0]);
        assert_eq!((one.n, one.mean), (1, 3.0));
        assert!(one.lo.is_nan() && one.hi.is_nan());
        assert!(mean_ci(&[]).mean.is_nan());
        // Equal values: an interval of width 0.
        let flat = mean_ci(&[0.5; 4]);
        assert_eq!((flat.lo, flat.hi), (0.5, 0.5));
        let c = mean_ci(&[0.9, 1.0, 1.0]).clamped(0.0, 1.0);
        assert!(c.hi == 1.0 && c.lo < 1.0);
    }
}
