//! A pose for every scan of a log, from the poses of the scans the filter processed.
//!
//! The filter matches only the scans taken after the robot moved `linear_update` / `angular_update`; the
//! benchmark metric needs a pose at every scan's stamp. A scan between two processed scans gets the
//! odometry increment from the processed scan before it, and (going back) from the processed scan after
//! it, blended by time: the poses agree with the filter's at the processed scans and the correction the
//! filter made between them is spread over the scans in between, rather than dropped on the next one.
//! Scans before the first processed scan are placed by odometry back from it, scans after the last by
//! odometry from it.

use crate::backend::SlamBackend;
use crate::error::SlamError;
use crate::loop_closure::LoopClosureReport;
use crate::outcome::UpdateOutcome;
use mrslam_core::pose::interpolate;
use mrslam_core::{LaserScan, Odometry, Pose2};

/// What the filter made of a log: a pose for every scan, and which scans it processed.
#[derive(Debug, Clone, PartialEq)]
pub struct LogRun {
    /// The best particle's robot pose at every scan (see [`poses_at_every_scan`]).
    pub poses: Vec<Pose2>,
    /// Indices of the scans the filter processed.
    pub processed: Vec<usize>,
    /// What loop closure did (`None` when the back-end did none: for the particle filter, when
    /// [`crate::SlamParams::loop_closure`] is off).
    pub loop_closure: Option<LoopClosureReport>,
}

/// Why [`map_log`] stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogRunError {
    /// The filter refused reading `index` (0-based, in the order given).
    #[error("reading {index}: {error}")]
    Reading {
        /// The reading's index.
        index: usize,
        /// What the filter said.
        error: SlamError,
    },
    /// No scan was processed (no scan had beams), so no scan has a pose.
    #[error("the filter processed no scan")]
    NothingProcessed,
}

/// Feeds `filter` (any [`SlamBackend`]) a log's readings (each scan with its odometry, in order) and places every
/// scan: the back-end's pose at the processed ones, its odometry (scan-matched when `scan_odometry` is on) in
/// between. `on_reading` sees each reading's outcome and the back-end after it (for progress, or to watch it);
/// then [`SlamBackend::finish`] ends the data (the particle filter smooths its trajectory when `loop_closure` is
/// on, [`crate::Rbpf::close_loops`]). The map is the back-end's afterwards.
///
/// Generic rather than over `dyn SlamBackend`: the caller's `on_reading` sees its own back-end type (the CLI
/// reads the particle filter's own statistics there); `B = dyn SlamBackend` works too.
pub fn map_log<'a, B: SlamBackend + ?Sized>(
    filter: &mut B,
    readings: impl IntoIterator<Item = (&'a Odometry, &'a LaserScan)>,
    mut on_reading: impl FnMut(&UpdateOutcome, &B),
) -> Result<LogRun, LogRunError> {
    let mut processed = Vec::new();
    let mut odometry = Vec::new();
    let mut stamps = Vec::new();
    for (index, (odom, scan)) in readings.into_iter().enumerate() {
        let out = filter.process(odom, scan).map_err(|error| LogRunError::Reading { index, error })?;
        odometry.push(filter.odometry_pose().unwrap_or(odom.pose));
        stamps.push(scan.stamp);
        if out.is_processed() {
            processed.push(index);
        }
        on_reading(&out, filter);
    }
    let loop_closure = filter.finish();
    let keyframes = filter.trajectory();
    debug_assert_eq!(keyframes.len(), processed.len(), "one trajectory node per processed scan");
    let anchors: Vec<(usize, Pose2)> = processed.iter().copied().zip(keyframes.into_iter().map(|(_, p)| p)).collect();
    let poses = poses_at_every_scan(&stamps, &odometry, &anchors).ok_or(LogRunError::NothingProcessed)?;
    Ok(LogRun { poses, processed, loop_closure })
}

