//! What a team study runs: its configurations (how many robots, range, coordination, merger) crossed with its
//! seeds, each trial's scenario, and which trials are one and the same run.
//!
//! Trials are configuration-major: `trial = configuration × seeds + seed index`, the configurations in the order
//! robots, then range, then coordination, then merger (the last varying fastest).

use crate::StudyError;
use mrslam_merge::Algorithm;
use mrslam_testbed::scenario::{Coordination, Scenario};

/// The longest communication range a study takes, metres: further is a typo (1e6 m reaches across any world).
pub const MAX_RANGE: f64 = 1e6;

/// One configuration of a team study: what its trials share besides the scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// How many robots: the first this many of the scenario's `[[robots]]`.
    pub robots: usize,
    /// Communication range, metres.
    pub range: f64,
    /// How a joined team explores.
    pub coordination: Coordination,
    /// The merger of the online merges.
    pub merger: Algorithm,
}

impl Config {
    /// The configuration in words: `N=2, range 6 m, frontiers, cascade`.
    pub fn describe(&self) -> String {
        format!("N={}, range {} m, {}, {}", self.robots, self.range, self.coordination, self.merger)
    }

    /// The team settings that change the run: none with one robot (it meets nobody, merges nothing and explores
    /// alone whatever the coordination), all of them otherwise.
    fn effective(&self) -> Option<(u64, Coordination, Algorithm)> {
        (self.robots > 1).then_some((self.range.to_bits(), self.coordination, self.merger))
    }
}

/// What a team study varies, as asked; `None` keeps the scenario's own value.
#[derive(Debug, Clone, Default)]
pub struct TeamAxes {
    /// Robot counts (the first N of the scenario's robots); default: all of them.
    pub robots: Option<Vec<usize>>,
    /// Communication ranges, metres; default: the scenario's `team.range`.
    pub ranges: Option<Vec<f64>>,
    /// Coordinations; default: the scenario's.
    pub coordinations: Option<Vec<Coordination>>,
    /// Online mergers; default: the scenario's `team.merger`.
    pub mergers: Option<Vec<Algorithm>>,
    /// Seeds: every configuration runs once per seed (the scenario's seed replaced).
    pub seeds: Vec<u64>,
    /// Simulated duration, seconds, instead of the scenario's.
    pub duration: Option<f64>,
}

/// A team study resolved and checked against its scenario.
#[derive(Debug, Clone)]
pub struct TeamStudy {
    /// The scenario, its duration replaced when asked.
    pub scenario: Scenario,
    /// Robot counts.
    pub robots: Vec<usize>,
    /// Communication ranges, metres.
    pub ranges: Vec<f64>,
    /// Coordinations.
    pub coordinations: Vec<Coordination>,
    /// Online mergers.
    pub mergers: Vec<Algorithm>,
    /// Seeds.
    pub seeds: Vec<u64>,
}

/// Refuses an empty list or a value given twice; `flag` names the list.
fn distinct<T: PartialEq + std::fmt::Display>(values: &[T], flag: &str) -> Result<(), StudyError> {
    if values.is_empty() {
        return Err(StudyError::Invalid(format!("{flag}: give at least one value")));
    }
    match values.iter().enumerate().find(|(i, v)| values[..*i].contains(v)) {
        Some((_, v)) => Err(StudyError::Invalid(format!("{flag}: {v} given twice"))),
        None => Ok(()),
    }
}

