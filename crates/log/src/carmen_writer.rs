//! Writing CARMEN logs: what [`crate::carmen::parse`] reads, so a simulated run can be mapped by any SLAM
//! that reads the benchmark logs (ours, GMapping, Cartographer's converters).
//!
//! Each scan is a `ROBOTLASER1` line, which carries the laser's geometry (start angle, field of view, beam
//! spacing, range limit) and its mount (the laser pose beside the robot's odometry pose), so no PARAM lines
//! are needed; the odometry stream is `ODOM` lines, or nothing when odometry is to be read from the scan lines
//! alone. Numbers are written with enough digits to read back what was written (ranges to the millimetre's
//! thousandth, poses to the micrometre, stamps to the microsecond).

use mrslam_core::{LaserScan, Odometry, Pose2, Xyt};
use std::io::Write;

/// The host name CARMEN lines carry; the readers ignore it.
const HOST: &str = "mrslam";

/// Writes CARMEN lines to `out`.
pub struct CarmenWriter<W: Write> {
    out: W,
    /// The previous odometry reading, for the velocities of an ODOM line.
    last_odometry: Option<Odometry>,
}

impl<W: Write> CarmenWriter<W> {
    /// A writer that starts with `header` as `#` comment lines.
    pub fn new(mut out: W, header: &str) -> std::io::Result<Self> {
        for line in header.lines() {
            writeln!(out, "# {line}")?;
        }
        Ok(Self { out, last_odometry: None })
    }

    /// Writes an `ODOM x y theta tv rv accel stamp host stamp` line; the velocities are the change since the
    /// previous ODOM line (tv signed by the direction of travel), accel 0.
    pub fn odometry(&mut self, odometry: &Odometry) -> std::io::Result<()> {
        let Xyt { x, y, theta } = Xyt::from_pose(&odometry.pose);
        let (tv, rv) = match self.last_odometry {
            Some(prev) if odometry.stamp > prev.stamp => {
                let dt = odometry.stamp - prev.stamp;
                let step = prev.pose.inv_mul(&odometry.pose);
                (step.translation.x.signum() * step.translation.vector.norm() / dt, step.rotation.angle() / dt)
            }
            _ => (0.0, 0.0),
        };
        self.last_odometry = Some(*odometry);
        let t = odometry.stamp;
        writeln!(self.out, "ODOM {x:.6} {y:.6} {theta:.6} {tv:.6} {rv:.6} 0 {t:.6} {HOST} {t:.6}")
    }

    /// Writes a `ROBOTLASER1` line: `scan` taken by a laser mounted at `mount` on a robot whose odometry pose
    /// at the scan is `odometry`.
    pub fn scan(&mut self, scan: &LaserScan, odometry: &Odometry, mount: &Pose2) -> std::io::Result<()> {
        let fov = scan.angle_increment * scan.len().saturating_sub(1) as f64;
        write!(
            self.out,
            "ROBOTLASER1 0 {:.9} {:.9} {:.9} {} 0.01 0 {}",
            scan.angle_min,
            fov,
            scan.angle_increment,
            scan.range_max,
            scan.len()
        )?;
        for &r in &scan.ranges {
            // A beam with no return (NaN, or beyond the range) is logged as CARMEN does: at the range limit.
            let r = if r.is_finite() { r } else { scan.range_max };
            write!(self.out, " {r:.6}")?;
        }
        let laser = Xyt::from_pose(&(odometry.pose * mount));
        let robot = Xyt::from_pose(&odometry.pose);
        let t = scan.stamp;
        writeln!(
            self.out,
            " 0 {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} 0 0 0 0 0 {t:.6} {HOST} {t:.6}",
            laser.x, laser.y, laser.theta, robot.x, robot.y, robot.theta
        )
    }

    /// Flushes and returns the output.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ReadOptions, carmen};
    use mrslam_core::pose;

    #[test]
    fn what_is_written_reads_back() {
        let mount = pose(0.1, -0.05, 0.02);
        let scans: Vec<(LaserScan, Odometry)> = (0..5)
            .map(|k| {
                let t = 10.0 + 0.2 * k as f64;
                let odom = Odometry { stamp: t, pose: pose(0.3 * k as f64, 0.01 * k as f64, 0.05 * k as f64) };
                let ranges = vec![1.25, f32::NAN, 3.5 + k as f32 * 0.001, 7.999];
                let scan = LaserScan {
                    stamp: t,
                    angle_min: -1.2,
                    angle_increment: 0.8,
                    range_min: 0.0,
                    range_max: 8.0,
                    ranges,
                };
                (scan, odom)
            })
            .collect();
        let mut w = CarmenWriter::new(Vec::new(), "a test\nsecond line").unwrap();
        for (scan, odom) in &scans {
            w.odometry(odom).unwrap();
            w.scan(scan, odom, &mount).unwrap();
        }
        let text = w.finish().unwrap();
        let log = carmen::parse(text.as_slice(), std::path::Path::new("w.clf"), &ReadOptions::default()).unwrap();
        assert_eq!(log.scans.len(), 5);
        assert_eq!(log.odometry.len(), 5);
        for ((scan, odom), rec) in scans.iter().zip(&log.scans) {
            assert_eq!(rec.scan.len(), 4);
            assert!((rec.scan.angle_min - scan.angle_min).abs() < 1e-9);
            assert!((rec.scan.angle_increment - scan.angle_increment).abs() < 1e-9);
            assert_eq!(rec.scan.range_max, 8.0);
            assert_eq!(rec.scan.ranges[0], 1.25);
            assert_eq!(rec.scan.ranges[1], 8.0, "no return is logged at the range limit");
            assert!((rec.scan.ranges[2] - scan.ranges[2]).abs() < 1e-6);
            assert!((rec.odometry.stamp - odom.stamp).abs() < 1e-9);
            let d = rec.odometry.pose.inv_mul(&odom.pose);
            assert!(d.translation.vector.norm() < 1e-5 && d.rotation.angle().abs() < 1e-5);
            let m = rec.laser_offset.inv_mul(&mount);
            assert!(m.translation.vector.norm() < 1e-5 && m.rotation.angle().abs() < 1e-5, "{:?}", rec.laser_offset);
        }
        // ODOM velocities: 0.3 m and 0.05 rad each 0.2 s.
        let v = log.odometry[2].forward_speed;
        assert!((v - 1.5).abs() < 0.01, "{v}");
    }
}
