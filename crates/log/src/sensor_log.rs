//! The neutral sensor log every reader produces: scans with their odometry, the odometry stream, the log's
//! parameters, what was skipped and what was repaired.

use crate::bag_summary::BagSummary;
use crate::source::Source;
use mrslam_core::{LaserScan, Odometry, Pose2};
use std::collections::BTreeMap;

/// One laser scan of a log with the robot's odometry at it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRecord {
    /// The robot's odometry pose when the scan was taken.
    pub odometry: Odometry,
    /// The scan in the laser's frame.
    pub scan: LaserScan,
    /// The laser's pose as logged, when the log has one (in a "corrected" CARMEN log, the scan-matched pose).
    pub logged_laser_pose: Option<Pose2>,
    /// The laser's mount: its pose on the robot.
    pub laser_offset: Pose2,
    /// Which laser: the CARMEN line kind (`FLASER`, `RLASER`, `ROBOTLASER1`) or a bag's topic.
    pub sensor: String,
    /// Where the scan sits in the log.
    pub source: Source,
}

/// One reading of the odometry stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryRecord {
    /// The robot's odometry pose and its stamp.
    pub odometry: Odometry,
    /// The translational velocity logged with it, m/s (negative when reversing; 0 when the log has none).
    pub forward_speed: f64,
}

/// A sensor log of any format, after the repairs of [`crate::repair`].
#[derive(Debug, Clone, Default)]
pub struct SensorLog {
    /// Laser scans with odometry, in stamp order (stable for equal stamps).
    pub scans: Vec<ScanRecord>,
    /// The odometry stream, in stamp order.
    pub odometry: Vec<OdometryRecord>,
    /// The log's parameters by name (CARMEN's PARAM lines).
    pub params: BTreeMap<String, String>,
    /// Records skipped, by kind (parameters count as read, not skipped).
    pub skipped: BTreeMap<String, usize>,
    /// What the repairs changed: reordering, duplicates, odometry interpolation.
    pub repairs: Repairs,
    /// A recorded bag's topics and what the read took from them (none for a CARMEN log).
    pub bag: Option<BagSummary>,
}

impl SensorLog {
    /// Total number of skipped records.
    pub fn skipped_total(&self) -> usize {
        self.skipped.values().sum()
    }
}

/// What the repairs changed in a log, counted.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Repairs {
    /// Sensor readings (laser or odometry) stamped before a reading above them; all were put in stamp order.
    pub out_of_order: usize,
    /// The largest step back, seconds.
    pub max_step_back: f64,
    /// Where the largest step back is (none when no stamp stepped back).
    pub max_step_back_at: Option<Source>,
    /// Scans dropped as exact repeats of another scan (same laser, stamp and ranges).
    pub duplicate_scans: usize,
    /// Scans kept that share their stamp with another, different scan.
    pub shared_scan_stamps: usize,
    /// Odometry readings dropped because another reading has the same stamp.
    pub duplicate_odometry: usize,
    /// Odometry increments that reported reversing (`tv` < 0) but moved forwards, turned round
    /// ([`ReadOptions::repair_reversing`](crate::ReadOptions::repair_reversing)).
    pub reversed_increments: usize,
    /// Scans whose odometry was interpolated from the odometry stream at the scan's stamp.
    pub interpolated_odometry: usize,
    /// Scans whose odometry is their own record's.
    pub line_odometry: usize,
    /// Increments of the odometry stream faster than a robot moves ([`crate::faster_than_a_robot`]).
    pub burst_increments: usize,
    /// Whether so many are ([`crate::repair::MAX_BURST_SHARE`]) that the stream is stamped in bursts, not when
    /// measured, and the scans kept their own odometry ([`crate::repair::odometry_at_scans`]).
    pub stamped_in_bursts: bool,
}

impl Repairs {
    /// One line for summaries, e.g. "4932 stamps out of order (max 0.50 s back, line 90), reordered".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.out_of_order > 0 {
            let at = self.max_step_back_at.as_ref().map_or_else(|| "line 0".to_string(), Source::to_string);
            parts.push(format!(
                "{} stamps out of order (max {:.2} s back, {at}), reordered",
                self.out_of_order, self.max_step_back
            ));
        } else {
            parts.push("stamps in order".to_string());
        }
        if self.duplicate_scans > 0 {
            parts.push(format!("{} repeated scans dropped", self.duplicate_scans));
        }
        if self.shared_scan_stamps > 0 {
            parts.push(format!("{} scans share a stamp", self.shared_scan_stamps));
        }
        if self.duplicate_odometry > 0 {
            parts.push(format!("{} ODOM lines with a repeated stamp dropped", self.duplicate_odometry));
        }
        if self.reversed_increments > 0 {
            parts.push(format!(
                "{} ODOM increments reported reversing but moved forwards, turned round",
                self.reversed_increments
            ));
        }
        parts.join(", ")
    }

    /// One line saying where the scans' odometry came from.
    pub fn describe_odometry(&self) -> String {
        let text = match (self.interpolated_odometry, self.line_odometry) {
            (0, n) => format!("the scan lines' own odometry fields ({n} scans)"),
            (n, 0) => format!("ODOM lines interpolated at every scan's stamp ({n} scans)"),
            (n, m) => format!("ODOM lines interpolated at {n} scans' stamps, the scan line's own fields at {m}"),
        };
        if self.stamped_in_bursts {
            format!(
                "{text}: the odometry stream is stamped in bursts ({} of its increments faster than {} m/s or {} \
                 rad/s), its stamps are not when it was measured",
                self.burst_increments,
                crate::robot_speed::MAX_SPEED,
                crate::robot_speed::MAX_TURN_RATE
            )
        } else {
            text
        }
    }
}