impl TeamStudy {
    /// Checks `axes` against `scenario` (which must have a `[team]` table): every robot count between 1 and the
    /// scenario's robots, ranges finite and at least 0, a positive duration, no list empty or with a value twice.
    pub fn new(mut scenario: Scenario, axes: TeamAxes) -> Result<TeamStudy, StudyError> {
        let bad = |m: String| Err(StudyError::Invalid(m));
        let name = format!("scenario `{}` ({})", scenario.name, scenario.path.display());
        let Some(team) = &scenario.team else {
            return bad(format!(
                "{name} has no [team] table: a team study varies a team's settings (see scenarios/team_two_rooms.toml)"
            ));
        };
        let have = scenario.robots.len();
        let robots = axes.robots.unwrap_or_else(|| vec![have]);
        distinct(&robots, "--robots")?;
        if let Some(&n) = robots.iter().find(|&&n| n == 0 || n > have) {
            let names: Vec<&str> = scenario.robots.iter().map(|r| r.name.as_str()).collect();
            return bad(format!(
                "--robots {n}: {name} has {have} robot{} ({}); a trial takes the first N, 1 <= N <= {have}",
                if have == 1 { "" } else { "s" },
                names.join(", ")
            ));
        }
        let ranges = axes.ranges.unwrap_or_else(|| vec![team.range]);
        distinct(&ranges, "--range")?;
        if let Some(r) = ranges.iter().find(|r| !(r.is_finite() && **r >= 0.0 && **r <= MAX_RANGE)) {
            return bad(format!("--range {r:e}: a range must be a number of metres from 0 to {MAX_RANGE:e}"));
        }
        let coordinations = axes.coordinations.unwrap_or_else(|| vec![team.coordination]);
        distinct(&coordinations, "--coordination")?;
        let mergers = axes.mergers.unwrap_or_else(|| vec![team.merger]);
        distinct(&mergers, "--merger")?;
        distinct(&axes.seeds, "--seeds")?;
        if let Some(d) = axes.duration {
            let most = mrslam_testbed::scenario::MAX_DURATION;
            if !(d > 0.0 && d <= most) {
                return bad(format!("--duration {d:e}: must be a positive number of seconds, at most {most:e}"));
            }
            scenario.duration = d;
        }
        Ok(TeamStudy { scenario, robots, ranges, coordinations, mergers, seeds: axes.seeds })
    }

    /// The configurations, in trial order.
    pub fn configs(&self) -> Vec<Config> {
        let mut out = Vec::new();
        for &robots in &self.robots {
            for &range in &self.ranges {
                for &coordination in &self.coordinations {
                    for &merger in &self.mergers {
                        out.push(Config { robots, range, coordination, merger });
                    }
                }
            }
        }
        out
    }

    /// Number of trials: configurations × seeds.
    pub fn trials(&self) -> usize {
        self.robots.len() * self.ranges.len() * self.coordinations.len() * self.mergers.len() * self.seeds.len()
    }

    /// Trial `trial`'s configuration and seed.
    pub fn trial(&self, trial: usize) -> (Config, u64) {
        let n = self.seeds.len();
        (self.configs()[trial / n], self.seeds[trial % n])
    }

    /// What trial `trial` runs, e.g. `N=2, range 6 m, frontiers, cascade, seed 3`.
    pub fn describe(&self, trial: usize) -> String {
        let (c, seed) = self.trial(trial);
        format!("{}, seed {seed}", c.describe())
    }

    /// The first trial whose run trial `trial`'s run is (itself, unless it has one robot and an earlier
    /// configuration with one robot has its seed: the team settings do not change a lone robot's run).
    pub fn run_of(&self, trial: usize) -> usize {
        let n = self.seeds.len();
        let configs = self.configs();
        let key = |t: usize| (configs[t / n].robots, configs[t / n].effective(), t % n);
        (0..=trial).find(|&t| key(t) == key(trial)).unwrap_or(trial)
    }

    /// The scenario of trial `trial`: the first N robots, the seed, the configuration's team settings. When the
    /// merge host is not among the N robots, the first robot hosts (the host only names the frame of the merge
    /// after driving, which a team trial does not run).
    pub fn scenario_of(&self, trial: usize) -> Scenario {
        let (c, seed) = self.trial(trial);
        let mut s = self.scenario.clone();
        s.seed = seed;
        s.robots.truncate(c.robots);
        if !s.robots.iter().any(|r| r.name == s.merge.host) {
            s.merge.host = s.robots[0].name.clone();
        }
        if let Some(team) = s.team.as_mut() {
            team.range = c.range;
            team.coordination = c.coordination;
            team.merger = c.merger;
        }
        s
    }

