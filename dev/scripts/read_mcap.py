#!/usr/bin/env python3
"""Reads a ROS 2 MCAP bag (e.g. one written by `mrslam run SCENARIO --mcap OUT.mcap`) with the MCAP project's
own Python libraries, independent of mrslam: every topic with its schema, encodings and message count, then
one message of each topic decoded from its embedded `ros2msg` schema (no ROS installation needed).

    python3 -m pip install mcap mcap-ros2-support      (tested with mcap 1.6.0, mcap-ros2-support 0.6.0)
    python3 dev/scripts/read_mcap.py OUT.mcap

Exits 1 when a channel is not CDR with a ros2msg schema, or a message does not decode.
"""
import math
import sys
from collections import Counter

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def brief(msg, typename):
    """A one-line view of a decoded message of the types mrslam writes."""
    if typename.endswith("LaserScan"):
        finite = [r for r in msg.ranges if math.isfinite(r)]
        return (f"stamp {msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d} frame {msg.header.frame_id} "
                f"{len(msg.ranges)} beams from {math.degrees(msg.angle_min):.2f} deg every "
                f"{math.degrees(msg.angle_increment):.3f} deg, {len(finite)} finite, range {msg.range_min}..{msg.range_max} m")
    if typename.endswith("Odometry"):
        p = msg.pose.pose
        yaw = 2 * math.atan2(p.orientation.z, p.orientation.w)
        return (f"stamp {msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d} {msg.header.frame_id} -> "
                f"{msg.child_frame_id}: x {p.position.x:.4f} y {p.position.y:.4f} yaw {yaw:.4f}, "
                f"forward {msg.twist.twist.linear.x:.3f} m/s")
    if typename.endswith("TFMessage"):
        return "; ".join(f"{t.header.frame_id} -> {t.child_frame_id} ({t.transform.translation.x:.3f}, "
                         f"{t.transform.translation.y:.3f})" for t in msg.transforms)
    if typename.endswith("OccupancyGrid"):
        counts = Counter(100 if v > 50 else (0 if 0 <= v <= 50 else -1) for v in msg.data)
        return (f"frame {msg.header.frame_id} {msg.info.width}x{msg.info.height} at {msg.info.resolution:.3f} m, "
                f"origin ({msg.info.origin.position.x:.2f}, {msg.info.origin.position.y:.2f}): "
                f"{counts[0]} free, {counts[100]} occupied, {counts[-1]} unknown")
    return str(msg)[:120]


def main(path):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        summary = reader.get_summary()
        print(f"{path}: profile {header.profile!r}, library {header.library!r}")
        counts = summary.statistics.channel_message_counts
        bad = 0
        for cid, ch in sorted(summary.channels.items(), key=lambda c: c[1].topic):
            schema = summary.schemas[ch.schema_id]
            ok = schema.encoding == "ros2msg" and ch.message_encoding == "cdr"
            bad += not ok
            print(f"  {ch.topic:<24} {schema.name:<28} {schema.encoding}/{ch.message_encoding} "
                  f"{counts.get(cid, 0):>6} msgs{'' if ok else '  <- not ros2msg/cdr'}")
        seen = set()
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            if channel.topic in seen:
                continue
            seen.add(channel.topic)
            print(f"  first {channel.topic}: {brief(decoded, schema.name)}")
        missing = {ch.topic for ch in summary.channels.values()} - seen
        if bad or missing:
            print(f"not a plain ROS 2 bag: {bad} channels not ros2msg/cdr, no message decoded on {sorted(missing)}")
            return 1
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1]))
