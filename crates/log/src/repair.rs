//! The repairs real logs of any format need, as functions of a [`SensorLog`], each counting what it
//! changed in [`SensorLog::repairs`].
//!
//! Real logs interleave sensors by arrival, so stamps step back now and then. A reader checks each sensor
//! reading's stamp in arrival order with a [`StampOrder`] (a long step back is refused), then calls
//! [`apply_all`]: readings put in stamp order, exact repeats dropped, odometry increments that reverse the
//! wrong way turned round, and each scan's odometry interpolated from the odometry stream at its stamp.

use crate::options::{OdometrySource, ReadOptions};
use crate::robot_speed::faster_than_a_robot;
use crate::sensor_log::{OdometryRecord, ScanRecord, SensorLog};
use crate::source::Source;
use mrslam_core::Odometry;

/// A sensor reading stamped too long before one above it (two logs joined, or a clock reset).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{stamp} is {:.3} s before the stamp {latest} on {latest_at}: more than the {limit} s a log may step back \
     (two logs joined, or a clock reset?)",
    latest - stamp
)]
pub struct StepBack {
    /// The reading's stamp.
    pub stamp: f64,
    /// The latest stamp above it.
    pub latest: f64,
    /// Where the latest stamp is.
    pub latest_at: Source,
    /// The bound it broke, seconds ([`ReadOptions::max_step_back`]).
    pub limit: f64,
}

/// Checks the stamps of a log's sensor readings in arrival order and counts those that step back.
#[derive(Debug, Clone)]
pub struct StampOrder {
    max_step_back: f64,
    order_odometry: bool,
    latest: Option<(f64, Source)>,
    out_of_order: usize,
    largest: f64,
    largest_at: Option<Source>,
}

impl StampOrder {
    /// A check with `options`' bound; odometry readings take part unless scans take their own odometry.
    pub fn new(options: &ReadOptions) -> StampOrder {
        StampOrder {
            max_step_back: options.max_step_back,
            // Scans that take their own record's odometry do not depend on the odometry stream's stamps.
            order_odometry: options.odometry != OdometrySource::Line,
            latest: None,
            out_of_order: 0,
            largest: 0.0,
            largest_at: None,
        }
    }

    /// Checks a scan stamped `stamp` at `source`, the next sensor reading in arrival order.
    pub fn scan(&mut self, stamp: f64, source: &Source) -> Result<(), StepBack> {
        self.observe(stamp, source)
    }

    /// Checks an odometry reading stamped `stamp` at `source`, the next sensor reading in arrival order.
    pub fn odometry(&mut self, stamp: f64, source: &Source) -> Result<(), StepBack> {
        if self.order_odometry { self.observe(stamp, source) } else { Ok(()) }
    }

    fn observe(&mut self, stamp: f64, source: &Source) -> Result<(), StepBack> {
        match &self.latest {
            Some((t, at)) if stamp < *t => {
                let back = t - stamp;
                if back > self.max_step_back {
                    return Err(StepBack { stamp, latest: *t, latest_at: at.clone(), limit: self.max_step_back });
                }
                self.out_of_order += 1;
                if back > self.largest {
                    self.largest = back;
                    self.largest_at = Some(source.clone());
                }
            }
            _ => self.latest = Some((stamp, source.clone())),
        }
        Ok(())
    }

    /// Writes the counts into `log`'s repairs.
    pub fn finish(self, log: &mut SensorLog) {
        let r = &mut log.repairs;
        r.out_of_order = self.out_of_order;
        r.max_step_back = self.largest;
        r.max_step_back_at = self.largest_at;
    }
}

/// Applies every repair in order: [`sort_by_stamp`], [`drop_repeated_odometry`], [`turn_reversed_increments`]
/// (when `options.repair_reversing`), [`drop_repeated_scans`], [`odometry_at_scans`].
pub fn apply_all(log: &mut SensorLog, options: &ReadOptions) {
    sort_by_stamp(log);
    drop_repeated_odometry(log);
    if options.repair_reversing {
        turn_reversed_increments(log);
    }
    drop_repeated_scans(log);
    odometry_at_scans(log, options.odometry, options.scan_latency);
}

