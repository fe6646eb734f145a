//! Sensor specifications as data: the lidars of the testbed's robots, from their data sheets.
//!
//! The simulator's lidar model (`mrslam-sim`) and the SLAM crate's synthetic scans both start from these, so
//! a scanner's numbers are written once.

use std::f64::consts::TAU;

/// A planar lidar's beam pattern, timing and range noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LidarSpec {
    /// Model name, e.g. "hokuyo_urg_04lx".
    pub name: &'static str,
    /// Field of view, radians (2π for a full turn).
    pub fov: f64,
    /// Angle between consecutive beams, radians.
    pub resolution: f64,
    /// Shortest measurable range, metres.
    pub range_min: f64,
    /// Longest measurable range, metres.
    pub range_max: f64,
    /// Time of one scan (one revolution), seconds.
    pub scan_period: f64,
    /// Constant part `a` of the range noise standard deviation `a + b * range`, metres.
    pub range_noise_const: f64,
    /// Proportional part `b` of the range noise standard deviation (dimensionless).
    pub range_noise_prop: f64,
    /// Standard deviation of each beam's actual direction around its nominal angle, radians.
    pub angular_jitter: f64,
    /// Probability that a beam returns no usable echo.
    pub dropout_prob: f64,
    /// Whether the scanner spins slowly enough for a moving robot to skew its scans.
    pub skew: bool,
}

impl LidarSpec {
    /// Hokuyo URG-04LX: 240°, 0.36° (667 beams), 0.06–4 m, 100 ms, 1 cm + 0.5 % of the range, 0.2 % dropouts.
    pub fn hokuyo_urg_04lx() -> Self {
        LidarSpec {
            name: "hokuyo_urg_04lx",
            fov: 240f64.to_radians(),
            resolution: 0.36f64.to_radians(),
            range_min: 0.06,
            range_max: 4.0,
            scan_period: 0.1,
            range_noise_const: 0.01,
            range_noise_prop: 0.005,
            angular_jitter: 0.0,
            dropout_prob: 0.002,
            skew: false,
        }
    }

    /// Slamtec RPLIDAR A1: 360°, 1° (360 beams), 0.2–6 m, 200 ms, 5 mm + 1 % of the range, 0.1° angular
    /// jitter, 1 % dropouts, skewed.
    pub fn rplidar_a1() -> Self {
        LidarSpec {
            name: "rplidar_a1",
            fov: TAU,
            resolution: 1f64.to_radians(),
            range_min: 0.2,
            range_max: 6.0,
            scan_period: 0.2,
            range_noise_const: 0.005,
            range_noise_prop: 0.01,
            angular_jitter: 0.1f64.to_radians(),
            dropout_prob: 0.01,
            skew: true,
        }
    }

    /// SICK LMS 200 class, as the FR079 log has it: 0.5° beams over 179.5° (the 360 beams CARMEN logs of the
    /// LMS's 361), 80 m nominal reach (cm mode; indoors the building ends the beams: FR079's longest return is
    /// 36.5 m), 0.05 m shortest range, a scan every 0.2 s (the log's 4.65 Hz, the serial line's rate), range noise
    /// 1 cm from the data sheet (cm mode's resolution; `mrslam sim replay` on FR079 fits 3.6 cm + 0.16 % of the
    /// range, which is mostly the replay world's 5 cm cells and the trajectory's error, not the sensor), no
    /// dropouts (FR079's 2 % of missed surfaces are glass and the map's gaps). The mirror sweeps a scan in
    /// 13 ms: no skew.
    pub fn sick_lms() -> Self {
        LidarSpec {
            name: "sick_lms",
            fov: 179.5f64.to_radians(),
            resolution: 0.5f64.to_radians(),
            range_min: 0.05,
            range_max: 80.0,
            scan_period: 0.2,
            range_noise_const: 0.01,
            range_noise_prop: 0.0,
            angular_jitter: 0.0,
            dropout_prob: 0.0,
            skew: false,
        }
    }

    /// True when the field of view is a full turn.
    pub fn is_full_circle(&self) -> bool {
        is_full_circle(self.fov)
    }

    /// Number of beams (see [`beam_count`]).
    pub fn beam_count(&self) -> usize {
        beam_count(self.fov, self.resolution)
    }
}

/// True when a field of view `fov` (radians) is a full turn.
pub fn is_full_circle(fov: f64) -> bool {
    fov >= TAU - 1e-9
}

/// Beams of a scanner of field of view `fov` and angle `resolution` between beams (radians):
/// `fov / resolution` for a full turn (the last beam would repeat the first), `floor(fov / resolution) + 1`
/// otherwise.
pub fn beam_count(fov: f64, resolution: f64) -> usize {
    if is_full_circle(fov) {
        (TAU / resolution).round().max(1.0) as usize
    } else {
        (fov / resolution + 1e-9).floor() as usize + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_presets_have_their_data_sheets_beam_counts() {
        assert_eq!(LidarSpec::hokuyo_urg_04lx().beam_count(), 667);
        assert_eq!(LidarSpec::rplidar_a1().beam_count(), 360);
        assert_eq!(LidarSpec::sick_lms().beam_count(), 360, "as FR079's log has it");
        assert!(LidarSpec::rplidar_a1().is_full_circle() && !LidarSpec::hokuyo_urg_04lx().is_full_circle());
    }
}
