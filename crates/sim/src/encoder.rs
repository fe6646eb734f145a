//! Wheel encoders and odometry integrated from their ticks, as on a real robot.
//!
//! Encoders count how far the wheels turned, not where the body went: slip and pushing against a
//! wall turn into odometry drift. The integration may use a mis-calibrated wheel radius and base.

use crate::error::{SimError, bad_param, check_positive};
use mrslam_core::{Odometry, Pose2, pose};
use std::f64::consts::TAU;

/// Encoder resolution and the odometry's calibration errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderParams {
    /// Ticks per wheel revolution (quantisation).
    pub ticks_per_rev: u32,
    /// Relative error of the left wheel radius assumed by the odometry (0.01 = 1 % too large).
    pub left_radius_error: f64,
    /// Relative error of the right wheel radius assumed by the odometry.
    pub right_radius_error: f64,
    /// Relative error of the wheel base assumed by the odometry.
    pub wheel_base_error: f64,
}

impl Default for EncoderParams {
    /// 2048 ticks per revolution, perfectly calibrated.
    fn default() -> Self {
        EncoderParams { ticks_per_rev: 2048, left_radius_error: 0.0, right_radius_error: 0.0, wheel_base_error: 0.0 }
    }
}

impl EncoderParams {
    /// The same encoders with a systematic calibration error (relative radius and base errors).
    pub fn with_calibration_error(mut self, left: f64, right: f64, base: f64) -> Self {
        self.left_radius_error = left;
        self.right_radius_error = right;
        self.wheel_base_error = base;
        self
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.ticks_per_rev == 0 {
            return Err(bad_param("EncoderParams.ticks_per_rev", "must be at least 1"));
        }
        for (f, v) in [
            ("EncoderParams.left_radius_error", self.left_radius_error),
            ("EncoderParams.right_radius_error", self.right_radius_error),
            ("EncoderParams.wheel_base_error", self.wheel_base_error),
        ] {
            if !(v.is_finite() && v > -0.5 && v < 0.5) {
                return Err(bad_param(f, format!("must lie in (-0.5, 0.5), got {v}")));
            }
        }
        Ok(())
    }
}

/// Two wheel encoders and the odometry integrated from them.
#[derive(Debug, Clone)]
pub struct Encoders {
    params: EncoderParams,
    /// True wheel rotation since start, radians (left, right).
    angle: [f64; 2],
    /// Ticks already integrated into the odometry.
    ticks: [i64; 2],
    /// Wheel radii and base the odometry assumes.
    radius: [f64; 2],
    base: f64,
    odom: Pose2,
    stamp: f64,
}

impl Encoders {
    /// Encoders of wheels of radius `wheel_radius` on a base of `wheel_base` metres; odometry at identity.
    pub fn new(params: EncoderParams, wheel_radius: f64, wheel_base: f64, stamp: f64) -> Result<Self, SimError> {
        params.validate()?;
        check_positive("RobotModel.wheel_radius", wheel_radius)?;
        check_positive("RobotModel.wheel_base", wheel_base)?;
        Ok(Encoders {
            params,
            angle: [0.0; 2],
            ticks: [0; 2],
            radius: [wheel_radius * (1.0 + params.left_radius_error), wheel_radius * (1.0 + params.right_radius_error)],
            base: wheel_base * (1.0 + params.wheel_base_error),
            odom: Pose2::identity(),
            stamp,
        })
    }

    /// Tick counts (left, right) since start.
    pub fn ticks(&self) -> [i64; 2] {
        self.tick_count()
    }

    fn tick_count(&self) -> [i64; 2] {
        let k = self.params.ticks_per_rev as f64 / TAU;
        self.angle.map(|a| (a * k).floor() as i64)
    }

