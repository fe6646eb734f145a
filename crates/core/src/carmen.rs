//! CARMEN laser logs (`.clf`, `.log`, optionally gzipped): FLASER, RLASER, ROBOTLASER1 and ODOM lines.
//!
//! Line layouts (fields separated by whitespace):
//! - `FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp`
//!   (RLASER alike, for a rear laser turned by pi). `x y theta` is the laser's logged pose,
//!   `odom_*` the robot's odometry.
//! - `ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode n r1..rn
//!   m v1..vm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv fwd_safety side_safety
//!   turn_axis ipc_timestamp host logger_timestamp`
//! - `ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp`
//!
//! PARAM lines set the old-style lasers' geometry (`laser_front_laser_resolution`, `..._fov`,
//! `robot_front_laser_max`, `robot_frontlaser_offset`, `..._side_offset`, `..._angular_offset`, and the
//! rear laser's alike); other PARAM lines, comments and unknown kinds (e.g. NEFF, SYNC) are
//! skipped and counted. A malformed line of a known kind is an error naming its line number: a log that
//! lies about its own format is not one to map from silently.
//!
//! Real logs interleave sensors by arrival, so stamps step back now and then: lines are put in stamp order,
//! exact repeats dropped, and each scan's odometry interpolated from the ODOM lines at its stamp
//! ([`OdometrySource`]); every repair is counted ([`Repairs`]). A step back of more than
//! [`ReadOptions::max_step_back`] is refused, naming the line.

use crate::scan::{LaserScan, Odometry};
use crate::{
    pose::interpolate,
    se2::{Pose2, pose},
};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// Which laser a scan came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaserSource {
    /// FLASER: the front laser.
    Front,
    /// RLASER: the rear laser.
    Rear,
    /// ROBOTLASER1: a laser with its geometry in the line.
    Robot,
}

/// One laser scan of the log with the odometry logged beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanRecord {
    /// The robot's odometry pose when the scan was taken.
    pub odometry: Odometry,
    /// The scan in the laser's frame.
    pub scan: LaserScan,
    /// The laser's pose as logged (in a "corrected" log, the scan-matched pose).
    pub logged_laser_pose: Pose2,
    /// The laser's pose on the robot (from PARAM offsets or the ROBOTLASER1 line).
    pub laser_offset: Pose2,
    /// Which laser.
    pub source: LaserSource,
    /// 1-based line number in the log.
    pub line: usize,
}

/// A parsed CARMEN log.
#[derive(Debug, Clone, Default)]
pub struct CarmenLog {
    /// Laser scans with odometry, in time order (stable for equal stamps).
    pub scans: Vec<ScanRecord>,
    /// ODOM lines, in time order.
    pub odometry: Vec<Odometry>,
    /// PARAM lines read.
    pub params: BTreeMap<String, String>,
    /// Lines skipped, by kind (PARAM lines count as read, not skipped).
    pub skipped: BTreeMap<String, usize>,
    /// What the reader repaired: reordering, duplicates, odometry interpolation.
    pub repairs: Repairs,
}

/// Where each scan's odometry comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OdometrySource {
    /// ODOM lines interpolated at the scan's stamp where ODOM lines bracket it; the scan line's own
    /// odometry fields elsewhere (and in logs without ODOM lines). The default: a scan line's odometry
    /// fields hold whichever ODOM message arrived last, up to one odometry period away from the scan.
    #[default]
    Interpolated,
    /// The odometry fields of the scan's own line (FLASER/RLASER `odom_*`, ROBOTLASER1 robot pose), as
    /// GMapping's log reader takes them.
    Line,
}

impl std::str::FromStr for OdometrySource {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "interpolated" => Ok(OdometrySource::Interpolated),
            "line" => Ok(OdometrySource::Line),
            _ => Err(format!("unknown odometry source '{s}' (expected interpolated or line)")),
        }
    }
}

impl std::fmt::Display for OdometrySource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OdometrySource::Interpolated => "interpolated",
            OdometrySource::Line => "line",
        })
    }
}

/// How a log is read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadOptions {
    /// Where each scan's odometry comes from.
    pub odometry: OdometrySource,
    /// A sensor line stamped more than this many seconds before a sensor line above it is refused.
    ///
    /// Real logs interleave sensors by arrival, so stamps step back by up to about one second (the
    /// Radish logs: up to 0.9 s); a step of many seconds means two logs concatenated or a clock reset,
    /// which reordering would silently scramble.
    pub max_step_back: f64,
    /// Repair ODOM increments that report driving backwards (`tv` < 0) but move the pose forwards: some
    /// robots' odometry integrates the speed's magnitude, so reversing reads as driving ahead. Counted in
    /// [`Repairs::reversed_increments`].
    pub repair_reversing: bool,
    /// Seconds by which each scan was taken before its stamp: odometry is interpolated at the stamp minus
    /// this (0: at the stamp). Only with [`OdometrySource::Interpolated`].
    pub scan_latency: f64,
}

