//! Planar lidar models: beam geometry, timing and the measurement noise of real scanners.
//!
//! Readings follow ROS REP 117: a beam that hits nothing within `range_max` reads `+inf`; a hit
//! closer than `range_min` reads `-inf`; a dropout (no usable echo) reads NaN. Core's
//! [`mrslam_core::LaserScan::is_max_range`] treats `+inf` as a max-range reading and
//! [`mrslam_core::LaserScan::is_valid`] rejects `-inf` and NaN.
//!
//! A real scanner spins: beam `i` of a scan is taken `i * time_increment` after the first, with
//! `time_increment = scan_period * resolution / 2π`. With `skew` on, each beam is cast from the pose
//! the robot had at that instant, so a moving robot's scan is distorted as on a real robot.

use crate::error::{SimError, bad_param, check_non_negative, check_positive};
use mrslam_core::sensor::{self, LidarSpec};
use mrslam_core::{Pose2, Xyt};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::{PI, TAU};

/// A planar lidar: every property of the beam pattern, timing and noise.
#[derive(Debug, Clone, PartialEq)]
pub struct LidarModel {
    /// Model name, e.g. "hokuyo_urg_04lx".
    pub name: String,
    /// Field of view, radians (2π for a full turn).
    pub fov: f64,
    /// Angle between consecutive beams, radians.
    pub resolution: f64,
    /// Shortest measurable range, metres.
    pub range_min: f64,
    /// Longest measurable range, metres.
    pub range_max: f64,
    /// Time of one scan (one revolution), seconds; a scan is published once per period.
    pub scan_period: f64,
    /// Constant part `a` of the range noise standard deviation `a + b * range`, metres.
    pub range_noise_const: f64,
    /// Proportional part `b` of the range noise standard deviation (dimensionless).
    pub range_noise_prop: f64,
    /// Standard deviation of each beam's actual direction around its nominal angle, radians.
    pub angular_jitter: f64,
    /// Probability that a beam returns no usable echo (reported as NaN).
    pub dropout_prob: f64,
    /// Pose of the sensor in the robot frame.
    pub mount: Pose2,
    /// Cast each beam at its own time within the scan (spinning-scanner skew); off: whole scan at its stamp.
    pub skew: bool,
}

impl LidarModel {
    /// A lidar of specification `spec` mounted at `mount` in the robot frame.
    pub fn from_spec(spec: &LidarSpec, mount: Pose2) -> Self {
        LidarModel {
            name: spec.name.into(),
            fov: spec.fov,
            resolution: spec.resolution,
            range_min: spec.range_min,
            range_max: spec.range_max,
            scan_period: spec.scan_period,
            range_noise_const: spec.range_noise_const,
            range_noise_prop: spec.range_noise_prop,
            angular_jitter: spec.angular_jitter,
            dropout_prob: spec.dropout_prob,
            mount,
            skew: spec.skew,
        }
    }

    /// Hokuyo URG-04LX ([`LidarSpec::hokuyo_urg_04lx`]) mounted 0.15 m ahead of the robot's centre. Experia's
    /// lidar.
    pub fn hokuyo_urg_04lx() -> Self {
        Self::from_spec(&LidarSpec::hokuyo_urg_04lx(), Pose2::new(nalgebra::Vector2::new(0.15, 0.0), 0.0))
    }

    /// Slamtec RPLIDAR A1 ([`LidarSpec::rplidar_a1`]) at the robot's centre. Prawn's lidar.
    pub fn rplidar_a1() -> Self {
        Self::from_spec(&LidarSpec::rplidar_a1(), Pose2::identity())
    }

    /// SICK LMS 200 class ([`LidarSpec::sick_lms`]) at the robot's centre (a scenario moves it with `mount`:
    /// FR079's log puts it 0.04 m behind the centre). FR079's Pioneer's lidar.
    pub fn sick_lms() -> Self {
        Self::from_spec(&LidarSpec::sick_lms(), Pose2::identity())
    }

