//! The fuzz corpora of the scenario, sweep and results parsers (fuzz/corpus/<target>/), replayed: nothing may
//! panic. (The scenario parser is testbed's; it is replayed here, beside the sweeps built on it.)
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_studies::Sweep;
use mrslam_studies::results::parse_results;
use mrslam_studies::summary::summarise;
use mrslam_testbed::scenario::Scenario;
use std::path::{Path, PathBuf};

/// Every text file of `fuzz/corpus/<target>`, with its path.
fn corpus(target: &str) -> Vec<(PathBuf, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus").join(target);
    let files: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    assert!(!files.is_empty(), "{}: empty corpus", dir.display());
    files.into_iter().filter_map(|p| Some((p.clone(), String::from_utf8(std::fs::read(&p).unwrap()).ok()?))).collect()
}

/// Where the fuzz targets anchor relative paths: beside the shipped scenarios.
fn beside_scenarios(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name)
}

#[test]
fn scenario_toml_corpus() {
    for (_, text) in corpus("scenario_toml") {
        let _ = Scenario::parse(&text, &beside_scenarios("fuzz.toml"));
    }
}

#[test]
fn sweep_toml_corpus() {
    for (_, text) in corpus("sweep_toml") {
        let _ = Sweep::parse(&text, &beside_scenarios("fuzz_sweep.toml"));
    }
}

#[test]
fn study_csv_corpus() {
    for (path, text) in corpus("study_csv") {
        if let Ok(rows) = parse_results(&text, &path) {
            let _ = summarise(&rows);
        }
    }
}
