//! `mrslam merge` and `mrslam map cut`, run as a user would.

use crate::util::{mrslam, p, text};
use mrslam_core::map_io::{read_ros_map, write_ros_map};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use std::path::Path;

#[test]
fn cut_then_merge_recovers_the_printed_transform() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(21, &FloorplanParams::default()), &d.join("plan.yaml")).unwrap();
    let o = mrslam(&["map", "cut", p(&d.join("plan.yaml")), p(&d.join("a.yaml")), p(&d.join("b.yaml")), "--seed", "3"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let truth: Vec<f64> = out
        .lines()
        .find(|l| l.starts_with("true transform"))
        .unwrap()
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    let (tx, ty, tth) = (truth[0], truth[1], truth[2]);

    let o = mrslam(&[
        "merge",
        p(&d.join("a.yaml")),
        p(&d.join("b.yaml")),
        "-o",
        p(&d.join("merged.yaml")),
        "--report",
        p(&d.join("report.json")),
        "--matches-png",
        p(&d.join("matches.png")),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stdout).contains("ACCEPTED"));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("report.json")).unwrap()).unwrap();
    for key in ["accepted", "algorithm", "transform", "scale", "matches", "inliers", "confidence", "acceptance_index"] {
        assert!(report.get(key).is_some(), "report lacks {key}: {report}");
    }
    assert!(report["time_ms"].as_f64().unwrap() > 0.0);
    // The default merger is the cascade; the paper's SIFT merger, its first stage, settles a clean cut.
    assert_eq!((report["algorithm"].as_str(), report["stage"].as_str()), (Some("cascade"), Some("sift")));
    assert!(report["timings_ms"]["sift/features"].as_f64().is_some());
    let t = &report["transform"];
    assert!((t["x"].as_f64().unwrap() - tx).abs() < 0.1, "{t} vs {truth:?}");
    assert!((t["y"].as_f64().unwrap() - ty).abs() < 0.1, "{t} vs {truth:?}");
    assert!((t["theta"].as_f64().unwrap() - tth).abs() < 0.02, "{t} vs {truth:?}");
    let merged = read_ros_map(&d.join("merged.yaml")).unwrap();
    assert!(merged.state_counts().0 > read_ros_map(&d.join("a.yaml")).unwrap().state_counts().0);
    // The preview beside it: the merged map cropped to its known cells.
    let preview = image::open(d.join("merged.png")).unwrap();
    assert!(preview.width() <= merged.width() as u32 && preview.height() <= merged.height() as u32);
    assert!(preview.width() > 50 && preview.height() > 50);
    let png = image::open(d.join("matches.png")).unwrap();
    assert!(png.width() > 100 && png.height() > 100);
}

/// Generates floor plan `seed` as `d/plan.yaml` and cuts it into `d/a.yaml` and `d/b.yaml` at `overlap`.
fn cut_plan(d: &Path, seed: u64, overlap: &str) {
    write_ros_map(&generate(seed, &FloorplanParams::default()), &d.join("plan.yaml")).unwrap();
    let (plan, a, b) = (d.join("plan.yaml"), d.join("a.yaml"), d.join("b.yaml"));
    let o = mrslam(&["map", "cut", p(&plan), p(&a), p(&b), "--overlap", overlap]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

#[test]
fn sift_without_the_doubled_image_still_merges_a_cut() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cut_plan(d, 21, "0.5");
    let (a, b, path) = (d.join("a.yaml"), d.join("b.yaml"), d.join("report.json"));
    let report = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["merge", p(&a), p(&b), "--algorithm", "sift", "--report"];
        args.push(p(&path));
        args.extend_from_slice(extra);
        let o = mrslam(&args);
        assert_eq!(o.status.code(), Some(0), "{extra:?}: {}{}", text(&o.stdout), text(&o.stderr));
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap()
    };
    let (doubled, own) = (report(&[]), report(&["--no-upscale"]));
    let t = |r: &serde_json::Value, k: &str| r["transform"][k].as_f64().unwrap();
    assert!((t(&doubled, "x") - t(&own, "x")).abs() < 0.1 && (t(&doubled, "y") - t(&own, "y")).abs() < 0.1);
    assert!((t(&doubled, "theta") - t(&own, "theta")).abs() < 0.02, "{doubled} vs {own}");
    // Other features: the doubled image's finest octave is gone (on this cut, more of them pass the ratio test).
    assert_ne!(own["matches"], doubled["matches"]);
}

