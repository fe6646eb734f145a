//! The ROS 2 (Humble) message types a bag of this crate holds, as serde structs that mirror the `.msg`
//! definitions field for field (CDR is positional: the field order and types are the layout, the names are
//! for the reader), and the definitions themselves as ROS 2 embeds them in a bag (`ros2msg`: the type's text,
//! then each type it uses after a line of 80 `=` and `MSG: package/Type`). [`crate::cdr_msg`] decodes into
//! these, [`crate::mcap_writer`] encodes from them.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds past `sec`, below 1e9.
    pub nanosec: u32,
}

/// `std_msgs/Header`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

/// `geometry_msgs/Pose`, and `geometry_msgs/Transform` (a translation and a rotation, laid out alike): a
/// point and an (x, y, z, w) quaternion.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pose {
    /// x, y, z.
    pub position: [f64; 3],
    /// x, y, z, w.
    pub orientation: [f64; 4],
}

/// A `float64[36]` covariance, as two halves: serde derives arrays of up to 32 elements, and a fixed array is
/// its elements back to back in CDR, so the bytes are the same.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Covariance(pub [f64; 18], pub [f64; 18]);

/// `geometry_msgs/PoseWithCovariance`.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Its covariance (row-major x, y, z, rotations about x, y, z).
    pub covariance: Covariance,
}

/// `geometry_msgs/TwistWithCovariance` (its `Twist`: linear then angular velocity, `Vector3` each).
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct TwistWithCovariance {
    /// Linear velocity, m/s.
    pub linear: [f64; 3],
    /// Angular velocity, rad/s.
    pub angular: [f64; 3],
    /// Its covariance.
    pub covariance: Covariance,
}

/// `sensor_msgs/LaserScan`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct LaserScan {
    /// Stamp of the first beam, and the laser's frame.
    pub header: Header,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres.
    pub ranges: Vec<f32>,
    /// Intensities (device units), or none.
    pub intensities: Vec<f32>,
}

/// `nav_msgs/Odometry`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct Odometry {
    /// Stamp, and the frame of the pose.
    pub header: Header,
    /// The frame of the twist (the robot's).
    pub child_frame_id: String,
    /// The robot's pose in `header.frame_id`.
    pub pose: PoseWithCovariance,
    /// The robot's velocity in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct TransformStamped {
    /// Stamp, and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// The child frame's pose in the parent frame.
    pub transform: Pose,
}

/// `tf2_msgs/TFMessage`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `nav_msgs/MapMetaData`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct MapMetaData {
    /// When the map was loaded (here: made).
    pub map_load_time: Time,
    /// Metres per cell.
    pub resolution: f32,
    /// Cells along x.
    pub width: u32,
    /// Cells along y.
    pub height: u32,
    /// The pose of cell (0, 0)'s corner in the map's frame.
    pub origin: Pose,
}

/// `nav_msgs/OccupancyGrid`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct OccupancyGrid {
    /// Stamp, and the map's frame.
    pub header: Header,
    /// Size, resolution and origin.
    pub info: MapMetaData,
    /// Row-major from (0, 0), rows along x: -1 unknown, else the occupancy probability in percent.
    pub data: Vec<i8>,
}

/// The message types written to a bag: their ROS 2 names and definitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Ros2Type {
    /// [`LaserScan`].
    LaserScan,
    /// [`Odometry`].
    Odometry,
    /// [`TfMessage`].
    TfMessage,
    /// [`OccupancyGrid`].
    OccupancyGrid,
}

/// The `.msg` text of every type used here, by its `package/Type` name (comments and constants left out).
const DEFINITIONS: &[(&str, &str)] = &[
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
    ("std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"),
    ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"),
    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs/Pose", "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"),
    ("geometry_msgs/PoseWithCovariance", "geometry_msgs/Pose pose\nfloat64[36] covariance\n"),
    ("geometry_msgs/Twist", "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n"),
    ("geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist twist\nfloat64[36] covariance\n"),
    ("geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"),
    (
        "geometry_msgs/TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    ),
    ("tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"),
    (
        "sensor_msgs/LaserScan",
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
         float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\n\
         float32[] intensities\n",
    ),
    (
        "nav_msgs/Odometry",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
         geometry_msgs/TwistWithCovariance twist\n",
    ),
    (
        "nav_msgs/MapMetaData",
        "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n\
         geometry_msgs/Pose origin\n",
    ),
    ("nav_msgs/OccupancyGrid", "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n"),
];

impl Ros2Type {
    /// The `package/Type` name, without the `msg/` ROS 2 puts in a schema's name.
    fn short_name(self) -> &'static str {
        match self {
            Ros2Type::LaserScan => "sensor_msgs/LaserScan",
            Ros2Type::Odometry => "nav_msgs/Odometry",
            Ros2Type::TfMessage => "tf2_msgs/TFMessage",
            Ros2Type::OccupancyGrid => "nav_msgs/OccupancyGrid",
        }
    }

    /// The name a ROS 2 bag's schema carries: `package/msg/Type`.
    pub(crate) fn name(self) -> String {
        self.short_name().replacen('/', "/msg/", 1)
    }

    /// The definition as ROS 2 embeds it (`ros2msg`): the type's text, then each type it uses, depth first,
    /// once, each after a line of 80 `=` and `MSG: package/Type`.
    pub(crate) fn definition(self) -> String {
        let text = |name: &str| DEFINITIONS.iter().find(|(n, _)| *n == name).map_or("", |(_, t)| t);
        let mut used: Vec<&str> = Vec::new();
        let mut stack: Vec<&str> = field_types(text(self.short_name())).into_iter().rev().collect();
        while let Some(name) = stack.pop() {
            if name == self.short_name() || used.contains(&name) {
                continue;
            }
            used.push(name);
            stack.extend(field_types(text(name)).into_iter().rev());
        }
        let mut out = text(self.short_name()).to_string();
        for name in used {
            out.push_str(&format!("{}\nMSG: {name}\n{}", "=".repeat(80), text(name)));
        }
        out
    }
}

/// The message types (`package/Type`) the fields of a definition text use, in field order.
fn field_types(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(|t| t.split('[').next().unwrap_or(t))
        .filter(|t| t.contains('/'))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_definition_lists_each_type_it_uses_once_after_its_own_text() {
        let d = Ros2Type::OccupancyGrid.definition();
        assert_eq!(Ros2Type::OccupancyGrid.name(), "nav_msgs/msg/OccupancyGrid");
        assert!(d.starts_with("std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n"), "{d}");
        let sections: Vec<&str> = d.lines().filter_map(|l| l.strip_prefix("MSG: ")).collect();
        assert_eq!(
            sections,
            [
                "std_msgs/Header",
                "builtin_interfaces/Time",
                "nav_msgs/MapMetaData",
                "geometry_msgs/Pose",
                "geometry_msgs/Point",
                "geometry_msgs/Quaternion"
            ]
        );
        assert_eq!(d.matches(&format!("{}\nMSG: ", "=".repeat(80))).count(), sections.len());
        // Every type any definition uses has its text here.
        for (_, text) in DEFINITIONS {
            for t in field_types(text) {
                assert!(DEFINITIONS.iter().any(|(n, _)| *n == t), "{t} has no definition");
            }
        }
        let tf = Ros2Type::TfMessage.definition();
        assert!(tf.contains("MSG: geometry_msgs/Vector3\n") && tf.contains("MSG: geometry_msgs/TransformStamped\n"));
    }
}
