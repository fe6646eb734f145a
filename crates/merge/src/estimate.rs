//! Robust estimation of the transform between matched points (paper Alg. 3, line 7).
//!
//! MSAC (RANSAC scoring inliers by truncated squared error, Torr & Zisserman 2000) with adaptive
//! iteration count and local optimisation (LO-RANSAC: least-squares refits on the inliers of each new best
//! model, Chum et al. 2003). Three models: rigid (2 points), similarity (2 points) and homography (4 points,
//! normalised DLT), the last as the paper does; every model reports its rigid part.

use mrslam_core::{Pose2, pose};
use nalgebra::{Matrix3, Point2, SMatrix, SVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Transform family estimated from matches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// Rotation and translation: both maps describe one world at one scale.
    Rigid,
    /// Rotation, translation and uniform scale.
    Similarity,
    /// Full projective transform, as the paper estimates.
    Homography,
}

impl Model {
    /// Every model, as the command line lists them.
    pub const ALL: [Model; 3] = [Model::Rigid, Model::Similarity, Model::Homography];

    /// The name: `rigid`, `similarity` or `homography`.
    pub const fn name(self) -> &'static str {
        match self {
            Model::Rigid => "rigid",
            Model::Similarity => "similarity",
            Model::Homography => "homography",
        }
    }

    /// Points needed for one hypothesis.
    pub fn sample_size(self) -> usize {
        match self {
            Model::Rigid | Model::Similarity => 2,
            Model::Homography => 4,
        }
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Model::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown model `{s}` (expected rigid, similarity or homography)"))
    }
}

/// Parameters of the robust estimator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RansacParams {
    /// Inlier threshold on the transfer error, metres.
    pub threshold: f64,
    /// Required probability of having drawn one all-inlier sample.
    pub confidence: f64,
    /// Upper bound on hypotheses drawn.
    pub max_iterations: usize,
    /// Least-squares refits per new best model (0 disables local optimisation: plain MSAC).
    pub local_optimisation_steps: usize,
    /// Seed of the sampler.
    pub seed: u64,
}

impl Default for RansacParams {
    fn default() -> Self {
        RansacParams { threshold: 0.15, confidence: 0.999, max_iterations: 5000, local_optimisation_steps: 3, seed: 0 }
    }
}

/// A transform from b's frame to a's frame with the matches that support it.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Model family.
    pub model: Model,
    /// Homogeneous 3×3 matrix mapping b points to a points.
    pub matrix: Matrix3<f64>,
    /// Indices (into the point lists) of the inliers.
    pub inliers: Vec<usize>,
    /// Hypotheses drawn.
    pub iterations: usize,
}

impl Estimate {
    /// The rigid part: rotation and translation of the matrix (scale and projective parts dropped).
    pub fn rigid(&self) -> Pose2 {
        let m = self.matrix / self.matrix[(2, 2)];
        let theta = (m[(1, 0)] - m[(0, 1)]).atan2(m[(0, 0)] + m[(1, 1)]);
        pose(m[(0, 2)], m[(1, 2)], theta)
    }

    /// Scale of the linear part (1 for a rigid model).
    pub fn scale(&self) -> f64 {
        let m = self.matrix / self.matrix[(2, 2)];
        (m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)]).abs().sqrt()
    }
}

/// Applies a homogeneous matrix to a point.
#[inline]
pub fn apply(m: &Matrix3<f64>, p: &Point2<f64>) -> Point2<f64> {
    let w = m[(2, 0)] * p.x + m[(2, 1)] * p.y + m[(2, 2)];
    Point2::new(
        (m[(0, 0)] * p.x + m[(0, 1)] * p.y + m[(0, 2)]) / w,
        (m[(1, 0)] * p.x + m[(1, 1)] * p.y + m[(1, 2)]) / w,
    )
}

/// Least-squares fit of a model to point pairs (`b[i]` ↦ `a[i]`); None when degenerate.
pub fn fit(model: Model, a: &[Point2<f64>], b: &[Point2<f64>]) -> Option<Matrix3<f64>> {
    match model {
        Model::Rigid => fit_similarity(a, b, false),
        Model::Similarity => fit_similarity(a, b, true),
        Model::Homography => fit_homography(a, b),
    }
}

