//! Writing a simulated run as a ROS 2 bag (one MCAP file) that `ros2 bag play`, Foxglove and other SLAMs
//! read: the messages are CDR ([`crate::ros2_msg`] serialized by `cdr-encoding`), each channel's schema the
//! ROS 2 definition (`ros2msg`), the file written by the foxglove `mcap` crate's [`mcap::Writer`] (zstd
//! chunks, with the summary and indexes ROS 2 seeks by) as the run goes.
//!
//! Topics and frames of robot `NAME` (REP 105's frames, each prefixed by the robot's name):
//! `/NAME/scan` (`sensor_msgs/LaserScan` in `NAME/laser`), `/NAME/odom` (`nav_msgs/Odometry`, `NAME/odom` to
//! `NAME/base_link`), `/NAME/ground_truth` (`nav_msgs/Odometry`, the true pose in `world`), `/NAME/map`
//! (`nav_msgs/OccupancyGrid` in `NAME/map`); `/tf` carries `NAME/odom -> NAME/base_link` with every odometry
//! message and `NAME/map -> NAME/odom` (the SLAM's correction), `/tf_static` `NAME/base_link -> NAME/laser`.
//! `/tf_static` and the maps are offered transient-local (latched), as ROS publishes them.

use crate::ros2_msg::{
    Covariance, Header, LaserScan as RosScan, MapMetaData, OccupancyGrid as RosGrid, Odometry as RosOdometry, Pose,
    PoseWithCovariance, Ros2Type, TfMessage, Time, TransformStamped, TwistWithCovariance,
};
use byteorder::LittleEndian;
use mcap::records::MessageHeader;
use mcap::{McapError, WriteOptions, Writer};
use mrslam_core::{LaserScan, OccupancyGrid, Odometry, Pose2, Xyt};
use serde::Serialize;
use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::io::{Seek, Write};

/// The frame the true poses and the true map are in.
pub const WORLD_FRAME: &str = "world";

/// What can go wrong writing a bag.
#[derive(Debug, thiserror::Error)]
pub enum McapWriteError {
    /// The MCAP writer failed (an I/O error, most likely).
    #[error("MCAP: {0}")]
    Mcap(#[from] McapError),
    /// A message could not be serialized.
    #[error("{topic}: CDR: {message}")]
    Cdr {
        /// The message's topic.
        topic: String,
        /// What went wrong.
        message: String,
    },
    /// A stamp a ROS 2 time cannot hold (negative, not finite, or past 2038).
    #[error("{topic}: stamp {stamp} s is not a ROS 2 time (0 to 2^31 s)")]
    Stamp {
        /// The message's topic.
        topic: String,
        /// The stamp, seconds.
        stamp: f64,
    },
}

/// A channel of the bag: its id and the sequence number of its next message.
struct Channel {
    id: u16,
    sequence: u32,
}

/// Writes a simulated run's messages to a ROS 2 MCAP bag, in the order they are given.
pub struct RunBagWriter<W: Write + Seek> {
    mcap: Writer<W>,
    /// Schema ids by type name.
    schemas: BTreeMap<String, u16>,
    /// Channels by topic.
    channels: BTreeMap<String, Channel>,
    /// Each robot's previous odometry, for the twist of the next.
    last_odometry: BTreeMap<String, Odometry>,
}

/// `NAME/frame`: a frame of robot `robot`.
pub fn robot_frame(robot: &str, frame: &str) -> String {
    format!("{robot}/{frame}")
}

/// A ROS 2 time from seconds, to the nearest nanosecond.
fn ros_time(topic: &str, t: f64) -> Result<Time, McapWriteError> {
    let ns = (t * 1e9).round();
    if !(ns >= 0.0 && ns < 2f64.powi(31) * 1e9) {
        return Err(McapWriteError::Stamp { topic: topic.to_string(), stamp: t });
    }
    let ns = ns as u64;
    Ok(Time { sec: (ns / 1_000_000_000) as i32, nanosec: (ns % 1_000_000_000) as u32 })
}

/// A planar pose as a 3D pose (z 0, rotation about z).
fn pose3(p: &Pose2) -> Pose {
    let Xyt { x, y, theta } = Xyt::from_pose(p);
    Pose { position: [x, y, 0.0], orientation: [0.0, 0.0, (theta / 2.0).sin(), (theta / 2.0).cos()] }
}

/// The QoS profile ROS 2 offered a topic with, as rosbag2 records it in a channel's metadata: reliable, and
/// transient-local (latched) or volatile.
fn qos_metadata(latched: bool) -> BTreeMap<String, String> {
    let (depth, durability) = if latched { (1, 1) } else { (10, 2) };
    let zero = "\n    sec: 0\n    nsec: 0";
    let yaml = format!(
        "- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n  deadline:{zero}\n  \
         lifespan:{zero}\n  liveliness: 1\n  liveliness_lease_duration:{zero}\n  avoid_ros_namespace_conventions: false"
    );
    BTreeMap::from([("offered_qos_profiles".to_string(), yaml)])
}

impl<W: Write + Seek> RunBagWriter<W> {
    /// Starts a bag in `out` (MCAP profile `ros2`).
    pub fn new(out: W) -> Result<Self, McapWriteError> {
        let options = WriteOptions::new().profile("ros2").library(concat!("mrslam ", env!("CARGO_PKG_VERSION")));
        Ok(Self {
            mcap: options.create(out)?,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            last_odometry: BTreeMap::new(),
        })
    }