/// The default bound on stamps stepping back, seconds ([`ReadOptions::max_step_back`]).
pub const MAX_STEP_BACK: f64 = 5.0;

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            odometry: OdometrySource::Interpolated,
            max_step_back: MAX_STEP_BACK,
            repair_reversing: true,
            scan_latency: 0.0,
        }
    }
}

/// What the reader repaired in a log, counted.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Repairs {
    /// Sensor lines (laser or ODOM) stamped before a sensor line above them; all were put in stamp order.
    pub out_of_order: usize,
    /// The largest step back, seconds.
    pub max_step_back: f64,
    /// Line of the largest step back (0 when none).
    pub max_step_back_line: usize,
    /// Scan lines dropped as exact repeats of another scan (same laser, stamp and ranges).
    pub duplicate_scans: usize,
    /// Scans kept that share their stamp with another, different scan.
    pub shared_scan_stamps: usize,
    /// ODOM lines dropped because another ODOM line has the same stamp.
    pub duplicate_odometry: usize,
    /// ODOM increments that reported reversing (`tv` < 0) but moved forwards, turned round
    /// ([`ReadOptions::repair_reversing`]).
    pub reversed_increments: usize,
    /// Scans whose odometry was interpolated from ODOM lines at the scan's stamp.
    pub interpolated_odometry: usize,
    /// Scans whose odometry is their own line's.
    pub line_odometry: usize,
}

impl Repairs {
    /// One line for summaries, e.g. "4932 stamps out of order (max 0.50 s back, line 90), reordered".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.out_of_order > 0 {
            parts.push(format!(
                "{} stamps out of order (max {:.2} s back, line {}), reordered",
                self.out_of_order, self.max_step_back, self.max_step_back_line
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
        match (self.interpolated_odometry, self.line_odometry) {
            (0, n) => format!("the scan lines' own odometry fields ({n} scans)"),
            (n, 0) => format!("ODOM lines interpolated at every scan's stamp ({n} scans)"),
            (n, m) => format!("ODOM lines interpolated at {n} scans' stamps, the scan line's own fields at {m}"),
        }
    }
}

/// Errors reading a log.
#[derive(Debug, thiserror::Error)]
pub enum CarmenError {
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A compressed log ends before its stream does.
    #[error("{path}: cut off after line {line}: the gzip stream ends early (a truncated download or copy?)")]
    Truncated {
        /// File at fault.
        path: PathBuf,
        /// Last complete line.
        line: usize,
    },
    /// A line of a known kind is malformed.
    #[error("{path}:{line}: {kind}: {message}")]
    Line {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Line kind (FLASER, ODOM, ...).
        kind: String,
        /// What is wrong.
        message: String,
    },
}

/// Laser geometry of the FLASER/RLASER lines, from PARAM lines or defaults.
#[derive(Default)]
struct OldLaser {
    fov_deg: Option<f64>,
    resolution_deg: Option<f64>,
    max_range: Option<f32>,
    offset_x: f64,
    offset_y: f64,
    offset_theta: f64,
}

impl CarmenLog {
    /// Reads a log file with the default [`ReadOptions`], gunzipping it when it starts with the gzip magic.
    pub fn read(path: &Path) -> Result<CarmenLog, CarmenError> {
        Self::read_with(path, &ReadOptions::default())
    }