#[test]
fn rejected_merge_exits_2_and_writes_no_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cut_plan(d, 22, "-0.2");
    let o = mrslam(&[
        "merge",
        p(&d.join("a.yaml")),
        p(&d.join("b.yaml")),
        "-o",
        p(&d.join("merged.yaml")),
        "--report",
        p(&d.join("report.json")),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stdout).contains("REJECTED") && text(&o.stdout).contains("reason:"));
    assert!(!d.join("merged.yaml").exists() && !d.join("merged.pgm").exists() && !d.join("merged.png").exists());
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["accepted"], false);
    assert!(report["reason"].as_str().is_some_and(|r| !r.is_empty()));
}

#[test]
fn one_colour_map_is_rejected_not_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(23, &FloorplanParams::default()), &d.join("a.yaml")).unwrap();
    std::fs::write(d.join("white.pgm"), [b"P5\n50 40\n255\n".as_slice(), &[254u8; 2000]].concat()).unwrap();
    std::fs::write(d.join("white.yaml"), "image: white.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    let o = mrslam(&["merge", p(&d.join("a.yaml")), p(&d.join("white.yaml")), "-o", p(&d.join("m.yaml"))]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("panicked"));
    assert!(!d.join("m.yaml").exists());
}

#[test]
fn unreadable_map_exits_1_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(24, &FloorplanParams::default()), &d.join("a.yaml")).unwrap();
    std::fs::write(d.join("broken.yaml"), "image: a.pgm\nresolution: fast\norigin: [0, 0, 0]\n").unwrap();
    let o = mrslam(&["merge", p(&d.join("a.yaml")), p(&d.join("broken.yaml")), "-o", p(&d.join("m.yaml"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(e.contains("broken.yaml:2") && e.contains("resolution"), "{e}");
    let o = mrslam(&["merge", p(&d.join("nope.yaml")), p(&d.join("a.yaml"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("nope.yaml"));
}

#[test]
fn outputs_that_cannot_be_written_fail_before_the_merge() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(24, &FloorplanParams::default()), &d.join("a.yaml")).unwrap();
    let map = d.join("a.yaml");
    let a = p(&map);
    let missing = |name: &str| d.join("no/such/folder").join(name);
    let (yaml, json, png) = (missing("m.yaml"), missing("r.json"), missing("m.png"));
    for (args, out) in [
        (vec!["merge", a, a, "-o", p(&yaml)], &yaml),
        (vec!["merge", a, a, "--report", p(&json)], &json),
        (vec!["merge", a, a, "--matches-png", p(&png)], &png),
    ] {
        let o = mrslam(&args);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(e.contains(p(out)) && e.contains("does not exist"), "{e}");
        assert!(!text(&o.stdout).contains("ACCEPTED"), "the merge ran before the output was checked");
    }
    // a folder named like a map
    let folder = d.join("folder.yaml");
    std::fs::create_dir(&folder).unwrap();
    let o = mrslam(&["merge", a, a, "-o", p(&folder)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("it is a folder"), "{}", text(&o.stderr));
}

#[test]
fn rmap_algorithm_writes_the_same_report() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cut_plan(d, 25, "0.6");
    let (a, b) = (d.join("a.yaml"), d.join("b.yaml"));
    for verify in [true, false] {
        let mut args = vec!["merge", p(&a), p(&b), "--algorithm", "rmap", "--report"];
        let report = d.join(format!("rmap_{verify}.json"));
        args.push(p(&report));
        if !verify {
            args.push("--no-verify");
        }
        let o = mrslam(&args);
        // Accepted (0) or rejected (2): both are answers; anything else is a failure.
        assert!(matches!(o.status.code(), Some(0) | Some(2)), "{}", text(&o.stderr));
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        assert_eq!(r["algorithm"], "rmap");
        assert!(r["time_ms"].as_f64().unwrap() > 0.0);
        if !verify && r["transform"].is_object() {
            assert_eq!(r["accepted"], true, "--no-verify accepts whatever the algorithm answers");
        }
    }
}

/// An 8 m x 6 m building at 5 cm that a half turn about its centre maps onto itself.
fn symmetric_building() -> mrslam_core::OccupancyGrid {
    let (w, h) = (160usize, 120usize);
    let mut g = mrslam_core::OccupancyGrid::new(w, h, 0.05, mrslam_core::pose(0.0, 0.0, 0.0)).unwrap();
    for iy in 0..h {
        for ix in 0..w {
            let border = ix < 2 || iy < 2 || ix >= w - 2 || iy >= h - 2;
            let inner = ((39..41).contains(&iy) && ix < 60) || ((79..81).contains(&iy) && ix >= 100);
            g.set(ix, iy, if border || inner { 2.0 } else { -2.0 });
        }
    }
    g
}

#[test]
fn correlative_refuses_an_ambiguous_pose_naming_the_rival_unless_the_test_is_off() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b, report) = (d.join("a.yaml"), d.join("b.yaml"), d.join("r.json"));
    write_ros_map(&symmetric_building(), &a).unwrap();
    // The same building seen from another frame, by another robot: one corner cell seen free (a map merged with
    // itself, the same image or the same cells, is refused).
    let mut other = symmetric_building();
    other.set_origin(mrslam_core::pose(1.5, -2.0, 0.0));
    other.set(0, 0, -mrslam_core::map_io::ROS_LOGODDS_LIMIT);
    write_ros_map(&other, &b).unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["merge", p(&a), p(&b), "--algorithm", "correlative", "--report", p(&report)];
        args.extend_from_slice(extra);
        let o = mrslam(&args);
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        (o, r)
    };
    let (o, r) = run(&[]);
    assert_eq!(o.status.code(), Some(2), "{}{}", text(&o.stdout), text(&o.stderr));
    let reason = r["reason"].as_str().unwrap();
    assert!(reason.starts_with("ambiguous") && reason.contains("deg and"), "{reason}");
    let (_, r) = run(&["--min-margin", "0"]);
    assert!(!r["reason"].as_str().unwrap_or("").starts_with("ambiguous"), "{r}");
}

#[test]
fn correlative_answers_are_checked_the_other_way_round_unless_one_way() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cut_plan(d, 21, "0.5");
    let report = d.join("r.json");
    let run = |extra: &[&str]| {
        let (a, b, m) = (d.join("a.yaml"), d.join("b.yaml"), d.join("m.yaml"));
        let mut args = vec!["merge", p(&a), p(&b), "-o", p(&m), "--algorithm", "correlative", "--report", p(&report)];
        args.extend_from_slice(extra);
        let o = mrslam(&args);
        assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        r
    };
    let (checked, one_way) = (run(&[]), run(&["--one-way"]));
    assert!(checked["timings_ms"]["cross_check"].is_number(), "{checked}");
    assert!(one_way["timings_ms"].get("cross_check").is_none(), "{one_way}");
    assert_eq!(checked["transform"], one_way["transform"], "the check accepts or refuses, it does not move the answer");
}

