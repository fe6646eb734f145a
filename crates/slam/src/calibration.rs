//! Online odometry calibration ([`crate::FilterParams::odometry_calibration`]; not GMapping).
//!
//! Model: a raw odometry increment (dx, dy, dθ) is corrected to ((1+a)·dx, (1+a)·dy, dθ + b·dx): a distance
//! scale error a (wheel radii, slip) and a heading drift b per metre driven forward (unequal wheel radii).
//! (A rotation scale error, a wrong wheel base, is not estimated: on a gently curving route turning and
//! driving go together and cannot be told apart from b; the scan observes the heading well anyway.)
//!
//! κ = (a, b) is estimated by an information filter whose measurements are the scan matches. At each update,
//! particle p's match m (the mode of the scan score plus the motion prior centred on its motion-model sample
//! s) implies the scan-only optimum z through H_s·(z − s) = (H_s + H_prior)·(m − s), H_s and H_prior being
//! the scan's and the prior's information at m (from the matcher). z − ĉ, with ĉ the calibrated odometry's
//! prediction from the particle's previous pose, measures J·(κ_true − κ) with information H_s, where J is the
//! increment's derivative by κ. A direction the scan does not observe (H_s ≈ 0) teaches nothing, which is
//! why the residual is not simply m − ĉ: there the prior holds the match at the sample. Particles contribute
//! by weight; older information fades by exp(−distance / memory), so that κ can follow a change of floor.

use mrslam_core::Xyt;
use mrslam_core::pose::normalize_angle;
use mrslam_core::{Pose2, pose};
use mrslam_matching::Information;

/// Prior standard deviation of each calibration parameter (distance scale error, heading drift in rad/m)
/// around 0, in the information units of the motion prior (those of the `field` matcher's score): a few
/// updates' worth of scan data override it.
const PRIOR_SIGMA: f64 = 0.02;
/// Largest magnitude of each calibration parameter.
const LIMIT: f64 = 0.3;

/// The calibration's state: the estimate, its information, and the odometry since the last processed scan.
#[derive(Debug, Clone, Default)]
pub(crate) struct OdometryCalibration {
    /// κ = (a, b).
    kappa: [f64; 2],
    /// Information about κ from the data (00 01 11), without the prior.
    info: [f64; 3],
    /// Raw odometry increments since the last processed scan, composed (robot frame of that scan).
    raw: Option<Pose2>,
    /// Calibrated increments since the last processed scan, composed.
    corrected: Option<Pose2>,
    /// Σ dx of the raw increments since the last processed scan.
    forward: f64,
}

/// One particle's match at an update, as the calibration learns from it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CalibrationMatch {
    /// The matched pose m.
    pub matched: Xyt,
    /// The motion-model sample s the match started from (the prior's centre).
    pub start: Xyt,
    /// The particle's pose at the previous update.
    pub previous: Xyt,
    /// The scan's information at m (map frame).
    pub scan: Information,
    /// The motion prior's information.
    pub prior: Information,
    /// The particle's normalised weight.
    pub weight: f64,
}

impl OdometryCalibration {
    /// The estimate (a, b).
    pub fn kappa(&self) -> [f64; 2] {
        self.kappa
    }

    /// The calibrated increment of a raw one.
    pub fn correct(&self, raw: Xyt) -> Xyt {
        let [a, b] = self.kappa;
        Xyt { x: (1.0 + a) * raw.x, y: (1.0 + a) * raw.y, theta: raw.theta + b * raw.x }
    }

    /// Records a raw increment and its calibrated version.
    pub fn record(&mut self, raw: Xyt, corrected: Xyt) {
        let compose = |acc: Option<Pose2>, d: Xyt| Some(acc.unwrap_or_else(Pose2::identity) * d.to_pose());
        self.raw = compose(self.raw, raw);
        self.corrected = compose(self.corrected, corrected);
        self.forward += raw.x;
    }

    /// Forgets the increments (after a processed scan).
    pub fn reset_increments(&mut self) {
        self.raw = None;
        self.corrected = None;
        self.forward = 0.0;
    }

