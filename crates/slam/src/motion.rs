//! The odometry motion model: GMapping's `MotionModel::drawFromMotion`.

use mrslam_core::{Pose2, pose, pose::normalize_angle};
#[cfg(test)]
use mrslam_core::{Xyt, pose::relative};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// GMapping's odometry noise parameters, named as GMapping's except `str` (`trans_from_rot`); defaults GMapping's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotionModel {
    /// `srr`: odometry translation error from translation (GMapping 0.1).
    pub srr: f64,
    /// `srt`: odometry rotation error from translation, rad/m (GMapping 0.2).
    pub srt: f64,
    /// GMapping's `str`: odometry translation error from rotation, m/rad (GMapping 0.1).
    pub trans_from_rot: f64,
    /// `stt`: odometry rotation error from rotation (GMapping 0.2).
    pub stt: f64,
}

impl Default for MotionModel {
    fn default() -> Self {
        MotionModel { srr: 0.1, srt: 0.2, trans_from_rot: 0.1, stt: 0.2 }
    }
}

/// A zero-mean Gaussian draw of standard deviation `sigma` (0 when sigma is 0, as GMapping's).
fn gaussian<R: Rng>(rng: &mut R, sigma: f64) -> f64 {
    if sigma == 0.0 {
        return 0.0;
    }
    let z: f64 = rng.sample(StandardNormal);
    z * sigma
}

impl MotionModel {
    /// Samples a new pose for a particle at `p` given the odometry moved from `old` to `new`.
    ///
    /// GMapping's formula: the increment `delta = old⁻¹ ⊕ new` (in the old odometry frame) gets noise
    /// `x += N(srr|dx| + str|dθ| + 0.3·srr|dy|)`, `y += N(srr|dy| + str|dθ| + 0.3·srr|dx|)` (`str`: `trans_from_rot`),
    /// `θ += N(stt|dθ| + srt·|(dx, dy)|)` (standard deviations), and is composed onto `p`.
    #[cfg(test)]
    pub fn draw_from_motion<R: Rng>(&self, rng: &mut R, p: &Pose2, new: &Pose2, old: &Pose2) -> Pose2 {
        let Xyt { x: dx, y: dy, theta: dt } = Xyt::from_pose(&relative(old, new));
        self.draw_increment(rng, p, dx, dy, dt)
    }

    /// Standard deviations (x, y, θ) of the noise on an increment (dx, dy, dθ) in the robot's frame.
    pub fn sigmas(&self, dx: f64, dy: f64, dt: f64) -> [f64; 3] {
        let sxy = 0.3 * self.srr;
        [
            self.srr * dx.abs() + self.trans_from_rot * dt.abs() + sxy * dy.abs(),
            self.srr * dy.abs() + self.trans_from_rot * dt.abs() + sxy * dx.abs(),
            self.stt * dt.abs() + self.srt * dx.hypot(dy),
        ]
    }

    /// Samples `p ⊕ noisy(dx, dy, dθ)` for an increment given in the robot's frame.
    pub fn draw_increment<R: Rng>(&self, rng: &mut R, p: &Pose2, dx: f64, dy: f64, dt: f64) -> Pose2 {
        let [sx, sy, st] = self.sigmas(dx, dy, dt);
        let nx = dx + gaussian(rng, sx);
        let ny = dy + gaussian(rng, sy);
        let nt = dt + gaussian(rng, st);
        p * pose(nx, ny, normalize_angle(nt))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn no_motion_no_noise() {
        let m = MotionModel { srr: 0.1, srt: 0.2, trans_from_rot: 0.1, stt: 0.2 };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let p = pose(1.0, 2.0, 0.3);
        let q = m.draw_from_motion(&mut rng, &p, &pose(5.0, 5.0, 1.0), &pose(5.0, 5.0, 1.0));
        assert_eq!(p, q);
    }

    #[test]
    fn spread_follows_srr() {
        let m = MotionModel { srr: 0.1, srt: 0.2, trans_from_rot: 0.1, stt: 0.2 };
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 20_000;
        let (mut sx, mut sxx, mut st) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            // 1 m straight ahead, seen from a rotated odometry frame: the increment is what counts.
            let q = m.draw_from_motion(
                &mut rng,
                &pose(0.0, 0.0, 0.0),
                &pose(2.0, 1.0 + 1.0, std::f64::consts::FRAC_PI_2),
                &pose(2.0, 1.0, std::f64::consts::FRAC_PI_2),
            );
            let Xyt { x, theta: t, .. } = Xyt::from_pose(&q);
            sx += x;
            sxx += x * x;
            st += t * t;
        }
        let mean = sx / n as f64;
        let sd = (sxx / n as f64 - mean * mean).sqrt();
        assert!((mean - 1.0).abs() < 0.005, "{mean}");
        assert!((sd - 0.1).abs() < 0.005, "{sd}");
        assert!(((st / n as f64).sqrt() - 0.2).abs() < 0.01);
    }
}
