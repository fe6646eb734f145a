//! `mrslam eval relations` run as a user would: a trajectory with a known error per relation gives exactly
//! that error; unmatched stamps are counted as missing; bad files are refused naming file, line and field.

use crate::util::mrslam;
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A trajectory around a circle of radius 5 m, one pose per second, heading along the circle, so that the
/// heading crosses ±180°; pose 6 is off by 0.3 m sideways and 0.2 rad.
fn circle(with_error: bool) -> String {
    let mut text = String::from("# stamp x y theta\n");
    for k in 0..12 {
        let a = k as f64 * std::f64::consts::PI / 6.0;
        let (mut x, mut y, mut t) = (5.0 * a.cos(), 5.0 * a.sin(), a + std::f64::consts::FRAC_PI_2);
        if with_error && k == 6 {
            // 0.3 m to the robot's left, turned by +0.2 rad.
            x += -0.3 * t.sin();
            y += 0.3 * t.cos();
            t += 0.2;
        }
        let t = (t + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
        text.push_str(&format!("{}.000000 {x:.9} {y:.9} {t:.9}\n", 100 + k));
    }
    text
}

/// Relations between consecutive poses of the true circle: 5 m chord, 30° turn; one relation whose second
/// stamp has no pose.
fn relations() -> String {
    let chord = 2.0 * 5.0 * (std::f64::consts::PI / 12.0).sin();
    let turn = std::f64::consts::PI / 6.0;
    let (x, y) = (chord * (turn / 2.0).cos(), chord * (turn / 2.0).sin());
    let mut text = String::new();
    for k in 0..11 {
        text.push_str(&format!("{}.000000 {}.000000 {x:.9} {y:.9} 0 0 0 {turn:.9}\n", 100 + k, 101 + k));
    }
    text.push_str("105.000000 150.000000 0 0 0 0 0 0\n");
    text
}

#[test]
fn a_known_error_per_relation_is_reported_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let rel = write(dir.path(), "c.relations", &relations());
    let perfect = write(dir.path(), "perfect.txt", &circle(false));
    let json = dir.path().join("perfect.json");
    let o = mrslam(&[
        "eval",
        "relations",
        perfect.to_str().unwrap(),
        rel.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!((m["used"].as_u64(), m["missing"].as_u64()), (Some(11), Some(1)));
    assert!(m["translation_max_m"].as_f64().unwrap() < 1e-6 && m["rotation_max_deg"].as_f64().unwrap() < 1e-6, "{m}");

    // Pose 6 is wrong: relation 5->6 sees the pose error directly (0.3 m, 0.2 rad); relation 6->7 sees it
    // from the other end. Every other relation is exact.
    let off = write(dir.path(), "off.txt", &circle(true));
    let json = dir.path().join("off.json");
    let o =
        mrslam(&["eval", "relations", off.to_str().unwrap(), rel.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("relations: 11 used, 1 missing") && out.contains("first missing relation: line 12"), "{out}");
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let f = |k: &str| m[k].as_f64().unwrap();
    assert!((f("rotation_max_deg") - 0.2f64.to_degrees()).abs() < 1e-5, "{m}");
    assert!((f("rotation_mean_deg") - 2.0 * 0.2f64.to_degrees() / 11.0).abs() < 1e-5, "{m}");
    // Seen from pose 7 back, the 0.2 rad turn at pose 6 also swings pose 7 about it: the larger error.
    let chord = 2.0 * 5.0 * (std::f64::consts::PI / 12.0).sin();
    let (first, second) = (&m["worst"][0], &m["worst"][1]);
    assert_eq!((first["line"].as_u64(), second["line"].as_u64()), (Some(7), Some(6)), "{m}");
    let swung = first["translation_m"].as_f64().unwrap();
    assert!(swung > 0.3 && swung <= 0.3 + 2.0 * 0.1f64.sin() * chord + 1e-6, "{m}");
    assert!((second["translation_m"].as_f64().unwrap() - 0.3).abs() < 1e-6, "{m}");
    for key in [
        "translation_mean_m",
        "translation_std_m",
        "translation_mean_sq_m2",
        "rotation_std_deg",
        "rotation_mean_sq_deg2",
    ] {
        assert!(m[key].as_f64().unwrap() > 0.0, "{key}: {m}");
    }
}

#[test]
fn unmatched_stamps_and_bad_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rel = write(dir.path(), "c.relations", &relations());
    let traj = write(dir.path(), "t.txt", &circle(false));
    let fails = |args: &[&str], needle: &str| {
        let o = mrslam(args);
        let e = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(e.contains(needle), "{args:?}: `{needle}` not in {e}");
    };
    let shifted = write(dir.path(), "shifted.txt", &circle(false).replace(".000000 ", ".500000 "));
    fails(&["eval", "relations", shifted.to_str().unwrap(), rel.to_str().unwrap()], "none of the 12 relations");
    let bad = write(dir.path(), "bad.txt", "100 0 0 0\n101 0 zero 0\n");
    fails(&["eval", "relations", bad.to_str().unwrap(), rel.to_str().unwrap()], "bad.txt:2: field y: `zero`");
    let short = write(dir.path(), "short.relations", "100 101 1 0 0\n");
    fails(
        &["eval", "relations", traj.to_str().unwrap(), short.to_str().unwrap()],
        "short.relations:1: expected 8 fields",
    );
    // (relations in a file named .json, so that the output's extension is not what refuses it)
    let rel_json = write(dir.path(), "c.json", &relations());
    fails(
        &[
            "eval",
            "relations",
            traj.to_str().unwrap(),
            rel_json.to_str().unwrap(),
            "--json",
            rel_json.to_str().unwrap(),
        ],
        "refusing to write an output over the input",
    );
    fails(
        &["eval", "relations", traj.to_str().unwrap(), rel.to_str().unwrap(), "--json", rel.to_str().unwrap()],
        "expected .json",
    );
    assert_eq!(std::fs::read_to_string(&rel).unwrap(), relations(), "the input was touched");
}
