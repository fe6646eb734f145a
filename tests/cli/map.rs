//! The `map` and `log` commands, run as a user would: good input, and every kind of bad input.

use crate::util::mrslam;
use std::path::{Path, PathBuf};
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A 6x4 map: a wall column of occupied pixels, free space, an unknown corner.
fn small_map(dir: &Path) -> PathBuf {
    #[rustfmt::skip]
    let px: [u8; 24] = [
        0, 254, 254, 254, 205, 205,
        0, 254, 254, 254, 254, 205,
        0, 254, 254, 254, 254, 254,
        0, 0,   0,   0,   0,   0,
    ];
    write(dir, "small.pgm", &[b"P5\n6 4\n255\n".as_slice(), &px].concat());
    write(dir, "small.yaml", b"image: small.pgm\nresolution: 0.1\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
}

fn assert_fails_with(args: &[&str], needles: &[&str]) {
    let o = mrslam(args);
    assert_eq!(o.status.code(), Some(1), "exit code for {args:?}; stderr: {}", stderr(&o));
    let e = stderr(&o);
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "stderr of {args:?} lacks `{n}`: {e}");
    }
}

#[test]
fn map_info_reports_size_counts_and_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let map = small_map(dir.path());
    let o = mrslam(&["map", "info", map.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("6 x 4 cells"), "{out}");
    assert!(out.contains("0.1 m/cell"), "{out}");
    assert!(out.contains("x -1.000 m, y 2.000 m"), "{out}");
    assert!(out.contains("12 free, 9 occupied, 3 unknown"), "{out}");
    assert!(out.contains("cells x 0..=5, y 0..=3"), "{out}");
}

#[test]
fn map_convert_round_trips_through_png_and_yaml() {
    let dir = tempfile::tempdir().unwrap();
    let map = small_map(dir.path());
    let png = dir.path().join("out.png");
    let o = mrslam(&["map", "convert", map.to_str().unwrap(), png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let yaml = dir.path().join("again.yaml");
    let o = mrslam(&["map", "convert", png.to_str().unwrap(), yaml.to_str().unwrap(), "--resolution", "0.1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = mrslam_core::map_io::read_ros_map(&map).unwrap();
    let b = mrslam_core::map_io::read_ros_map(&yaml).unwrap();
    assert_eq!(a.cells(), b.cells());
    assert!(dir.path().join("again.pgm").exists());
}

#[test]
fn bad_maps_exit_1_naming_file_and_problem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let meta = "resolution: 0.05\norigin: [0, 0, 0]\n";
    let missing = write(d, "missing.yaml", format!("image: nowhere.pgm\n{meta}").as_bytes());
    assert_fails_with(&["map", "info", missing.to_str().unwrap()], &["nowhere.pgm", "No such file"]);

    write(d, "magic.pgm", b"P6\n2 2\n255\n............");
    let magic = write(d, "magic.yaml", format!("image: magic.pgm\n{meta}").as_bytes());
    assert_fails_with(&["map", "info", magic.to_str().unwrap()], &["magic.pgm", "magic number `P6`"]);

    write(d, "trunc.pgm", b"P5\n20 20\n255\n\x00\x01");
    let trunc = write(d, "trunc.yaml", format!("image: trunc.pgm\n{meta}").as_bytes());
    assert_fails_with(&["map", "info", trunc.to_str().unwrap()], &["trunc.pgm", "truncated"]);

    write(d, "ok.pgm", b"P5\n1 1\n255\n\x00");
    let nores = write(d, "nores.yaml", b"image: ok.pgm\norigin: [0, 0, 0]\n");
    assert_fails_with(&["map", "info", nores.to_str().unwrap()], &["nores.yaml", "resolution"]);

    let negres = write(d, "negres.yaml", b"image: ok.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n");
    assert_fails_with(
        &["map", "info", negres.to_str().unwrap()],
        &["negres.yaml:2", "resolution", "between 0.0001 and 100"],
    );
    let zero = write(d, "zero.yaml", b"image: ok.pgm\nresolution: 0\norigin: [0, 0, 0]\n");
    assert_fails_with(&["map", "info", zero.to_str().unwrap()], &["zero.yaml:2", "resolution"]);

    write(d, "huge.pgm", b"P5\n300000 300000\n255\n\x00");
    let huge = write(d, "huge.yaml", format!("image: huge.pgm\n{meta}").as_bytes());
    assert_fails_with(&["map", "info", huge.to_str().unwrap()], &["huge.pgm", "exceeds the limit"]);

    assert_fails_with(&["map", "info", d.join("absent.yaml").to_str().unwrap()], &["absent.yaml"]);
    let txt = write(d, "map.txt", b"hello");
    assert_fails_with(&["map", "info", txt.to_str().unwrap()], &["map.txt", "unknown map format"]);
}

#[test]
fn convert_to_unwritable_place_fails_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let map = small_map(dir.path());
    let out = dir.path().join("no/such/dir/out.yaml");
    assert_fails_with(
        &["map", "convert", map.to_str().unwrap(), out.to_str().unwrap()],
        &["out.yaml", "does not exist"],
    );
    assert!(!out.exists());
}

#[test]
fn log_info_counts_and_bad_line_names_its_number() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(
        dir.path(),
        "good.clf",
        b"PARAM laser_front_laser_resolution 1.0 0 h 0\nODOM 0 0 0 0 0 0 1.0 h 1.0\nFLASER 3 1 2 3 0 0 0 0 0 0 1.5 h 1.5\nNEFF 3 h 3\n",
    );
    let o = mrslam(&["log", "info", good.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("scans:     1") && out.contains("1 NEFF") && out.contains("3 beams"), "{out}");

    let bad = write(dir.path(), "bad.clf", b"ODOM 0 0 0 0 0 0 1.0 h 1.0\nFLASER 3 1 2 3 0 0\n");
    assert_fails_with(&["log", "info", bad.to_str().unwrap()], &["bad.clf:2", "FLASER", "expected at least"]);
}

#[test]
fn log_info_reads_odom_lines_of_another_clock_with_odometry_line() {
    // As GMapping writes a log: between the stamped ODOM lines, ODOM lines of another clock.
    let dir = tempfile::tempdir().unwrap();
    let log = write(
        dir.path(),
        "gmapping.log",
        b"ODOM 0.1 0 0 0 0 0 10.0 h 10.0\nFLASER 3 1 2 3 0.1 0 0 0.1 0 0 10.0 h 10.0\nODOM 9 9 0 0 0 0 0.7 h 0.7\n\
ODOM 0.2 0 0 0 0 0 11.0 h 11.0\nFLASER 3 1 2 3 0.2 0 0 0.2 0 0 11.0 h 11.0\n",
    );
    assert_fails_with(&["log", "info", log.to_str().unwrap()], &["gmapping.log:3: ODOM", "--odometry line"]);
    let o = mrslam(&["log", "info", log.to_str().unwrap(), "--odometry", "line"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("scans use the scan lines' own odometry fields (2 scans)"), "{}", stdout(&o));
}
