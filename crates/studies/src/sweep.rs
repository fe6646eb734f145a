//! Simulation-level studies: a sweep file varies a scenario; every variant runs simulation, SLAM and merge.
//!
//! ```toml
//! scenario = "paper_corridor.toml"     # relative to the sweep file
//! algorithms = ["sift", "rmap"]        # default: the scenario's
//! seeds = [1, 2, 3]                    # every variant runs once per seed
//!
//! [[vary]]                             # all [[vary]] lists step together (equal lengths):
//! robot = "experia"                    # variant i sets each field to its i-th value
//! field = "route_end_x"                # route_end_x, route_end_y (the last waypoint), or speed
//! values = [24.2, 28.0, 32.0]
//! ```
//!
//! Trials: variant-major, `trial = variant * seeds.len() + seed index`. A trial's overlap is the run's
//! observed overlap (Jaccard of the true cells each robot's beams crossed), not an assumed one.

use super::algorithms::parse_algorithms;
use super::results::{TrialRow, sort_rows};
use super::shard::Shard;
use super::{Progress, StudyError};
use mrslam_core::pose;
use mrslam_core::toml_lines::TomlLines;
use mrslam_merge::Algorithm;
use mrslam_sim::World;
use mrslam_testbed::runner::{RunOptions, run};
use mrslam_testbed::scenario::{ControllerKind, Scenario};
use rayon::prelude::*;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    scenario: String,
    algorithms: Option<Vec<String>>,
    seeds: Vec<u64>,
    #[serde(default)]
    vary: Vec<VaryFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VaryFile {
    robot: String,
    field: String,
    values: Vec<f64>,
}

/// A parameter a sweep may vary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// x of the robot's last waypoint, metres.
    RouteEndX,
    /// y of the robot's last waypoint, metres.
    RouteEndY,
    /// Cruise speed, m/s.
    Speed,
}

/// Field names a sweep accepts.
pub const FIELDS: &[&str] = &["route_end_x", "route_end_y", "speed"];

/// One varied parameter.
#[derive(Debug, Clone)]
pub struct Vary {
    /// Index of the robot in the scenario.
    pub robot: usize,
    /// The field.
    pub field: Field,
    /// Its value in each variant.
    pub values: Vec<f64>,
}

/// A resolved sweep.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The sweep file.
    pub path: PathBuf,
    /// The base scenario.
    pub scenario: Scenario,
    /// Algorithms, in row order.
    pub algorithms: Vec<Algorithm>,
    /// Seeds each variant runs with.
    pub seeds: Vec<u64>,
    /// The varied parameters (stepping together).
    pub vary: Vec<Vary>,
}

impl Sweep {
    /// Reads and checks a sweep file (and the scenario it names); errors name the file, line and field.
    pub fn from_file(path: &Path) -> Result<Sweep, StudyError> {
        let text = mrslam_core::input::read_text_limited(path, mrslam_core::input::CONFIG_LIMIT)
            .map_err(|e| StudyError::file(path, e))?;
        Self::parse(&text, path)
    }

