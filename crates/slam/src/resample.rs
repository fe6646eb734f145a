//! Weight normalisation, the effective sample size and systematic resampling.

/// Normalises log weights as GMapping's `normalize()`: `w_i ∝ exp(gain·(l_i − max l))`, with
/// `gain = 1/(ogain·N)`. Returns the normalised weights (summing to 1) and Neff = 1/Σw².
pub fn normalize(log_weights: &[f64], gain: f64) -> (Vec<f64>, f64) {
    if log_weights.is_empty() {
        return (Vec::new(), 0.0);
    }
    let lmax = log_weights.iter().copied().filter(|l| l.is_finite()).fold(f64::NEG_INFINITY, f64::max);
    let mut w: Vec<f64> = log_weights
        .iter()
        .map(|&l| if lmax.is_finite() && l.is_finite() { (gain * (l - lmax)).exp() } else { 0.0 })
        .collect();
    let sum: f64 = w.iter().sum();
    if !(sum > 0.0 && sum.is_finite()) {
        // Nothing usable: fall back to uniform.
        let u = 1.0 / w.len() as f64;
        w.iter_mut().for_each(|x| *x = u);
    } else {
        w.iter_mut().for_each(|x| *x /= sum);
    }
    let neff = neff(&w);
    (w, neff)
}

/// Effective sample size of normalised weights: 1/Σw².
pub fn neff(weights: &[f64]) -> f64 {
    let s: f64 = weights.iter().map(|w| w * w).sum();
    if s > 0.0 { 1.0 / s } else { 0.0 }
}

/// Systematic (low-variance) resampling, as GMapping's `uniform_resampler`: `n` indices drawn with one
/// offset `u` in [0, 1) scaled to a stride of `total/n`. Index i is drawn ⌊n·w_i⌋ or ⌈n·w_i⌉ times.
pub fn systematic(weights: &[f64], n: usize, u: f64) -> Vec<usize> {
    let total: f64 = weights.iter().sum();
    if weights.is_empty() || n == 0 || !(total > 0.0 && total.is_finite()) {
        return (0..n).map(|i| i % weights.len().max(1)).collect();
    }
    let stride = total / n as f64;
    let mut target = stride * u.clamp(0.0, 1.0 - f64::EPSILON);
    let mut out = Vec::with_capacity(n);
    let mut cum = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        cum += w;
        while cum > target && out.len() < n {
            out.push(i);
            target += stride;
        }
    }
    // Rounding can leave the last draw(s) short: give them to the last index with weight.
    let last = weights.iter().rposition(|&w| w > 0.0).unwrap_or(0);
    while out.len() < n {
        out.push(last);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_weights_give_neff_n() {
        let (w, n) = normalize(&[-3.0; 30], 1.0 / 90.0);
        assert!((n - 30.0).abs() < 1e-9);
        assert!(w.iter().all(|&x| (x - 1.0 / 30.0).abs() < 1e-12));
    }

    #[test]
    fn one_dominant_weight_gives_neff_one() {
        let mut l = vec![-1e6; 30];
        l[7] = 0.0;
        let (w, n) = normalize(&l, 1.0 / 90.0);
        assert!((n - 1.0).abs() < 1e-9, "{n}");
        assert!((w[7] - 1.0).abs() < 1e-9);
        // gain smooths: a likelihood gap of ogain*N*ln(2) halves the weight
        let (w, _) = normalize(&[0.0, -90.0 * 2f64.ln()], 1.0 / 90.0);
        assert!((w[0] / w[1] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn non_finite_weights_do_not_poison() {
        let (w, n) = normalize(&[f64::NAN, 0.0, f64::NEG_INFINITY], 1.0);
        assert_eq!(w, vec![0.0, 1.0, 0.0]);
        assert!((n - 1.0).abs() < 1e-12);
    }

    #[test]
    fn systematic_counts_are_floor_or_ceil_of_expected() {
        let w = [0.5, 0.25, 0.125, 0.0625, 0.0625, 0.0];
        for k in 0..50 {
            let u = k as f64 / 50.0;
            let idx = systematic(&w, 10, u);
            assert_eq!(idx.len(), 10);
            assert!(idx.windows(2).all(|p| p[0] <= p[1]), "sorted");
            for (i, &wi) in w.iter().enumerate() {
                let c = idx.iter().filter(|&&j| j == i).count() as f64;
                let e = wi * 10.0;
                assert!(c >= e.floor() && c <= e.ceil(), "index {i}: {c} draws, expected {e} (u {u})");
            }
        }
        let idx = systematic(&[0.25; 4], 4, 0.3);
        assert_eq!(idx, vec![0, 1, 2, 3], "uniform weights keep every particle once");
    }
}
