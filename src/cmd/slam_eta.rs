//! The time a SLAM run has left. The filter's cost lies in the scans it processes (after the robot moved
//! `linear_update` or turned `angular_update`, or `temporal_update` seconds passed), not in the scans it skips:
//! a log that starts with the robot standing still runs through its first scans at once. The estimate counts the
//! processed scans ahead, from the odometry as the filter gates it, instead of scans.
//!
//! Nor does a processed scan cost the same all along: with loop closure on, each one is searched against the
//! submaps passed before and the pose graph grows, so later scans cost more than early ones (on the ACES log an
//! estimate at the mean cost so far was 1.6 times too short throughout). The estimate therefore fits the cost
//! per processed scan as growing linearly with the scans done, through the time taken by the first half of the
//! scans done and by all of them, and sums that cost over the scans ahead.

use indicatif::ProgressState;
use mrslam_core::{Odometry, Xyt, pose::relative};
use std::fmt::Write;
use std::sync::{Arc, Mutex};

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

/// The fewest processed scans the growing cost is fitted from.
const MIN_FIT: usize = 25;

/// Seconds left after `elapsed` seconds with `pos` scans read, from `counts` ([`processed_so_far`]) and what
/// was seen so far (`history`: processed scans done and the seconds they took, in order); `None` before the first
/// processed scan.
pub fn seconds_left(counts: &[usize], pos: usize, elapsed: f64, history: &[(usize, f64)]) -> Option<f64> {
    let total = *counts.last()?;
    let done = *counts.get(pos.checked_sub(1)?)?;
    if done == 0 {
        return None;
    }
    // The latest moment when at most half the scans done now were done; the first few scans' times are noise
    // (start-up, a slow first match), so the fit waits for [`MIN_FIT`] of them.
    let half = history.iter().rev().find(|(d, _)| 2 * d <= done && *d >= MIN_FIT).copied();
    Some(match half {
        Some(half) => left_at_growing_cost(total, half, (done, elapsed)),
        None => elapsed * (total - done) as f64 / done as f64,
    })
}

/// Seconds the scans from `now.0` to `total` take when scan `k` costs `a + 2 c k` (the time of the first `d`
/// being `a d + c d²`), fitted through `half` and `now` (processed scans done, seconds); with a cost that falls
/// instead (c < 0), the recent cost per scan.
fn left_at_growing_cost(total: usize, half: (usize, f64), now: (usize, f64)) -> f64 {
    let ((d1, t1), (d2, t2)) = ((half.0 as f64, half.1), (now.0 as f64, now.1));
    let n = total as f64;
    if d2 <= d1 {
        return t2 * (n - d2) / d2;
    }
    let c = (t2 / d2 - t1 / d1) / (d2 - d1);
    if c < 0.0 {
        return (t2 - t1) / (d2 - d1) * (n - d2);
    }
    let a = t1 / d1 - c * d1;
    (a * (n - d2) + c * (n * n - d2 * d2)).max(0.0)
}

/// A progress bar key writing [`seconds_left`] as `HH:MM:SS`, keeping the history it needs.
pub fn eta_key(counts: Vec<usize>) -> impl Fn(&ProgressState, &mut dyn Write) + Send + Sync + Clone + 'static {
    let history: Arc<Mutex<Vec<(usize, f64)>>> = Arc::default();
    move |state: &ProgressState, w: &mut dyn Write| {
        let (pos, elapsed) = (state.pos() as usize, state.elapsed().as_secs_f64());
        let done = pos.checked_sub(1).and_then(|i| counts.get(i)).copied().unwrap_or(0);
        let left = match history.lock() {
            Ok(mut h) => {
                if done > 0 && h.last().is_none_or(|(d, _)| *d < done) {
                    h.push((done, elapsed));
                }
                seconds_left(&counts, pos, elapsed, &h)
            }
            Err(_) => seconds_left(&counts, pos, elapsed, &[]),
        };
        let _ = match left {
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
        assert_eq!(seconds_left(&counts, 100, 10.0, &[]), Some(200.0));
        assert_eq!(seconds_left(&counts, 200, 10.0, &[]), Some(0.0));
        assert_eq!(seconds_left(&counts, 0, 10.0, &[]), None);
    }

    #[test]
    fn a_cost_per_scan_that_grows_is_extrapolated_and_one_that_falls_is_taken_at_its_recent_rate() {
        let counts: Vec<usize> = (1..=1000).collect();
        // Scan k costs 1 + k / 100 ms: the first d take d + d² / 200 ms, all 1000 take 6 s.
        let time = |d: usize| (d as f64 + (d * d) as f64 / 200.0) / 1000.0;
        let history: Vec<(usize, f64)> = (1..=250).map(|d| (d, time(d))).collect();
        let left = seconds_left(&counts, 250, time(250), &history).unwrap();
        assert!((left - (time(1000) - time(250))).abs() < 1e-9, "{left}");
        // At the mean cost so far it would have said 1.7 s instead of 5.4 s.
        assert!(left > 3.0 * time(250) * 3.0, "{left}");
        // A cost that falls (a slow start): the recent cost, 1 ms a scan.
        let history = [(10, 0.9), (100, 1.0), (200, 1.1)];
        let left = seconds_left(&counts, 200, 1.1, &history).unwrap();
        assert!((left - 0.8).abs() < 1e-9, "{left}");
    }
}