/// Puts the scans and the odometry stream in stamp order (stable for equal stamps).
pub fn sort_by_stamp(log: &mut SensorLog) {
    log.scans.sort_by(|a, b| a.scan.stamp.total_cmp(&b.scan.stamp));
    log.odometry.sort_by(|a, b| a.odometry.stamp.total_cmp(&b.odometry.stamp));
}

/// Drops odometry readings that repeat the stamp of the one before (sorted already), keeping the first;
/// counted in [`Repairs::duplicate_odometry`](crate::Repairs::duplicate_odometry).
pub fn drop_repeated_odometry(log: &mut SensorLog) {
    let before = log.odometry.len();
    log.odometry.dedup_by(|b, a| a.odometry.stamp == b.odometry.stamp);
    log.repairs.duplicate_odometry += before - log.odometry.len();
}

/// Turns round the translation of every odometry increment that reports reversing (`tv` < 0 at its end)
/// but moves the pose forwards, and integrates the increments again from the first reading; counted in
/// [`Repairs::reversed_increments`](crate::Repairs::reversed_increments).
pub fn turn_reversed_increments(log: &mut SensorLog) {
    let odometry: &mut [OdometryRecord] = &mut log.odometry;
    let mut repaired = 0;
    let Some(first) = odometry.first() else { return };
    let mut previous_raw = first.odometry.pose;
    let mut integrated = first.odometry.pose;
    for o in odometry.iter_mut().skip(1) {
        let raw = o.odometry.pose;
        let mut step = previous_raw.inv_mul(&raw);
        if o.forward_speed < 0.0 && step.translation.x > 0.0 {
            step.translation.vector = -step.translation.vector;
            repaired += 1;
        }
        integrated *= step;
        previous_raw = raw;
        if repaired > 0 {
            o.odometry.pose = integrated;
        }
    }
    log.repairs.reversed_increments += repaired;
}

/// Drops exact repeats of scans (sorted by stamp already: same stamp, laser and ranges as a scan kept);
/// counted in [`Repairs::duplicate_scans`](crate::Repairs::duplicate_scans), and the scans kept that share a
/// stamp with another in [`Repairs::shared_scan_stamps`](crate::Repairs::shared_scan_stamps).
pub fn drop_repeated_scans(log: &mut SensorLog) {
    let mut kept: Vec<ScanRecord> = Vec::with_capacity(log.scans.len());
    for s in std::mem::take(&mut log.scans) {
        // Earlier scans with the same stamp sit right before this one.
        let same_stamp = kept.iter().rev().take_while(|k| k.scan.stamp == s.scan.stamp);
        let mut shares = false;
        let mut repeat = false;
        for k in same_stamp {
            shares = true;
            repeat |= k.sensor == s.sensor && k.scan.ranges == s.scan.ranges;
        }
        if repeat {
            log.repairs.duplicate_scans += 1;
        } else {
            if shares {
                log.repairs.shared_scan_stamps += 1;
            }
            kept.push(s);
        }
    }
    log.scans = kept;
}

/// Share of an odometry stream's increments that may be faster than a robot moves ([`faster_than_a_robot`]) before
/// the stream counts as stamped in bursts ([`odometry_at_scans`]); a few are a robot carried or reset.
pub const MAX_BURST_SHARE: f64 = 0.01;

/// The increments of an odometry stream (in stamp order) faster than a robot moves.
fn burst_increments(odometry: &[OdometryRecord]) -> usize {
    odometry
        .windows(2)
        .filter(|w| {
            let (a, b) = (&w[0].odometry, &w[1].odometry);
            faster_than_a_robot(&a.pose, &b.pose, b.stamp - a.stamp)
        })
        .count()
}

