//! What every CLI test needs: the binary, its output as text, paths as arguments, a refusal checked, a map.

use mrslam_core::map_io::write_ros_map;
use mrslam_merge::floorplan::{FloorplanParams, generate};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `mrslam` binary under test with `args`.
pub fn mrslam(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrslam")).args(args).output().expect("mrslam runs")
}

/// Bytes of stdout or stderr as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A path as a command-line argument.
pub fn p(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 path")
}

/// The repository's root (scenarios, worlds and test data are found from it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `args`, expects exit 1 and a message with every needle, and no panic.
pub fn fails_with(args: &[&str], needles: &[&str]) -> Output {
    let o = mrslam(args);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "exit code of {args:?}; stdout {} stderr {e}", text(&o.stdout));
    assert!(!e.contains("panicked"), "{e}");
    for n in needles {
        assert!(e.contains(n), "stderr of {args:?} lacks `{n}`: {e}");
    }
    o
}

/// A generated floor plan written as `name`.yaml + .pgm in `dir`.
pub fn plan(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let path = dir.join(format!("{name}.yaml"));
    write_ros_map(&generate(seed, &FloorplanParams::default()), &path).expect("the plan is written");
    path
}
