//! A bag's messages made into a [`SensorLog`]: the scan topic, the odometry (a `nav_msgs/Odometry` topic or
//! the `/tf` transform from the odometry frame to the robot's) and the laser's mount (`/tf_static`) chosen as
//! [`TopicChoice`](crate::TopicChoice) says or, where it says nothing, the one candidate the bag has; then
//! the stamps checked in file order and the repairs of [`crate::repair`] applied, as for a CARMEN log.

use crate::bag_messages::{Arrived, BagMessages};
use crate::bag_summary::BagSummary;
use crate::error::LogError;
use crate::options::{OdometrySource, ReadOptions};
use crate::repair::{self, StampOrder};
use crate::ros_msg::{MsgKind, Planar, angle};
use crate::sensor_log::{OdometryRecord, ScanRecord, SensorLog};
use crate::source::Source;
use mrslam_core::{LaserScan, Odometry, Pose2, pose};
use std::collections::BTreeMap;

/// The topics of `kind` in the bag, by name.
fn topics_of(bag: &BagMessages, kind: MsgKind) -> Vec<String> {
    bag.topics.values().filter(|t| MsgKind::of(&t.type_name) == Some(kind)).map(|t| t.name.clone()).collect()
}

/// The topic `asked` for, or the one candidate; an error naming the candidates otherwise.
fn pick(bag: &BagMessages, asked: Option<&String>, kind: MsgKind, what: &str, flag: &str) -> Result<String, LogError> {
    let candidates = topics_of(bag, kind);
    let list = || if candidates.is_empty() { "none".to_string() } else { candidates.join(", ") };
    match asked {
        Some(t) if candidates.contains(t) => Ok(t.clone()),
        Some(t) => Err(bag.error(format!("{flag} {t}: no {what} topic of that name (the bag's: {})", list()))),
        None => match candidates.as_slice() {
            [one] => Ok(one.clone()),
            [] => Err(bag.error(format!("no {what} topic (topics: {})", all_topics(bag)))),
            _ => Err(bag.error(format!("{} {what} topics ({}): choose one with {flag}", candidates.len(), list()))),
        },
    }
}

fn all_topics(bag: &BagMessages) -> String {
    let all: Vec<String> = bag.topics.values().map(|t| format!("{} {}", t.name, t.type_name)).collect();
    if all.is_empty() { "none".to_string() } else { all.join(", ") }
}

fn to_pose(p: &Planar) -> Pose2 {
    pose(p.x, p.y, p.yaw)
}

/// One odometry reading with where it came from.
struct Reading {
    arrival: usize,
    source: Source,
    record: OdometryRecord,
}

