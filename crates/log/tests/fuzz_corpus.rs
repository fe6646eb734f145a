//! The fuzz corpora of the log readers (fuzz/corpus/<target>/, kept by `cargo fuzz`), replayed: every input
//! that once found a bug, or reached new code, must still be read without a panic.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_log::{ReadOptions, carmen, read_log};
use std::path::{Path, PathBuf};

/// Every file of `fuzz/corpus/<target>`, with its path, in name order.
fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus").join(target);
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    paths.sort();
    assert!(!paths.is_empty(), "{}: empty corpus", dir.display());
    paths.into_iter().map(|p| (p.clone(), std::fs::read(&p).unwrap())).collect()
}

#[test]
fn carmen_log_corpus() {
    for (path, bytes) in corpus("carmen_log") {
        let _ = carmen::parse(bytes.as_slice(), &path, &ReadOptions::default());
        // As the fuzz target does: with bounds small enough for the corpus to reach them.
        let small = ReadOptions { max_line_bytes: 64, max_bytes: 1024, ..ReadOptions::default() };
        let _ = carmen::parse(bytes.as_slice(), &path, &small);
    }
}

/// Replays the corpus of a bag target as the target does (each input written to a file named `.ext`, then
/// `read_log`); the seeds (`seed-*`, cut from tests/data/bags) must read into logs with scans, the inputs that
/// found a bug (`crash-*`: a panic, an allocation of what a header claims, a hang) must be refused.
fn bag_corpus(target: &str, ext: &str) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(format!("input.{ext}"));
    let mut seeds = 0;
    for (path, bytes) in corpus(target) {
        std::fs::write(&file, &bytes).unwrap();
        let read = read_log(&file, &ReadOptions::default());
        let name = path.file_name().unwrap().to_string_lossy();
        if name.starts_with("seed-") {
            let log = read.unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(log.scans.len() > 5 && !log.odometry.is_empty(), "{name}: {} scans", log.scans.len());
            seeds += 1;
        } else if name.starts_with("crash-") {
            assert!(read.is_err(), "{name}: read");
        }
    }
    assert!(seeds > 0, "{target}: no seed");
}

#[test]
fn ros1_bag_corpus() {
    bag_corpus("ros1_bag", "bag");
}

#[test]
fn mcap_bag_corpus() {
    bag_corpus("mcap_bag", "mcap");
}

#[test]
fn sqlite_bag_corpus() {
    bag_corpus("sqlite_bag", "db3");
}
