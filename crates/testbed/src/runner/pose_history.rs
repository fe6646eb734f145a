//! A robot's recent true and odometry poses, to pair a scan with the poses of the instant it was taken.
//!
//! The simulator publishes a scan when its period ends, stamped at its first beam: a SICK-class scan delivered
//! now was taken 0.2 s ago. A real robot's SLAM looks its odometry up at the scan's stamp (ROS's tf lookup at
//! `header.stamp`), and so do the testbed's runs and `mrslam sim log`.

use mrslam_core::pose::interpolate;
use mrslam_core::{LaserScan, Pose2};
use mrslam_sim::LidarModel;
use std::collections::VecDeque;

/// (time, true pose, odometry pose) at the ends of a robot's last steps, oldest first.
#[derive(Debug, Clone, Default)]
pub struct PoseHistory {
    steps: VecDeque<(f64, Pose2, Pose2)>,
}

impl PoseHistory {
    /// Seconds of history kept: several scan periods of the slowest lidar.
    pub const SPAN: f64 = 2.0;

    /// Appends the poses at the end of a step at `time` and forgets what is older than [`Self::SPAN`].
    pub fn push(&mut self, time: f64, true_pose: Pose2, odometry: Pose2) {
        self.steps.push_back((time, true_pose, odometry));
        while self.steps.front().is_some_and(|s| s.0 < time - Self::SPAN) {
            self.steps.pop_front();
        }
    }

    /// True before the first step is pushed.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// The true pose and odometry pose at `time`, interpolated between the steps that bracket it (the nearest
    /// end of the history outside it); `None` while the history is empty.
    pub fn at(&self, time: f64) -> Option<(Pose2, Pose2)> {
        let k = self.steps.partition_point(|h| h.0 < time);
        let (a, b) = match (k.checked_sub(1).and_then(|i| self.steps.get(i)), self.steps.get(k)) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => (a, a),
            (None, Some(b)) => (b, b),
            (None, None) => return None,
        };
        let s = if b.0 > a.0 { ((time - a.0) / (b.0 - a.0)).clamp(0.0, 1.0) } else { 0.0 };
        Some((interpolate(&a.1, &b.1, s), interpolate(&a.2, &b.2, s)))
    }
}

/// The instant a scan's odometry and truth are looked up at: its stamp (its first beam) for a scanner that sweeps
/// too fast to skew (SICK, Hokuyo); for one that sweeps while the robot moves (RPLidar), the middle beam's time,
/// which halves the worst beam's skew.
pub fn pairing_time(lidar: &LidarModel, scan: &LaserScan) -> f64 {
    if lidar.skew {
        scan.stamp + 0.5 * scan.len().saturating_sub(1) as f64 * lidar.time_increment()
    } else {
        scan.stamp
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn poses_between_two_steps_are_interpolated_and_outside_clamped() {
        let mut h = PoseHistory::default();
        assert!(h.at(0.0).is_none());
        h.push(1.0, pose(0.0, 0.0, 0.0), pose(10.0, 0.0, 0.0));
        h.push(1.2, pose(0.2, 0.0, 0.2), pose(10.4, 0.0, 0.0));
        let (truth, odom) = h.at(1.05).unwrap();
        assert!((truth.translation.x - 0.05).abs() < 1e-12);
        assert!((truth.rotation.angle() - 0.05).abs() < 1e-12);
        assert!((odom.translation.x - 10.1).abs() < 1e-12);
        assert!((h.at(0.5).unwrap().0.translation.x).abs() < 1e-12, "before the history: its first step");
        assert!((h.at(9.0).unwrap().0.translation.x - 0.2).abs() < 1e-12, "after it: its last step");
    }

    #[test]
    fn steps_older_than_the_span_are_forgotten() {
        let mut h = PoseHistory::default();
        for k in 0..1000 {
            let t = k as f64 * 0.01;
            h.push(t, pose(t, 0.0, 0.0), pose(t, 0.0, 0.0));
        }
        assert!(h.steps.len() <= (PoseHistory::SPAN / 0.01) as usize + 2);
        assert!((h.at(9.5).unwrap().0.translation.x - 9.5).abs() < 1e-9);
    }
}