/// Closed-form 2D Umeyama/Kabsch fit, with or without scale.
fn fit_similarity(a: &[Point2<f64>], b: &[Point2<f64>], with_scale: bool) -> Option<Matrix3<f64>> {
    let n = a.len() as f64;
    if a.len() < 2 {
        return None;
    }
    let ca = a.iter().fold(nalgebra::Vector2::zeros(), |s, p| s + p.coords) / n;
    let cb = b.iter().fold(nalgebra::Vector2::zeros(), |s, p| s + p.coords) / n;
    let (mut sxx, mut sxy, mut var_b) = (0.0, 0.0, 0.0);
    for (pa, pb) in a.iter().zip(b) {
        let (qa, qb) = (pa.coords - ca, pb.coords - cb);
        sxx += qb.x * qa.x + qb.y * qa.y;
        sxy += qb.x * qa.y - qb.y * qa.x;
        var_b += qb.norm_squared();
    }
    if var_b < 1e-12 {
        return None;
    }
    let theta = sxy.atan2(sxx);
    let s = if with_scale { sxx.hypot(sxy) / var_b } else { 1.0 };
    let (c, si) = (theta.cos() * s, theta.sin() * s);
    let t = ca - nalgebra::Vector2::new(c * cb.x - si * cb.y, si * cb.x + c * cb.y);
    Some(Matrix3::new(c, -si, t.x, si, c, t.y, 0.0, 0.0, 1.0))
}