    /// Checks a sweep from its text; `path` names it in errors and anchors the scenario's path.
    pub fn parse(text: &str, path: &Path) -> Result<Sweep, StudyError> {
        let at = |line: usize, message: String| StudyError::Results { path: path.to_path_buf(), line, message };
        let file: SweepFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| mrslam_core::toml_lines::line_at(text, s.start));
            at(line, e.message().to_string())
        })?;
        let lines = TomlLines::new(text);
        let line_of = |field: &str| lines.line(field);
        let dir = path.parent().unwrap_or(Path::new("."));
        let scenario = Scenario::from_file(&dir.join(&file.scenario))
            .map_err(|e| at(line_of("scenario"), format!("scenario: {e}")))?;
        let algorithms = match &file.algorithms {
            Some(names) => parse_algorithms(names),
            None => super::check_algorithms(&scenario.merge.algorithms).map(|()| scenario.merge.algorithms.clone()),
        }
        .map_err(|e| at(line_of("algorithms"), format!("algorithms: {e}")))?;
        if file.seeds.is_empty() {
            return Err(at(line_of("seeds"), "seeds: give at least one seed".into()));
        }
        if let Some(k) = (1..file.seeds.len()).find(|&k| file.seeds[..k].contains(&file.seeds[k])) {
            // The same seed twice runs the same trial twice: its results would count twice in the summary.
            return Err(at(line_of("seeds"), format!("seeds[{k}] = {}: given twice", file.seeds[k])));
        }
        let mut vary = Vec::new();
        for (i, v) in file.vary.iter().enumerate() {
            let f = |name: &str| format!("vary[{i}].{name}");
            let robot = scenario.robots.iter().position(|r| r.name == v.robot).ok_or_else(|| {
                let names: Vec<&str> = scenario.robots.iter().map(|r| r.name.as_str()).collect();
                at(
                    line_of(&f("robot")),
                    format!("{}: no robot `{}` in the scenario (robots: {})", f("robot"), v.robot, names.join(", ")),
                )
            })?;
            let field = match v.field.as_str() {
                "route_end_x" => Field::RouteEndX,
                "route_end_y" => Field::RouteEndY,
                "speed" => Field::Speed,
                other => {
                    return Err(at(
                        line_of(&f("field")),
                        format!("{}: unknown field `{other}` (expected one of {})", f("field"), FIELDS.join(", ")),
                    ));
                }
            };
            if v.values.is_empty() {
                return Err(at(line_of(&f("values")), format!("{}: give at least one value", f("values"))));
            }
            let bound = mrslam_sim::MAX_WORLD_COORDINATE;
            if let Some(k) = v.values.iter().position(|x| !(x.is_finite() && x.abs() <= bound)) {
                let field = format!("{}[{k}]", f("values"));
                let message = format!(
                    "{field} = {:e}: must be a finite number within {bound:e} of 0 (metres or m/s)",
                    v.values[k]
                );
                return Err(at(line_of(&field), message));
            }
            // A field the robot's controller does not read would make every variant the same run.
            let controller = scenario.robots[robot].controller;
            if controller == ControllerKind::Idle || (field != Field::Speed && controller != ControllerKind::Waypoints)
            {
                let message = format!(
                    "{}: robot `{}` is driven by its `{}` controller, which does not read `{}`: every variant would be \
                     the same run",
                    f("field"),
                    v.robot,
                    match controller {
                        ControllerKind::Waypoints => "waypoints",
                        ControllerKind::Explore => "explore",
                        ControllerKind::Idle => "idle",
                    },
                    v.field
                );
                return Err(at(line_of(&f("field")), message));
            }
            if field != Field::Speed && scenario.robots[robot].route.is_empty() {
                let message = format!("{}: robot `{}` has no route whose end could move", f("field"), v.robot);
                return Err(at(line_of(&f("field")), message));
            }
            if let Some(first) = file.vary.first()
                && first.values.len() != v.values.len()
            {
                return Err(at(
                    line_of(&f("values")),
                    format!(
                        "{}: {} values, but vary[0] has {}: all [[vary]] lists step together and need equal lengths",
                        f("values"),
                        v.values.len(),
                        first.values.len()
                    ),
                ));
            }
            vary.push(Vary { robot, field, values: v.values.clone() });
        }
        let sweep = Sweep { path: path.to_path_buf(), scenario, algorithms, seeds: file.seeds, vary };
        // Every variant must be drivable: check each waypoint and speed now, not an hour into the study.
        let world = World::from_spec(&sweep.scenario.world).map_err(|e| at(line_of("scenario"), e.to_string()))?;
        for k in 0..sweep.variants() {
            let s = sweep.variant(k, sweep.seeds[0]);
            for (i, v) in sweep.vary.iter().enumerate() {
                let r = &s.robots[v.robot];
                let value = v.values[k];
                let problem = match v.field {
                    Field::Speed => (!(value > 0.0 && value <= r.model.max_speed))
                        .then(|| format!("speed {value} outside (0, {}] m/s", r.model.max_speed)),
                    Field::RouteEndX | Field::RouteEndY => r.route.last().and_then(|p| {
                        let (lo, hi) = world.bounds();
                        if p.x < lo.x || p.y < lo.y || p.x > hi.x || p.y > hi.y {
                            Some(format!("waypoint ({:.2}, {:.2}) lies outside the world", p.x, p.y))
                        } else if world.footprint_collides(&r.model.footprint, &pose(p.x, p.y, 0.0)) {
                            Some(format!("the robot cannot stand at waypoint ({:.2}, {:.2})", p.x, p.y))
                        } else {
                            None
                        }
                    }),
                };
                if let Some(p) = problem {
                    let field = format!("vary[{i}].values[{k}]");
                    return Err(at(line_of(&field), format!("{field} = {value}: {p}")));
                }
            }
        }
        Ok(sweep)
    }

    /// Number of variants (1 when nothing varies).
    pub fn variants(&self) -> usize {
        self.vary.first().map_or(1, |v| v.values.len())
    }

    /// Number of trials: variants × seeds.
    pub fn trials(&self) -> usize {
        self.variants() * self.seeds.len()
    }

    /// What trial `trial` runs, e.g. `seed 7, experia.route_end_x=29, prawn.route_end_x=21`.
    pub fn describe(&self, trial: usize) -> String {
        let n = self.seeds.len();
        let mut s = format!("seed {}", self.seeds[trial % n]);
        for v in &self.vary {
            let field = FIELDS[v.field as usize];
            s.push_str(&format!(", {}.{field}={}", self.scenario.robots[v.robot].name, v.values[trial / n]));
        }
        s
    }

    /// The scenario of variant `k` run with `seed`.
    pub fn variant(&self, k: usize, seed: u64) -> Scenario {
        let mut s = self.scenario.clone();
        s.seed = seed;
        for v in &self.vary {
            let r = &mut s.robots[v.robot];
            let value = v.values[k];
            match v.field {
                Field::RouteEndX => {
                    if let Some(p) = r.route.last_mut() {
                        p.x = value;
                    }
                }
                Field::RouteEndY => {
                    if let Some(p) = r.route.last_mut() {
                        p.y = value;
                    }
                }
                Field::Speed => r.speed = value,
            }
        }
        s
    }
}

