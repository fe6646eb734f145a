//! Laser scans and odometry readings, as a robot's drivers deliver them.

use crate::pose::interpolate;
use crate::se2::Pose2;
use nalgebra::Point2;

/// One planar laser scan, laid out as ROS's `sensor_msgs/LaserScan`.
///
/// Beam `i` points at `angle_min + i * angle_increment` in the sensor frame. A range outside
/// `[range_min, range_max)` or not finite is invalid; `range_max` or +inf means "nothing within range".
#[derive(Debug, Clone, PartialEq)]
pub struct LaserScan {
    /// Time the first beam was taken, seconds.
    pub stamp: f64,
    /// Angle of the first beam in the sensor frame, radians.
    pub angle_min: f64,
    /// Angle between consecutive beams, radians (negative for clockwise scanners).
    pub angle_increment: f64,
    /// Shortest range the sensor reports, metres.
    pub range_min: f32,
    /// Longest range the sensor reports, metres.
    pub range_max: f32,
    /// Measured ranges, metres, one per beam.
    pub ranges: Vec<f32>,
}

impl LaserScan {
    /// Number of beams.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// True when the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Angle of beam `i` in the sensor frame.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min + i as f64 * self.angle_increment
    }

    /// True when beam `i` measured a hit inside the sensor's range limits.
    pub fn is_valid(&self, i: usize) -> bool {
        let r = self.ranges[i];
        r.is_finite() && r >= self.range_min && r < self.range_max
    }

    /// True when beam `i` saw nothing within range (max-range reading or +inf).
    pub fn is_max_range(&self, i: usize) -> bool {
        let r = self.ranges[i];
        r == f32::INFINITY || (r.is_finite() && r >= self.range_max)
    }

    /// Number of valid beams.
    pub fn valid_count(&self) -> usize {
        (0..self.len()).filter(|&i| self.is_valid(i)).count()
    }

    /// End point of beam `i` at range `r`, in the frame in which the sensor sits at `sensor_pose`.
    pub fn point_at(&self, sensor_pose: &Pose2, i: usize, r: f64) -> Point2<f64> {
        let a = self.angle(i);
        sensor_pose * Point2::new(r * a.cos(), r * a.sin())
    }

    /// End points of the valid beams, with their beam index, in the frame of `sensor_pose`.
    pub fn endpoints<'a>(&'a self, sensor_pose: &'a Pose2) -> impl Iterator<Item = (usize, Point2<f64>)> + 'a {
        (0..self.len())
            .filter(|&i| self.is_valid(i))
            .map(move |i| (i, self.point_at(sensor_pose, i, self.ranges[i] as f64)))
    }
}

/// An odometry reading: the robot's pose as its wheel encoders integrate it, in the odometry frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry {
    /// Time of the reading, seconds.
    pub stamp: f64,
    /// Integrated pose in the odometry frame.
    pub pose: Pose2,
}

impl Odometry {
    /// The pose at `t` between this reading and a later one `next`, interpolated; at either reading's own stamp
    /// that reading's pose as it is (through the interpolation its heading would come back an ulp off, and a
    /// particle filter turns an ulp into another map).
    pub fn towards(&self, next: &Odometry, t: f64) -> Pose2 {
        if t == self.stamp || next.stamp <= self.stamp {
            self.pose
        } else if t == next.stamp {
            next.pose
        } else {
            interpolate(&self.pose, &next.pose, (t - self.stamp) / (next.stamp - self.stamp))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::se2::pose;

    #[test]
    fn a_pose_between_readings_is_either_reading_as_it_is_at_its_stamp() {
        // 0.173078: a heading whose trip through an interpolation comes back an ulp off.
        let a = Odometry { stamp: 1.0, pose: pose(0.0, 0.0, -0.173078) };
        let b = Odometry { stamp: 2.0, pose: pose(1.0, 0.0, 0.280918) };
        assert_eq!((a.towards(&b, 1.0), a.towards(&b, 2.0)), (a.pose, b.pose));
        assert!((crate::Xyt::from_pose(&a.towards(&b, 1.5)).x - 0.5).abs() < 1e-12);
        assert_eq!(a.towards(&Odometry { stamp: 1.0, ..b }, 1.0), a.pose, "two readings of one stamp");
    }

    fn scan(ranges: Vec<f32>) -> LaserScan {
        LaserScan {
            stamp: 0.0,
            angle_min: -std::f64::consts::FRAC_PI_2,
            angle_increment: std::f64::consts::FRAC_PI_2,
            range_min: 0.1,
            range_max: 4.0,
            ranges,
        }
    }

    #[test]
    fn validity_follows_range_limits() {
        let s = scan(vec![0.05, 1.0, 4.0, f32::NAN, f32::INFINITY, -1.0]);
        let valid: Vec<bool> = (0..s.len()).map(|i| s.is_valid(i)).collect();
        assert_eq!(valid, [false, true, false, false, false, false]);
        assert!(s.is_max_range(2) && s.is_max_range(4) && !s.is_max_range(3));
        assert_eq!(s.valid_count(), 1);
    }

    #[test]
    fn endpoints_are_in_the_given_frame() {
        let s = scan(vec![1.0, 2.0, 3.0]);
        let p = pose(1.0, 1.0, std::f64::consts::FRAC_PI_2);
        let pts: Vec<_> = s.endpoints(&p).collect();
        // beam 0 points to the sensor's right (-y), which is +x in the world after a +90 deg turn
        assert!((pts[0].1.x - 2.0).abs() < 1e-9 && (pts[0].1.y - 1.0).abs() < 1e-9);
        // beam 1 points straight ahead: +y in the world
        assert!((pts[1].1.x - 1.0).abs() < 1e-9 && (pts[1].1.y - 3.0).abs() < 1e-9);
    }
}