/// Normalising similarity (Hartley): centroid to origin, mean distance √2.
fn normaliser(p: &[Point2<f64>]) -> Option<Matrix3<f64>> {
    let n = p.len() as f64;
    let c = p.iter().fold(nalgebra::Vector2::zeros(), |s, q| s + q.coords) / n;
    let d = p.iter().map(|q| (q.coords - c).norm()).sum::<f64>() / n;
    if d < 1e-12 {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / d;
    Some(Matrix3::new(s, 0.0, -s * c.x, 0.0, s, -s * c.y, 0.0, 0.0, 1.0))
}

/// Normalised DLT homography from ≥ 4 pairs.
fn fit_homography(a: &[Point2<f64>], b: &[Point2<f64>]) -> Option<Matrix3<f64>> {
    if a.len() < 4 {
        return None;
    }
    let (na, nb) = (normaliser(a)?, normaliser(b)?);
    // Accumulate AᵀA (9×9) directly: no 2n×9 matrix is built.
    let mut ata = SMatrix::<f64, 9, 9>::zeros();
    for (pa, pb) in a.iter().zip(b) {
        let q = apply(&na, pa);
        let r = apply(&nb, pb);
        let rows = [
            SVector::<f64, 9>::from_row_slice(&[-r.x, -r.y, -1.0, 0.0, 0.0, 0.0, q.x * r.x, q.x * r.y, q.x]),
            SVector::<f64, 9>::from_row_slice(&[0.0, 0.0, 0.0, -r.x, -r.y, -1.0, q.y * r.x, q.y * r.y, q.y]),
        ];
        for row in rows {
            ata += row * row.transpose();
        }
    }
    let eig = ata.symmetric_eigen();
    let (k, _) = eig.eigenvalues.iter().enumerate().min_by(|x, y| x.1.total_cmp(y.1))?;
    let h = eig.eigenvectors.column(k);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let m = na.try_inverse()? * hn * nb;
    if m[(2, 2)].abs() < 1e-12 {
        return None;
    }
    let m = m / m[(2, 2)];
    m.iter().all(|v| v.is_finite()).then_some(m)
}

/// Robustly estimates the transform taking `b[i]` to `a[i]`. None when there are too few pairs or no
/// hypothesis has enough support.
pub fn estimate(model: Model, a: &[Point2<f64>], b: &[Point2<f64>], p: &RansacParams) -> Option<Estimate> {
    let n = a.len();
    let k = model.sample_size();
    if n < k || n != b.len() {
        return None;
    }
    let thr2 = p.threshold * p.threshold;
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    let score = |m: &Matrix3<f64>| -> f64 {
        a.iter().zip(b).map(|(pa, pb)| (apply(m, pb) - pa).norm_squared().min(thr2)).sum()
    };
    let inliers_of = |m: &Matrix3<f64>| -> Vec<usize> {
        (0..n).filter(|&i| (apply(m, &b[i]) - a[i]).norm_squared() < thr2).collect()
    };
    let mut best: Option<(f64, Matrix3<f64>)> = None;
    let mut needed = p.max_iterations;
    let mut iterations = 0;
    let mut idx = [0usize; 4];
    let (mut sa, mut sb) = ([Point2::origin(); 4], [Point2::origin(); 4]);
    while iterations < needed.min(p.max_iterations) {
        iterations += 1;
        // Draw k distinct indices.
        for j in 0..k {
            loop {
                let c = rng.random_range(0..n);
                if !idx[..j].contains(&c) {
                    idx[j] = c;
                    break;
                }
            }
            sa[j] = a[idx[j]];
            sb[j] = b[idx[j]];
        }
        // A rigid motion preserves distances: reject samples that cannot be one before fitting.
        if model == Model::Rigid {
            let (da, db) = ((sa[0] - sa[1]).norm(), (sb[0] - sb[1]).norm());
            if db < 2.0 * p.threshold || (da - db).abs() > 2.0 * p.threshold {
                continue;
            }
        }
        let Some(m) = fit(model, &sa[..k], &sb[..k]) else { continue };
        let mut s = score(&m);
        if best.as_ref().is_some_and(|(bs, _)| s >= *bs) {
            continue;
        }
        let mut m = m;
        for _ in 0..p.local_optimisation_steps {
            let inl = inliers_of(&m);
            if inl.len() <= k {
                break;
            }
            let (ia, ib): (Vec<_>, Vec<_>) = inl.iter().map(|&i| (a[i], b[i])).unzip();
            match fit(model, &ia, &ib) {
                Some(r) => {
                    let rs = score(&r);
                    if rs < s {
                        s = rs;
                        m = r;
                    } else {
                        break;
                    }
                }
                None => break,
            }
        }
        let inlier_count = inliers_of(&m).len();
        best = Some((s, m));
        let w = inlier_count as f64 / n as f64;
        if w > 0.0 {
            let miss = 1.0 - w.powi(k as i32);
            needed = if miss <= 1e-12 {
                iterations
            } else {
                ((1.0 - p.confidence).ln() / miss.ln()).ceil().max(1.0) as usize
            };
        }
    }
    let (_, m) = best?;
    let inliers = inliers_of(&m);
    if inliers.len() < k {
        return None;
    }
    // Final least-squares refinement on all inliers.
    let (ia, ib): (Vec<_>, Vec<_>) = inliers.iter().map(|&i| (a[i], b[i])).unzip();
    let m = fit(model, &ia, &ib).unwrap_or(m);
    let inliers = inliers_of(&m);
    Some(Estimate { model, matrix: m, inliers, iterations })
}

/// Up to `count` distinct transforms by sequential RANSAC: each round removes the previous winners' inliers.
///
/// The first is [`estimate`]'s answer. Self-similar maps (a corridor) give a wrong transform more support
/// than the right one; the later rounds keep the right one in play for verification to pick.
pub fn estimate_many(
    model: Model,
    a: &[Point2<f64>],
    b: &[Point2<f64>],
    p: &RansacParams,
    count: usize,
) -> Vec<Estimate> {
    let mut out: Vec<Estimate> = Vec::new();
    let mut left: Vec<usize> = (0..a.len()).collect();
    for round in 0..count {
        let (ra, rb): (Vec<_>, Vec<_>) = left.iter().map(|&i| (a[i], b[i])).unzip();
        let Some(mut e) = estimate(model, &ra, &rb, &RansacParams { seed: p.seed.wrapping_add(round as u64), ..*p })
        else {
            break;
        };
        // Too small a consensus to be worth verifying: the remaining matches hold nothing more.
        if e.inliers.len() <= model.sample_size() {
            break;
        }
        e.inliers = e.inliers.iter().map(|&i| left[i]).collect();
        let taken: std::collections::BTreeSet<usize> = e.inliers.iter().copied().collect();
        left.retain(|i| !taken.contains(i));
        out.push(e);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(t: &Pose2, scale: f64, n: usize, outliers: usize, seed: u64) -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for i in 0..n + outliers {
            let pb = Point2::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0));
            let pa = if i < n {
                let q = t * Point2::from(pb.coords * scale);
                q + nalgebra::Vector2::new(rng.random_range(-0.02..0.02), rng.random_range(-0.02..0.02))
            } else {
                Point2::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0))
            };
            a.push(pa);
            b.push(pb);
        }
        (a, b)
    }

    #[test]
    fn recovers_rigid_transform_among_outliers() {
        let t = pose(3.0, -1.5, 0.7);
        let (a, b) = scene(&t, 1.0, 30, 70, 1);
        let e = estimate(Model::Rigid, &a, &b, &RansacParams::default()).unwrap();
        let r = e.rigid();
        assert!((r.translation.vector - t.translation.vector).norm() < 0.02);
        assert!((r.rotation.angle() - 0.7).abs() < 0.003);
        assert!(e.inliers.iter().all(|&i| i < 30) && e.inliers.len() >= 28);
    }

    #[test]
    fn recovers_similarity_scale() {
        let t = pose(-2.0, 4.0, -2.0);
        let (a, b) = scene(&t, 2.0, 40, 40, 2);
        let e = estimate(Model::Similarity, &a, &b, &RansacParams::default()).unwrap();
        assert!((e.scale() - 2.0).abs() < 0.005, "{}", e.scale());
        assert!((e.rigid().rotation.angle() + 2.0).abs() < 0.003);
    }

    #[test]
    fn homography_of_rigid_scene_has_that_rigid_part() {
        let t = pose(1.0, 2.0, 2.5);
        let (a, b) = scene(&t, 1.0, 40, 20, 3);
        let e = estimate(Model::Homography, &a, &b, &RansacParams::default()).unwrap();
        let r = e.rigid();
        assert!((r.translation.vector - t.translation.vector).norm() < 0.05, "{r:?}");
        assert!((r.rotation.angle() - 2.5).abs() < 0.01);
        assert!(e.inliers.len() >= 38);
    }

    #[test]
    fn too_few_or_degenerate_points_give_none() {
        let p = Point2::new(1.0, 1.0);
        assert!(estimate(Model::Rigid, &[p], &[p], &RansacParams::default()).is_none());
        assert!(estimate(Model::Homography, &[p; 6], &[p; 6], &RansacParams::default()).is_none());
    }

    #[test]
    fn sequential_rounds_find_a_weaker_second_transform() {
        let (t1, t2) = (pose(3.0, -1.5, 0.7), pose(-4.0, 2.0, -2.2));
        let (mut a, mut b) = scene(&t1, 1.0, 30, 20, 5);
        let (a2, b2) = scene(&t2, 1.0, 15, 0, 6);
        a.extend(a2);
        b.extend(b2);
        let many = estimate_many(Model::Rigid, &a, &b, &RansacParams::default(), 3);
        assert!(many.len() >= 2);
        let angle = |e: &Estimate| e.rigid().rotation.angle();
        assert!((angle(&many[0]) - 0.7).abs() < 0.01 && (angle(&many[1]) + 2.2).abs() < 0.01);
        assert!(many[1].inliers.iter().all(|&i| i >= 50) && many[1].inliers.len() >= 14);
    }

    #[test]
    fn same_seed_same_answer() {
        let (a, b) = scene(&pose(1.0, 1.0, 1.0), 1.0, 20, 60, 4);
        let p = RansacParams::default();
        assert_eq!(estimate(Model::Rigid, &a, &b, &p), estimate(Model::Rigid, &a, &b, &p));
    }
}
