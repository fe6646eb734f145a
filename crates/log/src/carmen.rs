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
//! The reader parses the lines into a [`SensorLog`] (each scan's [`Source`] its line, its `sensor` the line's
//! kind), checking the sensor lines' stamps in file order ([`repair::StampOrder`]: a step back of more than
//! [`ReadOptions::max_step_back`] is refused, naming the line), then applies [`repair::apply_all`].

use crate::error::LogError;
use crate::options::ReadOptions;
use crate::repair::{self, StampOrder};
use crate::sensor_log::{OdometryRecord, ScanRecord, SensorLog};
use crate::source::Source;
use mrslam_core::{LaserScan, Odometry, pose};
use std::io::{BufRead, Read};
use std::path::Path;

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

/// Parses a CARMEN log from a reader and repairs it as `options` say; `path` only names the source in errors.
///
/// Sensor lines are put in stamp order (stable for equal stamps); exact repeats of a scan and ODOM
/// lines repeating a stamp are dropped; each scan's odometry is taken as `options.odometry` says.
/// Every repair is counted in [`SensorLog::repairs`].
pub fn parse(reader: impl BufRead, path: &Path, options: &ReadOptions) -> Result<SensorLog, LogError> {
    let mut log = SensorLog::default();
    let mut front = OldLaser::default();
    let mut rear = OldLaser::default();
    let mut order = StampOrder::new(options);
    // Every read goes through two bounds: the whole log's bytes and each line's, so that a device or a
    // decompression bomb is refused before it fills memory.
    let mut reader = reader.take(options.max_bytes.saturating_add(1));
    let mut bytes = Vec::new();
    let mut line_no = 0;
    // And what the records hold in memory, under the same bound: parsed, a log takes more room than its text.
    let mut held: u64 = 0;
    loop {
        bytes.clear();
        let line_limit = (options.max_line_bytes as u64).saturating_add(1);
        let n = (&mut reader).take(line_limit).read_until(b'\n', &mut bytes).map_err(|cause| match cause.kind() {
            // A gzip stream that ends before its end marker: a truncated file.
            std::io::ErrorKind::UnexpectedEof => LogError::Truncated { path: path.to_path_buf(), line: line_no },
            _ => LogError::Io { path: path.to_path_buf(), cause },
        })?;
        if n == 0 {
            break;
        }
        line_no += 1;
        if reader.limit() == 0 {
            return Err(LogError::TooLarge { path: path.to_path_buf(), limit: options.max_bytes, compressed: false });
        }
        if n as u64 == line_limit && bytes.last() != Some(&b'\n') {
            return Err(LogError::LineTooLong {
                path: path.to_path_buf(),
                line: line_no,
                limit: options.max_line_bytes,
            });
        }
        let line = std::str::from_utf8(&bytes).map_err(|e| LogError::Io {
            path: path.to_path_buf(),
            cause: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("line {line_no}: not UTF-8 text: {e}")),
        })?;
        let mut fields = line.split_whitespace();
        let Some(kind) = fields.next() else { continue };
        let rest: Vec<&str> = fields.collect();
        let source = Source::Line(line_no);
        let err = |message: String| LogError::Record {
            path: path.to_path_buf(),
            at: Source::Line(line_no),
            kind: kind.to_string(),
            message,
        };
        let stepped_back = |e: repair::StepBack| {
            err(format!(
                "ipc_timestamp {e}{}",
                if kind == "ODOM" {
                    "; `--odometry line` takes each scan's odometry from its own line and leaves the ODOM lines' \
                     stamps alone"
                } else {
                    ""
                }
            ))
        };
        match kind {
            "PARAM" => {
                if let [name, value, ..] = rest.as_slice() {
                    log.params.insert(name.to_string(), value.to_string());
                    let num = value.parse::<f64>().ok();
                    let laser = if name.contains("front") { &mut front } else { &mut rear };
                    match *name {
                        "laser_front_laser_fov" | "laser_rear_laser_fov" => laser.fov_deg = num,
                        "laser_front_laser_resolution" | "laser_rear_laser_resolution" => laser.resolution_deg = num,
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
            }
            "FLASER" | "RLASER" => {
                let rear_laser = kind == "RLASER";
                let laser = if rear_laser { &rear } else { &front };
                let record = parse_old_laser(&rest, laser, kind, rear_laser, source).map_err(err)?;
                order.scan(record.scan.stamp, &record.source).map_err(stepped_back)?;
                held += scan_bytes(&record);
                log.scans.push(record);
            }
            "ROBOTLASER1" => {
                let record = parse_robot_laser(&rest, kind, source).map_err(err)?;
                order.scan(record.scan.stamp, &record.source).map_err(stepped_back)?;
                held += scan_bytes(&record);
                log.scans.push(record);
            }
            "ODOM" => {
                let v = numbers(&rest, 7, "x y theta tv rv accel ipc_timestamp").map_err(err)?;
                let odometry = Odometry { stamp: v[6], pose: pose(v[0], v[1], v[2]) };
                log.odometry.push(OdometryRecord { odometry, forward_speed: v[3] });
                held += std::mem::size_of::<OdometryRecord>() as u64;
                order.odometry(v[6], &source).map_err(stepped_back)?;
            }
            k if k.starts_with('#') => *log.skipped.entry("comment".into()).or_default() += 1,
            k => *log.skipped.entry(k.to_string()).or_default() += 1,
        }
        if held > options.max_bytes {
            return Err(LogError::TooMuchHeld { path: path.to_path_buf(), line: line_no, limit: options.max_bytes });
        }
    }
    order.finish(&mut log);
    repair::apply_all(&mut log, options);
    Ok(log)
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

/// The memory a scan's record holds: the record, its ranges and its sensor's name.
fn scan_bytes(record: &ScanRecord) -> u64 {
    (std::mem::size_of::<ScanRecord>() + 4 * record.scan.ranges.len() + record.sensor.len()) as u64
}

fn parse_old_laser(f: &[&str], laser: &OldLaser, kind: &str, rear: bool, source: Source) -> Result<ScanRecord, String> {
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
    let turn = if rear { std::f64::consts::PI } else { 0.0 };
    let range_max = laser.max_range.unwrap_or(80.0).max(1e-3);
    let stamp = v[6];
    Ok(ScanRecord {
        odometry: Odometry { stamp, pose: pose(v[3], v[4], v[5]) },
        scan: LaserScan { stamp, angle_min: -fov / 2.0, angle_increment: inc, range_min: 0.0, range_max, ranges },
        logged_laser_pose: Some(pose(v[0], v[1], v[2])),
        laser_offset: pose(laser.offset_x, laser.offset_y, turn + laser.offset_theta),
        sensor: kind.to_string(),
        source,
    })
}

fn parse_robot_laser(f: &[&str], kind: &str, source: Source) -> Result<ScanRecord, String> {
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
        logged_laser_pose: Some(laser),
        laser_offset: robot.inv_mul(&laser),
        sensor: kind.to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OdometrySource, read_log};
    use mrslam_core::Xyt;

    fn parse_default(text: &str, path: &str) -> Result<SensorLog, LogError> {
        parse(text.as_bytes(), Path::new(path), &ReadOptions::default())
    }

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
        let log = parse_default(LOG, "t.log").unwrap();
        assert_eq!(log.scans.len(), 3);
        assert_eq!(log.skipped.get("NEFF"), Some(&1));
        assert_eq!(log.skipped.get("comment"), Some(&1));
        // time-ordered: ROBOTLASER1 (2.5), FLASER (3.0), RLASER (4.0); ODOM 1.0 before 2.0
        let stamps: Vec<f64> = log.scans.iter().map(|s| s.scan.stamp).collect();
        assert_eq!(stamps, [2.5, 3.0, 4.0]);
        assert_eq!(log.odometry.iter().map(|o| o.odometry.stamp).collect::<Vec<_>>(), [1.0, 2.0]);
        let Xyt { x, y, theta: t } = Xyt::from_pose(&log.odometry[1].odometry.pose);
        assert!((x - 0.5).abs() < 1e-12 && (y - 0.25).abs() < 1e-12 && (t - 0.1).abs() < 1e-12);

        let rl = &log.scans[0];
        assert_eq!(rl.sensor, "ROBOTLASER1");
        assert_eq!(rl.scan.ranges, [4.0, 5.0, 6.0]);
        assert_eq!((rl.scan.angle_min, rl.scan.angle_increment, rl.scan.range_max), (-1.5, 1.5, 20.0));
        assert_close(Xyt::from_pose(&rl.odometry.pose), (2.0, 2.0, 0.5));
        let Xyt { x: ox, y: oy, .. } = Xyt::from_pose(&rl.laser_offset);
        assert!((ox.hypot(oy) - 0.1f64.hypot(0.2)).abs() < 1e-9);

        let fl = &log.scans[1];
        assert_eq!(fl.sensor, "FLASER");
        assert_eq!(fl.scan.ranges, [1.0, 2.0, 3.5]);
        assert!((fl.scan.angle_increment - 1f64.to_radians()).abs() < 1e-12);
        assert!((fl.scan.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(fl.scan.range_max, 8.0);
        assert_close(Xyt::from_pose(&fl.odometry.pose), (0.9, 1.0, 0.2));
        assert_close(Xyt::from_pose(&fl.logged_laser_pose.unwrap()), (1.1, 1.2, 0.3));
        assert_eq!(fl.source, Source::Line(5));

        let rr = &log.scans[2];
        assert_eq!(rr.sensor, "RLASER");
        assert!((Xyt::from_pose(&rr.laser_offset).theta - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn a_line_longer_than_the_bound_is_refused_naming_it() {
        let opts = ReadOptions { max_line_bytes: 64, ..ReadOptions::default() };
        let text = format!("# CARMEN\nODOM 0 0 0 0 0 0 1.0 h 1\n{}\n", "9 ".repeat(40));
        let e = parse(text.as_bytes(), Path::new("l.clf"), &opts).unwrap_err();
        assert!(matches!(e, LogError::LineTooLong { line: 3, limit: 64, .. }), "{e}");
        assert!(e.to_string().starts_with("l.clf:3: line longer than 64 bytes"), "{e}");
        // A line of exactly the bound, newline included, is read; so is a last line without a newline.
        let exact = format!("{}\n{}", "#".repeat(63), "#".repeat(64));
        assert_eq!(parse(exact.as_bytes(), Path::new("l.clf"), &opts).unwrap().skipped["comment"], 2);
        // Bytes that never end a line (an endless device) stop at the bound.
        let e = parse(std::io::BufReader::new(std::io::repeat(b'x')), Path::new("x.clf"), &opts).unwrap_err();
        assert!(matches!(e, LogError::LineTooLong { line: 1, .. }), "{e}");
    }

    #[test]
    fn a_log_larger_than_the_bound_is_refused() {
        // Lines as loggers write them, longer than the record each becomes.
        let line = "ODOM 0.000000 0.000000 0.000000 0.000000 0.000000 0.000000 1.000000 nohost 1.000000\n";
        let text = line.repeat(100);
        let opts = ReadOptions { max_bytes: 1000, ..ReadOptions::default() };
        let e = parse(text.as_bytes(), Path::new("big.clf"), &opts).unwrap_err();
        assert!(matches!(e, LogError::TooLarge { limit: 1000, compressed: false, .. }), "{e}");
        assert!(e.to_string().starts_with("big.clf: more than 1000 bytes: refused"), "{e}");
        // Exactly the bound is read.
        let exact = ReadOptions { max_bytes: text.len() as u64, ..ReadOptions::default() };
        assert_eq!(parse(text.as_bytes(), Path::new("big.clf"), &exact).unwrap().odometry.len(), 1);
        // Scans whose ranges take more room parsed than as text stop at the bound on what the records hold, before
        // the bound on the text: 1000 ranges of `1 ` are 2000 bytes of text and 4000 held.
        let scan = format!("FLASER 1000 {}0 0 0 0 0 0 1.0 h 1\n", "1 ".repeat(1000));
        let two = scan.clone() + &scan.replace(" 1.0 h", " 2.0 h");
        let bound = ReadOptions { max_bytes: 5000, ..ReadOptions::default() };
        assert!(two.len() < 5000);
        let e = parse(two.as_bytes(), Path::new("wide.clf"), &bound).unwrap_err();
        assert!(matches!(e, LogError::TooMuchHeld { line: 2, .. }), "{e}");
        assert!(e.to_string().contains("wide.clf: its records would hold more than"), "{e}");
        assert_eq!(parse(scan.as_bytes(), Path::new("one.clf"), &bound).unwrap().scans.len(), 1);
        // Endless empty lines (short lines, so the line bound never trips) stop at the total bound.
        let lines = std::io::BufReader::new(std::io::repeat(b'\n'));
        let e = parse(lines, Path::new("n.clf"), &ReadOptions { max_bytes: 1 << 20, ..opts }).unwrap_err();
        assert!(matches!(e, LogError::TooLarge { .. }), "{e}");
    }

    #[test]
    fn short_line_names_its_number() {
        let text = "ODOM 0 0 0 0 0 0 1 h 1\nFLASER 3 1.0 2.0\n";
        let e = parse_default(text, "bad.clf").unwrap_err().to_string();
        assert!(e.starts_with("bad.clf:2: FLASER:"), "{e}");
        let e = parse_default("ODOM 1 2 x 0 0 0 1 h 1\n", "b.clf").unwrap_err().to_string();
        assert!(e.contains("b.clf:1: ODOM: field 3"), "{e}");
        let e = parse_default("FLASER 99999999 1\n", "b.clf").unwrap_err().to_string();
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
        assert_eq!(read_log(&p, &ReadOptions::default()).unwrap().scans.len(), 3);
        let e = read_log(&dir.path().join("missing.log"), &ReadOptions::default()).unwrap_err().to_string();
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
            let e = read_log(&p, &ReadOptions::default()).unwrap_err().to_string();
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
        let log = parse_default(&text, "i.clf").unwrap();
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
        let ordered = parse_default(&text, "s.clf").unwrap();
        assert_eq!(ordered.repairs.out_of_order, 0);
        assert_eq!(
            ordered.scans.iter().map(|s| s.odometry).collect::<Vec<_>>(),
            log.scans.iter().map(|s| s.odometry).collect::<Vec<_>>()
        );
        // The line's own fields on request.
        let opts = ReadOptions { odometry: OdometrySource::Line, ..ReadOptions::default() };
        let text: String = lines.iter().map(|(_, l)| format!("{l}\n")).collect();
        let own = parse(text.as_bytes(), Path::new("i.clf"), &opts).unwrap();
        assert_eq!(own.repairs.line_odometry, 14);
        assert_close(Xyt::from_pose(&own.scans[0].odometry.pose), (9.0, 9.0, 9.0 - 2.0 * std::f64::consts::PI));
    }

    #[test]
    fn a_large_step_back_is_refused_naming_the_line() {
        let text = "ODOM 0 0 0 0 0 0 100.0 h 1\nODOM 0 0 0 0 0 0 101.0 h 1\nODOM 0 0 0 0 0 0 90.0 h 1\n";
        let e = parse_default(text, "b.clf").unwrap_err().to_string();
        assert!(e.starts_with("b.clf:3: ODOM: ipc_timestamp 90 is 11.000 s before the stamp 101 on line 2"), "{e}");
        let opts = ReadOptions { max_step_back: 20.0, ..ReadOptions::default() };
        let log = parse(text.as_bytes(), Path::new("b.clf"), &opts).unwrap();
        assert_eq!((log.repairs.out_of_order, log.repairs.max_step_back_at), (1, Some(Source::Line(3))));
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
        let e = parse_default(text, "g.log").unwrap_err().to_string();
        assert!(
            e.starts_with("g.log:3: ODOM: ipc_timestamp 0.7 is 9.300 s before") && e.contains("--odometry line"),
            "{e}"
        );
        let opts = ReadOptions { odometry: OdometrySource::Line, ..ReadOptions::default() };
        let log = parse(text.as_bytes(), Path::new("g.log"), &opts).unwrap();
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
        let log = parse_default(text, "d.clf").unwrap();
        let r = &log.repairs;
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
        let log = parse_default(text, "p.clf").unwrap();
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
        let log = parse_default(text, "r.clf").unwrap();
        assert_eq!(log.repairs.reversed_increments, 1);
        let xs: Vec<f64> = log.odometry.iter().map(|o| o.odometry.pose.translation.x).collect();
        assert_eq!(xs, [0.0, 1.0, 0.0, 1.0]);
        assert_close(Xyt::from_pose(&log.scans[0].odometry.pose), (0.5, 0.0, 0.0));
        assert!(log.repairs.describe().contains("1 ODOM increments reported reversing"));
        let keep = ReadOptions { repair_reversing: false, ..ReadOptions::default() };
        let log = parse(text.as_bytes(), Path::new("r.clf"), &keep).unwrap();
        assert_eq!(log.repairs.reversed_increments, 0);
        assert_eq!(log.odometry[2].odometry.pose.translation.x, 2.0);
        // A scan taken 0.5 s before its stamp takes the odometry of then.
        let late = ReadOptions { scan_latency: 0.5, ..ReadOptions::default() };
        let log = parse(text.as_bytes(), Path::new("r.clf"), &late).unwrap();
        assert_close(Xyt::from_pose(&log.scans[0].odometry.pose), (0.0, 0.0, 0.0));
        assert_eq!(log.scans[0].odometry.stamp, 2.5);
    }
}