    /// The names of the presets, as scenario files and the command line give them.
    pub const PRESETS: [&'static str; 3] = ["hokuyo_urg_04lx", "rplidar_a1", "sick_lms"];

    /// The preset called `name` (one of [`LidarModel::PRESETS`]).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "hokuyo_urg_04lx" => Some(Self::hokuyo_urg_04lx()),
            "rplidar_a1" => Some(Self::rplidar_a1()),
            "sick_lms" => Some(Self::sick_lms()),
            _ => None,
        }
    }

    /// The same model without any noise, jitter or dropouts (geometry only).
    pub fn noiseless(mut self) -> Self {
        self.range_noise_const = 0.0;
        self.range_noise_prop = 0.0;
        self.angular_jitter = 0.0;
        self.dropout_prob = 0.0;
        self
    }

    /// True when the field of view is a full turn.
    pub fn is_full_circle(&self) -> bool {
        sensor::is_full_circle(self.fov)
    }

    /// Number of beams: `fov / resolution` for a full turn, `floor(fov / resolution) + 1` otherwise.
    pub fn beam_count(&self) -> usize {
        sensor::beam_count(self.fov, self.resolution)
    }

    /// Angle of the first beam in the sensor frame (the pattern is centred on the sensor's x axis).
    pub fn angle_min(&self) -> f64 {
        if self.is_full_circle() { -PI } else { -0.5 * (self.beam_count() - 1) as f64 * self.resolution }
    }

    /// Time between consecutive beams, seconds.
    pub fn time_increment(&self) -> f64 {
        self.scan_period * self.resolution / TAU
    }

    /// Standard deviation of the range noise at range `r`.
    pub fn range_sigma(&self, r: f64) -> f64 {
        self.range_noise_const + self.range_noise_prop * r
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), SimError> {
        check_positive("LidarModel.fov", self.fov)?;
        if self.fov > TAU + 1e-9 {
            return Err(bad_param("LidarModel.fov", "must be at most 2π"));
        }
        check_positive("LidarModel.resolution", self.resolution)?;
        if self.fov / self.resolution > 1e6 {
            return Err(bad_param("LidarModel.resolution", "more than a million beams"));
        }
        check_non_negative("LidarModel.range_min", self.range_min)?;
        check_positive("LidarModel.range_max", self.range_max)?;
        if self.range_min >= self.range_max {
            return Err(bad_param("LidarModel.range_min", "must be less than range_max"));
        }
        check_positive("LidarModel.scan_period", self.scan_period)?;
        check_non_negative("LidarModel.range_noise_const", self.range_noise_const)?;
        check_non_negative("LidarModel.range_noise_prop", self.range_noise_prop)?;
        check_non_negative("LidarModel.angular_jitter", self.angular_jitter)?;
        if !(0.0..=1.0).contains(&self.dropout_prob) {
            return Err(bad_param("LidarModel.dropout_prob", "must lie in [0, 1]"));
        }
        let Xyt { x, y, theta: t } = Xyt::from_pose(&self.mount);
        if !(x.is_finite() && y.is_finite() && t.is_finite()) {
            return Err(bad_param("LidarModel.mount", "must be finite"));
        }
        Ok(())
    }

    /// Direction of beam `i` in the sensor frame, with angular jitter drawn from `rng`.
    pub fn beam_direction(&self, i: usize, rng: &mut ChaCha8Rng) -> f64 {
        let a = self.angle_min() + i as f64 * self.resolution;
        if self.angular_jitter > 0.0 {
            let n: f64 = StandardNormal.sample(rng);
            a + self.angular_jitter * n
        } else {
            a
        }
    }

    /// Turns a true range (`None`: nothing within `range_max`) into a reading, drawing noise from `rng`.
    pub fn measure(&self, true_range: Option<f64>, rng: &mut ChaCha8Rng) -> f32 {
        if self.dropout_prob > 0.0 && rng.random::<f64>() < self.dropout_prob {
            return f32::NAN;
        }
        let Some(r) = true_range.filter(|&r| r <= self.range_max) else {
            return f32::INFINITY;
        };
        if r < self.range_min {
            return f32::NEG_INFINITY;
        }
        let sigma = self.range_sigma(r);
        let m = if sigma > 0.0 {
            let n: f64 = StandardNormal.sample(rng);
            r + sigma * n
        } else {
            r
        };
        if m >= self.range_max { f32::INFINITY } else { m.max(self.range_min) as f32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn presets_have_the_papers_beam_counts() {
        let h = LidarModel::hokuyo_urg_04lx();
        let r = LidarModel::rplidar_a1();
        assert_eq!(h.beam_count(), 667);
        assert_eq!(r.beam_count(), 360);
        assert!(h.validate().is_ok() && r.validate().is_ok());
        assert!((h.angle_min() + 666.0 * 0.5 * h.resolution).abs() < 1e-12);
        assert!((h.time_increment() * 1000.0 - 0.1).abs() < 1e-9);
        assert!(!h.skew && r.skew);
        for name in LidarModel::PRESETS {
            let m = LidarModel::preset(name).unwrap();
            assert!(m.validate().is_ok() && m.name == name, "{name}");
        }
        let s = LidarModel::sick_lms();
        assert_eq!(s.beam_count(), 360);
        assert!((s.angle_min() + 89.75f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn readings_follow_rep_117() {
        let m = LidarModel::hokuyo_urg_04lx().noiseless();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert_eq!(m.measure(None, &mut rng), f32::INFINITY);
        assert_eq!(m.measure(Some(5.0), &mut rng), f32::INFINITY);
        assert_eq!(m.measure(Some(0.01), &mut rng), f32::NEG_INFINITY);
        assert_eq!(m.measure(Some(1.5), &mut rng), 1.5);
        let d = LidarModel { dropout_prob: 1.0, ..m };
        assert!(d.measure(Some(1.5), &mut rng).is_nan());
    }

    #[test]
    fn validation_rejects_bad_models() {
        let m = LidarModel::rplidar_a1();
        assert!(LidarModel { range_min: 7.0, ..m.clone() }.validate().is_err());
        assert!(LidarModel { resolution: 0.0, ..m.clone() }.validate().is_err());
        assert!(LidarModel { dropout_prob: 1.5, ..m }.validate().is_err());
    }
}