#[test]
fn correlative_refuses_maps_that_do_not_mark_their_walls_and_the_cascade_still_merges_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cut_plan(d, 21, "0.5");
    // Both maps' walls dropped to unknown, as map_server reads light-grey walls: only their boundaries are left.
    let bare = |name: &str| {
        let mut g = read_ros_map(&d.join(format!("{name}.yaml"))).unwrap();
        for y in 0..g.height() {
            for x in 0..g.width() {
                if g.state(x, y) == mrslam_core::CellState::Occupied {
                    g.set(x, y, 0.0);
                }
            }
        }
        let path = d.join(format!("{name}_bare.yaml"));
        write_ros_map(&g, &path).unwrap();
        path
    };
    let (a, b) = (bare("a"), bare("b"));
    let report = d.join("r.json");
    let run = |algorithm: &str| {
        let o = mrslam(&["merge", p(&a), p(&b), "--algorithm", algorithm, "--report", p(&report)]);
        let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        (o, r)
    };
    let (o, r) = run("correlative");
    assert_eq!(o.status.code(), Some(2), "{}{}", text(&o.stdout), text(&o.stderr));
    let reason = r["reason"].as_str().unwrap();
    assert!(reason.starts_with("map a does not mark its walls (0 occupied cells)"), "{reason}");
    // The cascade's SIFT stage takes them (their walls from the boundary).
    let (o, r) = run("cascade");
    assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
    assert_eq!((r["algorithm"].as_str(), r["stage"].as_str()), (Some("cascade"), Some("sift")), "{r}");
}
