//! `mrslam run --mcap` and `mrslam sim log --mcap`: a simulated run as a ROS 2 bag, read back by the MCAP
//! project's own reader (the `mcap` crate, not mrslam's bag reader) and a CDR decoder written here from the
//! ROS 2 message definitions, and replayed into `mrslam slam`.

use crate::util::{mrslam, p, text};
use byteorder::LittleEndian;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn scenario() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/paper_two_rooms.toml")
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `sensor_msgs/msg/LaserScan` as ROS 2 Humble defines it (header: `builtin_interfaces/Time` then the frame).
#[derive(Deserialize)]
struct Scan {
    sec: i32,
    nanosec: u32,
    frame_id: String,
    angle_min: f32,
    angle_max: f32,
    angle_increment: f32,
    _time_increment: f32,
    _scan_time: f32,
    range_min: f32,
    range_max: f32,
    ranges: Vec<f32>,
    intensities: Vec<f32>,
}

/// `nav_msgs/msg/OccupancyGrid`: header, `MapMetaData` (load time, resolution, width, height, origin pose),
/// data.
#[derive(Deserialize)]
struct Grid {
    _sec: i32,
    _nanosec: u32,
    frame_id: String,
    _load_sec: i32,
    _load_nanosec: u32,
    resolution: f32,
    width: u32,
    height: u32,
    _origin: [f64; 7],
    data: Vec<i8>,
}

/// Decodes a CDR message (little-endian encapsulation header first).
fn cdr<T: for<'de> Deserialize<'de>>(data: &[u8]) -> T {
    assert_eq!(data[..2], [0, 1], "plain CDR, little-endian");
    cdr_encoding::from_bytes::<T, LittleEndian>(&data[4..]).unwrap().0
}