/// The odometry as asked: a topic, or `/tf`'s transforms to the base frame; with the base frame and a
/// description.
fn odometry(bag: &BagMessages, options: &ReadOptions) -> Result<(Vec<Reading>, String, String), LogError> {
    let choice = &options.topics;
    let odometry_topics = topics_of(bag, MsgKind::Odometry);
    let topic = match (&choice.odom, &choice.base_frame) {
        (Some(_), _) => Some(pick(bag, choice.odom.as_ref(), MsgKind::Odometry, "nav_msgs/Odometry", "--odom")?),
        (None, Some(_)) => None,
        (None, None) if odometry_topics.len() <= 1 => odometry_topics.first().cloned(),
        (None, None) => {
            return Err(bag.error(format!(
                "{} nav_msgs/Odometry topics ({}): choose one with --odom, or odometry from /tf with --base-frame",
                odometry_topics.len(),
                odometry_topics.join(", ")
            )));
        }
    };
    if let Some(topic) = topic {
        let msgs = bag.odometry.get(&topic).map(Vec::as_slice).unwrap_or_default();
        let readings = msgs.iter().map(|a: &Arrived<_>| Reading {
            arrival: a.arrival,
            source: a.source.clone(),
            record: OdometryRecord {
                odometry: Odometry { stamp: a.msg.stamp, pose: to_pose(&a.msg.pose) },
                forward_speed: a.msg.forward_speed,
            },
        });
        let first = msgs.first().map(|a| (a.msg.frame_id.clone(), a.msg.child_frame_id.clone()));
        let (frame, child) = first.unwrap_or_default();
        let base = choice.base_frame.clone().unwrap_or_else(|| child.clone());
        return Ok((readings.collect(), base, format!("topic {topic} ({frame} -> {child})")));
    }
    let base = match &choice.base_frame {
        Some(b) => b.clone(),
        None => base_frame(bag)?,
    };
    let to_base: Vec<&Arrived<_>> = bag.transforms.iter().filter(|a| a.msg.child == base).collect();
    let Some(first) = to_base.first() else {
        return Err(
            bag.error(format!("no odometry: no /tf transform to the base frame {base} (topics: {})", all_topics(bag)))
        );
    };
    let parent = first.msg.parent.clone();
    if let Some(other) = to_base.iter().find(|a| a.msg.parent != parent) {
        return Err(bag.error(format!(
            "{}: /tf has {base} in {} here but in {parent} before; odometry needs one odometry frame",
            other.source, other.msg.parent
        )));
    }
    let readings = to_base.iter().map(|a| Reading {
        arrival: a.arrival,
        source: a.source.clone(),
        record: OdometryRecord {
            odometry: Odometry { stamp: a.msg.stamp, pose: to_pose(&a.msg.pose) },
            forward_speed: 0.0,
        },
    });
    Ok((readings.collect(), base.clone(), format!("/tf: {parent} -> {base}")))
}

/// The robot's frame for odometry from `/tf` when none was named: the frame of `/tf` the laser's static
/// chain reaches, else the one child frame of `/tf`.
fn base_frame(bag: &BagMessages) -> Result<String, LogError> {
    let mut children: Vec<&str> = bag.transforms.iter().map(|a| a.msg.child.as_str()).collect();
    children.sort_unstable();
    children.dedup();
    let laser = bag.scans.values().flatten().next().map(|a| a.msg.frame_id.as_str());
    let parents: BTreeMap<&str, &str> =
        bag.static_transforms.iter().map(|t| (t.child.as_str(), t.parent.as_str())).collect();
    let mut frame = laser;
    for _ in 0..=parents.len() {
        match frame {
            Some(f) if children.contains(&f) => return Ok(f.to_string()),
            Some(f) => frame = parents.get(f).copied(),
            None => break,
        }
    }
    match children.as_slice() {
        [one] => Ok(one.to_string()),
        [] => Err(bag.error(format!(
            "no odometry: no nav_msgs/Odometry topic and no /tf transforms (topics: {})",
            all_topics(bag)
        ))),
        _ => Err(bag.error(format!(
            "/tf moves {} frames ({}): choose the robot's with --base-frame",
            children.len(),
            children.join(", ")
        ))),
    }
}

/// The laser's mount on `base`: the `/tf_static` chain from `base` to `laser`, with a description.
fn mount(bag: &BagMessages, base: &str, laser: &str) -> (Pose2, String) {
    if laser == base || laser.is_empty() {
        return (Pose2::identity(), format!("the scans are in the base frame {base}: identity"));
    }
    let parents: BTreeMap<&str, (&str, Pose2)> =
        bag.static_transforms.iter().map(|t| (t.child.as_str(), (t.parent.as_str(), to_pose(&t.pose)))).collect();
    let (mut frame, mut chain, mut names) = (laser, Pose2::identity(), vec![laser]);
    while let Some(&(parent, t)) = parents.get(frame) {
        chain = t * chain;
        frame = parent;
        names.push(parent);
        if frame == base {
            names.reverse();
            return (chain, format!("/tf_static: {}", names.join(" -> ")));
        }
        if names.len() > parents.len() + 1 {
            break;
        }
    }
    (Pose2::identity(), format!("no /tf_static chain from {base} to {laser}: identity"))
}