/// Runs the sweep's trials of this shard in parallel, calling `progress` after each.
pub fn run_sweep(sweep: &Sweep, shard: Shard, progress: &dyn Progress) -> Result<Vec<TrialRow>, StudyError> {
    let n_seeds = sweep.seeds.len();
    let selected: Vec<usize> = (0..sweep.trials()).filter(|t| shard.selects(*t) && !progress.skip(*t)).collect();
    let rows: Vec<Vec<TrialRow>> = selected
        .par_iter()
        .map(|&trial| {
            let scenario = sweep.variant(trial / n_seeds, sweep.seeds[trial % n_seeds]);
            let r = run_trial(sweep, &scenario, trial)?;
            progress.finished(&r)?;
            Ok(r)
        })
        .collect::<Result<_, _>>()?;
    let mut rows: Vec<TrialRow> = rows.into_iter().flatten().collect();
    sort_rows(&mut rows, &sweep.algorithms);
    Ok(rows)
}

fn run_trial(sweep: &Sweep, scenario: &Scenario, trial: usize) -> Result<Vec<TrialRow>, StudyError> {
    // The runner merges with every algorithm of the sweep, in its order, and scores each against the truth.
    let out = run(scenario, RunOptions { algorithms: Some(sweep.algorithms.clone()), ..RunOptions::default() })
        .map_err(|e| StudyError::Trial { trial, message: format!("seed {}: {e}", scenario.seed) })?;
    let report = &out.report;
    Ok(report
        .merges
        .iter()
        .map(|m| TrialRow {
            trial,
            overlap_target: None,
            overlap: report.observed_overlap,
            seed: scenario.seed,
            algorithm: m.algorithm.clone(),
            accepted: m.accepted,
            success: m.success,
            false_merge: m.accepted && !m.success,
            rotation_error_deg: m.rotation_error_deg,
            translation_error_m: m.translation_error_m,
            time_ms: m.time_ms,
            rotation_error_at_end_deg: m.rotation_error_at_end_deg,
            translation_error_at_end_m: m.translation_error_at_end_m,
            stage: m.stage.clone().unwrap_or_default(),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes `text` as a sweep beside the shipped scenarios and reads it.
    fn sweep_error(text: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        let scenarios = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let text = text.replace("SCENARIO", &scenarios.join("paper_corridor.toml").display().to_string());
        let path = dir.path().join("sweep.toml");
        std::fs::write(&path, text).unwrap();
        Sweep::from_file(&path).unwrap_err().to_string()
    }

    #[test]
    fn sweep_errors_name_the_line_of_the_value() {
        let head = "# robots, values and routes are described below\nscenario = \"SCENARIO\"\nseeds = [1]\n";
        let vary = |robot: &str, values: &str| {
            format!("[[vary]]\nrobot = \"{robot}\"\nfield = \"speed\"\nvalues = {values}\n")
        };
        let e = sweep_error(&format!("{head}{}{}", vary("experia", "[0.3, 0.4]"), vary("prawn", "[0.3]")));
        assert!(e.contains("sweep.toml:11: vary[1].values: 1 values, but vary[0] has 2"), "{e}");
        let e = sweep_error(&format!("{head}{}{}", vary("experia", "[0.3, 0.4]"), vary("prawn", "[0.3, 9.0]")));
        assert!(e.contains("sweep.toml:11: vary[1].values[1] = 9: speed 9 outside"), "{e}");
        let e = sweep_error(&format!("{head}{}{}", vary("experia", "[0.3]"), vary("robbie", "[0.3]")));
        assert!(e.contains("sweep.toml:9: vary[1].robot: no robot `robbie`"), "{e}");
        // A value far past any world is refused, in a line of ordinary length.
        let far = "[[vary]]\nrobot = \"experia\"\nfield = \"route_end_x\"\nvalues = [1e300]\n";
        let e = sweep_error(&format!("{head}{far}"));
        assert!(e.contains("sweep.toml:7: vary[0].values[0] = 1e300: must be a finite number within 1e7"), "{e}");
        assert!(e.len() < 300, "{e}");
        // A seed given twice would count one trial twice.
        let twice = head.replace("seeds = [1]", "seeds = [1, 2, 1]");
        let e = sweep_error(&format!("{twice}{}", vary("experia", "[0.3]")));
        assert!(e.contains("sweep.toml:3: seeds[2] = 1: given twice"), "{e}");
        // A route's end on a robot that explores (it has no route to follow) varies nothing.
        let explorers = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/team_two_rooms.toml");
        let head = head.replace("\"SCENARIO\"", &format!("{:?}", explorers.display().to_string()));
        let robot = Scenario::from_file(&explorers).unwrap().robots[0].name.clone();
        let far = format!("[[vary]]\nrobot = \"{robot}\"\nfield = \"route_end_x\"\nvalues = [3.0]\n");
        let e = sweep_error(&format!("{head}{far}"));
        assert!(e.contains("sweep.toml:6: vary[0].field: robot") && e.contains("`explore` controller"), "{e}");
    }
}