#[test]
fn a_runs_bag_holds_every_robots_topics_with_ros2_schemas_and_decodes() {
    let dir = tempfile::tempdir().unwrap();
    let (out, bag) = (dir.path().join("run"), dir.path().join("run.mcap"));
    let o = mrslam(&["run", p(&scenario()), "--out", p(&out), "--mcap", p(&bag), "--algorithm", "sift", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains(&format!("ROS 2 bag: {}", bag.display())), "{}", text(&o.stdout));
    let report = json(&out.join("report.json"));
    let steps = report["steps"].as_u64().unwrap();
    assert_eq!(report["merges"][0]["accepted"], true, "{report}");
    // Written under a temporary name and renamed: nothing else is left beside it.
    let names: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names.len(), 2, "{names:?}");

    let bytes = std::fs::read(&bag).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let stats = summary.stats.as_ref().unwrap();
    let mut topics = BTreeMap::new();
    for (id, c) in &summary.channels {
        let schema = c.schema.as_ref().expect("every channel has a schema");
        assert_eq!((schema.encoding.as_str(), c.message_encoding.as_str()), ("ros2msg", "cdr"), "{}", c.topic);
        let definition = String::from_utf8(schema.data.to_vec()).unwrap();
        let count = stats.channel_message_counts.get(id).copied().unwrap_or(0);
        topics.insert(c.topic.clone(), (schema.name.clone(), count, definition));
    }
    let expected = [
        ("/experia/ground_truth", "nav_msgs/msg/Odometry"),
        ("/experia/map", "nav_msgs/msg/OccupancyGrid"),
        ("/experia/odom", "nav_msgs/msg/Odometry"),
        ("/experia/scan", "sensor_msgs/msg/LaserScan"),
        ("/merged_map", "nav_msgs/msg/OccupancyGrid"),
        ("/prawn/ground_truth", "nav_msgs/msg/Odometry"),
        ("/prawn/map", "nav_msgs/msg/OccupancyGrid"),
        ("/prawn/odom", "nav_msgs/msg/Odometry"),
        ("/prawn/scan", "sensor_msgs/msg/LaserScan"),
        ("/tf", "tf2_msgs/msg/TFMessage"),
        ("/tf_static", "tf2_msgs/msg/TFMessage"),
        ("/truth_map", "nav_msgs/msg/OccupancyGrid"),
    ];
    let got: Vec<(&str, &str)> = topics.iter().map(|(t, (s, ..))| (t.as_str(), s.as_str())).collect();
    assert_eq!(got, expected);
    // The definitions as ROS 2 embeds them: the type's fields, then each type used after a line of 80 `=`.
    let scan_definition = &topics["/experia/scan"].2;
    assert!(scan_definition.starts_with("std_msgs/Header header\nfloat32 angle_min\n"), "{scan_definition}");
    let separator = format!("{}\nMSG: ", "=".repeat(80));
    for section in ["std_msgs/Header\n", "builtin_interfaces/Time\n"] {
        assert!(scan_definition.contains(&format!("{separator}{section}")), "{scan_definition}");
    }
    assert!(topics["/tf"].2.contains(&format!("{separator}geometry_msgs/TransformStamped\n")));
    // Counts: a scan message per scan, odometry and truth every step, one of each map and of the mounts; /tf
    // the odometry's every step and the SLAM's map -> odom once the SLAM has had a scan.
    for robot in ["experia", "prawn"] {
        let scans = report["robots"][robot]["scans"].as_u64().unwrap();
        assert_eq!(topics[&format!("/{robot}/scan")].1, scans, "{robot}");
        assert_eq!(topics[&format!("/{robot}/odom")].1, steps, "{robot}");
        assert_eq!(topics[&format!("/{robot}/ground_truth")].1, steps, "{robot}");
        assert_eq!(topics[&format!("/{robot}/map")].1, 1, "{robot}");
    }
    assert!((3 * steps..=4 * steps).contains(&topics["/tf"].1), "{} /tf for {steps} steps", topics["/tf"].1);
    assert_eq!((topics["/tf_static"].1, topics["/merged_map"].1, topics["/truth_map"].1), (1, 1, 1));

    // One scan and the merged map decoded by a decoder written from the ROS 2 definitions.
    let mut decoded = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        match m.channel.topic.as_str() {
            "/experia/scan" if m.sequence == 10 => {
                let s: Scan = cdr(&m.data);
                let stamp = f64::from(s.sec) + f64::from(s.nanosec) * 1e-9;
                // Stamped at its first beam, logged when it came in (the step's end, within a scan period).
                let logged = m.log_time as f64 * 1e-9;
                assert!(stamp <= logged && logged - stamp < 0.1 + 1e-9, "stamp {stamp}, logged {logged}");
                assert_eq!(s.frame_id, "experia/laser");
                // The Hokuyo URG-04LX preset: 667 beams over 240 degrees, 0.06 to 4 m.
                assert_eq!(s.ranges.len(), 667);
                assert!((s.angle_increment.to_degrees() - 0.36).abs() < 1e-3, "{}", s.angle_increment);
                let span = s.angle_max - s.angle_min - s.angle_increment * 666.0;
                assert!(span.abs() < 1e-4, "angle_max {} angle_min {}", s.angle_max, s.angle_min);
                assert_eq!((s.range_min, s.range_max), (0.06, 4.0));
                let hits = s.ranges.iter().filter(|r| r.is_finite() && **r >= s.range_min && **r < s.range_max);
                assert!(hits.count() > 300);
                assert!(s.intensities.is_empty());
                decoded += 1;
            }
            "/merged_map" => {
                let g: Grid = cdr(&m.data);
                assert_eq!(g.frame_id, "experia/map", "the merged map is in the host's map frame");
                assert_eq!(g.data.len(), (g.width * g.height) as usize);
                assert!((g.resolution - 0.05).abs() < 1e-6);
                let occupied = g.data.iter().filter(|&&v| v > 50).count();
                let free = g.data.iter().filter(|&&v| (0..=50).contains(&v)).count();
                assert!(occupied > 500 && free > 5000, "{occupied} occupied, {free} free");
                assert!(g.data.iter().all(|&v| v == -1 || (0..=100).contains(&v)));
                decoded += 1;
            }
            _ => {}
        }
    }
    assert_eq!(decoded, 2);
}

