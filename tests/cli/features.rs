//! `mrslam features`, as a user would: on a map, on a plain image, and on bad input.

use mrslam_core::map_io::write_ros_map;
use mrslam_merge::floorplan::{FloorplanParams, generate};
use std::process::Command;

#[test]
fn features_of_a_map_as_json_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(31, &FloorplanParams::default()), &d.join("plan.yaml")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["features", d.join("plan.yaml").to_str().unwrap(), "--json"])
        .arg(d.join("kp.json"))
        .arg("--png")
        .arg(d.join("kp.png"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let n: usize = out.split(", ").find_map(|s| s.strip_suffix(" keypoints").and_then(|v| v.parse().ok())).unwrap();
    assert!(n > 50, "{out}");
    let kp: Vec<serde_json::Value> = serde_json::from_slice(&std::fs::read(d.join("kp.json")).unwrap()).unwrap();
    assert_eq!(kp.len(), n);
    for key in ["x", "y", "size", "angle", "response", "octave"] {
        assert!(kp[0][key].is_number(), "{key} missing");
    }
    assert_eq!(kp[0]["descriptor"].as_array().unwrap().len(), 128);
    let png = image::open(d.join("kp.png")).unwrap();
    assert!(png.width() > 400);
}

#[test]
fn flat_image_has_no_keypoints_and_garbage_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("flat.pgm"), [b"P5\n64 64\n255\n".as_slice(), &[128u8; 64 * 64]].concat()).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mrslam")).arg("features").arg(d.join("flat.pgm")).output().unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains(" 0 keypoints"));
    std::fs::write(d.join("junk.png"), b"not a png").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mrslam")).arg("features").arg(d.join("junk.png")).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("junk.png"));
}