    /// Reads a log file with `options`, gunzipping it when it starts with the gzip magic bytes.
    pub fn read_with(path: &Path, options: &ReadOptions) -> Result<CarmenLog, CarmenError> {
        let io = |cause| CarmenError::Io { path: path.to_path_buf(), cause };
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut magic = [0u8; 2];
        let n = file.read(&mut magic).map_err(io)?;
        let file = std::fs::File::open(path).map_err(io)?;
        let reader: Box<dyn BufRead> = if n == 2 && magic == [0x1f, 0x8b] {
            Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(file)))
        } else {
            Box::new(BufReader::new(file))
        };
        Self::parse_with(reader, path, options)
    }

    /// Parses a log from a reader with the default [`ReadOptions`]; `path` only names the source in errors.
    pub fn parse(reader: impl BufRead, path: &Path) -> Result<CarmenLog, CarmenError> {
        Self::parse_with(reader, path, &ReadOptions::default())
    }

    /// Parses a log from a reader; `path` only names the source in errors.
    ///
    /// Sensor lines are put in stamp order (stable for equal stamps); exact repeats of a scan and ODOM
    /// lines repeating a stamp are dropped; each scan's odometry is taken as `options.odometry` says.
    /// Every repair is counted in [`CarmenLog::repairs`].
    pub fn parse_with(reader: impl BufRead, path: &Path, options: &ReadOptions) -> Result<CarmenLog, CarmenError> {
        let mut log = CarmenLog::default();
        let mut front = OldLaser::default();
        let mut rear = OldLaser::default();
        // The latest sensor stamp so far in file order, and its line.
        let mut latest: Option<(f64, usize)> = None;
        // ODOM readings with their translational velocity `tv`.
        let mut odometry: Vec<(Odometry, f64)> = Vec::new();
        for (i, line) in reader.lines().enumerate() {
            let line_no = i + 1;
            let line = line.map_err(|cause| match cause.kind() {
                // A gzip stream that ends before its end marker: a truncated file.
                std::io::ErrorKind::UnexpectedEof => CarmenError::Truncated { path: path.to_path_buf(), line: i },
                _ => CarmenError::Io { path: path.to_path_buf(), cause },
            })?;
            let mut fields = line.split_whitespace();
            let Some(kind) = fields.next() else { continue };
            let rest: Vec<&str> = fields.collect();
            let err = |message: String| CarmenError::Line {
                path: path.to_path_buf(),
                line: line_no,
                kind: kind.to_string(),
                message,
            };
            let stamp = match kind {
                "PARAM" => {
                    if let [name, value, ..] = rest.as_slice() {
                        log.params.insert(name.to_string(), value.to_string());
                        let num = value.parse::<f64>().ok();
                        let laser = if name.contains("front") { &mut front } else { &mut rear };
                        match *name {
                            "laser_front_laser_fov" | "laser_rear_laser_fov" => laser.fov_deg = num,
                            "laser_front_laser_resolution" | "laser_rear_laser_resolution" => {
                                laser.resolution_deg = num
                            }
                            "robot_front_laser_max" | "robot_rear_laser_max" => laser.max_range = num.map(|v| v as f32),
                            "robot_frontlaser_offset" | "robot_rearlaser_offset" => laser.offset_x = num.unwrap_or(0.0),
                            "robot_frontlaser_side_offset" | "robot_rearlaser_side_offset" => {
                                laser.offset_y = num.unwrap_or(0.0)
                            }
                            "robot_frontlaser_angular_offset" | "robot_rearlaser_angular_offset" => {
                                laser.offset_theta = num.unwrap_or(0.0)
                            }
                            _ => {}
                        }
                    }
                    None
                }
                "FLASER" | "RLASER" => {
                    let (laser, source) =
                        if kind == "FLASER" { (&front, LaserSource::Front) } else { (&rear, LaserSource::Rear) };
                    let record = parse_old_laser(&rest, laser, source, line_no).map_err(err)?;
                    let stamp = record.scan.stamp;
                    log.scans.push(record);
                    Some(stamp)
                }
                "ROBOTLASER1" => {
                    let record = parse_robot_laser(&rest, line_no).map_err(err)?;
                    let stamp = record.scan.stamp;
                    log.scans.push(record);
                    Some(stamp)
                }
                "ODOM" => {
                    let v = numbers(&rest, 7, "x y theta tv rv accel ipc_timestamp").map_err(err)?;
                    odometry.push((Odometry { stamp: v[6], pose: pose(v[0], v[1], v[2]) }, v[3]));
                    // Scans that take their own line's odometry do not depend on the ODOM lines' stamps.
                    (options.odometry != OdometrySource::Line).then_some(v[6])
                }
                k if k.starts_with('#') => {
                    *log.skipped.entry("comment".into()).or_default() += 1;
                    None
                }
                k => {
                    *log.skipped.entry(k.to_string()).or_default() += 1;
                    None
                }
            };
            if let Some(stamp) = stamp {
                match latest {
                    Some((t, at)) if stamp < t => {
                        let back = t - stamp;
                        if back > options.max_step_back {
                            return Err(err(format!(
                                "ipc_timestamp {stamp} is {back:.3} s before the stamp {t} on line {at}: more than \
                                 the {} s a log may step back (two logs joined, or a clock reset?){}",
                                options.max_step_back,
                                if kind == "ODOM" {
                                    "; `--odometry line` takes each scan's odometry from its own line and leaves the \
                                     ODOM lines' stamps alone"
                                } else {
                                    ""
                                }
                            )));
                        }
                        let r = &mut log.repairs;
                        r.out_of_order += 1;
                        if back > r.max_step_back {
                            r.max_step_back = back;
                            r.max_step_back_line = line_no;
                        }
                    }
                    _ => latest = Some((stamp, line_no)),
                }
            }
        }
        log.scans.sort_by(|a, b| a.scan.stamp.total_cmp(&b.scan.stamp));
        odometry.sort_by(|a, b| a.0.stamp.total_cmp(&b.0.stamp));
        let before = odometry.len();
        odometry.dedup_by(|b, a| a.0.stamp == b.0.stamp);
        log.repairs.duplicate_odometry = before - odometry.len();
        if options.repair_reversing {
            log.repairs.reversed_increments = repair_reversing(&mut odometry);
        }
        log.odometry = odometry.into_iter().map(|(o, _)| o).collect();
        log.drop_duplicates();
        log.assign_odometry(options.odometry, options.scan_latency);
        Ok(log)
    }

    /// Drops exact repeats of scans (sorted by stamp already).
    fn drop_duplicates(&mut self) {
        let mut kept: Vec<ScanRecord> = Vec::with_capacity(self.scans.len());
        for s in std::mem::take(&mut self.scans) {
            // Earlier scans with the same stamp sit right before this one.
            let same_stamp = kept.iter().rev().take_while(|k| k.scan.stamp == s.scan.stamp);
            let mut shares = false;
            let mut repeat = false;
            for k in same_stamp {
                shares = true;
                repeat |= k.source == s.source && k.scan.ranges == s.scan.ranges;
            }
            if repeat {
                self.repairs.duplicate_scans += 1;
            } else {
                if shares {
                    self.repairs.shared_scan_stamps += 1;
                }
                kept.push(s);
            }
        }
        self.scans = kept;
    }

    /// Sets each scan's odometry as `source` says (see [`OdometrySource`]).
    fn assign_odometry(&mut self, source: OdometrySource, latency: f64) {
        let odometry = &self.odometry;
        let mut interpolated = 0;
        if source == OdometrySource::Interpolated && odometry.len() >= 2 {
            // Both sorted: walk the ODOM lines once.
            let mut k = 0;
            for s in &mut self.scans {
                let t = s.scan.stamp - latency;
                while k + 2 < odometry.len() && odometry[k + 1].stamp <= t {
                    k += 1;
                }
                let (a, b) = (&odometry[k], &odometry[k + 1]);
                if a.stamp <= t && t <= b.stamp {
                    let span = b.stamp - a.stamp;
                    let f = if span > 0.0 { (t - a.stamp) / span } else { 0.0 };
                    s.odometry = Odometry { stamp: s.scan.stamp, pose: interpolate(&a.pose, &b.pose, f) };
                    interpolated += 1;
                }
            }
        }
        self.repairs.interpolated_odometry = interpolated;
        self.repairs.line_odometry = self.scans.len() - interpolated;
    }

    /// Total number of skipped lines.
    pub fn skipped_total(&self) -> usize {
        self.skipped.values().sum()
    }
}

