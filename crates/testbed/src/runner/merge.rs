//! The merge after driving stops: which two robots' maps are merged, each algorithm's merge scored against the
//! true transform between the two SLAM frames.
//!
//! A run merges one pair: the scenario's merge host and the first other robot in the scenario's order (with
//! two robots, the other one). Further robots drive, map and are evaluated, but their maps are not merged.

use super::agent::Agent;
use super::evaluate::Evaluated;
use super::options::{RunError, RunOptions};
use super::record::merge_view;
use crate::eval::{map_acceptance, transform_error};
use crate::report::MergeResult;
use crate::scenario::Scenario;
use mrslam_core::{OccupancyGrid, Xyt};
use mrslam_merge::{Algorithm, MergeOutcome, MergeParams, Merger, merge};

/// The host robot's name and the other's: a run takes two or more robots of distinct names, one of them the
/// host; the other is the first robot in the scenario's order that is not the host. A team of one robot has no
/// pair (`None`).
///
/// [`Scenario::from_file`] checks this; a scenario built or changed in code may not hold to it.
pub(super) fn merge_pair(scenario: &Scenario) -> Result<Option<(String, String)>, RunError> {
    let robots = &scenario.robots;
    if robots.len() == 1 && scenario.team.is_some() {
        return Ok(None);
    }
    if robots.len() < 2 {
        return Err(RunError::Scenario(format!(
            "a run takes at least two robots (a merge needs two maps), found {}",
            robots.len()
        )));
    }
    for (i, r) in robots.iter().enumerate() {
        if robots[..i].iter().any(|q| q.name == r.name) {
            return Err(RunError::Scenario(format!("two robots share the name `{}`", r.name)));
        }
    }
    let host = &scenario.merge.host;
    if !robots.iter().any(|r| r.name == *host) {
        return Err(RunError::Scenario(format!("the merge host `{host}` is not one of the robots")));
    }
    let other = robots.iter().find(|r| r.name != *host).map(|r| r.name.clone()).unwrap_or_default();
    Ok(Some((host.clone(), other)))
}

/// Share of the truth cells seen by either robot of the pair that both saw.
pub(super) fn observed_overlap(agents: &[Agent], (host, other): (&str, &str)) -> f64 {
    let observed = |name: &str| agents.iter().find(|a| a.setup.name == name).map_or(&[][..], |a| &a.observed[..]);
    let (oa, ob) = (observed(host), observed(other));
    let both = oa.iter().zip(ob).filter(|(x, y)| **x && **y).count();
    let either = oa.iter().zip(ob).filter(|(x, y)| **x || **y).count();
    if either == 0 { 0.0 } else { both as f64 / either as f64 }
}

/// Merges the other robot's map into the host's with each algorithm's merger and scores each merge against the
/// true transform between the two SLAM frames (and against the one at the end of the run).
pub(super) fn merge_maps(
    scenario: &Scenario,
    mergers: &[(Algorithm, Box<dyn Merger>)],
    evaluated: &Evaluated,
    (host, other): (&str, &str),
    truth: &OccupancyGrid,
    opts: &mut RunOptions,
) -> (Vec<MergeResult>, Vec<MergeOutcome>) {
    let true_t = evaluated.frames[host].inv_mul(&evaluated.frames[other]);
    let end_t = evaluated.end_frames[host].inv_mul(&evaluated.end_frames[other]);
    let mut merges = Vec::new();
    let mut results = Vec::new();
    for (algorithm, merger) in mergers {
        let out = merge(merger.as_ref(), &evaluated.maps[host], &evaluated.maps[other], &MergeParams::default());
        let err = out.report.transform.map(|t| transform_error(&t.to_pose(), &true_t));
        let err_at_end = out.report.transform.map(|t| transform_error(&t.to_pose(), &end_t));
        let success = out.report.accepted
            && err.is_some_and(|(r, t)| {
                r.to_degrees() <= scenario.success.rotation_deg && t <= scenario.success.translation_m
            });
        results.push(MergeResult {
            algorithm: algorithm.to_string(),
            accepted: out.report.accepted,
            success,
            rotation_error_deg: err.map(|e| e.0.to_degrees()),
            translation_error_m: err.map(|e| e.1),
            rotation_error_at_end_deg: err_at_end.map(|e| e.0.to_degrees()),
            translation_error_at_end_m: err_at_end.map(|e| e.1),
            acceptance_index: out.report.acceptance_index,
            merged_map_acceptance: out.merged.as_ref().map(|m| map_acceptance(truth, m, &evaluated.frames[host])),
            time_ms: out.report.time_ms,
            reason: out.report.reason.clone(),
            stage: out.report.stage.clone(),
            transform: out.report.transform,
            true_transform: Xyt::from_pose(&true_t),
            true_transform_at_end: Xyt::from_pose(&end_t),
            inliers: out.report.inliers,
            matches: out.report.matches,
        });
        if let Some(v) = opts.viz.as_deref_mut() {
            v.merge(&merge_view(&out, host, other, err));
        }
        merges.push(out);
    }
    (results, merges)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::tests::two_rooms;

    #[test]
    fn the_host_comes_first_in_the_merge_pair() {
        let mut s = two_rooms();
        let (a, b) = (s.robots[0].name.clone(), s.robots[1].name.clone());
        assert_eq!(merge_pair(&s).unwrap().unwrap(), (a.clone(), b.clone()));
        s.merge.host = b.clone();
        assert_eq!(merge_pair(&s).unwrap().unwrap(), (b.clone(), a.clone()));
        // A third robot: the host is merged with the first other robot.
        let mut third = s.robots[0].clone();
        third.name = "third".into();
        s.robots.push(third);
        assert_eq!(merge_pair(&s).unwrap().unwrap(), (b.clone(), a.clone()));
        s.merge.host = "third".into();
        assert_eq!(merge_pair(&s).unwrap().unwrap(), ("third".to_string(), a));
    }
}