#[test]
fn a_simulated_runs_bag_replayed_into_slam_maps_each_robot_as_its_carmen_log_does() {
    let dir = tempfile::tempdir().unwrap();
    let (logs, bag) = (dir.path().join("logs"), dir.path().join("run.mcap"));
    let o = mrslam(&["sim", "log", p(&scenario()), "--out", p(&logs), "--mcap", p(&bag), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for name in ["experia", "prawn"] {
        let relations = logs.join(format!("{name}.relations"));
        let slam = |input: &Path, tag: &str, extra: &[&str]| {
            let summary = dir.path().join(format!("{name}_{tag}.json"));
            let trajectory = dir.path().join(format!("{name}_{tag}.txt"));
            let map = dir.path().join(format!("{name}_{tag}.yaml"));
            let mut args = vec!["slam", p(input), "-o", p(&map), "--trajectory", p(&trajectory)];
            args.extend(["--relations", p(&relations), "--summary", p(&summary), "--quiet"]);
            args.extend(extra);
            let o = mrslam(&args);
            assert!(o.status.success(), "{tag}: {}", text(&o.stderr));
            let metric = json(&summary)["metric"].clone();
            let poses: Vec<Vec<f64>> = std::fs::read_to_string(&trajectory)
                .unwrap()
                .lines()
                .filter(|l| !l.starts_with('#'))
                .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
                .collect();
            (metric, poses)
        };
        let (scan, odom) = (format!("/{name}/scan"), format!("/{name}/odom"));
        let (from_bag, bag_poses) = slam(&bag, "bag", &["--scan", &scan, "--odom", &odom]);
        let (from_log, log_poses) = slam(&logs.join(format!("{name}.clf")), "clf", &[]);
        // Every scan of the robot, at the same stamps; the relations (drawn from the truth) all found.
        assert_eq!(bag_poses.len(), log_poses.len(), "{name}");
        assert!(bag_poses.iter().zip(&log_poses).all(|(a, b)| (a[0] - b[0]).abs() < 1e-6), "{name}: stamps differ");
        assert_eq!(from_bag["missing"], 0, "{from_bag}");
        // The bag carries the run at full precision (the CARMEN text to 6 decimals), so the filters' draws part
        // ways, but both map the robot as well: within 0.03 m (measured 0.006 / 0.014 m from the bag, 0.008 /
        // 0.014 m from the log, seed 11) and 2 degrees of the truth per relation, and close to each other.
        let (tb, tl) =
            (from_bag["translation_mean_m"].as_f64().unwrap(), from_log["translation_mean_m"].as_f64().unwrap());
        let (rb, rl) =
            (from_bag["rotation_mean_deg"].as_f64().unwrap(), from_log["rotation_mean_deg"].as_f64().unwrap());
        eprintln!("{name}: bag {tb:.4} m {rb:.3} deg, CARMEN log {tl:.4} m {rl:.3} deg");
        assert!(tb < 0.03 && rb < 2.0, "{name}: SLAM on the bag {tb} m, {rb} deg");
        assert!((tb - tl).abs() < 0.01 && (rb - rl).abs() < 0.5, "{name}: bag {tb} m {rb} deg, log {tl} m {rl} deg");
        let apart = bag_poses.iter().zip(&log_poses).map(|(a, b)| (a[1] - b[1]).hypot(a[2] - b[2])).fold(0.0, f64::max);
        assert!(apart < 0.15, "{name}: trajectories {apart} m apart");
    }
}

#[test]
fn a_bag_over_an_input_or_of_another_kind_is_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A scenario file named like a bag: it is read, so it is not written over.
    let named_like_a_bag = d.join("scenario.mcap");
    std::fs::write(
        &named_like_a_bag,
        std::fs::read_to_string(scenario()).unwrap().replace(
            "\"../worlds/two_rooms.toml\"",
            &format!("{:?}", Path::new(env!("CARGO_MANIFEST_DIR")).join("worlds/two_rooms.toml")),
        ),
    )
    .unwrap();
    let before = std::fs::read(&named_like_a_bag).unwrap();
    let out = d.join("out");
    let o = mrslam(&["run", p(&named_like_a_bag), "--out", p(&out), "--mcap", p(&named_like_a_bag), "--quiet"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("--mcap") && text(&o.stderr).contains("refusing to write an output over the input")
    );
    assert_eq!(std::fs::read(&named_like_a_bag).unwrap(), before);
    assert!(!out.exists());
    let o = mrslam(&["run", p(&scenario()), "--out", p(&out), "--mcap", p(&d.join("run.bag")), "--quiet"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("`.bag` is not a format written here; expected .mcap"), "{}", text(&o.stderr));
    // The bag and a log of `sim log` on one file.
    let logs = d.join("logs");
    std::fs::create_dir(&logs).unwrap();
    let clash = logs.join("experia.clf");
    let o = mrslam(&["sim", "log", p(&scenario()), "--out", p(&logs), "--mcap", p(&clash), "--quiet"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--mcap"), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_dir(&logs).unwrap().count(), 0);
}
