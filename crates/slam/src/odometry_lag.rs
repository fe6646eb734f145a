//! How late a log's per-scan odometry is, read from the scans themselves, and that odometry re-timed.
//!
//! A log without an odometry stream carries one odometry pose per scan line, written by a logger that took the
//! last reading it had: on ACES read without its ODOM lines the scan lines' odometry is the robot's pose of
//! about 0.12 s before the scan (compared with its ODOM lines), and a turn then reaches the filter a tenth of a
//! second late. There is no clock to compare with, but the scans saw the turn when it happened: each scan's
//! heading change, matched against the scans before it, against the odometry's heading change over the same
//! interval shifted by a lag; the lag that explains the scans best is the odometry's. The odometry of each scan
//! is then the line odometry interpolated at the scan's stamp plus that lag (the next scan's line holds the pose
//! of a moment between the two).

use crate::motion::MotionModel;
use crate::params::SlamParams;
use crate::scan_odometry::{OdometryStep, ScanOdometry};
use mrslam_core::pose::normalize_angle;
use mrslam_core::{LaserScan, Odometry, Pose2, Xyt};

/// Scans matched to estimate the lag, at most: the first of the log (a few minutes of driving; the estimate
/// needs turns, not the whole log).
pub const LAG_SCANS: usize = 1500;
/// Lags tried, seconds: from `-LAG_LIMIT` to `LAG_LIMIT` in steps of [`LAG_STEP`].
pub const LAG_LIMIT: f64 = 0.5;
/// Step of the lags tried, seconds.
pub const LAG_STEP: f64 = 0.005;
/// The lag is applied only when it explains the scans' headings this much better than no lag (sum of squared
/// heading residuals at most this share of the unshifted one): a log whose odometry is on time is left as it is.
pub const LAG_MIN_GAIN: f64 = 0.8;
/// Nor when it is shorter than this, seconds.
pub const LAG_MIN_S: f64 = 0.02;

/// The estimate's matches trust the odometry's increment this many times less than scan odometry does.
pub const PRIOR_LOOSENING: f64 = 10.0;

/// What [`estimate_lag`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LagEstimate {
    /// The lag that explains the scans' heading changes best, seconds (positive: the odometry is late).
    pub lag_s: f64,
    /// The lag the odometry was re-timed by instead, seconds, when one was given
    /// ([`crate::ScanOdometryParams::line_lag_s`]).
    pub given_s: Option<f64>,
    /// Scan pairs whose matched heading change was compared.
    pub pairs: usize,
    /// Sum of squared heading residuals at `lag_s` over the same at no lag.
    pub residual_ratio: f64,
}

impl LagEstimate {
    /// Whether the lag is worth re-timing the odometry by: long enough, and clearly better than none.
    pub fn applies(&self) -> bool {
        self.lag_s.abs() >= LAG_MIN_S && self.residual_ratio <= LAG_MIN_GAIN
    }

    /// The lag the odometry is re-timed by: the one given, else the estimate when it applies, else 0.
    pub fn used_s(&self) -> f64 {
        self.given_s.unwrap_or(if self.applies() { self.lag_s } else { 0.0 })
    }
}

