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
//! `robot_front_laser_max`); other PARAM lines, comments and unknown kinds (e.g. NEFF, SYNC) are
//! skipped and counted. A malformed line of a known kind is an error naming its line number: a log that
//! lies about its own format is not one to map from silently.

use crate::pose::{Pose2, pose};
use crate::scan::{LaserScan, Odometry};
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
struct OldLaser {
    fov_deg: Option<f64>,
    resolution_deg: Option<f64>,
    max_range: Option<f32>,
    offset_x: f64,
}

impl CarmenLog {
    /// Reads a log file, gunzipping it when it starts with the gzip magic bytes.
    pub fn read(path: &Path) -> Result<CarmenLog, CarmenError> {
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
        Self::parse(reader, path)
    }

    /// Parses a log from a reader; `path` only names the source in errors.
    pub fn parse(reader: impl BufRead, path: &Path) -> Result<CarmenLog, CarmenError> {
        let mut log = CarmenLog::default();
        let mut front = OldLaser { fov_deg: None, resolution_deg: None, max_range: None, offset_x: 0.0 };
        let mut rear = OldLaser { fov_deg: None, resolution_deg: None, max_range: None, offset_x: 0.0 };
        for (i, line) in reader.lines().enumerate() {
            let line_no = i + 1;
            let line = line.map_err(|cause| CarmenError::Io { path: path.to_path_buf(), cause })?;
            let mut fields = line.split_whitespace();
            let Some(kind) = fields.next() else { continue };
            let rest: Vec<&str> = fields.collect();
            let err = |message: String| CarmenError::Line {
                path: path.to_path_buf(),
                line: line_no,
                kind: kind.to_string(),
                message,
            };
            match kind {
                "PARAM" => {
                    if let [name, value, ..] = rest.as_slice() {
                        log.params.insert(name.to_string(), value.to_string());
                        let num = value.parse::<f64>().ok();
                        match *name {
                            "laser_front_laser_fov" => front.fov_deg = num,
                            "laser_front_laser_resolution" => front.resolution_deg = num,
                            "robot_front_laser_max" => front.max_range = num.map(|v| v as f32),
                            "robot_frontlaser_offset" => front.offset_x = num.unwrap_or(0.0),
                            "laser_rear_laser_fov" => rear.fov_deg = num,
                            "laser_rear_laser_resolution" => rear.resolution_deg = num,
                            "robot_rear_laser_max" => rear.max_range = num.map(|v| v as f32),
                            "robot_rearlaser_offset" => rear.offset_x = num.unwrap_or(0.0),
                            _ => {}
                        }
                    }
                }
                "FLASER" | "RLASER" => {
                    let (laser, source) =
                        if kind == "FLASER" { (&front, LaserSource::Front) } else { (&rear, LaserSource::Rear) };
                    log.scans.push(parse_old_laser(&rest, laser, source, line_no).map_err(err)?);
                }
                "ROBOTLASER1" => log.scans.push(parse_robot_laser(&rest, line_no).map_err(err)?),
                "ODOM" => {
                    let v = numbers(&rest, 7, "x y theta tv rv accel ipc_timestamp").map_err(err)?;
                    log.odometry.push(Odometry { stamp: v[6], pose: pose(v[0], v[1], v[2]) });
                }
                k if k.starts_with('#') => *log.skipped.entry("comment".into()).or_default() += 1,
                k => *log.skipped.entry(k.to_string()).or_default() += 1,
            }
        }
        log.scans.sort_by(|a, b| a.scan.stamp.total_cmp(&b.scan.stamp));
        log.odometry.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        Ok(log)
    }

    /// Total number of skipped lines.
    pub fn skipped_total(&self) -> usize {
        self.skipped.values().sum()
    }
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
        laser_offset: pose(laser.offset_x, 0.0, turn),
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
    use crate::pose::pose_xyt;

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

    fn assert_close(a: (f64, f64, f64), b: (f64, f64, f64)) {
        assert!((a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12 && (a.2 - b.2).abs() < 1e-12, "{a:?} != {b:?}");
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
        let (x, y, t) = pose_xyt(&log.odometry[1].pose);
        assert!((x - 0.5).abs() < 1e-12 && (y - 0.25).abs() < 1e-12 && (t - 0.1).abs() < 1e-12);

        let rl = &log.scans[0];
        assert_eq!(rl.source, LaserSource::Robot);
        assert_eq!(rl.scan.ranges, [4.0, 5.0, 6.0]);
        assert_eq!((rl.scan.angle_min, rl.scan.angle_increment, rl.scan.range_max), (-1.5, 1.5, 20.0));
        assert_close(pose_xyt(&rl.odometry.pose), (2.0, 2.0, 0.5));
        let (ox, oy, _) = pose_xyt(&rl.laser_offset);
        assert!((ox.hypot(oy) - 0.1f64.hypot(0.2)).abs() < 1e-9);

        let fl = &log.scans[1];
        assert_eq!(fl.source, LaserSource::Front);
        assert_eq!(fl.scan.ranges, [1.0, 2.0, 3.5]);
        assert!((fl.scan.angle_increment - 1f64.to_radians()).abs() < 1e-12);
        assert!((fl.scan.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(fl.scan.range_max, 8.0);
        assert_close(pose_xyt(&fl.odometry.pose), (0.9, 1.0, 0.2));
        assert_close(pose_xyt(&fl.logged_laser_pose), (1.1, 1.2, 0.3));
        assert_eq!(fl.line, 5);

        let rr = &log.scans[2];
        assert_eq!(rr.source, LaserSource::Rear);
        assert!((pose_xyt(&rr.laser_offset).2 - std::f64::consts::PI).abs() < 1e-12);
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
}
