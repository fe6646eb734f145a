//! The three ROS message types a bag's scans and odometry come from, decoded into plain values whatever the
//! wire format (ROS 1 serialization or ROS 2 CDR): `sensor_msgs/LaserScan`, `nav_msgs/Odometry` and
//! `tf2_msgs/TFMessage`, the 3D poses in them taken to the plane (x, y and the yaw about z).

/// The message types this crate decodes, by their ROS 1 (`sensor_msgs/LaserScan`) or ROS 2
/// (`sensor_msgs/msg/LaserScan`) name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MsgKind {
    /// `sensor_msgs/LaserScan`.
    Scan,
    /// `nav_msgs/Odometry`.
    Odometry,
    /// `tf2_msgs/TFMessage` (`/tf` and `/tf_static`).
    Transforms,
}

impl MsgKind {
    /// The kind of a type name, ROS 1 or ROS 2 spelling; `None` for types this crate does not decode.
    pub(crate) fn of(type_name: &str) -> Option<MsgKind> {
        match type_name.replace("/msg/", "/").as_str() {
            "sensor_msgs/LaserScan" => Some(MsgKind::Scan),
            "nav_msgs/Odometry" => Some(MsgKind::Odometry),
            "tf2_msgs/TFMessage" => Some(MsgKind::Transforms),
            _ => None,
        }
    }
}

/// A `sensor_msgs/LaserScan`, its geometry as the message has it (float32 fields widened).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ScanMsg {
    /// `header.stamp`, seconds ([`stamp_seconds`]).
    pub stamp: f64,
    /// `header.frame_id`: the laser's frame.
    pub frame_id: String,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres; +inf = no return within range, NaN = invalid, as ROS (REP 117) defines them.
    pub ranges: Vec<f32>,
}

/// A planar rigid transform: x, y and the yaw of a 3D pose (its quaternion's rotation about z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Planar {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Yaw, radians.
    pub yaw: f64,
}

impl Planar {
    /// The planar part of a position and an (x, y, z, w) quaternion, the yaw to the nanoradian.
    ///
    /// A yaw that went through a quaternion comes back 1-2 ulp off; rounded to 1e-9 rad (far below any
    /// odometry's resolution) a bag made from a text log of up to nine decimals reads the text's headings
    /// exactly, so the filter, which amplifies an ulp into another resampling, maps the bag as the text.
    pub(crate) fn from_3d(x: f64, y: f64, q: [f64; 4]) -> Planar {
        let [qx, qy, qz, qw] = q;
        let yaw = (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz));
        Planar { x, y, yaw: to_nanoradian(yaw) }
    }
}

/// `radians` rounded to the nearest 1e-9; a non-finite value is returned as it is.
fn to_nanoradian(radians: f64) -> f64 {
    const PER_RADIAN: f64 = 1e9;
    let n = (radians * PER_RADIAN).round();
    if n.is_finite() { n / PER_RADIAN } else { radians }
}

/// A `nav_msgs/Odometry`: the pose of `child_frame_id` in `frame_id`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OdometryMsg {
    /// `header.stamp`, seconds.
    pub stamp: f64,
    /// The odometry frame.
    pub frame_id: String,
    /// The robot's frame.
    pub child_frame_id: String,
    /// The robot's pose in the odometry frame.
    pub pose: Planar,
    /// `twist.twist.linear.x`, m/s.
    pub forward_speed: f64,
}

/// One `geometry_msgs/TransformStamped` of a `tf2_msgs/TFMessage`: `child` in `parent`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TransformMsg {
    /// `header.stamp`, seconds.
    pub stamp: f64,
    /// `header.frame_id`.
    pub parent: String,
    /// `child_frame_id`.
    pub child: String,
    /// The child's pose in the parent.
    pub pose: Planar,
}

/// A decoded message.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Msg {
    /// A laser scan.
    Scan(ScanMsg),
    /// An odometry reading.
    Odometry(OdometryMsg),
    /// The transforms of one TF message.
    Transforms(Vec<TransformMsg>),
}

