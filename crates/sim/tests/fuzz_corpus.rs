//! The world files of the fuzz corpus (fuzz/corpus/world_toml/), replayed: none may panic.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use std::path::Path;

#[test]
fn world_toml_corpus() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/world_toml");
    // As the fuzz target: beside the shipped worlds, so a bitmap path resolves as theirs do.
    let anchor = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../worlds/fuzz.toml");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        if let Ok(text) = std::str::from_utf8(&bytes)
            && let Ok(spec) = mrslam_sim::WorldSpec::from_toml_str(text, &anchor)
        {
            let _ = mrslam_sim::World::from_spec(&spec);
        }
        n += 1;
    }
    assert!(n > 0, "{}: empty corpus", dir.display());
}
