//! What every CLI test needs: the binary, its output as text, paths as arguments.

use std::path::Path;
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