/// Turns round the translation of every ODOM increment that reports reversing (`tv` < 0 at its end) but
/// moves the pose forwards, and integrates the increments again from the first reading; returns how many.
fn repair_reversing(odometry: &mut [(Odometry, f64)]) -> usize {
    let mut repaired = 0;
    let Some(first) = odometry.first() else { return 0 };
    let mut previous_raw = first.0.pose;
    let mut integrated = first.0.pose;
    for (o, tv) in odometry.iter_mut().skip(1) {
        let raw = o.pose;
        let mut step = previous_raw.inv_mul(&raw);
        if *tv < 0.0 && step.translation.x > 0.0 {
            step.translation.vector = -step.translation.vector;
            repaired += 1;
        }
        integrated *= step;
        previous_raw = raw;
        if repaired > 0 {
            o.pose = integrated;
        }
    }
    repaired
}

/// Parses the first `n` fields as finite numbers, naming the expected layout on failure.
fn numbers(fields: &[&str], n: usize, layout: &str) -> Result<Vec<f64>, String> {
    if fields.len() < n {
        return Err(format!("expected at least {n} fields ({layout}), found {}", fields.len()));
    }
    fields[..n]
        .iter()
        .enumerate()
        .map(|(k, f)| {
            f.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("field {} (`{f}`) is not a finite number", k + 1))
        })
        .collect()
}

