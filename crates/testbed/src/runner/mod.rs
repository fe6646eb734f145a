//! The simulation loop: drive the robots, run their SLAMs, merge two of their maps, evaluate against truth.
//!
//! A run (`run`) sets up the simulator and one agent per robot (`agent`: its SLAM back-end and controller),
//! drives until the merge time (`drive`), scores each robot's SLAM (`evaluate`), merges the pair of maps the
//! scenario names (`merge`) and returns a [`RunOutput`] that `write_outputs` writes (`outputs`); with a
//! recording asked for, `record` hands the rerun recorder plain data along the way.

mod agent;
mod coordinate;
mod coverage;
mod drive;
mod evaluate;
mod merge;
mod options;
mod outputs;
mod pose_history;
mod record;
mod team;

pub use options::{RobotStep, RunError, RunOptions, RunOutput, StepTap};
pub use outputs::{merge_overlay, output_files, write_outputs};
pub use pose_history::{PoseHistory, pairing_time};
pub use record::merge_view;

use crate::report::RunReport;
use crate::scenario::Scenario;
use mrslam_merge::{Algorithm, Merger, MergerConfig};
use mrslam_sim::{Sim, SimConfig};
use std::time::Instant;

/// `algorithm`'s merger settings from the scenario's merge settings, its random draws seeded by the scenario's seed.
pub fn merger_for(algorithm: Algorithm, scenario: &Scenario) -> MergerConfig {
    let m = &scenario.merge;
    MergerConfig {
        model: m.model,
        encoding: m.encoding,
        ratio: m.ratio,
        candidates: m.candidates,
        hypotheses: m.hypotheses,
        wall_dilation: m.wall_dilation,
        upscale: m.upscale,
        ..MergerConfig::new(algorithm, scenario.seed)
    }
}

/// Runs a scenario end to end: the robots drive and map until the merge time (`drive`), each robot's
/// SLAM is evaluated against the truth (`evaluate_robots`), then the merge pair's maps are merged by each
/// algorithm and every merge is scored against the true transform (`merge_maps`).
pub fn run(scenario: &Scenario, mut opts: RunOptions) -> Result<RunOutput, RunError> {
    let wall = Instant::now();
    let pair = merge::merge_pair(scenario)?;
    let config = SimConfig { dt: scenario.dt, ..SimConfig::default() };
    let mut sim = Sim::with_config(&scenario.world, scenario.seed, config)?;
    let truth = sim.true_map(scenario.truth_resolution)?;
    let mut agents = agent::add_robots(scenario, &mut sim, &truth)?;
    let algorithms = opts.algorithms.clone().unwrap_or_else(|| scenario.merge.algorithms.clone());
    if let Some(v) = opts.viz.as_deref_mut() {
        record::viz_begin(v, &sim, &truth, &agents, &algorithms, scenario.team.is_some());
    }
    let mut teams = scenario.team.as_ref().map(|setup| {
        // The run waits for its online attempts (they block the step): each may use every core (trials run
        // side by side share rayon's threads), and robots' maps are rarely settled by `sift`, so the cascade
        // runs `sift+boundary` beside it; neither changes an answer.
        let merger = MergerConfig { parallel: true, side_by_side: true, ..merger_for(setup.merger, scenario) };
        team::Teams::new(scenario, setup, &truth, merger.build())
    });
    let steps = drive::drive(scenario, &mut sim, &mut agents, &truth, teams.as_mut(), &mut opts)?;
    let merge_at = sim.time();
    if let Some(v) = opts.viz.as_deref_mut() {
        v.set_time(steps, merge_at);
    }
    // The data ends for every SLAM when the drive ends: the particle filter closes loops there when its
    // parameters ask for it, as `mrslam slam` does at the end of a log (no preset of the simulated robots does).
    for a in agents.iter_mut() {
        a.slam.finish();
    }
    let team = teams.map(|t| t.report(merge_at, &agents, &truth)).transpose()?;
    let evaluated = evaluate::evaluate_robots(&agents, &truth, &mut opts)?;
    let (mut results, mut merges, mut observed_overlap) = (Vec::new(), Vec::new(), 0.0);
    if let Some((host, other)) = &pair {
        let mergers: Vec<(Algorithm, Box<dyn Merger>)> =
            algorithms.iter().map(|&a| (a, merger_for(a, scenario).build())).collect();
        let pair = (host.as_str(), other.as_str());
        (results, merges) = merge::merge_maps(scenario, &mergers, &evaluated, pair, &truth, &mut opts);
        observed_overlap = merge::observed_overlap(&agents, pair);
    }
    let report = RunReport {
        scenario: scenario.name.clone(),
        seed: scenario.seed,
        sim_s: merge_at,
        wall_s: wall.elapsed().as_secs_f64(),
        steps,
        merge_at_s: merge_at,
        merge_pair: pair.map(|(host, other)| [host, other]),
        robots: evaluated.robots,
        merges: results,
        observed_overlap,
        team,
    };
    Ok(RunOutput { report, maps: evaluated.maps, truth, merges, frames: evaluated.frames, paths: evaluated.paths })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::path::Path;

    /// The paper's two-rooms scenario, for the runner's tests.
    pub(crate) fn two_rooms() -> Scenario {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper_two_rooms.toml");
        Scenario::from_file(&path).unwrap()
    }

    #[test]
    fn a_scenario_changed_in_code_is_refused_before_the_run_not_by_a_panic() {
        let refused = |s: &Scenario| match run(s, RunOptions::default()) {
            Err(RunError::Scenario(m)) => m,
            Err(e) => panic!("unexpected error {e}"),
            Ok(_) => panic!("the run went ahead"),
        };
        let mut s = two_rooms();
        s.robots.pop();
        assert_eq!(refused(&s), "a run takes at least two robots (a merge needs two maps), found 1");
        let mut s = two_rooms();
        s.merge.host = "nobody".into();
        assert_eq!(refused(&s), "the merge host `nobody` is not one of the robots");
        let mut s = two_rooms();
        s.robots[1].name = s.robots[0].name.clone();
        assert!(refused(&s).contains("share the name"));
    }

    #[test]
    fn a_scenarios_merger_follows_its_settings_and_seed() {
        let mut s = two_rooms();
        s.seed = 17;
        s.merge.hypotheses = 3;
        for a in Algorithm::ALL {
            let c = merger_for(a, &s);
            assert_eq!((c.algorithm, c.seed, c.hypotheses), (a, 17, 3));
            assert_eq!(c.build().name(), a.name());
        }
    }
}