/// Estimates the lag of `odometry` (one pose per scan of `scans`, stamps in order) behind the scans: the first
/// [`LAG_SCANS`] scans matched one after the other by the scan odometry of `params`, for a laser mounted at
/// `laser`; `None` when too few scans matched or the robot never turned.
pub fn estimate_lag(
    odometry: &[Odometry],
    scans: &[&LaserScan],
    params: &SlamParams,
    laser: Pose2,
) -> Option<LagEstimate> {
    let n = odometry.len().min(scans.len()).min(LAG_SCANS);
    if n < 10 {
        return None;
    }
    // The scans' own heading changes: the matcher's prior on the odometry's increment loosened, or it would pull
    // each match toward the late odometry it is to be compared with.
    let m = params.motion;
    let loose = MotionModel {
        srr: PRIOR_LOOSENING * m.srr,
        srt: PRIOR_LOOSENING * m.srt,
        trans_from_rot: PRIOR_LOOSENING * m.trans_from_rot,
        stt: PRIOR_LOOSENING * m.stt,
    };
    let mut matcher =
        ScanOdometry::new(&params.scan_odometry, &params.matcher, &params.map, loose, Xyt::from_pose(&laser));
    let mut matched: Vec<Option<f64>> = Vec::with_capacity(n);
    let mut last: Option<f64> = None;
    for (o, s) in odometry.iter().zip(scans).take(n) {
        let (pose, step) = matcher.update(&o.pose, s);
        let heading = Xyt::from_pose(&pose).theta;
        matched.push(match (step, last) {
            (OdometryStep::Matched, Some(before)) => Some(normalize_angle(heading - before)),
            _ => None,
        });
        last = Some(heading);
    }
    let stamps: Vec<f64> = odometry[..n].iter().map(|o| o.stamp).collect();
    let headings = unwrapped(&odometry[..n]);
    let residual = |lag: f64| -> f64 {
        (1..n)
            .filter_map(|k| {
                let m = matched[k]?;
                let d = at(&stamps, &headings, stamps[k] + lag) - at(&stamps, &headings, stamps[k - 1] + lag);
                Some((m - d) * (m - d))
            })
            .sum()
    };
    let pairs = matched.iter().flatten().count();
    let none = residual(0.0);
    if pairs < 10 || none <= 0.0 {
        return None;
    }
    let steps = (LAG_LIMIT / LAG_STEP).round() as i32;
    let (lag_s, best) = (-steps..=steps)
        .map(|i| f64::from(i) * LAG_STEP)
        .map(|lag| (lag, residual(lag)))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.abs().total_cmp(&b.0.abs())))?;
    Some(LagEstimate { lag_s, given_s: None, pairs, residual_ratio: best / none })
}

/// Re-times per-scan odometry by its lag when `params` ask for it (scan odometry with
/// [`crate::ScanOdometryParams::line_lag`]): by the lag given in `line_lag_s`, else by the estimate when it
/// [`applies`](LagEstimate::applies); the estimate, applied or not (reported beside a lag given). For logs
/// without an odometry stream only: a stream is interpolated at the scans' own stamps.
pub fn retime_line_odometry(
    odometry: &mut [Odometry],
    scans: &[&LaserScan],
    params: &SlamParams,
    laser: Pose2,
) -> Option<LagEstimate> {
    if !(params.scan_odometry.enabled && params.scan_odometry.line_lag) {
        return None;
    }
    let mut estimate = estimate_lag(odometry, scans, params, laser)?;
    let given = params.scan_odometry.line_lag_s;
    estimate.given_s = (given != 0.0).then_some(given);
    if estimate.used_s() != 0.0 {
        retime(odometry, estimate.used_s());
    }
    Some(estimate)
}

/// Each scan's odometry moved to the pose of `lag` seconds after its stamp, interpolated between the scans'
/// odometry around that moment (held at the last one beyond the log's end, at the first before its start).
pub fn retime(odometry: &mut [Odometry], lag: f64) {
    let original: Vec<Odometry> = odometry.to_vec();
    let mut k = 0;
    for o in odometry.iter_mut() {
        let t = o.stamp + lag;
        while k + 1 < original.len() && original[k + 1].stamp <= t {
            k += 1;
        }
        o.pose = match original.get(k + 1) {
            _ if t <= original[0].stamp => original[0].pose,
            Some(b) => original[k].towards(b, t),
            None => original[k].pose,
        };
    }
}

/// The odometry's headings with the 2π jumps taken out.
fn unwrapped(odometry: &[Odometry]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(odometry.len());
    for o in odometry {
        let h = Xyt::from_pose(&o.pose).theta;
        out.push(match out.last() {
            Some(&before) => before + normalize_angle(h - before),
            None => h,
        });
    }
    out
}