    /// One step of the information filter from the matches of an update (in particle order, so the result
    /// does not depend on threads); what it knew fades over `memory` metres driven.
    pub fn update(&mut self, matches: impl Iterator<Item = CalibrationMatch>, memory: f64) {
        let (Some(raw), Some(corrected)) = (self.raw, self.corrected) else { return };
        let Xyt { x: rx, y: ry, .. } = Xyt::from_pose(&raw);
        let forward = self.forward;
        let dot = |u: &[f64; 3], v: &[f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let diff = |p: &Xyt, q: &Xyt| [p.x - q.x, p.y - q.y, normalize_angle(p.theta - q.theta)];
        let (mut a, mut g) = ([0.0f64; 3], [0.0f64; 2]);
        for CalibrationMatch { matched, start, previous: prev, scan: hs, prior: hp, weight: w } in matches {
            // the calibrated odometry's prediction from the previous pose
            let Xyt { x: cx, y: cy, theta: ct } = Xyt::from_pose(&(pose(prev.x, prev.y, prev.theta) * corrected));
            let c = Xyt { x: cx, y: cy, theta: ct };
            // H_s (z - c) = (H_s + H_prior) (m - s) + H_s (s - c)
            let mut ht = hs;
            add_sym(&mut ht, &hp, 1.0);
            let (r1, r2) = (sym_mul(&ht, &diff(&matched, &start)), sym_mul(&hs, &diff(&start, &c)));
            let r = [r1[0] + r2[0], r1[1] + r2[1], r1[2] + r2[2]];
            // J's columns, d(increment)/d(a, b), in the map frame
            let (s, co) = prev.theta.sin_cos();
            let cols = [[co * rx - s * ry, s * rx + co * ry, 0.0], [0.0, 0.0, forward]];
            let hcols = [sym_mul(&hs, &cols[0]), sym_mul(&hs, &cols[1])];
            a[0] += w * dot(&cols[0], &hcols[0]);
            a[1] += w * dot(&cols[0], &hcols[1]);
            a[2] += w * dot(&cols[1], &hcols[1]);
            g[0] += w * dot(&cols[0], &r);
            g[1] += w * dot(&cols[1], &r);
        }
        let fade = (-forward.abs() / memory).exp();
        for (i, ak) in self.info.iter_mut().zip(a) {
            *i = fade * *i + ak;
        }
        let p0 = 1.0 / (PRIOR_SIGMA * PRIOR_SIGMA);
        let (h00, h01, h11) = (self.info[0] + p0, self.info[1], self.info[2] + p0);
        let det = h00 * h11 - h01 * h01;
        if det.is_finite() && det > 0.0 {
            let step = [(h11 * g[0] - h01 * g[1]) / det, (h00 * g[1] - h01 * g[0]) / det];
            for (k, s) in self.kappa.iter_mut().zip(step) {
                *k = (*k + s).clamp(-LIMIT, LIMIT);
            }
        }
    }
}

/// Adds the symmetric 3x3 matrix `m` times `w` to `acc`.
fn add_sym(acc: &mut Information, m: &Information, w: f64) {
    for k in 0..6 {
        acc[k] += w * m[k];
    }
}

/// The symmetric 3x3 matrix `m` times vector `v`.
fn sym_mul(m: &Information, v: &[f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[1] * v[0] + m[3] * v[1] + m[4] * v[2],
        m[2] * v[0] + m[4] * v[1] + m[5] * v[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrects_increments_and_composes_what_it_saw() {
        let mut c = OdometryCalibration { kappa: [-0.1, 0.02], ..Default::default() };
        let Xyt { x: dx, y: dy, theta: dt } = c.correct(Xyt { x: 1.0, y: 0.5, theta: 0.1 });
        assert!((dx - 0.9).abs() < 1e-12 && (dy - 0.45).abs() < 1e-12 && (dt - 0.12).abs() < 1e-12);
        let forward = Xyt { x: 1.0, y: 0.0, theta: 0.0 };
        c.record(forward, c.correct(forward));
        c.record(forward, c.correct(forward));
        assert!((c.forward - 2.0).abs() < 1e-12);
        assert!((Xyt::from_pose(&c.raw.unwrap()).x - 2.0).abs() < 1e-12);
        c.reset_increments();
        assert!(c.raw.is_none() && c.corrected.is_none() && c.forward == 0.0);
        // Nothing recorded: an update learns nothing.
        c.update(std::iter::empty(), 20.0);
        assert_eq!(c.kappa(), [-0.1, 0.02]);
    }
}
