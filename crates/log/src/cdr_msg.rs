//! ROS 2 CDR encoding of the three message types ([`crate::ros_msg`]), through the `cdr-encoding` crate
//! (serde; RustDDS's CDR, maintained by Atostek) into the message structs of [`crate::ros2_msg`], which mirror
//! the ROS 2 (Humble) definitions field for field; the 4-byte encapsulation header in front of every
//! serialized message says the byte order.

use crate::ros_msg::{Msg, MsgKind, OdometryMsg, Planar, ScanMsg, TransformMsg, stamp_seconds};
use crate::ros2_msg::{LaserScan, Odometry, Pose, TfMessage, Time};
use byteorder::{BigEndian, LittleEndian};
use serde::Deserialize;

fn stamp(t: &Time) -> Result<f64, String> {
    stamp_seconds(i64::from(t.sec), t.nanosec)
}

fn planar(p: &Pose) -> Planar {
    Planar::from_3d(p.position[0], p.position[1], p.orientation)
}

/// Decodes `bytes` (encapsulation header first) as a `T` in the byte order the header says.
fn from_cdr<T: for<'de> Deserialize<'de>>(bytes: &[u8]) -> Result<T, String> {
    let (head, body) = bytes.split_at_checked(4).ok_or("message shorter than its 4-byte CDR header")?;
    let decoded = match head[..2] {
        [0, 1] => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        [0, 0] => cdr_encoding::from_bytes::<T, BigEndian>(body),
        _ => return Err(format!("encapsulation {:02x}{:02x} is not plain CDR", head[0], head[1])),
    };
    decoded.map(|(t, _)| t).map_err(|e| format!("CDR: {e}"))
}

/// Decodes one CDR message of `kind`.
pub(crate) fn decode(kind: MsgKind, bytes: &[u8]) -> Result<Msg, String> {
    Ok(match kind {
        MsgKind::Scan => {
            let m: LaserScan = from_cdr(bytes)?;
            Msg::Scan(ScanMsg {
                stamp: stamp(&m.header.stamp)?,
                frame_id: m.header.frame_id,
                angle_min: m.angle_min,
                angle_increment: m.angle_increment,
                range_min: m.range_min,
                range_max: m.range_max,
                ranges: m.ranges,
            })
        }
        MsgKind::Odometry => {
            let m: Odometry = from_cdr(bytes)?;
            Msg::Odometry(OdometryMsg {
                stamp: stamp(&m.header.stamp)?,
                frame_id: m.header.frame_id,
                child_frame_id: m.child_frame_id,
                pose: planar(&m.pose.pose),
                forward_speed: m.twist.linear[0],
            })
        }
        MsgKind::Transforms => {
            let m: TfMessage = from_cdr(bytes)?;
            let transforms = m.transforms.into_iter().map(|t| {
                Ok(TransformMsg {
                    stamp: stamp(&t.header.stamp)?,
                    parent: t.header.frame_id,
                    child: t.child_frame_id,
                    pose: planar(&t.transform),
                })
            });
            Msg::Transforms(transforms.collect::<Result<_, String>>()?)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TFMessage of one transform as ROS 2 writes it: CDR little-endian, each field aligned to its size
    /// from the end of the 4-byte header.
    fn one_transform() -> Vec<u8> {
        let mut b = vec![0, 1, 0, 0];
        b.extend(1u32.to_le_bytes()); // one transform
        b.extend(5i32.to_le_bytes());
        b.extend(250_000_000u32.to_le_bytes());
        b.extend(5u32.to_le_bytes());
        b.extend(b"odom\0");
        b.extend([0, 0, 0]); // to 4
        b.extend(10u32.to_le_bytes());
        b.extend(b"base_link\0");
        b.extend([0, 0]); // to 8 from byte 4
        for v in [1.0f64, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
        b
    }

    #[test]
    fn a_cdr_transform_decodes_and_a_cut_one_is_refused() {
        let b = one_transform();
        let Msg::Transforms(ts) = decode(MsgKind::Transforms, &b).unwrap() else { panic!("not transforms") };
        assert_eq!(ts.len(), 1);
        let t = &ts[0];
        assert_eq!((t.stamp, t.parent.as_str(), t.child.as_str()), (5.25, "odom", "base_link"));
        assert_eq!((t.pose.x, t.pose.y, t.pose.yaw), (1.0, -2.0, 0.0));
        assert!(decode(MsgKind::Transforms, &b[..b.len() - 3]).is_err());
        assert!(decode(MsgKind::Transforms, &b[..3]).unwrap_err().contains("CDR header"));
        let mut odd = b.clone();
        odd[1] = 7;
        assert!(decode(MsgKind::Transforms, &odd).unwrap_err().contains("encapsulation"));
    }
}
