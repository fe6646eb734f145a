//! The fuzz corpora of core's parsers (fuzz/corpus/<target>/, kept by `cargo fuzz`), replayed: every input
//! that once found a bug, or reached new code, must still be read without a panic.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_core::map_io::{
    MapMode, MapYaml, decode_grey_image, grid_from_image, parse_map_yaml, read_grey_image_limited,
};
use mrslam_core::relations::{parse_relations, parse_trajectory, score};
use std::path::{Path, PathBuf};

/// Every file of `fuzz/corpus/<target>`, with its path.
fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus").join(target);
    let files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    assert!(!files.is_empty(), "{}: empty corpus", dir.display());
    files
}

#[test]
fn map_yaml_corpus() {
    for (path, bytes) in corpus("map_yaml") {
        if let Ok(text) = std::str::from_utf8(&bytes) {
            let _ = parse_map_yaml(text, &path);
        }
    }
}

#[test]
fn grey_image_corpus() {
    let meta = MapYaml {
        image: String::new(),
        resolution: 0.05,
        origin: [0.0; 3],
        negate: false,
        occupied_thresh: 0.65,
        free_thresh: 0.196,
        mode: MapMode::Trinary,
    };
    for (path, bytes) in corpus("grey_image") {
        // As the fuzz target does: the file read with a bound of 4 KiB, then its bytes decoded.
        let _ = read_grey_image_limited(&path, 4096);
        if let Ok(img) = decode_grey_image(&bytes, &path) {
            let _ = grid_from_image(&img, &meta);
        }
    }
}

#[test]
fn relations_corpus() {
    for (path, bytes) in corpus("relations") {
        if let Ok(text) = std::str::from_utf8(&bytes)
            && let (Ok(r), Ok(t)) = (parse_relations(text, &path), parse_trajectory(text, &path))
        {
            let _ = score(&t, &r, 0.001);
        }
    }
}