    /// The coverage sampling period of the study's runs, seconds: the spacing of its coverage curves.
    pub fn coverage_step(&self) -> f64 {
        self.scenario.team.as_ref().map_or(2.0, |t| t.coverage_period)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn two_rooms() -> Scenario {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/team_two_rooms.toml");
        Scenario::from_file(&path).unwrap()
    }

    fn axes(robots: &[usize], coordinations: &[Coordination], seeds: &[u64]) -> TeamAxes {
        TeamAxes {
            robots: Some(robots.to_vec()),
            coordinations: Some(coordinations.to_vec()),
            seeds: seeds.to_vec(),
            ..TeamAxes::default()
        }
    }

    #[test]
    fn trials_are_configuration_major_and_lone_robots_share_their_runs() {
        let s = TeamStudy::new(two_rooms(), axes(&[1, 2], &Coordination::ALL, &[7, 8])).unwrap();
        assert_eq!(s.trials(), 8);
        assert_eq!(s.configs().len(), 4);
        assert_eq!(s.describe(0), "N=1, range 6 m, none, cascade, seed 7");
        assert_eq!(s.describe(3), "N=1, range 6 m, frontiers, cascade, seed 8");
        assert_eq!(s.describe(7), "N=2, range 6 m, frontiers, cascade, seed 8");
        // One robot: the coordination changes nothing, so trials 2 and 3 are the runs of trials 0 and 1.
        let runs: Vec<usize> = (0..8).map(|t| s.run_of(t)).collect();
        assert_eq!(runs, [0, 1, 0, 1, 4, 5, 6, 7]);
        let sc = s.scenario_of(5);
        assert_eq!((sc.seed, sc.robots.len()), (8, 2));
        assert_eq!(sc.team.as_ref().unwrap().coordination, Coordination::None);
        let lone = s.scenario_of(3);
        assert_eq!(
            (lone.robots.len(), lone.robots[0].name.as_str(), lone.merge.host.as_str()),
            (1, "experia", "experia")
        );
    }

    #[test]
    fn the_host_follows_the_robots_kept_and_the_duration_is_replaced() {
        let mut sc = two_rooms();
        sc.merge.host = "prawn".into();
        let s = TeamStudy::new(sc, TeamAxes { duration: Some(20.0), ..axes(&[1, 2], &[Coordination::None], &[1]) })
            .unwrap();
        assert_eq!(s.scenario.duration, 20.0);
        assert_eq!(s.scenario_of(0).merge.host, "experia");
        assert_eq!(s.scenario_of(1).merge.host, "prawn");
    }

    #[test]
    fn bad_axes_are_refused_naming_the_flag() {
        let e = |a: TeamAxes| TeamStudy::new(two_rooms(), a).unwrap_err().to_string();
        let msg = e(axes(&[1, 3], &[Coordination::None], &[1]));
        assert!(
            msg.starts_with("--robots 3: scenario `team_two_rooms` (") && msg.contains("has 2 robots (experia, prawn)")
        );
        assert!(e(axes(&[0], &[Coordination::None], &[1])).starts_with("--robots 0:"));
        assert_eq!(e(axes(&[1], &[Coordination::None], &[])), "--seeds: give at least one value");
        assert_eq!(e(axes(&[1], &[Coordination::None, Coordination::None], &[1])), "--coordination: none given twice");
        let bad_range = TeamAxes { ranges: Some(vec![f64::NAN]), ..axes(&[1], &[Coordination::None], &[1]) };
        assert!(e(bad_range).starts_with("--range NaN:"));
        let bad_duration = TeamAxes { duration: Some(0.0), ..axes(&[1], &[Coordination::None], &[1]) };
        assert_eq!(e(bad_duration), "--duration 0e0: must be a positive number of seconds, at most 1e6");
        let far_range = TeamAxes { ranges: Some(vec![1e300]), ..axes(&[1], &[Coordination::None], &[1]) };
        assert_eq!(e(far_range), "--range 1e300: a range must be a number of metres from 0 to 1e6");
        let long = TeamAxes { duration: Some(1e300), ..axes(&[1], &[Coordination::None], &[1]) };
        assert_eq!(e(long), "--duration 1e300: must be a positive number of seconds, at most 1e6");
        let mut no_team = two_rooms();
        no_team.team = None;
        let msg = TeamStudy::new(no_team, axes(&[1], &[Coordination::None], &[1])).unwrap_err().to_string();
        assert!(msg.contains("has no [team] table"), "{msg}");
    }
}
