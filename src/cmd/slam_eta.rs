//! The time a SLAM run has left. The filter's cost lies in the scans it processes (after the robot moved
//! `linear_update` or turned `angular_update`, or `temporal_update` seconds passed), not in the scans it skips:
//! a log that starts with the robot standing still runs through its first scans at once. The estimate counts the
//! processed scans ahead, from the odometry as the filter gates it, instead of scans.

use indicatif::ProgressState;
use mrslam_core::{Odometry, Xyt, pose::relative};
use std::fmt::Write;

/// The filter's gate: metres, radians, seconds (negative: no temporal update).
#[derive(Debug, Clone, Copy)]
pub struct Gate {
    /// `filter.linear_update`.
    pub linear: f64,
    /// `filter.angular_update`.
    pub angular: f64,
    /// `filter.temporal_update`.
    pub temporal: f64,
}

/// For each scan (its odometry and stamp), how many scans the filter will have processed up to and including it:
/// the first, then each after the odometry moved or turned past the gate since the last processed one.
pub fn processed_so_far(odometry: &[Odometry], gate: Gate) -> Vec<usize> {
    let mut counts = Vec::with_capacity(odometry.len());
    let (mut linear, mut angular, mut done) = (0.0, 0.0, 0);
    let mut last_stamp = f64::NEG_INFINITY;
    for (i, o) in odometry.iter().enumerate() {
        if i > 0 {
            let Xyt { x, y, theta } = Xyt::from_pose(&relative(&odometry[i - 1].pose, &o.pose));
            linear += x.hypot(y);
            angular += theta.abs();
        }
        let due = i == 0
            || linear >= gate.linear
            || angular >= gate.angular
            || (gate.temporal >= 0.0 && o.stamp - last_stamp > gate.temporal);
        if due {
            done += 1;
            (linear, angular, last_stamp) = (0.0, 0.0, o.stamp);
        }
        counts.push(done);
    }
    counts
}

/// Seconds left after `elapsed` seconds with `pos` scans read, from `counts` ([`processed_so_far`]); `None`
/// before the first processed scan.
pub fn seconds_left(counts: &[usize], pos: usize, elapsed: f64) -> Option<f64> {
    let total = *counts.last()?;
    let done = *counts.get(pos.checked_sub(1)?)?;
    (done > 0).then(|| elapsed * (total - done) as f64 / done as f64)
}

/// A progress bar key writing [`seconds_left`] as `HH:MM:SS`.
pub fn eta_key(counts: Vec<usize>) -> impl Fn(&ProgressState, &mut dyn Write) + Send + Sync + Clone + 'static {
    move |state: &ProgressState, w: &mut dyn Write| {
        let _ = match seconds_left(&counts, state.pos() as usize, state.elapsed().as_secs_f64()) {
            Some(s) => {
                let s = s.round() as u64;
                write!(w, "{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
            }
            None => w.write_str("--:--:--"),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn a_standing_start_costs_nothing_in_the_estimate() {
        // 100 scans standing still, then 100 scans 0.1 m apart: with a 0.5 m gate the filter processes the
        // first scan, then every fifth moving one.
        let odometry: Vec<Odometry> = (0..200)
            .map(|i| Odometry { stamp: i as f64 * 0.1, pose: pose(0.1 * (i as f64 - 99.0).max(0.0), 0.0, 0.0) })
            .collect();
        let gate = Gate { linear: 0.5, angular: 0.5, temporal: -1.0 };
        let counts = processed_so_far(&odometry, gate);
        assert_eq!((counts[99], counts[199]), (1, 21));
        // Half the scans read in 10 s, one processed scan of 21 done: 200 s left, not 10 s.
        assert_eq!(seconds_left(&counts, 100, 10.0), Some(200.0));
        assert_eq!(seconds_left(&counts, 200, 10.0), Some(0.0));
        assert_eq!(seconds_left(&counts, 0, 10.0), None);
    }
}