/// A LaserScan's float32 angle as a double: among the doubles that round to it, the one that is a whole
/// number of hundredths of a degree when there is one (what drivers compute the geometry from: -90°, 1°,
/// 0.5°, 0.25°, -135°), else the float32 itself. Either is within the float32's rounding of the angle the
/// driver meant; the first is that angle exactly, so a scan reads as the same scan written from a text log.
pub(crate) fn angle(v: f32) -> f64 {
    let wide = f64::from(v);
    let hundredths = (wide.to_degrees() * 100.0).round();
    let snapped = (hundredths / 100.0).to_radians();
    if snapped as f32 == v { snapped } else { wide }
}

/// A header stamp in seconds: the double nearest to `sec.nanosec` read as a decimal number, so a stamp
/// written from text (`70.289900`) reads back as that text parses.
pub(crate) fn stamp_seconds(sec: i64, nanosec: u32) -> Result<f64, String> {
    if nanosec >= 1_000_000_000 {
        return Err(format!("stamp nanoseconds {nanosec} are not below 1e9"));
    }
    let sign = if sec < 0 { "-" } else { "" };
    // A negative stamp is sec + nanosec: -2 s + 0.5 s = -1.5 s.
    let (whole, frac) = if sec < 0 && nanosec > 0 {
        (sec.unsigned_abs() - 1, 1_000_000_000 - nanosec)
    } else {
        (sec.unsigned_abs(), nanosec)
    };
    format!("{sign}{whole}.{frac:09}").parse().map_err(|e| format!("stamp {sec}.{nanosec:09}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_read_as_their_decimal_text() {
        assert_eq!(stamp_seconds(70, 289_900_000).unwrap(), "70.2899".parse::<f64>().unwrap());
        assert_eq!(stamp_seconds(1435, 809_999_000).unwrap(), 1435.809999);
        assert_eq!(stamp_seconds(-2, 500_000_000).unwrap(), -1.5);
        assert!(stamp_seconds(1, 1_000_000_000).is_err());
    }

    #[test]
    fn float32_angles_read_as_the_whole_hundredths_of_a_degree_they_round() {
        use std::f64::consts::PI;
        assert_eq!(angle(-PI as f32 / 2.0), -PI / 2.0);
        assert_eq!(angle((PI / 180.0) as f32), PI / 180.0);
        assert_eq!(angle(0.25f64.to_radians() as f32), 0.25f64.to_radians());
        // 2 pi / 1024 (a Hokuyo URG's step) is no whole hundredth of a degree: the float32 as it is.
        let step = (2.0 * PI / 1024.0) as f32;
        assert_eq!(angle(step), f64::from(step));
    }

    #[test]
    fn types_are_known_by_either_spelling_and_quaternions_give_the_yaw() {
        assert_eq!(MsgKind::of("sensor_msgs/msg/LaserScan"), Some(MsgKind::Scan));
        assert_eq!(MsgKind::of("nav_msgs/Odometry"), Some(MsgKind::Odometry));
        assert_eq!(MsgKind::of("tf2_msgs/msg/TFMessage"), Some(MsgKind::Transforms));
        assert_eq!(MsgKind::of("std_msgs/String"), None);
        let t: f64 = 2.5;
        let p = Planar::from_3d(1.0, 2.0, [0.0, 0.0, (t / 2.0).sin(), (t / 2.0).cos()]);
        assert!((p.yaw - t).abs() < 1e-15 && p.x == 1.0 && p.y == 2.0);
    }

    #[test]
    fn a_heading_of_up_to_nine_decimals_survives_its_quaternion_exactly() {
        // Every heading of a CARMEN line written with 6 or 9 decimals, as a bag converter stores it.
        let mut off_before = 0;
        for i in -314_159..=314_159 {
            for text in [format!("{:.6}", f64::from(i) * 1e-5), format!("{:.9}", f64::from(i) * 1.000_000_001e-5)] {
                let theta: f64 = text.parse().unwrap();
                let q = [0.0, 0.0, (theta / 2.0).sin(), (theta / 2.0).cos()];
                let [_, _, qz, qw] = q;
                off_before += usize::from((2.0 * qw * qz).atan2(1.0 - 2.0 * qz * qz) != theta);
                assert_eq!(Planar::from_3d(0.0, 0.0, q).yaw, theta, "{text}");
            }
        }
        assert!(off_before > 1000, "the rounding is what makes them exact ({off_before} were off)");
    }
}