fn parse_count(fields: &[&str], at: usize, what: &str) -> Result<usize, String> {
    let f = fields.get(at).ok_or_else(|| format!("missing {what}"))?;
    let n: usize = f.parse().map_err(|_| format!("{what} `{f}` is not a count"))?;
    if n > 100_000 {
        return Err(format!("{what} {n} is implausibly large"));
    }
    Ok(n)
}

fn parse_old_laser(f: &[&str], laser: &OldLaser, source: LaserSource, line: usize) -> Result<ScanRecord, String> {
    let n = parse_count(f, 0, "beam count")?;
    let ranges: Vec<f32> = numbers(&f[1..], n, "ranges")?.into_iter().map(|v| v as f32).collect();
    let tail = &f[1 + n..];
    let v = numbers(tail, 7, "x y theta odom_x odom_y odom_theta ipc_timestamp after the ranges")?;
    // Old CARMEN lasers span 180 degrees unless PARAM says otherwise; an odd beam count includes both ends.
    let fov = laser.fov_deg.unwrap_or(180.0).to_radians();
    let inc = match laser.resolution_deg {
        Some(r) if r > 0.0 => r.to_radians(),
        _ if n > 1 && n % 2 == 1 => fov / (n - 1) as f64,
        _ => fov / n.max(1) as f64,
    };
    let turn = if source == LaserSource::Rear { std::f64::consts::PI } else { 0.0 };
    let range_max = laser.max_range.unwrap_or(80.0).max(1e-3);
    let stamp = v[6];
    Ok(ScanRecord {
        odometry: Odometry { stamp, pose: pose(v[3], v[4], v[5]) },
        scan: LaserScan { stamp, angle_min: -fov / 2.0, angle_increment: inc, range_min: 0.0, range_max, ranges },
        logged_laser_pose: pose(v[0], v[1], v[2]),
        laser_offset: pose(laser.offset_x, laser.offset_y, turn + laser.offset_theta),
        source,
        line,
    })
}