    /// Writes `message` of type `ty` on `topic` at `log_time` (seconds), adding its schema and channel the
    /// first time.
    fn write<T: Serialize>(
        &mut self,
        topic: &str,
        ty: Ros2Type,
        log_time: f64,
        message: &T,
    ) -> Result<(), McapWriteError> {
        let latched = matches!(ty, Ros2Type::OccupancyGrid) || topic == "/tf_static";
        let time = ros_time(topic, log_time)?;
        let ns = u64::from(time.sec as u32) * 1_000_000_000 + u64::from(time.nanosec);
        let cdr_error =
            |e: cdr_encoding::Error| McapWriteError::Cdr { topic: topic.to_string(), message: e.to_string() };
        // The encapsulation header: plain CDR, little-endian.
        let mut data = vec![0, 1, 0, 0];
        cdr_encoding::to_writer::<T, LittleEndian, _>(&mut data, message).map_err(cdr_error)?;
        let channel = match self.channels.entry(topic.to_string()) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let schema = match self.schemas.get(&ty.name()) {
                    Some(&id) => id,
                    None => {
                        let id = self.mcap.add_schema(&ty.name(), "ros2msg", ty.definition().as_bytes())?;
                        self.schemas.insert(ty.name(), id);
                        id
                    }
                };
                let id = self.mcap.add_channel(schema, topic, "cdr", &qos_metadata(latched))?;
                e.insert(Channel { id, sequence: 0 })
            }
        };
        let header =
            MessageHeader { channel_id: channel.id, sequence: channel.sequence, log_time: ns, publish_time: ns };
        channel.sequence = channel.sequence.wrapping_add(1);
        self.mcap.write_to_known_channel(&header, &data)?;
        Ok(())
    }

    /// `/tf_static`: each robot's laser mount (`NAME/base_link -> NAME/laser`), stamped `stamp`.
    pub fn mounts(&mut self, stamp: f64, mounts: &[(&str, Pose2)]) -> Result<(), McapWriteError> {
        let time = ros_time("/tf_static", stamp)?;
        let transforms = mounts
            .iter()
            .map(|(robot, mount)| TransformStamped {
                header: Header { stamp: time, frame_id: robot_frame(robot, "base_link") },
                child_frame_id: robot_frame(robot, "laser"),
                transform: pose3(mount),
            })
            .collect();
        self.write("/tf_static", Ros2Type::TfMessage, stamp, &TfMessage { transforms })
    }

    /// `/NAME/scan`: a scan of robot `robot`, stamped when its first beam was taken, received at `received`.
    pub fn scan(&mut self, robot: &str, received: f64, scan: &LaserScan) -> Result<(), McapWriteError> {
        let topic = format!("/{robot}/scan");
        let last = scan.angle_min + scan.angle_increment * scan.len().saturating_sub(1) as f64;
        let message = RosScan {
            header: Header { stamp: ros_time(&topic, scan.stamp)?, frame_id: robot_frame(robot, "laser") },
            angle_min: scan.angle_min as f32,
            angle_max: last as f32,
            angle_increment: scan.angle_increment as f32,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: scan.range_min,
            range_max: scan.range_max,
            ranges: scan.ranges.clone(),
            intensities: Vec::new(),
        };
        self.write(&topic, Ros2Type::LaserScan, received, &message)
    }

    /// `/NAME/odom` and its `/tf` (`NAME/odom -> NAME/base_link`): robot `robot`'s wheel odometry; the twist is
    /// the change since its previous odometry (zero for the first).
    pub fn odometry(&mut self, robot: &str, odometry: &Odometry) -> Result<(), McapWriteError> {
        let (linear, angular) = match self.last_odometry.get(robot) {
            Some(prev) if odometry.stamp > prev.stamp => {
                let dt = odometry.stamp - prev.stamp;
                let step = prev.pose.inv_mul(&odometry.pose);
                ([step.translation.x / dt, step.translation.y / dt, 0.0], [0.0, 0.0, step.rotation.angle() / dt])
            }
            _ => ([0.0; 3], [0.0; 3]),
        };
        self.last_odometry.insert(robot.to_string(), *odometry);
        let (odom, base) = (robot_frame(robot, "odom"), robot_frame(robot, "base_link"));
        let topic = format!("/{robot}/odom");
        let header = Header { stamp: ros_time(&topic, odometry.stamp)?, frame_id: odom.clone() };
        let message = RosOdometry {
            header: header.clone(),
            child_frame_id: base.clone(),
            pose: PoseWithCovariance { pose: pose3(&odometry.pose), covariance: Covariance::default() },
            twist: TwistWithCovariance { linear, angular, covariance: Covariance::default() },
        };
        self.write(&topic, Ros2Type::Odometry, odometry.stamp, &message)?;
        let tf = TransformStamped { header, child_frame_id: base, transform: pose3(&odometry.pose) };
        self.write("/tf", Ros2Type::TfMessage, odometry.stamp, &TfMessage { transforms: vec![tf] })
    }

    /// `/NAME/ground_truth`: robot `robot`'s true pose at `stamp`, in the [`WORLD_FRAME`].
    pub fn ground_truth(&mut self, robot: &str, stamp: f64, pose: &Pose2) -> Result<(), McapWriteError> {
        let topic = format!("/{robot}/ground_truth");
        let message = RosOdometry {
            header: Header { stamp: ros_time(&topic, stamp)?, frame_id: WORLD_FRAME.to_string() },
            child_frame_id: robot_frame(robot, "base_link"),
            pose: PoseWithCovariance { pose: pose3(pose), covariance: Covariance::default() },
            twist: TwistWithCovariance { linear: [0.0; 3], angular: [0.0; 3], covariance: Covariance::default() },
        };
        self.write(&topic, Ros2Type::Odometry, stamp, &message)
    }

    /// `/tf` `NAME/map -> NAME/odom` at `stamp`: where robot `robot`'s SLAM puts its odometry frame in its map.
    pub fn map_to_odom(&mut self, robot: &str, stamp: f64, map_to_odom: &Pose2) -> Result<(), McapWriteError> {
        let tf = TransformStamped {
            header: Header { stamp: ros_time("/tf", stamp)?, frame_id: robot_frame(robot, "map") },
            child_frame_id: robot_frame(robot, "odom"),
            transform: pose3(map_to_odom),
        };
        self.write("/tf", Ros2Type::TfMessage, stamp, &TfMessage { transforms: vec![tf] })
    }

    /// An occupancy grid on `topic` in `frame` (e.g. `/NAME/map` in `NAME/map`, see [`robot_frame`]), made at
    /// `stamp`.
    pub fn map(&mut self, topic: &str, frame: &str, stamp: f64, grid: &OccupancyGrid) -> Result<(), McapWriteError> {
        let time = ros_time(topic, stamp)?;
        let message = RosGrid {
            header: Header { stamp: time, frame_id: frame.to_string() },
            info: MapMetaData {
                map_load_time: time,
                resolution: grid.resolution() as f32,
                width: grid.width() as u32,
                height: grid.height() as u32,
                origin: pose3(grid.origin()),
            },
            data: grid.to_ros_int8(),
        };
        self.write(topic, Ros2Type::OccupancyGrid, stamp, &message)
    }

    /// Writes the summary and the indexes, and gives the output back (to commit it, for an atomic file).
    pub fn finish(mut self) -> Result<W, McapWriteError> {
        self.mcap.finish()?;
        Ok(self.mcap.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cdr_msg::decode;
    use crate::ros_msg::{Msg, MsgKind};
    use mrslam_core::pose;

    #[test]
    fn a_written_bag_has_ros2_schemas_and_its_messages_decode_as_written() {
        let mut w = RunBagWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
        w.mounts(0.0, &[("r1", pose(0.1, 0.0, 0.0))]).unwrap();
        let scan = LaserScan {
            stamp: 0.25,
            angle_min: -1.0,
            angle_increment: 0.5,
            range_min: 0.1,
            range_max: 10.0,
            ranges: vec![1.0, f32::INFINITY, 2.5, f32::NAN, 3.0],
        };
        w.scan("r1", 0.3, &scan).unwrap();
        w.odometry("r1", &Odometry { stamp: 0.3, pose: pose(1.0, 2.0, 0.5) }).unwrap();
        w.odometry("r1", &Odometry { stamp: 0.4, pose: pose(1.1, 2.0, 0.5) }).unwrap();
        w.map_to_odom("r1", 0.4, &pose(0.0, 0.0, 0.1)).unwrap();
        w.ground_truth("r1", 0.4, &pose(5.0, 5.0, 0.0)).unwrap();
        let grid = OccupancyGrid::new(3, 2, 0.05, pose(-1.0, -2.0, 0.0)).unwrap();
        w.map("/r1/map", "r1/map", 0.4, &grid).unwrap();
        let bytes = w.finish().unwrap().into_inner();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let mut topics: Vec<(&str, &str, &str, &str)> = summary
            .channels
            .values()
            .map(|c| {
                let s = c.schema.as_ref().unwrap();
                (c.topic.as_str(), s.name.as_str(), s.encoding.as_str(), c.message_encoding.as_str())
            })
            .collect();
        topics.sort();
        assert_eq!(
            topics,
            [
                ("/r1/ground_truth", "nav_msgs/msg/Odometry", "ros2msg", "cdr"),
                ("/r1/map", "nav_msgs/msg/OccupancyGrid", "ros2msg", "cdr"),
                ("/r1/odom", "nav_msgs/msg/Odometry", "ros2msg", "cdr"),
                ("/r1/scan", "sensor_msgs/msg/LaserScan", "ros2msg", "cdr"),
                ("/tf", "tf2_msgs/msg/TFMessage", "ros2msg", "cdr"),
                ("/tf_static", "tf2_msgs/msg/TFMessage", "ros2msg", "cdr"),
            ]
        );
        let stats = summary.stats.unwrap();
        assert_eq!(stats.message_count, 9);
        let mut seen = 0;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            match m.channel.topic.as_str() {
                "/r1/scan" => {
                    let Msg::Scan(s) = decode(MsgKind::Scan, &m.data).unwrap() else { panic!("not a scan") };
                    assert_eq!((s.stamp, s.frame_id.as_str(), s.angle_increment), (0.25, "r1/laser", 0.5));
                    assert_eq!(s.ranges[..3], [1.0, f32::INFINITY, 2.5]);
                    assert!(s.ranges[3].is_nan());
                    assert_eq!(m.log_time, 300_000_000);
                    seen += 1;
                }
                "/r1/odom" if m.sequence == 1 => {
                    let Msg::Odometry(o) = decode(MsgKind::Odometry, &m.data).unwrap() else { panic!("not odometry") };
                    assert_eq!((o.frame_id.as_str(), o.child_frame_id.as_str()), ("r1/odom", "r1/base_link"));
                    assert!((o.pose.x - 1.1).abs() < 1e-12 && (o.pose.yaw - 0.5).abs() < 1e-12);
                    // 0.1 m along world x in 0.1 s, heading 0.5 rad: the robot's forward speed is cos 0.5 m/s.
                    assert!((o.forward_speed - 0.5f64.cos()).abs() < 1e-9, "{}", o.forward_speed);
                    seen += 1;
                }
                "/tf_static" => {
                    let Msg::Transforms(t) = decode(MsgKind::Transforms, &m.data).unwrap() else { panic!() };
                    assert_eq!(
                        (t[0].parent.as_str(), t[0].child.as_str(), t[0].pose.x),
                        ("r1/base_link", "r1/laser", 0.1)
                    );
                    seen += 1;
                }
                "/r1/map" => {
                    let g: RosGrid = cdr_encoding::from_bytes::<RosGrid, LittleEndian>(&m.data[4..]).unwrap().0;
                    assert_eq!((g.info.width, g.info.height, g.info.origin.position[1]), (3, 2, -2.0));
                    assert_eq!(g.data, vec![-1; 6]);
                    seen += 1;
                }
                _ => {}
            }
        }
        assert_eq!(seen, 4);
    }

    #[test]
    fn a_stamp_ros_cannot_hold_is_refused() {
        let mut w = RunBagWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
        let e = w.ground_truth("r1", -1.0, &Pose2::identity()).unwrap_err().to_string();
        assert!(e.contains("/r1/ground_truth") && e.contains("-1 s"), "{e}");
        assert_eq!(ros_time("t", 1.5).unwrap(), Time { sec: 1, nanosec: 500_000_000 });
    }
}