    /// The wheels turned by `dphi` radians (left, right); integrates new ticks into the odometry.
    pub fn advance(&mut self, dphi: [f64; 2], stamp: f64) {
        self.angle[0] += dphi[0];
        self.angle[1] += dphi[1];
        let t = self.tick_count();
        let per_tick = TAU / self.params.ticks_per_rev as f64;
        let dl = (t[0] - self.ticks[0]) as f64 * per_tick * self.radius[0];
        let dr = (t[1] - self.ticks[1]) as f64 * per_tick * self.radius[1];
        self.ticks = t;
        self.stamp = stamp;
        if dl == 0.0 && dr == 0.0 {
            return;
        }
        let ds = 0.5 * (dl + dr);
        let dth = (dr - dl) / self.base;
        // Exact arc integration (the robot moved on a circle during the tick interval).
        let (dx, dy) = if dth.abs() < 1e-9 {
            (ds, 0.0)
        } else {
            let r = ds / dth;
            (r * dth.sin(), r * (1.0 - dth.cos()))
        };
        self.odom *= pose(dx, dy, dth);
    }

    /// The odometry reading: the integrated pose in the odometry frame (identity at start).
    pub fn odometry(&self) -> Odometry {
        Odometry { stamp: self.stamp, pose: self.odom }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::Xyt;
    use std::f64::consts::PI;

    #[test]
    fn straight_line_is_quantised_to_ticks() {
        let mut e = Encoders::new(EncoderParams::default(), 0.05, 0.3, 0.0).unwrap();
        // one full revolution plus a fraction of a tick
        e.advance([TAU + 0.5 * TAU / 2048.0; 2], 1.0);
        let Xyt { x, y, theta: t } = Xyt::from_pose(&e.odometry().pose);
        assert!((x - TAU * 0.05).abs() < 1e-12 && y.abs() < 1e-12 && t.abs() < 1e-12);
        assert_eq!(e.ticks(), [2048, 2048]);
        assert_eq!(e.odometry().stamp, 1.0);
    }

    #[test]
    fn turning_in_place_integrates_heading() {
        let mut e =
            Encoders::new(EncoderParams { ticks_per_rev: 100_000, ..Default::default() }, 0.05, 0.3, 0.0).unwrap();
        // wheels travel +-0.15 * pi/2 -> quarter turn
        let phi = 0.15 * PI / 2.0 / 0.05;
        for _ in 0..100 {
            e.advance([-phi / 100.0, phi / 100.0], 0.0);
        }
        let Xyt { x, y, theta: t } = Xyt::from_pose(&e.odometry().pose);
        assert!(x.abs() < 1e-4 && y.abs() < 1e-4 && (t - PI / 2.0).abs() < 1e-3, "{x} {y} {t}");
    }

    #[test]
    fn calibration_error_scales_distance() {
        let p = EncoderParams::default().with_calibration_error(0.01, 0.01, 0.0);
        let mut e = Encoders::new(p, 0.05, 0.3, 0.0).unwrap();
        e.advance([100.0, 100.0], 0.0);
        let Xyt { x, .. } = Xyt::from_pose(&e.odometry().pose);
        assert!((x / 5.0 - 1.01).abs() < 1e-3);
        assert!(EncoderParams { ticks_per_rev: 0, ..p }.validate().is_err());
    }

    #[test]
    fn arc_integration_matches_circle() {
        let mut e =
            Encoders::new(EncoderParams { ticks_per_rev: 1 << 20, ..Default::default() }, 0.05, 0.3, 0.0).unwrap();
        // radius R = 1 m circle, half a turn: left travels (1-0.15)*pi, right (1+0.15)*pi
        for _ in 0..1000 {
            e.advance([0.85 * PI / 0.05 / 1000.0, 1.15 * PI / 0.05 / 1000.0], 0.0);
        }
        let Xyt { x, y, theta: t } = Xyt::from_pose(&e.odometry().pose);
        assert!(x.abs() < 1e-4 && (y - 2.0).abs() < 1e-4 && (t.abs() - PI).abs() < 1e-4, "{x} {y} {t}");
    }
}
