//! `mrslam merge` with three or more maps, run as a user would.

use crate::util::{mrslam, p, text};
use mrslam_core::map_io::{read_ros_map, write_ros_map};
use mrslam_core::{OccupancyGrid, Pose2, pose};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::resample::resample;
use std::path::Path;

/// The cells of `map` in the window [x0, x1) x [y0, y1) (fractions of its size), re-rendered at `res` in the
/// frame `t_new_world` takes the building's frame to.
fn cut(map: &OccupancyGrid, (x0, x1, y0, y1): (f64, f64, f64, f64), t_new_world: &Pose2, res: f64) -> OccupancyGrid {
    let (w, h) = (map.width() as f64, map.height() as f64);
    let (i0, i1, j0, j1) = ((x0 * w) as usize, (x1 * w) as usize, (y0 * h) as usize, (y1 * h) as usize);
    let (o, r) = (map.origin().translation, map.resolution());
    let mut g = OccupancyGrid::new(i1 - i0, j1 - j0, r, pose(o.x + i0 as f64 * r, o.y + j0 as f64 * r, 0.0)).unwrap();
    for j in j0..j1 {
        for i in i0..i1 {
            g.set(i - i0, j - j0, map.get(i, j));
        }
    }
    resample(&g, t_new_world, res)
}

/// Three overlapping cuts of one floor plan written as a.yaml, b.yaml, c.yaml (c at `res_c`); returns the
/// true `T_a_k` of each.
fn three_cuts(d: &Path, res_c: f64) -> Vec<Pose2> {
    let plan = generate(41, &FloorplanParams::default());
    let moves = [pose(0.5, -1.0, 0.3), pose(-2.0, 2.5, -1.7), pose(3.0, 1.0, 2.4)];
    let windows = [(0.0, 0.65, 0.0, 0.65), (0.35, 1.0, 0.0, 0.65), (0.0, 0.65, 0.35, 1.0)];
    for (k, name) in ["a", "b", "c"].iter().enumerate() {
        let res = if k == 2 { res_c } else { plan.resolution() };
        write_ros_map(&cut(&plan, windows[k], &moves[k], res), &d.join(format!("{name}.yaml"))).unwrap();
    }
    moves.iter().map(|m| moves[0] * m.inverse()).collect()
}

/// Reads the report and checks each listed map's transform into a's frame against the truth.
fn check_transforms(report: &serde_json::Value, truth: &[Pose2], tol_m: f64) {
    for (k, t) in truth.iter().enumerate() {
        let est = &report["transforms"][k];
        let est = pose(est["x"].as_f64().unwrap(), est["y"].as_f64().unwrap(), est["theta"].as_f64().unwrap());
        let d = est.inverse() * t;
        let (rot, trans) = (d.rotation.angle().to_degrees().abs(), d.translation.vector.norm());
        assert!(rot <= 1.0 && trans <= tol_m, "map {k}: off by {rot} deg, {trans} m: {report}");
    }
}

#[test]
fn three_maps_are_placed_in_the_first_maps_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = three_cuts(d, 0.05);
    let (a, b, c) = (d.join("a.yaml"), d.join("b.yaml"), d.join("c.yaml"));
    let (m, r) = (d.join("merged.yaml"), d.join("report.json"));
    let o = mrslam(&["merge", p(&a), p(&b), p(&c), "-o", p(&m), "--report", p(&r)]);
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}{}", text(&o.stderr));
    assert!(out.contains("merge of 3 maps (cascade): 3 of 3 in the frame of a.yaml"), "{out}");
    assert!(out.contains("a.yaml + b.yaml: ACCEPTED"), "{out}");
    assert!(out.contains("tree") && out.contains(" -> "), "{out}");
    assert!(!out.contains("left out"), "{out}");
    assert!(!out.contains("WARNING"), "every cycle of accepted pairs closes: {out}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&r).unwrap()).unwrap();
    assert_eq!(report["maps"], 3);
    assert_eq!(report["pairs"].as_array().unwrap().len(), 3);
    assert_eq!(report["pairs"][0]["report"]["accepted"], true, "{report}");
    assert_eq!(report["tree"].as_array().unwrap().len(), 2);
    assert_eq!(report["not_connected"].as_array().unwrap().len(), 0);
    assert_eq!(report["disagreements"].as_array().unwrap().len(), 0);
    assert_eq!(report["files"][2].as_str().unwrap(), p(&c));
    check_transforms(&report, &truth, 0.1);
    let merged = read_ros_map(&m).unwrap();
    assert_eq!(merged.resolution(), 0.05);
    let a_free = read_ros_map(&a).unwrap().state_counts().0;
    assert!(merged.state_counts().0 as f64 > 1.8 * a_free as f64, "the merged map should hold much more than a");
}

