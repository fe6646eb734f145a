//! The merge algorithms a study can compare, built for one trial.

use mrslam_merge::{Merger, RmapMerger, RmapParams, SiftMerger, SiftMergerParams};

/// Algorithm names a study accepts.
pub const STUDY_ALGORITHMS: &[&str] = &["sift", "rmap"];

/// The merger called `name` with default parameters, its random draws seeded by `seed`; None when unknown.
pub fn study_merger(name: &str, seed: u64) -> Option<Box<dyn Merger>> {
    match name {
        "sift" => {
            let mut p = SiftMergerParams::default();
            p.ransac.seed = seed;
            Some(Box::new(SiftMerger::new(p)))
        }
        "rmap" => Some(Box::new(RmapMerger::new(RmapParams::default()))),
        _ => None,
    }
}

/// Checks a list of algorithm names: known, not repeated, not empty.
pub fn check_algorithms(names: &[String]) -> Result<(), super::StudyError> {
    let bad = |m: String| Err(super::StudyError::Invalid(m));
    if names.is_empty() {
        return bad("no algorithms given".into());
    }
    for (i, n) in names.iter().enumerate() {
        if !STUDY_ALGORITHMS.contains(&n.as_str()) {
            return bad(format!("unknown algorithm `{n}` (expected one of {})", STUDY_ALGORITHMS.join(", ")));
        }
        if names[..i].contains(n) {
            return bad(format!("algorithm `{n}` given twice"));
        }
    }
    Ok(())
}