/// `values` (one per stamp, stamps in order) linearly interpolated at `t`, held beyond the ends.
fn at(stamps: &[f64], values: &[f64], t: f64) -> f64 {
    let i = stamps.partition_point(|&s| s <= t);
    match i {
        0 => values[0],
        i if i == stamps.len() => values[i - 1],
        i => {
            let (s0, s1) = (stamps[i - 1], stamps[i]);
            let f = if s1 > s0 { (t - s0) / (s1 - s0) } else { 0.0 };
            values[i - 1] + f * (values[i] - values[i - 1])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{self, Drift, Lidar};
    use mrslam_core::pose;

    #[test]
    fn retiming_by_a_lag_interpolates_the_later_pose() {
        let mut odo: Vec<Odometry> = (0..5)
            .map(|i| Odometry { stamp: f64::from(i) * 0.2, pose: pose(f64::from(i), 0.0, 0.1 * f64::from(i)) })
            .collect();
        retime(&mut odo, 0.05);
        let x: Vec<f64> = odo.iter().map(|o| Xyt::from_pose(&o.pose).x).collect();
        assert!((x[0] - 0.25).abs() < 1e-12 && (x[2] - 2.25).abs() < 1e-12, "{x:?}");
        assert_eq!(x[4], 4.0, "held at the end");
        assert!((Xyt::from_pose(&odo[1].pose).theta - 0.125).abs() < 1e-12);
        let stamps: Vec<f64> = odo.iter().map(|o| o.stamp).collect();
        assert_eq!(stamps, [0.0, 0.2, 0.4, 0.6000000000000001, 0.8], "stamps stay the scans'");
    }

    #[test]
    fn a_lag_given_is_used_instead_of_the_estimate_and_a_lag_beyond_a_second_is_refused() {
        let path: Vec<Pose2> =
            synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.05).into_iter().take(200).collect();
        let laser = pose(0.1, 0.0, 0.0);
        let run = synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), laser, &Drift::none(), 3);
        let scans: Vec<&LaserScan> = run.scans.iter().collect();
        let mut params = SlamParams::default();
        params.set("scan_odometry", "true").unwrap();
        params.set("scan_odometry_line_lag_s", "0.1").unwrap();
        let mut odo = run.odometry.clone();
        let lag = retime_line_odometry(&mut odo, &scans, &params, laser).expect("an estimate");
        assert_eq!((lag.given_s, lag.used_s()), (Some(0.1), 0.1), "{lag:?}");
        assert!(!lag.applies(), "on-time odometry: the estimate alone would not re-time it: {lag:?}");
        let mut expected = run.odometry.clone();
        retime(&mut expected, 0.1);
        assert_eq!(odo, expected);
        params.set("scan_odometry_line_lag_s", "2").unwrap();
        let err = params.validate().unwrap_err().to_string();
        assert!(err.contains("scan_odometry.line_lag_s") && err.contains("within ±1 s"), "{err}");
    }

    #[test]
    fn the_lag_of_late_odometry_is_found_from_the_scans_and_on_time_odometry_is_left_alone() {
        // 0.5 m/s and 0.5 rad/s turns at every waypoint of the office loop, scans at 10 Hz, wheels that slip a little.
        let path: Vec<Pose2> =
            synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.05).into_iter().take(600).collect();
        let drift = Drift { scale: 0.02, heading_per_m: 0.01, sigma_trans: 0.02, sigma_rot: 0.02 };
        let laser = pose(0.1, 0.0, 0.0);
        let run = synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), laser, &drift, 3);
        let scans: Vec<&LaserScan> = run.scans.iter().collect();
        let params = SlamParams::default();
        let on_time = estimate_lag(&run.odometry, &scans, &params, laser).expect("an estimate");
        assert!(!on_time.applies() && on_time.lag_s.abs() < 0.02, "{on_time:?}");
        // The same odometry 0.1 s late: each scan carries the pose of the scan before it.
        let mut late = run.odometry.clone();
        retime(&mut late, -0.1);
        let found = estimate_lag(&late, &scans, &params, laser).expect("an estimate");
        assert!(found.applies() && (found.lag_s - 0.1).abs() <= 0.01, "{found:?}");
        // Re-timed by the lag found, the odometry is the on-time one again (but for the first scan's, and the
        // last's, which has no later line to take its pose from).
        retime(&mut late, found.lag_s);
        let n = late.len();
        for (k, (a, b)) in late.iter().zip(&run.odometry).enumerate().take(n - 1).skip(1) {
            let d = Xyt::from_pose(&a.pose.inv_mul(&b.pose));
            assert!(d.x.hypot(d.y) < 0.01 && d.theta.abs() < 0.01, "scan {k}: {d:?}");
        }
    }
}