#[test]
fn a_map_that_joins_nothing_exits_2_and_the_rest_are_merged() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = three_cuts(d, 0.05);
    // A fourth map of one colour: nothing to match.
    std::fs::write(d.join("white.pgm"), [b"P5\n50 40\n255\n".as_slice(), &[254u8; 2000]].concat()).unwrap();
    std::fs::write(d.join("white.yaml"), "image: white.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    let maps = ["a.yaml", "b.yaml", "c.yaml", "white.yaml"].map(|n| d.join(n));
    let (m, r) = (d.join("merged.yaml"), d.join("report.json"));
    let mut args = vec!["merge"];
    args.extend(maps.iter().map(|x| p(x)));
    args.extend(["-o", p(&m), "--report", p(&r)]);
    let o = mrslam(&args);
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(2), "{out}{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("panicked"));
    assert!(out.contains("3 of 4 in the frame of a.yaml"), "{out}");
    assert!(out.contains("white.yaml: not connected") && out.contains("left out:   white.yaml joins no other map"));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&r).unwrap()).unwrap();
    assert_eq!(report["not_connected"], serde_json::json!([3]));
    assert_eq!(report["components"], serde_json::json!([[0, 1, 2], [3]]));
    assert!(report["transforms"][3].is_null());
    for q in report["pairs"].as_array().unwrap().iter().filter(|q| q["b"] == 3) {
        assert_eq!(q["report"]["accepted"], false);
        assert!(q["report"]["reason"].as_str().is_some_and(|s| !s.is_empty()), "{q}");
    }
    check_transforms(&report, &truth, 0.1);
    assert!(m.exists(), "the three maps that join are merged");
}

#[test]
fn a_map_at_another_resolution_is_placed_as_for_two_maps() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = three_cuts(d, 0.10);
    let (a, b, c) = (d.join("a.yaml"), d.join("b.yaml"), d.join("c.yaml"));
    let m = d.join("merged.yaml");
    let r = d.join("report.json");
    let o = mrslam(&["merge", p(&a), p(&b), p(&c), "-o", p(&m), "--report", p(&r)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&r).unwrap()).unwrap();
    // Two cells of the coarse map.
    check_transforms(&report, &truth, 0.2);
    assert_eq!(read_ros_map(&m).unwrap().resolution(), 0.05, "the merged map keeps the first map's resolution");
}

#[test]
fn bad_input_and_pair_only_flags_exit_1_naming_the_cause() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(42, &FloorplanParams::default()), &d.join("a.yaml")).unwrap();
    write_ros_map(&generate(43, &FloorplanParams::default()), &d.join("b.yaml")).unwrap();
    let (a, b) = (d.join("a.yaml"), d.join("b.yaml"));
    std::fs::write(d.join("broken.yaml"), "image: a.pgm\nresolution: fast\norigin: [0, 0, 0]\n").unwrap();
    let o = mrslam(&["merge", p(&a), p(&b), p(&d.join("broken.yaml")), "-o", p(&d.join("m.yaml"))]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(e.contains("broken.yaml:2") && e.contains("resolution"), "{e}");
    let o = mrslam(&["merge", p(&a), p(&b), p(&d.join("nope.yaml"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("nope.yaml"));
    // An output over the third input.
    let c = d.join("c.yaml");
    std::fs::copy(&b, &c).unwrap();
    std::fs::copy(d.join("b.pgm"), d.join("c.pgm")).unwrap();
    let o = mrslam(&["merge", p(&a), p(&b), p(&c), "-o", p(&c)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("refusing to write an output over"), "{}", text(&o.stderr));
    // Flags that draw or record a pair.
    for (flag, value) in [("--matches-png", "m.png"), ("--rrd", "m.rrd")] {
        let out = d.join(value);
        let o = mrslam(&["merge", p(&a), p(&b), p(&c), flag, p(&out)]);
        assert_eq!(o.status.code(), Some(1), "{flag}");
        let e = text(&o.stderr);
        assert!(e.contains(flag) && e.contains("3 maps were given"), "{e}");
        assert!(!out.exists());
    }
}
