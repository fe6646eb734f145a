//! The merge algorithms a study compares, read and checked.

use mrslam_merge::Algorithm;

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

    #[test]
    fn a_trial_and_a_simulated_run_build_the_same_merger_for_the_same_seed() {
        use mrslam_merge::MergerConfig;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper_two_rooms.toml");
        let mut s = mrslam_testbed::scenario::Scenario::from_file(&path).unwrap();
        // The scenario's merge settings set to the defaults a study uses.
        (s.merge.candidates, s.merge.hypotheses, s.merge.wall_dilation) = (1, 1, 0);
        s.seed = 23;
        for a in Algorithm::ALL {
            assert_eq!(mrslam_testbed::runner::merger_for(a, &s), MergerConfig::new(a, 23), "{a}");
        }
    }
}
