//! The merge algorithms a study compares, built for one trial.

use mrslam_merge::{
    Algorithm, Cascade, CorrelativeMerger, CorrelativeParams, MapEncoding, Merger, RmapMerger, RmapParams, SiftMerger,
    SiftMergerParams,
};

/// `algorithm`'s merger with default parameters for a map-level trial seeded `seed`.
///
/// The correlative merger has no random draws. Only the SIFT merger's draws (also a cascade's) (its RANSAC) follow `seed`; the
/// R-map merger's orientation draws keep their default seed ([`RmapParams::default`], 0) in every trial, as the published studies were computed. A
/// simulated run ([`mrslam_testbed::runner::merger_for`]) seeds both with the scenario's seed.
pub fn study_merger(algorithm: Algorithm, seed: u64) -> Box<dyn Merger> {
    study_merger_encoded(algorithm, seed, MapEncoding::default())
}

/// [`study_merger`] with the SIFT merger's map-to-image encoding chosen (the other mergers have none).
pub fn study_merger_encoded(algorithm: Algorithm, seed: u64, encoding: MapEncoding) -> Box<dyn Merger> {
    let mut sift = SiftMergerParams { encoding, ..SiftMergerParams::default() };
    sift.ransac.seed = seed;
    match algorithm {
        Algorithm::Sift => Box::new(SiftMerger::new(sift)),
        Algorithm::Rmap => Box::new(RmapMerger::new(RmapParams::default())),
        Algorithm::Correlative => Box::new(CorrelativeMerger::default()),
        Algorithm::Cascade => Box::new(Cascade::new(sift, CorrelativeParams::default())),
    }
}

/// Checks a list of algorithms: not empty, none repeated.
pub fn check_algorithms(algorithms: &[Algorithm]) -> Result<(), super::StudyError> {
    let bad = |m: String| Err(super::StudyError::Invalid(m));
    if algorithms.is_empty() {
        return bad("no algorithms given".into());
    }
    for (i, a) in algorithms.iter().enumerate() {
        if algorithms[..i].contains(a) {
            return bad(format!("algorithm `{a}` given twice"));
        }
    }
    Ok(())
}

/// Reads a list of algorithm names, then checks it as [`check_algorithms`] does; an unknown name's error
/// lists the valid ones.
pub fn parse_algorithms<S: AsRef<str>>(names: &[S]) -> Result<Vec<Algorithm>, super::StudyError> {
    let algorithms = names
        .iter()
        .map(|n| n.as_ref().parse::<Algorithm>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| super::StudyError::Invalid(e.to_string()))?;
    check_algorithms(&algorithms)?;
    Ok(algorithms)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_read_and_checked() {
        assert_eq!(parse_algorithms(&["sift", "rmap"]).unwrap(), [Algorithm::Sift, Algorithm::Rmap]);
        let err = |names: &[&str]| parse_algorithms(names).unwrap_err().to_string();
        assert_eq!(
            err(&["sift", "magic"]),
            "unknown algorithm `magic` (expected one of sift, rmap, correlative, cascade)"
        );
        assert_eq!(err(&["rmap", "rmap"]), "algorithm `rmap` given twice");
        assert_eq!(err(&[]), "no algorithms given");
    }
}