/// Sets each scan's odometry as `source` says (see [`OdometrySource`]), interpolating the odometry stream
/// (sorted already) at the scan's stamp minus `latency`; counted in
/// [`Repairs::interpolated_odometry`](crate::Repairs::interpolated_odometry) and
/// [`Repairs::line_odometry`](crate::Repairs::line_odometry).
///
/// A stream with more than [`MAX_BURST_SHARE`] of its increments faster than a robot moves is stamped in bursts
/// (a logger that stamps what it buffered on arrival: on the Intel log six readings 0.05 rad apart within 6 ms,
/// 59 % of the increments), so its stamps do not say when a reading was measured and interpolating at a scan's
/// stamp places the scan anywhere in a burst: every scan keeps its own odometry, the reading that arrived last
/// before it (counted in [`Repairs::burst_increments`](crate::Repairs::burst_increments)).
pub fn odometry_at_scans(log: &mut SensorLog, source: OdometrySource, latency: f64) {
    let odometry = &log.odometry;
    let bursts = burst_increments(odometry);
    let in_bursts = bursts as f64 > MAX_BURST_SHARE * odometry.len().saturating_sub(1) as f64;
    let mut interpolated = 0;
    if source == OdometrySource::Interpolated && !in_bursts && odometry.len() >= 2 {
        // Both sorted: walk the odometry stream once.
        let mut k = 0;
        for s in &mut log.scans {
            let t = s.scan.stamp - latency;
            while k + 2 < odometry.len() && odometry[k + 1].odometry.stamp <= t {
                k += 1;
            }
            let (a, b) = (&odometry[k].odometry, &odometry[k + 1].odometry);
            if a.stamp <= t && t <= b.stamp {
                s.odometry = Odometry { stamp: s.scan.stamp, pose: a.towards(b, t) };
                interpolated += 1;
            }
        }
    }
    log.repairs.burst_increments = bursts;
    log.repairs.stamped_in_bursts = in_bursts;
    log.repairs.interpolated_odometry = interpolated;
    log.repairs.line_odometry = log.scans.len() - interpolated;
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::{LaserScan, Pose2, Xyt, pose};

    fn scan(stamp: f64, sensor: &str, ranges: &[f32], line: usize) -> ScanRecord {
        ScanRecord {
            odometry: Odometry { stamp, pose: pose(9.0, 9.0, 0.0) },
            scan: LaserScan {
                stamp,
                angle_min: 0.0,
                angle_increment: 0.1,
                range_min: 0.0,
                range_max: 10.0,
                ranges: ranges.to_vec(),
            },
            logged_laser_pose: None,
            laser_offset: Pose2::identity(),
            sensor: sensor.to_string(),
            source: Source::Line(line),
        }
    }

    fn odom(stamp: f64, x: f64, forward_speed: f64) -> OdometryRecord {
        OdometryRecord { odometry: Odometry { stamp, pose: pose(x, 0.0, 0.0) }, forward_speed }
    }

    fn xs(log: &SensorLog) -> Vec<f64> {
        log.odometry.iter().map(|o| o.odometry.pose.translation.x).collect()
    }

    #[test]
    fn stamp_order_counts_steps_back_and_refuses_long_ones() {
        let mut log = SensorLog::default();
        let mut order = StampOrder::new(&ReadOptions::default());
        for (k, stamp) in [1.0, 2.0, 1.5, 3.0, 2.2, 2.2].into_iter().enumerate() {
            order.scan(stamp, &Source::Line(k + 1)).unwrap();
        }
        let e = order.clone().odometry(-5.0, &Source::Line(7)).unwrap_err();
        assert_eq!((e.latest, e.latest_at.clone()), (3.0, Source::Line(4)));
        assert!(e.to_string().starts_with("-5 is 8.000 s before the stamp 3 on line 4: more than the 5 s"), "{e}");
        order.finish(&mut log);
        assert_eq!(log.repairs.out_of_order, 3);
        assert!((log.repairs.max_step_back - 0.8).abs() < 1e-12);
        assert_eq!(log.repairs.max_step_back_at, Some(Source::Line(5)));
        // Scans that take their own odometry leave the odometry stream's stamps alone.
        let line = ReadOptions { odometry: OdometrySource::Line, ..ReadOptions::default() };
        let mut order = StampOrder::new(&line);
        order.scan(10.0, &Source::Line(1)).unwrap();
        order.odometry(0.0, &Source::Line(2)).unwrap();
        let mut log = SensorLog::default();
        order.finish(&mut log);
        assert_eq!(log.repairs.out_of_order, 0);
    }

    #[test]
    fn sorting_is_stable_for_equal_stamps() {
        let mut log = SensorLog {
            scans: vec![scan(2.0, "A", &[1.0], 1), scan(1.0, "A", &[2.0], 2), scan(1.0, "B", &[3.0], 3)],
            odometry: vec![odom(2.0, 0.0, 0.0), odom(1.0, 1.0, 0.0), odom(1.0, 2.0, 0.0)],
            ..SensorLog::default()
        };
        sort_by_stamp(&mut log);
        let lines: Vec<Source> = log.scans.iter().map(|s| s.source.clone()).collect();
        assert_eq!(lines, [Source::Line(2), Source::Line(3), Source::Line(1)]);
        assert_eq!(xs(&log), [1.0, 2.0, 0.0]);
        assert_eq!(log.repairs, crate::Repairs::default());
    }

    #[test]
    fn repeated_odometry_stamps_keep_the_first() {
        let mut log = SensorLog {
            odometry: vec![odom(1.0, 0.0, 0.0), odom(1.0, 1.0, 0.0), odom(1.0, 5.0, 0.0), odom(2.0, 2.0, 0.0)],
            ..SensorLog::default()
        };
        drop_repeated_odometry(&mut log);
        assert_eq!(xs(&log), [0.0, 2.0]);
        assert_eq!(log.repairs.duplicate_odometry, 2);
    }

    #[test]
    fn reversing_read_as_driving_ahead_is_turned_round_and_integrated_again() {
        let mut log = SensorLog {
            odometry: vec![odom(0.0, 0.0, 0.0), odom(1.0, 1.0, 1.0), odom(2.0, 2.0, -1.0), odom(3.0, 3.0, 1.0)],
            ..SensorLog::default()
        };
        turn_reversed_increments(&mut log);
        assert_eq!(xs(&log), [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(log.repairs.reversed_increments, 1);
        // Reversing that moves backwards is what it says.
        let mut log = SensorLog { odometry: vec![odom(0.0, 1.0, 0.0), odom(1.0, 0.5, -0.5)], ..SensorLog::default() };
        turn_reversed_increments(&mut log);
        assert_eq!((xs(&log), log.repairs.reversed_increments), (vec![1.0, 0.5], 0));
    }

    #[test]
    fn exact_repeats_are_dropped_and_shared_stamps_counted() {
        let mut log = SensorLog {
            scans: vec![
                scan(1.0, "FLASER", &[1.0, 2.0], 1),
                scan(1.0, "FLASER", &[1.0, 2.0], 2),
                scan(1.0, "RLASER", &[1.0, 2.0], 3),
                scan(1.0, "FLASER", &[1.0, 3.0], 4),
                scan(2.0, "FLASER", &[1.0, 2.0], 5),
            ],
            ..SensorLog::default()
        };
        drop_repeated_scans(&mut log);
        let lines: Vec<Source> = log.scans.iter().map(|s| s.source.clone()).collect();
        assert_eq!(lines, [Source::Line(1), Source::Line(3), Source::Line(4), Source::Line(5)]);
        assert_eq!((log.repairs.duplicate_scans, log.repairs.shared_scan_stamps), (1, 2));
    }

    #[test]
    fn odometry_is_interpolated_where_the_stream_brackets_a_scan() {
        let scans = vec![scan(0.5, "A", &[1.0], 1), scan(1.5, "A", &[1.0], 2), scan(3.5, "A", &[1.0], 3)];
        let odometry = vec![odom(1.0, 0.0, 0.0), odom(2.0, 2.0, 0.0), odom(3.0, 4.0, 0.0)];
        let mut log = SensorLog { scans, odometry, ..SensorLog::default() };
        let before = log.clone();
        odometry_at_scans(&mut log, OdometrySource::Interpolated, 0.0);
        assert_eq!((log.repairs.interpolated_odometry, log.repairs.line_odometry), (1, 2));
        let x = |log: &SensorLog, k: usize| Xyt::from_pose(&log.scans[k].odometry.pose).x;
        assert_eq!((x(&log, 0), x(&log, 1), x(&log, 2)), (9.0, 1.0, 9.0));
        // A latency moves the instant interpolated at; the stamp stays the scan's.
        let mut late = before.clone();
        odometry_at_scans(&mut late, OdometrySource::Interpolated, 0.25);
        assert_eq!((x(&late, 1), late.scans[1].odometry.stamp), (0.5, 1.5));
        // The scans' own odometry on request.
        let mut own = before;
        odometry_at_scans(&mut own, OdometrySource::Line, 0.0);
        assert_eq!((own.repairs.interpolated_odometry, own.repairs.line_odometry), (0, 3));
        assert_eq!(x(&own, 1), 9.0);
    }

    #[test]
    fn a_scan_stamped_at_a_reading_takes_that_reading_bit_for_bit() {
        // Headings whose trip through an interpolation comes back an ulp off (0.173078 of ACES among them).
        let headings = [-0.173078, 0.280918, 0.003153, 1.0, -2.5];
        let mut scans = Vec::new();
        let mut odometry = Vec::new();
        for (k, &theta) in headings.iter().enumerate() {
            let stamp = k as f64;
            scans.push(scan(stamp, "A", &[1.0], k + 1));
            odometry.push(OdometryRecord {
                odometry: Odometry { stamp, pose: pose(k as f64, 0.5, theta) },
                forward_speed: 0.0,
            });
        }
        let mut log = SensorLog { scans, odometry, ..SensorLog::default() };
        odometry_at_scans(&mut log, OdometrySource::Interpolated, 0.0);
        assert_eq!(log.repairs.interpolated_odometry, headings.len());
        for (s, o) in log.scans.iter().zip(&log.odometry) {
            assert_eq!(s.odometry.pose, o.odometry.pose);
        }
    }

    #[test]
    fn a_stream_stamped_in_bursts_is_not_interpolated() {
        // 0.1 m every 0.1 s (1 m/s), then stamped in bursts: ten readings within a millisecond each 0.1 s.
        let steady: Vec<OdometryRecord> = (0..200).map(|k| odom(k as f64 * 0.1, k as f64 * 0.1, 0.0)).collect();
        let burst: Vec<OdometryRecord> =
            (0..200).map(|k| odom((k / 10) as f64 * 0.1 + (k % 10) as f64 * 1e-4, k as f64 * 0.1, 0.0)).collect();
        let scans = vec![scan(5.05, "A", &[1.0], 1)];
        let mut good = SensorLog { scans: scans.clone(), odometry: steady.clone(), ..SensorLog::default() };
        odometry_at_scans(&mut good, OdometrySource::Interpolated, 0.0);
        assert_eq!((good.repairs.burst_increments, good.repairs.stamped_in_bursts), (0, false));
        assert!((Xyt::from_pose(&good.scans[0].odometry.pose).x - 5.05).abs() < 1e-9);
        let mut bursty = SensorLog { scans: scans.clone(), odometry: burst, ..SensorLog::default() };
        odometry_at_scans(&mut bursty, OdometrySource::Interpolated, 0.0);
        assert!(bursty.repairs.stamped_in_bursts, "{:?}", bursty.repairs);
        assert_eq!((bursty.repairs.interpolated_odometry, bursty.repairs.line_odometry), (0, 1));
        assert_eq!(Xyt::from_pose(&bursty.scans[0].odometry.pose).x, 9.0, "the scan's own odometry");
        assert!(bursty.repairs.describe_odometry().contains("stamped in bursts"));
        // One jump (a robot carried) in a steady stream is not a burst: the stream is still interpolated.
        let mut carried = steady;
        for o in &mut carried[150..] {
            o.odometry.pose = pose(o.odometry.pose.translation.x + 20.0, 0.0, 0.0);
        }
        let mut jumped = SensorLog { scans, odometry: carried, ..SensorLog::default() };
        odometry_at_scans(&mut jumped, OdometrySource::Interpolated, 0.0);
        assert_eq!((jumped.repairs.burst_increments, jumped.repairs.stamped_in_bursts), (1, false));
        assert_eq!(jumped.repairs.interpolated_odometry, 1);
    }
}
