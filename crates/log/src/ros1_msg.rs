//! ROS 1 serialization of the three message types ([`crate::ros_msg`]): little-endian, packed (no
//! alignment), strings and variable arrays prefixed by a `uint32` length, fixed arrays bare, `time` as
//! `uint32` seconds and nanoseconds, every `Header` starting with a `uint32` seq.
//!
//! Why a decoder of our own: the one serde implementation on crates.io (`serde_rosmsg`) has had no release
//! since 2017; the layout of three fixed message types is a few dozen lines over a bounds-checked cursor.

use crate::ros_msg::{Msg, MsgKind, OdometryMsg, Planar, ScanMsg, TransformMsg, stamp_seconds};

/// A bounds-checked little-endian reader over one message's bytes.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| {
            format!("message ends at byte {} inside a field of {n} bytes at byte {}", self.bytes.len(), self.at)
        })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }

    fn f64s<const N: usize>(&mut self) -> Result<[f64; N], String> {
        let mut a = [0.0; N];
        for v in &mut a {
            *v = self.f64()?;
        }
        Ok(a)
    }

    fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        let bytes = self.take(n)?;
        String::from_utf8(bytes.to_vec()).map_err(|_| format!("a string at byte {} is not UTF-8", self.at - n))
    }

    /// A `float32[]`, its length checked against the bytes left before anything is allocated.
    fn f32s(&mut self) -> Result<Vec<f32>, String> {
        let n = self.u32()? as usize;
        let bytes = self.take(n.checked_mul(4).ok_or("array length overflows")?)?;
        Ok(bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
    }

    /// A `std_msgs/Header`: seq, stamp, frame_id; the stamp in seconds and the frame.
    fn header(&mut self) -> Result<(f64, String), String> {
        let _seq = self.u32()?;
        let (sec, nsec) = (self.u32()?, self.u32()?);
        Ok((stamp_seconds(i64::from(sec), nsec)?, self.string()?))
    }

    /// A `geometry_msgs/Pose` or `Transform`: position (x, y, z) then quaternion (x, y, z, w).
    fn pose(&mut self) -> Result<Planar, String> {
        let [x, y, _z] = self.f64s::<3>()?;
        Ok(Planar::from_3d(x, y, self.f64s::<4>()?))
    }
}

/// Decodes one ROS 1 message of `kind`.
pub(crate) fn decode(kind: MsgKind, bytes: &[u8]) -> Result<Msg, String> {
    let mut c = Cursor { bytes, at: 0 };
    Ok(match kind {
        MsgKind::Scan => {
            let (stamp, frame_id) = c.header()?;
            let angle_min = c.f32()?;
            let _angle_max = c.f32()?;
            let angle_increment = c.f32()?;
            let _time_increment = c.f32()?;
            let _scan_time = c.f32()?;
            let (range_min, range_max) = (c.f32()?, c.f32()?);
            let ranges = c.f32s()?;
            Msg::Scan(ScanMsg { stamp, frame_id, angle_min, angle_increment, range_min, range_max, ranges })
        }
        MsgKind::Odometry => {
            let (stamp, frame_id) = c.header()?;
            let child_frame_id = c.string()?;
            let pose = c.pose()?;
            let _pose_covariance = c.f64s::<36>()?;
            let [forward_speed, ..] = c.f64s::<6>()?;
            Msg::Odometry(OdometryMsg { stamp, frame_id, child_frame_id, pose, forward_speed })
        }
        MsgKind::Transforms => {
            let n = c.u32()? as usize;
            // Each transform takes at least 72 bytes: no more can fit in what is left.
            if n > bytes.len() / 72 {
                return Err(format!("{n} transforms cannot fit in a message of {} bytes", bytes.len()));
            }
            let mut transforms = Vec::with_capacity(n);
            for _ in 0..n {
                let (stamp, parent) = c.header()?;
                let child = c.string()?;
                transforms.push(TransformMsg { stamp, parent, child, pose: c.pose()? });
            }
            Msg::Transforms(transforms)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(out: &mut Vec<u8>, sec: u32, nsec: u32, frame: &str) {
        for v in [7, sec, nsec, frame.len() as u32] {
            out.extend(v.to_le_bytes());
        }
        out.extend(frame.as_bytes());
    }

    #[test]
    fn a_scan_decodes_and_a_cut_one_is_refused() {
        let mut b = Vec::new();
        header(&mut b, 70, 289_900_000, "laser");
        for v in [-1.5f32, 1.5, 1.5, 0.0, 0.0, 0.1, 30.0] {
            b.extend(v.to_le_bytes());
        }
        b.extend(3u32.to_le_bytes());
        for v in [1.0f32, f32::INFINITY, f32::NAN] {
            b.extend(v.to_le_bytes());
        }
        b.extend(0u32.to_le_bytes());
        let Msg::Scan(s) = decode(MsgKind::Scan, &b).unwrap() else { panic!("not a scan") };
        assert_eq!((s.stamp, s.frame_id.as_str(), s.angle_min, s.angle_increment), (70.2899, "laser", -1.5, 1.5));
        assert_eq!((s.range_min, s.range_max, s.ranges[0], s.ranges[1]), (0.1, 30.0, 1.0, f32::INFINITY));
        assert!(s.ranges[2].is_nan());
        let e = decode(MsgKind::Scan, &b[..b.len() - 6]).unwrap_err();
        assert!(e.contains("message ends"), "{e}");
        // A length prefix larger than the message is refused before any allocation.
        let mut huge = b[..b.len() - 20].to_vec();
        huge.extend(u32::MAX.to_le_bytes());
        assert!(decode(MsgKind::Scan, &huge).is_err());
    }

    #[test]
    fn transforms_decode_with_their_frames() {
        let mut b = 1u32.to_le_bytes().to_vec();
        header(&mut b, 1, 0, "odom");
        b.extend(9u32.to_le_bytes());
        b.extend(b"base_link");
        let t: f64 = 0.5;
        for v in [1.0, 2.0, 0.0, 0.0, 0.0, (t / 2.0).sin(), (t / 2.0).cos()] {
            b.extend(f64::to_le_bytes(v));
        }
        let Msg::Transforms(ts) = decode(MsgKind::Transforms, &b).unwrap() else { panic!("not transforms") };
        assert_eq!((ts[0].parent.as_str(), ts[0].child.as_str(), ts[0].pose.x), ("odom", "base_link", 1.0));
        assert!((ts[0].pose.yaw - t).abs() < 1e-15);
        b[0] = 200;
        assert!(decode(MsgKind::Transforms, &b).unwrap_err().contains("cannot fit"));
    }
}
