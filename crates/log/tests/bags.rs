//! Bags of every format read as the CARMEN text they were made from (tests/data/bags: the ACES log's
//! first 10 s, converted by the Python `rosbags` library; dev/scripts/make_bag_test_data.sh), and bad bags
//! refused with errors naming the file and the place.

#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_core::Xyt;
use mrslam_log::{LogError, ReadOptions, SensorLog, TopicChoice, read_log};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/bags").join(name)
}

fn read(path: &Path) -> SensorLog {
    read_log(path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The bag's log against the CARMEN log's: the same scans (stamps, ranges, geometry) with the same
/// odometry, the same odometry stream.
fn assert_same(bag: &SensorLog, carmen: &SensorLog, name: &str) {
    assert_eq!(bag.scans.len(), carmen.scans.len(), "{name}");
    assert!(!bag.scans.is_empty());
    for (b, c) in bag.scans.iter().zip(&carmen.scans) {
        let (sb, sc) = (&b.scan, &c.scan);
        assert_eq!(sb.stamp, sc.stamp, "{name}");
        assert_eq!(sb.ranges, sc.ranges, "{name} at {}", sb.stamp);
        assert_eq!((sb.angle_min, sb.angle_increment), (sc.angle_min, sc.angle_increment), "{name}");
        assert_eq!((sb.range_min, sb.range_max), (sc.range_min, sc.range_max), "{name}");
        let (pb, pc) = (Xyt::from_pose(&b.odometry.pose), Xyt::from_pose(&c.odometry.pose));
        // Exactly: the quaternion's yaw is read to the nanoradian, and an ulp would change the filter's map.
        assert_eq!((pb.x, pb.y, pb.theta), (pc.x, pc.y, pc.theta), "{name} at {}", sb.stamp);
        assert_eq!(b.laser_offset, c.laser_offset, "{name}");
        assert_eq!(b.sensor, "/scan");
    }
    assert_eq!(bag.odometry.len(), carmen.odometry.len(), "{name}");
    for (b, c) in bag.odometry.iter().zip(&carmen.odometry) {
        assert_eq!(b.odometry.stamp, c.odometry.stamp, "{name}");
        assert_eq!(b.forward_speed, c.forward_speed, "{name}");
    }
    assert_eq!(bag.repairs.out_of_order, carmen.repairs.out_of_order, "{name}");
    assert_eq!(bag.repairs.interpolated_odometry, carmen.repairs.interpolated_odometry, "{name}");
}

#[test]
fn every_format_reads_as_the_carmen_text_it_was_made_from() {
    let carmen = read(&data("aces_10s.clf"));
    // 68 FLASER lines; the last, after the last ODOM line, takes its own line's odometry (the bag: the last
    // odometry reading, held).
    assert_eq!((carmen.scans.len(), carmen.repairs.interpolated_odometry), (68, 67));
    let formats = [
        ("aces_10s.bag", "ROS 1 bag (uncompressed chunks)"),
        ("aces_10s_bz2.bag", "ROS 1 bag (bz2 chunks)"),
        ("aces_10s_lz4.bag", "ROS 1 bag (lz4 chunks)"),
        ("aces_10s_zstd.mcap", "MCAP (zstd chunks)"),
        ("aces_10s_mcap", "ROS 2 bag folder: MCAP (uncompressed chunks)"),
        ("aces_10s_mcap/aces_10s_mcap.mcap", "MCAP (uncompressed chunks)"),
        ("aces_10s_sqlite3", "ROS 2 bag folder: rosbag2 SQLite3"),
        ("aces_10s_sqlite3/aces_10s_sqlite3.db3", "rosbag2 SQLite3"),
    ];
    for (name, format) in formats {
        let bag = read(&data(name));
        assert_same(&bag, &carmen, name);
        let summary = bag.bag.as_ref().expect("a bag summary");
        assert_eq!(summary.format, format, "{name}");
        let counts: Vec<(&str, usize)> = summary.topics.iter().map(|t| (t.name.as_str(), t.count)).collect();
        assert_eq!(counts, [("/odom", 68), ("/scan", 68), ("/tf", 68), ("/tf_static", 1)], "{name}");
        assert_eq!(summary.scan_topic, "/scan");
        assert!(summary.odometry.starts_with("topic /odom (odom -> base_link)"), "{}", summary.odometry);
        assert_eq!(summary.laser_mount, "/tf_static: base_link -> laser");
    }
}

#[test]
fn odometry_from_tf_reads_as_odometry_from_the_topic() {
    let tf = TopicChoice { base_frame: Some("base_link".into()), ..TopicChoice::default() };
    let options = ReadOptions { topics: tf, ..ReadOptions::default() };
    let bag = read_log(&data("aces_10s_lz4.bag"), &options).unwrap();
    assert_eq!(bag.bag.as_ref().unwrap().odometry, "/tf: odom -> base_link");
    let carmen = read(&data("aces_10s.clf"));
    assert_eq!(bag.scans.len(), carmen.scans.len());
    for (b, c) in bag.scans.iter().zip(&carmen.scans) {
        let (pb, pc) = (Xyt::from_pose(&b.odometry.pose), Xyt::from_pose(&c.odometry.pose));
        assert_eq!((pb.x, pb.y, pb.theta), (pc.x, pc.y, pc.theta));
    }
}

#[test]
fn a_log_without_odom_lines_reads_as_its_bag() {
    let carmen = read(&data("aces_10s_no_odom.clf"));
    assert_eq!(carmen.repairs.line_odometry, 68);
    let bag = read(&data("aces_10s_no_odom.bag"));
    assert_eq!(bag.scans.len(), carmen.scans.len());
    for (b, c) in bag.scans.iter().zip(&carmen.scans) {
        assert_eq!(b.scan.ranges, c.scan.ranges);
        let (pb, pc) = (Xyt::from_pose(&b.odometry.pose), Xyt::from_pose(&c.odometry.pose));
        assert_eq!((pb.x, pb.y, pb.theta), (pc.x, pc.y, pc.theta));
    }
}

fn error(path: &Path, options: &ReadOptions) -> String {
    match read_log(path, options) {
        Ok(_) => panic!("{} read", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_bag_whose_messages_pass_the_byte_bound_is_refused() {
    // The 10 s bags hold about 100 KB of messages (the compressed ones decompress to that): refused past
    // 64 KB in every format, read whole under the default bound.
    let small = ReadOptions { max_bytes: 65536, ..ReadOptions::default() };
    for name in ["aces_10s_bz2.bag", "aces_10s.bag", "aces_10s_zstd.mcap", "aces_10s_sqlite3", "aces_10s_mcap"] {
        let path = data(name);
        let e = read_log(&path, &small).map(|_| ()).unwrap_err();
        assert!(matches!(e, LogError::TooLarge { limit: 65536, .. }), "{name}: {e}");
        // A folder's error names the file in it.
        assert!(e.to_string().starts_with(&path.display().to_string()), "{e}");
        assert!(e.to_string().contains(": more than 65536 bytes: refused before it exhausts memory"), "{e}");
        assert!(read(&path).scans.len() > 10, "{name}");
    }
}

#[test]
fn truncated_bags_are_refused_naming_the_file_and_the_byte() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["aces_10s_bz2.bag", "aces_10s.bag", "aces_10s_zstd.mcap", "aces_10s_mcap/aces_10s_mcap.mcap"] {
        let bytes = std::fs::read(data(name)).unwrap();
        let file = Path::new(name).file_name().unwrap();
        let cut = dir.path().join(file);
        for at in [bytes.len() - 1, bytes.len() / 2, 40] {
            std::fs::write(&cut, &bytes[..at]).unwrap();
            let e = error(&cut, &ReadOptions::default());
            assert!(e.starts_with(&cut.display().to_string()), "{name} cut at {at}: {e}");
            assert!(e.contains("cut off") && e.contains("byte"), "{name} cut at {at}: {e}");
        }
    }
    let db = std::fs::read(data("aces_10s_sqlite3/aces_10s_sqlite3.db3")).unwrap();
    let cut = dir.path().join("cut.db3");
    std::fs::write(&cut, &db[..db.len() / 2]).unwrap();
    let e = error(&cut, &ReadOptions::default());
    assert!(e.starts_with(&cut.display().to_string()) && e.contains("SQLite3"), "{e}");
}

#[test]
fn a_chunk_that_does_not_decompress_is_refused_naming_its_offset() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["aces_10s_bz2.bag", "aces_10s_lz4.bag"] {
        let mut bytes = std::fs::read(data(name)).unwrap();
        // Past the bag header record (4096 bytes of padding) lies the first chunk's compressed data.
        for b in &mut bytes[4400..4600] {
            *b ^= 0x5a;
        }
        let bad = dir.path().join(name);
        std::fs::write(&bad, &bytes).unwrap();
        let e = error(&bad, &ReadOptions::default());
        assert!(e.starts_with(&format!("{}: the chunk at byte ", bad.display())), "{e}");
        assert!(e.contains("decompress"), "{e}");
    }
    let mut bytes = std::fs::read(data("aces_10s_zstd.mcap")).unwrap();
    for b in &mut bytes[2000..2200] {
        *b ^= 0x5a;
    }
    let bad = dir.path().join("bad.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let e = error(&bad, &ReadOptions::default());
    assert!(e.starts_with(&format!("{}: MCAP, the chunk at byte ", bad.display())), "{e}");
}

/// An MCAP file written by the `mcap` crate: one `compression` chunk holding a channel and 20 messages, the
/// chunk's declared uncompressed size grown by `more` bytes (shrunk when negative); with the chunk's byte offset.
fn mcap_chunk_declaring_more(compression: mcap::Compression, more: i64) -> (Vec<u8>, usize) {
    let out = std::io::Cursor::new(Vec::new());
    let mut w = mcap::WriteOptions::new().compression(Some(compression)).create(out).unwrap();
    let schema = w.add_schema("std_msgs/msg/String", "ros2msg", b"string data").unwrap();
    let channel = w.add_channel(schema, "/chatter", "cdr", &Default::default()).unwrap();
    for k in 0..20 {
        let header =
            mcap::records::MessageHeader { channel_id: channel, sequence: k, log_time: k.into(), publish_time: 0 };
        w.write_to_known_channel(&header, &[7; 100]).unwrap();
    }
    w.finish().unwrap();
    let mut bytes = w.into_inner().into_inner();
    // Past the magic, records (opcode, u64 length) up to the chunk; its uncompressed size 16 bytes in.
    let mut at = 8;
    while bytes[at] != 0x06 {
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
    }
    let size = at + 9 + 16;
    let declared = u64::from_le_bytes(bytes[size..size + 8].try_into().unwrap());
    bytes[size..size + 8].copy_from_slice(&declared.saturating_add_signed(more).to_le_bytes());
    (bytes, at)
}

#[test]
fn a_compressed_chunk_declaring_another_size_than_it_holds_is_refused_naming_its_offset() {
    // The `mcap` crate's reader once spun forever on a chunk declaring more (found by fuzzing), and its
    // decompression underflowed on one declaring less (found by fuzzing, 2026-12-07): each read runs on a
    // thread of its own, and one that takes long fails the test.
    let dir = tempfile::tempdir().unwrap();
    for (name, compression, codec) in
        [("zstd.mcap", mcap::Compression::Zstd, "zstd"), ("lz4.mcap", mcap::Compression::Lz4, "lz4")]
    {
        // As written, the file reads: it has no scan.
        let (bytes, _) = mcap_chunk_declaring_more(compression, 0);
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        assert!(error(&path, &ReadOptions::default()).contains("no sensor_msgs/LaserScan topic"), "{name}");
        for more in [1, 4096, -1, -1000] {
            let (bytes, at) = mcap_chunk_declaring_more(compression, more);
            std::fs::write(&path, &bytes).unwrap();
            let (done, result) = std::sync::mpsc::channel();
            let read = path.clone();
            std::thread::spawn(move || done.send(error(&read, &ReadOptions::default())));
            let e = result
                .recv_timeout(std::time::Duration::from_secs(60))
                .unwrap_or_else(|_| panic!("{name}, {more} more bytes declared: still reading after 60 s"));
            let expected = format!("{}: MCAP, the chunk at byte {at}: its {codec} data expands to ", path.display());
            assert!(e.starts_with(&expected), "{name}, {more} more bytes declared: {e}");
            let says = if more > 0 { "fewer than the" } else { "more than the" };
            assert!(
                e.contains(says) && e.contains("it declares uncompressed"),
                "{name}, {more} more bytes declared: {e}"
            );
        }
    }
}

#[test]
fn a_compressed_chunk_declaring_more_than_its_bytes_can_expand_to_is_refused_naming_its_offset() {
    // The `mcap` crate reserves a chunk's declared uncompressed size before it decompresses: a chunk of a few
    // hundred bytes declaring 1 GiB would cost 1 GiB of zeroed memory before it failed.
    let dir = tempfile::tempdir().unwrap();
    for (name, compression, codec) in
        [("zstd.mcap", mcap::Compression::Zstd, "zstd"), ("lz4.mcap", mcap::Compression::Lz4, "lz4")]
    {
        let (bytes, at) = mcap_chunk_declaring_more(compression, (1 << 30) - 4096);
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let e = error(&path, &ReadOptions::default());
        let expected = format!("{}: MCAP, the chunk at byte {at}: it declares ", path.display());
        assert!(e.starts_with(&expected), "{name}: {e}");
        assert!(e.contains(&format!("more than {codec} can expand them to")), "{name}: {e}");
    }
}

/// A ROS 1 bag written here: one uncompressed chunk of `messages` (topic, type, serialized message).
fn ros1_bag(messages: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    fn record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
        let mut header = Vec::new();
        for (name, value) in fields {
            header.extend(((name.len() + 1 + value.len()) as u32).to_le_bytes());
            header.extend(name.as_bytes());
            header.push(b'=');
            header.extend(*value);
        }
        out.extend((header.len() as u32).to_le_bytes());
        out.extend(header);
        out.extend((data.len() as u32).to_le_bytes());
        out.extend(data);
    }
    let mut chunk = Vec::new();
    for (k, (topic, type_name, msg)) in messages.iter().enumerate() {
        let conn = (k as u32).to_le_bytes();
        let mut own = Vec::new();
        record(&mut own, &[("type", type_name.as_bytes())], &[]);
        // The connection's own fields are the header part of that record only.
        let own_len = u32::from_le_bytes(own[..4].try_into().unwrap()) as usize;
        record(&mut chunk, &[("op", &[7]), ("conn", &conn), ("topic", topic.as_bytes())], &own[4..4 + own_len]);
        let time = [1u32.to_le_bytes(), 0u32.to_le_bytes()].concat();
        record(&mut chunk, &[("op", &[2]), ("conn", &conn), ("time", &time)], msg);
    }
    let mut bag = b"#ROSBAG V2.0\n".to_vec();
    let index_pos = 0u64.to_le_bytes();
    record(
        &mut bag,
        &[("op", &[3]), ("index_pos", &index_pos), ("conn_count", &[0; 4]), ("chunk_count", &[0; 4])],
        &[],
    );
    let size = (chunk.len() as u32).to_le_bytes();
    record(&mut bag, &[("op", &[5]), ("compression", b"none"), ("size", &size)], &chunk);
    bag
}

/// A ROS 1 LaserScan of three beams, stamped 1 s, in frame `laser`.
fn scan_msg() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [0u32, 1, 0, 5] {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"laser");
    for v in [-0.1f32, 0.1, 0.1, 0.0, 0.0, 0.0, 10.0] {
        b.extend(v.to_le_bytes());
    }
    b.extend(3u32.to_le_bytes());
    for v in [1.0f32, 2.0, 3.0] {
        b.extend(v.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    b
}

#[test]
fn a_bag_without_a_scan_topic_or_with_two_is_refused_naming_the_topics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.bag");
    std::fs::write(&path, ros1_bag(&[("/chatter", "std_msgs/String", vec![0; 4])])).unwrap();
    let e = error(&path, &ReadOptions::default());
    assert_eq!(e, format!("{}: no sensor_msgs/LaserScan topic (topics: /chatter std_msgs/String)", path.display()));

    let two = [("/front", "sensor_msgs/LaserScan", scan_msg()), ("/rear", "sensor_msgs/LaserScan", scan_msg())];
    std::fs::write(&path, ros1_bag(&two)).unwrap();
    let e = error(&path, &ReadOptions::default());
    assert_eq!(
        e,
        format!("{}: 2 sensor_msgs/LaserScan topics (/front, /rear): choose one with --scan", path.display())
    );
    let rear = ReadOptions {
        topics: TopicChoice { scan: Some("/rear".into()), ..TopicChoice::default() },
        ..ReadOptions::default()
    };
    // The scan topic chosen, the bag still has no odometry.
    let e = error(&path, &rear);
    assert!(e.contains("no odometry") && e.contains("/front sensor_msgs/LaserScan"), "{e}");
    let wrong = ReadOptions {
        topics: TopicChoice { scan: Some("/side".into()), ..TopicChoice::default() },
        ..ReadOptions::default()
    };
    assert!(
        error(&path, &wrong)
            .ends_with("--scan /side: no sensor_msgs/LaserScan topic of that name (the bag's: /front, /rear)")
    );

    // A message cut short names its topic and index.
    let mut cut = scan_msg();
    cut.truncate(30);
    std::fs::write(&path, ros1_bag(&[("/scan", "sensor_msgs/LaserScan", cut)])).unwrap();
    let e = error(&path, &ReadOptions::default());
    assert!(
        e.starts_with(&format!("{}: topic /scan message 0: sensor_msgs/LaserScan: message ends", path.display())),
        "{e}"
    );
    assert!(matches!(read_log(&path, &ReadOptions::default()), Err(LogError::Record { .. })));
}