/// Builds the log from a bag's messages as `options` say; `format` names the bag's format in the summary.
pub(crate) fn assemble(bag: BagMessages, options: &ReadOptions, format: String) -> Result<SensorLog, LogError> {
    if options.odometry == OdometrySource::Line {
        return Err(bag.error(
            "--odometry line: a bag's scans carry no odometry of their own (odometry is interpolated at each scan)"
                .into(),
        ));
    }
    let scan_topic = pick(&bag, options.topics.scan.as_ref(), MsgKind::Scan, "sensor_msgs/LaserScan", "--scan")?;
    let (readings, base, odometry_from) = odometry(&bag, options)?;
    let scans = bag.scans.get(&scan_topic).map(Vec::as_slice).unwrap_or_default();
    let laser_frame = scans.first().map_or("", |a| a.msg.frame_id.as_str());
    let (laser_offset, laser_mount) = mount(&bag, &base, laser_frame);

    // Stamps checked in file order, as the CARMEN reader checks its lines.
    let mut order = StampOrder::new(options);
    let mut log = SensorLog::default();
    let mut next_scan = scans.iter().peekable();
    for r in &readings {
        while let Some(s) = next_scan.next_if(|s| s.arrival < r.arrival) {
            order.scan(s.msg.stamp, &s.source).map_err(|e| step_back(&bag, &s.source, e))?;
        }
        order.odometry(r.record.odometry.stamp, &r.source).map_err(|e| step_back(&bag, &r.source, e))?;
    }
    for s in next_scan {
        order.scan(s.msg.stamp, &s.source).map_err(|e| step_back(&bag, &s.source, e))?;
    }
    order.finish(&mut log);

    // A scan holds the last reading at or before its stamp, as a CARMEN scan line's own odometry fields hold
    // the last reading received (the repairs below interpolate the stream instead wherever its readings
    // bracket the scan and are not stamped in a burst); before the first reading, the first, when it is no
    // further from it than the longest interval between two readings; scans farther outside the span are
    // dropped, counted.
    let mut stamps: Vec<(f64, Pose2)> =
        readings.iter().map(|r| (r.record.odometry.stamp, r.record.odometry.pose)).collect();
    stamps.sort_by(|a, b| a.0.total_cmp(&b.0));
    let longest = stamps.windows(2).map(|w| w[1].0 - w[0].0).fold(0.0, f64::max);
    let held = |t: f64| match (stamps.first(), stamps.last()) {
        (Some(first), _) if t < first.0 => (first.0 - t <= longest).then_some(first.1),
        (_, Some(last)) if t > last.0 => (t - last.0 <= longest).then_some(last.1),
        (Some(_), Some(_)) => Some(stamps[stamps.partition_point(|r| r.0 <= t).max(1) - 1].1),
        _ => None,
    };
    let mut outside = 0;
    for a in scans {
        let s = &a.msg;
        let Some(pose) = held(s.stamp - options.scan_latency) else {
            outside += 1;
            continue;
        };
        log.scans.push(ScanRecord {
            odometry: Odometry { stamp: s.stamp, pose },
            scan: LaserScan {
                stamp: s.stamp,
                angle_min: angle(s.angle_min),
                angle_increment: angle(s.angle_increment),
                range_min: s.range_min,
                range_max: s.range_max,
                ranges: s.ranges.clone(),
            },
            logged_laser_pose: None,
            laser_offset,
            sensor: scan_topic.clone(),
            source: a.source.clone(),
        });
    }
    if outside > 0 {
        log.skipped.insert("scans beyond the odometry's time span".into(), outside);
    }
    log.odometry = readings.into_iter().map(|r| r.record).collect();
    repair::apply_all(&mut log, options);
    log.bag = Some(BagSummary {
        format,
        topics: bag.topics.into_values().collect(),
        scan_topic,
        odometry: odometry_from,
        laser_mount,
    });
    Ok(log)
}

fn step_back(bag: &BagMessages, at: &Source, e: repair::StepBack) -> LogError {
    LogError::Record {
        path: bag.path.clone(),
        at: at.clone(),
        kind: "stamp".into(),
        message: format!("header stamp {e}"),
    }
}
