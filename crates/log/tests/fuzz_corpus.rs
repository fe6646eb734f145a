//! The fuzz corpus of the CARMEN reader (fuzz/corpus/carmen_log/, kept by `cargo fuzz`), replayed: every
//! input that once found a bug, or reached new code, must still be read without a panic.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_log::{ReadOptions, carmen};
use std::path::Path;

#[test]
fn carmen_log_corpus() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/carmen_log");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let _ = carmen::parse(bytes.as_slice(), &path, &ReadOptions::default());
        // As the fuzz target does: with bounds small enough for the corpus to reach them.
        let small = ReadOptions { max_line_bytes: 64, max_bytes: 1024, ..ReadOptions::default() };
        let _ = carmen::parse(bytes.as_slice(), &path, &small);
        files += 1;
    }
    assert!(files > 0, "{}: empty corpus", dir.display());
}