fn parse_robot_laser(f: &[&str], line: usize) -> Result<ScanRecord, String> {
    let head = numbers(f, 6, "type start_angle fov resolution max_range accuracy")?;
    let n = parse_count(f, 7, "beam count")?;
    let ranges: Vec<f32> = numbers(&f[8..], n, "ranges")?.into_iter().map(|v| v as f32).collect();
    let m = parse_count(f, 8 + n, "remission count")?;
    let tail = f.get(9 + n + m..).ok_or("line ends inside the remissions")?;
    let v = numbers(tail, 12, "laser pose, robot pose, tv rv, safety distances, turn axis, ipc_timestamp")?;
    let laser = pose(v[0], v[1], v[2]);
    let robot = pose(v[3], v[4], v[5]);
    let range_max = (head[4] as f32).max(1e-3);
    let stamp = v[11];
    Ok(ScanRecord {
        odometry: Odometry { stamp, pose: robot },
        scan: LaserScan { stamp, angle_min: head[1], angle_increment: head[3], range_min: 0.0, range_max, ranges },
        logged_laser_pose: laser,
        laser_offset: robot.inv_mul(&laser),
        source: LaserSource::Robot,
        line,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::se2::Xyt;

    const LOG: &str = "\
# CARMEN Logfile
PARAM laser_front_laser_resolution 1.0 1.0 host 1.0
PARAM robot_front_laser_max 8.0 1.0 host 1.0
ODOM 0.5 0.25 0.1 0.3 0.0 0.0 2.0 host 2.0
FLASER 3 1.0 2.0 3.5 1.1 1.2 0.3 0.9 1.0 0.2 3.0 host 3.0
NEFF 12.0 3.0 host 3.0
ROBOTLASER1 0 -1.5 3.0 1.5 20.0 0.01 0 3 4.0 5.0 6.0 0 2.1 2.2 0.5 2.0 2.0 0.5 0.1 0.0 0.5 0.5 0.0 2.5 host 2.5
RLASER 2 7.0 8.0 0 0 0 0 0 0 4.0 host 4.0
ODOM 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0
";

    fn assert_close(a: Xyt, b: (f64, f64, f64)) {
        assert!(
            (a.x - b.0).abs() < 1e-12 && (a.y - b.1).abs() < 1e-12 && (a.theta - b.2).abs() < 1e-12,
            "{a:?} != {b:?}"
        );
    }

    #[test]
    fn parses_every_line_kind() {
        let log = CarmenLog::parse(LOG.as_bytes(), Path::new("t.log")).unwrap();
        assert_eq!(log.scans.len(), 3);
        assert_eq!(log.skipped.get("NEFF"), Some(&1));
        assert_eq!(log.skipped.get("comment"), Some(&1));
        // time-ordered: ROBOTLASER1 (2.5), FLASER (3.0), RLASER (4.0); ODOM 1.0 before 2.0
        let stamps: Vec<f64> = log.scans.iter().map(|s| s.scan.stamp).collect();
        assert_eq!(stamps, [2.5, 3.0, 4.0]);
        assert_eq!(log.odometry.iter().map(|o| o.stamp).collect::<Vec<_>>(), [1.0, 2.0]);
        let Xyt { x, y, theta: t } = Xyt::from_pose(&log.odometry[1].pose);
        assert!((x - 0.5).abs() < 1e-12 && (y - 0.25).abs() < 1e-12 && (t - 0.1).abs() < 1e-12);

        let rl = &log.scans[0];
        assert_eq!(rl.source, LaserSource::Robot);
        assert_eq!(rl.scan.ranges, [4.0, 5.0, 6.0]);
        assert_eq!((rl.scan.angle_min, rl.scan.angle_increment, rl.scan.range_max), (-1.5, 1.5, 20.0));
        assert_close(Xyt::from_pose(&rl.odometry.pose), (2.0, 2.0, 0.5));
        let Xyt { x: ox, y: oy, .. } = Xyt::from_pose(&rl.laser_offset);
        assert!((ox.hypot(oy) - 0.1f64.hypot(0.2)).abs() < 1e-9);

        let fl = &log.scans[1];
        assert_eq!(fl.source, LaserSource::Front);
        assert_eq!(fl.scan.ranges, [1.0, 2.0, 3.5]);
        assert!((fl.scan.angle_increment - 1f64.to_radians()).abs() < 1e-12);
        assert!((fl.scan.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(fl.scan.range_max, 8.0);
        assert_close(Xyt::from_pose(&fl.odometry.pose), (0.9, 1.0, 0.2));
        assert_close(Xyt::from_pose(&fl.logged_laser_pose), (1.1, 1.2, 0.3));
        assert_eq!(fl.line, 5);

        let rr = &log.scans[2];
        assert_eq!(rr.source, LaserSource::Rear);
        assert!((Xyt::from_pose(&rr.laser_offset).theta - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn short_line_names_its_number() {
        let text = "ODOM 0 0 0 0 0 0 1 h 1\nFLASER 3 1.0 2.0\n";
        let e = CarmenLog::parse(text.as_bytes(), Path::new("bad.clf")).unwrap_err().to_string();
        assert!(e.starts_with("bad.clf:2: FLASER:"), "{e}");
        let e = CarmenLog::parse("ODOM 1 2 x 0 0 0 1 h 1\n".as_bytes(), Path::new("b.clf")).unwrap_err().to_string();
        assert!(e.contains("b.clf:1: ODOM: field 3"), "{e}");
        let e = CarmenLog::parse("FLASER 99999999 1\n".as_bytes(), Path::new("b.clf")).unwrap_err().to_string();
        assert!(e.contains("implausibly large"), "{e}");
    }

    #[test]
    fn reads_gzip_transparently() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.gz");
        let mut enc = flate2::write::GzEncoder::new(std::fs::File::create(&p).unwrap(), flate2::Compression::fast());
        enc.write_all(LOG.as_bytes()).unwrap();
        enc.finish().unwrap();
        assert_eq!(CarmenLog::read(&p).unwrap().scans.len(), 3);
        let e = CarmenLog::read(&dir.path().join("missing.log")).unwrap_err().to_string();
        assert!(e.contains("missing.log"), "{e}");
    }

    #[test]
    fn a_truncated_gzip_is_refused() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        for _ in 0..200 {
            enc.write_all(LOG.as_bytes()).unwrap();
        }
        let bytes = enc.finish().unwrap();
        for cut in [bytes.len() - 4, bytes.len() - 8, bytes.len() / 2, 12] {
            std::fs::write(&p, &bytes[..cut]).unwrap();
            let e = CarmenLog::read(&p).unwrap_err().to_string();
            assert!(e.contains("log.gz") && e.contains("cut off"), "cut at {cut}: {e}");
        }
    }

    /// An ODOM stream at 10 Hz moving 1 m/s along x and turning 0.1 rad/s, and FLASER lines at 5 Hz whose
    /// own odometry fields are stale, written in arrival order (each line up to 0.15 s late).
    fn interleaved_lines() -> Vec<(f64, String)> {
        let mut lines = Vec::new();
        for k in 0..30 {
            let t = 1.0 + 0.1 * k as f64;
            let arrival = t + if k % 3 == 0 { 0.15 } else { 0.0 };
            lines.push((arrival, format!("ODOM {:.6} 0 {:.6} 1 0.1 0 {t:.6} h {t:.6}", t - 1.0, 0.1 * (t - 1.0))));
        }
        for k in 0..14 {
            let t = 1.05 + 0.2 * k as f64;
            lines.push((t + 0.02, format!("FLASER 3 1.0 2.0 {}.5 0 0 0 9 9 9 {t:.6} h {t:.6}", k)));
        }
        lines.sort_by(|a, b| a.0.total_cmp(&b.0));
        lines
    }

    #[test]
    fn interleaved_stamps_are_reordered_counted_and_interpolated() {
        let lines = interleaved_lines();
        let text: String = lines.iter().map(|(_, l)| format!("{l}\n")).collect();
        let log = CarmenLog::parse(text.as_bytes(), Path::new("i.clf")).unwrap();
        assert!(log.repairs.out_of_order > 5, "{:?}", log.repairs);
        assert!((log.repairs.max_step_back - 0.15).abs() < 0.06, "{:?}", log.repairs);
        assert_eq!((log.repairs.interpolated_odometry, log.repairs.line_odometry), (14, 0));
        for s in &log.scans {
            let e = s.scan.stamp - 1.0;
            assert_close(Xyt::from_pose(&s.odometry.pose), (e, 0.0, 0.1 * e));
            assert_eq!(s.odometry.stamp, s.scan.stamp);
        }
        // The same lines in stamp order read the same.
        let mut sorted = lines.clone();
        sorted.sort_by(|a, b| {
            let stamp = |l: &str| l.split_whitespace().rev().nth(2).unwrap().parse::<f64>().unwrap();
            stamp(&a.1).total_cmp(&stamp(&b.1))
        });
        let text: String = sorted.iter().map(|(_, l)| format!("{l}\n")).collect();
        let ordered = CarmenLog::parse(text.as_bytes(), Path::new("s.clf")).unwrap();
        assert_eq!(ordered.repairs.out_of_order, 0);
        assert_eq!(
            ordered.scans.iter().map(|s| s.odometry).collect::<Vec<_>>(),
            log.scans.iter().map(|s| s.odometry).collect::<Vec<_>>()
        );
        // The line's own fields on request.
        let opts = ReadOptions { odometry: OdometrySource::Line, ..ReadOptions::default() };
        let text: String = lines.iter().map(|(_, l)| format!("{l}\n")).collect();
        let own = CarmenLog::parse_with(text.as_bytes(), Path::new("i.clf"), &opts).unwrap();
        assert_eq!(own.repairs.line_odometry, 14);
        assert_close(Xyt::from_pose(&own.scans[0].odometry.pose), (9.0, 9.0, 9.0 - 2.0 * std::f64::consts::PI));
    }

    #[test]
    fn a_large_step_back_is_refused_naming_the_line() {
        let text = "ODOM 0 0 0 0 0 0 100.0 h 1\nODOM 0 0 0 0 0 0 101.0 h 1\nODOM 0 0 0 0 0 0 90.0 h 1\n";
        let e = CarmenLog::parse(text.as_bytes(), Path::new("b.clf")).unwrap_err().to_string();
        assert!(e.starts_with("b.clf:3: ODOM: ipc_timestamp 90 is 11.000 s before the stamp 101 on line 2"), "{e}");
        let opts = ReadOptions { max_step_back: 20.0, ..ReadOptions::default() };
        let log = CarmenLog::parse_with(text.as_bytes(), Path::new("b.clf"), &opts).unwrap();
        assert_eq!((log.repairs.out_of_order, log.repairs.max_step_back_line), (1, 3));
    }

    #[test]
    fn odometry_lines_out_of_time_are_refused_unless_scans_take_their_own_odometry() {
        // As GMapping writes its logs: ODOM lines of another clock between the stamped ones.
        let text = "\
ODOM 0.1 0 0 0 0 0 10.0 h 10.0
FLASER 3 1 2 3 0.1 0 0 0.1 0 0 10.0 h 10.0
ODOM 9 9 0 0 0 0 0.7 h 0.7
ODOM 0.2 0 0 0 0 0 11.0 h 11.0
FLASER 3 1 2 3 0.2 0 0 0.2 0 0 11.0 h 11.0
";
        let e = CarmenLog::parse(text.as_bytes(), Path::new("g.log")).unwrap_err().to_string();
        assert!(
            e.starts_with("g.log:3: ODOM: ipc_timestamp 0.7 is 9.300 s before") && e.contains("--odometry line"),
            "{e}"
        );
        let opts = ReadOptions { odometry: OdometrySource::Line, ..ReadOptions::default() };
        let log = CarmenLog::parse_with(text.as_bytes(), Path::new("g.log"), &opts).unwrap();
        assert_eq!((log.scans.len(), log.repairs.out_of_order, log.repairs.line_odometry), (2, 0, 2));
        assert_close(Xyt::from_pose(&log.scans[1].odometry.pose), (0.2, 0.0, 0.0));
    }

    #[test]
    fn repeated_scans_and_odometry_stamps_are_dropped_and_counted() {
        let text = "\
ODOM 0 0 0 0 0 0 1.0 h 1
ODOM 1 0 0 0 0 0 1.0 h 1
ODOM 2 0 0 0 0 0 2.0 h 1
FLASER 2 1.0 2.0 0 0 0 0 0 0 1.5 h 1
FLASER 2 1.0 2.0 0 0 0 0 0 0 1.5 h 1
FLASER 2 1.0 3.0 0 0 0 0 0 0 1.5 h 1
";
        let log = CarmenLog::parse(text.as_bytes(), Path::new("d.clf")).unwrap();
        let r = log.repairs;
        assert_eq!((r.duplicate_scans, r.shared_scan_stamps, r.duplicate_odometry), (1, 1, 1));
        assert_eq!(log.scans.len(), 2);
        // The first ODOM line of a repeated stamp is kept: x goes 0 -> 2 over 1 s.
        assert_close(Xyt::from_pose(&log.scans[0].odometry.pose), (1.0, 0.0, 0.0));
        assert!(r.describe().contains("1 repeated scans dropped"), "{}", r.describe());
    }

    #[test]
    fn param_lines_set_the_lasers_mounting() {
        let text = "\
PARAM robot_frontlaser_offset 0.2 h 1
PARAM robot_frontlaser_side_offset 0.1 h 1
PARAM robot_frontlaser_angular_offset 0.05 h 1
FLASER 2 1.0 2.0 0 0 0 0 0 0 1.5 h 1
";
        let log = CarmenLog::parse(text.as_bytes(), Path::new("p.clf")).unwrap();
        assert_close(Xyt::from_pose(&log.scans[0].laser_offset), (0.2, 0.1, 0.05));
    }

    #[test]
    fn reversing_read_as_driving_ahead_is_turned_round() {
        let text = "\
ODOM 0 0 0 0 0 0 0.0 h 1
ODOM 1 0 0 1 0 0 1.0 h 1
ODOM 2 0 0 -1 0 0 2.0 h 1
ODOM 3 0 0 1 0 0 3.0 h 1
FLASER 2 1.0 2.0 0 0 0 0 0 0 2.5 h 1
";
        let log = CarmenLog::parse(text.as_bytes(), Path::new("r.clf")).unwrap();
        assert_eq!(log.repairs.reversed_increments, 1);
        let xs: Vec<f64> = log.odometry.iter().map(|o| o.pose.translation.x).collect();
        assert_eq!(xs, [0.0, 1.0, 0.0, 1.0]);
        assert_close(Xyt::from_pose(&log.scans[0].odometry.pose), (0.5, 0.0, 0.0));
        assert!(log.repairs.describe().contains("1 ODOM increments reported reversing"));
        let keep = ReadOptions { repair_reversing: false, ..ReadOptions::default() };
        let log = CarmenLog::parse_with(text.as_bytes(), Path::new("r.clf"), &keep).unwrap();
        assert_eq!(log.repairs.reversed_increments, 0);
        assert_eq!(log.odometry[2].pose.translation.x, 2.0);
        // A scan taken 0.5 s before its stamp takes the odometry of then.
        let late = ReadOptions { scan_latency: 0.5, ..ReadOptions::default() };
        let log = CarmenLog::parse_with(text.as_bytes(), Path::new("r.clf"), &late).unwrap();
        assert_close(Xyt::from_pose(&log.scans[0].odometry.pose), (0.0, 0.0, 0.0));
        assert_eq!(log.scans[0].odometry.stamp, 2.5);
    }
}