/// Poses for every scan, given each scan's stamp and odometry and the filter's poses at the processed
/// scans as (index into the scans, pose), in increasing index order.
///
/// Returns `None` when `processed` is empty or an index is out of range or not increasing.
pub fn poses_at_every_scan(stamps: &[f64], odometry: &[Pose2], processed: &[(usize, Pose2)]) -> Option<Vec<Pose2>> {
    let n = stamps.len();
    if odometry.len() != n || processed.is_empty() || processed.windows(2).any(|w| w[1].0 <= w[0].0) {
        return None;
    }
    if processed.last().is_some_and(|&(i, _)| i >= n) {
        return None;
    }
    // The pose of scan i by odometry from processed scan (k, pose_k).
    let carried = |i: usize, (k, pose_k): (usize, Pose2)| pose_k * odometry[k].inv_mul(&odometry[i]);
    let mut out = Vec::with_capacity(n);
    let mut next = 0; // index into `processed` of the first processed scan at or after i
    for i in 0..n {
        while next < processed.len() && processed[next].0 < i {
            next += 1;
        }
        let pose = match (next.checked_sub(1).map(|p| processed[p]), processed.get(next).copied()) {
            (_, Some((k, p))) if k == i => p,
            (None, Some(after)) => carried(i, after),
            (Some(before), None) => carried(i, before),
            (Some(before), Some(after)) => {
                let span = stamps[after.0] - stamps[before.0];
                let f = if span > 0.0 { ((stamps[i] - stamps[before.0]) / span).clamp(0.0, 1.0) } else { 0.5 };
                interpolate(&carried(i, before), &carried(i, after), f)
            }
            (None, None) => return None,
        };
        out.push(pose);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::{Xyt, pose};

    #[test]
    fn processed_scans_keep_their_poses_and_the_correction_is_spread_between_them() {
        // Odometry drives straight along x, 1 m per scan; the filter corrected scan 4 to y = 0.4.
        let stamps: Vec<f64> = (0..7).map(|i| i as f64).collect();
        let odometry: Vec<Pose2> = (0..7).map(|i| pose(i as f64, 0.0, 0.0)).collect();
        let processed = [(0, pose(0.0, 0.0, 0.0)), (4, pose(4.0, 0.4, 0.0))];
        let poses = poses_at_every_scan(&stamps, &odometry, &processed).unwrap();
        assert_eq!(poses.len(), 7);
        assert_eq!(poses[0], processed[0].1);
        assert_eq!(poses[4], processed[1].1);
        for (i, p) in poses.iter().enumerate().take(4) {
            let Xyt { x, y, theta: t } = Xyt::from_pose(p);
            assert!((x - i as f64).abs() < 1e-12 && (y - 0.1 * i as f64).abs() < 1e-12 && t.abs() < 1e-12);
        }
        // After the last processed scan: odometry from it.
        let Xyt { x, y, .. } = Xyt::from_pose(&poses[6]);
        assert!((x - 6.0).abs() < 1e-12 && (y - 0.4).abs() < 1e-12);
    }

    #[test]
    fn scans_before_the_first_processed_one_are_carried_back_through_a_turn() {
        let stamps = [0.0, 1.0, 2.0];
        let odometry = [pose(0.0, 0.0, 0.0), pose(1.0, 0.0, 0.0), pose(1.0, 0.0, std::f64::consts::FRAC_PI_2)];
        // The filter's frame starts at scan 2 facing +x.
        let poses = poses_at_every_scan(&stamps, &odometry, &[(2, pose(0.0, 0.0, 0.0))]).unwrap();
        let Xyt { x, y, theta: t } = Xyt::from_pose(&poses[0]);
        assert!((x - 0.0).abs() < 1e-12 && (y - 1.0).abs() < 1e-12 && (t + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn bad_indices_are_refused() {
        let o = [pose(0.0, 0.0, 0.0); 3];
        let s = [0.0, 1.0, 2.0];
        assert!(poses_at_every_scan(&s, &o, &[]).is_none());
        assert!(poses_at_every_scan(&s, &o, &[(3, o[0])]).is_none());
        assert!(poses_at_every_scan(&s, &o, &[(1, o[0]), (1, o[0])]).is_none());
        assert!(poses_at_every_scan(&s, &o[..2], &[(1, o[0])]).is_none());
    }
}
