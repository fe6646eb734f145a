//! Scenario files: the world, the robots, their routes and sensors, SLAM and merge settings, success criteria.
//!
//! A scenario is TOML (see `scenarios/paper_corridor.toml`); paths inside it are relative to the file.
//! Every error names the file, the line and the field at fault. The file's tables (`file`) are resolved into
//! robots (`robot`) and merge settings (`merge`); `error` places each error in the file.

mod error;
mod file;
mod merge;
mod robot;
mod team;

pub use error::{ScenarioError, at};
pub use merge::{MergeSetup, MergeWhen};
pub use robot::{ControllerKind, RobotSetup};
pub use team::{Coordination, TeamSetup};

use error::Ctx;
use file::ScenarioFile;
use mrslam_core::toml_lines::{TomlLines, line_at};
use mrslam_sim::{World, WorldSpec};
use std::path::{Path, PathBuf};

/// The longest simulated time a scenario may ask for, seconds (11.6 days).
pub const MAX_DURATION: f64 = 1e6;

/// The shortest physics step, seconds: a shorter one only makes a run take forever.
pub const MIN_DT: f64 = 1e-4;

/// A merge counts as a success when accepted and within these errors of the truth.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Success {
    /// Largest rotation error, degrees.
    pub rotation_deg: f64,
    /// Largest translation error, metres.
    pub translation_m: f64,
}

/// A resolved scenario, ready to run.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Name (default: the file stem).
    pub name: String,
    /// The file's `description`: free text for people choosing a scenario; the run does not use it.
    pub description: Option<String>,
    /// The scenario file.
    pub path: PathBuf,
    /// The world file.
    pub world_path: PathBuf,
    /// The world.
    pub world: WorldSpec,
    /// Seed of every random draw.
    pub seed: u64,
    /// Longest simulated time, seconds.
    pub duration: f64,
    /// Physics step, seconds.
    pub dt: f64,
    /// Resolution of the ground-truth map, metres.
    pub truth_resolution: f64,
    /// The robots.
    pub robots: Vec<RobotSetup>,
    /// Merge settings.
    pub merge: MergeSetup,
    /// Success thresholds.
    pub success: Success,
    /// The `[team]` table: robots merge their maps while they drive and may explore together; `None` merges
    /// once, after driving, as the paper does.
    pub team: Option<TeamSetup>,
}

impl Scenario {
    /// Reads and resolves a scenario file (and the world it names).
    pub fn from_file(path: &Path) -> Result<Scenario, ScenarioError> {
        let text = mrslam_core::input::read_text_limited(path, mrslam_core::input::CONFIG_LIMIT).map_err(|e| {
            ScenarioError { path: path.to_path_buf(), line: 0, field: "file".into(), message: e.to_string() }
        })?;
        Self::parse(&text, path)
    }

    /// Resolves a scenario from its text; `path` names it in errors and anchors relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Scenario, ScenarioError> {
        let cx = Ctx { path, lines: TomlLines::new(text) };
        let file: ScenarioFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| line_at(text, s.start));
            ScenarioError { path: path.to_path_buf(), line, field: "toml".into(), message: e.message().to_string() }
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let world_path = dir.join(&file.world);
        let world = WorldSpec::from_toml_file(&world_path)
            .map_err(|e| cx.err("world", format!("cannot load world `{}`: {e}", file.world)))?;
        let built = World::from_spec(&world).map_err(|e| cx.err("world", e.to_string()))?;
        if !(file.duration > 0.0 && file.duration <= MAX_DURATION) {
            return Err(cx.err("duration", format!("must lie in (0, {MAX_DURATION:e}] s, got {:e}", file.duration)));
        }
        let dt = file.dt.unwrap_or(0.01);
        if !(MIN_DT..=0.1).contains(&dt) {
            return Err(cx.err("dt", format!("must lie in [{MIN_DT}, 0.1] s, got {dt:e}")));
        }
        let truth_resolution = file.truth_resolution.unwrap_or(0.05);
        let (lo, hi) = (mrslam_core::map_io::MIN_RESOLUTION, mrslam_core::map_io::MAX_RESOLUTION);
        if !(lo..=hi).contains(&truth_resolution) {
            return Err(
                cx.err("truth_resolution", format!("must be between {lo} and {hi} m, got {truth_resolution:e}"))
            );
        }
        // A run merges two maps, so it needs two robots at least; a team may be one robot (a study's baseline).
        let team = file.team.as_ref().map(|t| team::resolve_team(&cx, t)).transpose()?;
        let fewest = if team.is_some() { 1 } else { 2 };
        if file.robots.len() < fewest {
            return Err(cx.err(
                "robots",
                match team {
                    None => format!("need at least two robots (a merge takes two maps), found {}", file.robots.len()),
                    Some(_) => "a team needs at least one robot, found none".to_string(),
                },
            ));
        }
        let robots = file
            .robots
            .iter()
            .enumerate()
            .map(|(i, r)| robot::resolve_robot(&cx, i, r, &world, &built))
            .collect::<Result<Vec<_>, _>>()?;
        for (i, b) in robots.iter().enumerate() {
            if let Some(j) = robots[..i].iter().position(|a| a.name == b.name) {
                return Err(cx.err(
                    format!("robots[{i}].name"),
                    format!("robots[{j}] and robots[{i}] are both named `{}`", b.name),
                ));
            }
        }
        for (i, b) in robots.iter().enumerate() {
            for a in &robots[..i] {
                let apart = (a.start.translation.vector - b.start.translation.vector).norm();
                let need = a.model.footprint.bounding_radius() + b.model.footprint.bounding_radius();
                if apart < need {
                    return Err(cx.err(
                        format!("robots[{i}].start"),
                        format!(
                            "robot `{}` would start {apart:.2} m from robot `{}`, so their bodies overlap; starts \
                             must lie at least {need:.2} m apart",
                            b.name, a.name
                        ),
                    ));
                }
            }
        }
        let merge = merge::resolve_merge(&cx, &file.merge, &robots, file.duration)?;
        let success = Success {
            rotation_deg: file.success.rotation_deg.unwrap_or(2.0),
            translation_m: file.success.translation_m.unwrap_or(0.3),
        };
        let name = file
            .name
            .clone()
            .unwrap_or_else(|| path.file_stem().map_or("scenario".into(), |s| s.to_string_lossy().into_owned()));
        Ok(Scenario {
            name,
            description: file.description.clone(),
            path: path.to_path_buf(),
            world_path,
            world,
            seed: file.seed,
            duration: file.duration,
            dt,
            truth_resolution,
            robots,
            merge,
            success,
            team,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_merge::Algorithm;
    use mrslam_slam::SlamParams;

    /// `paper_two_rooms.toml` with `edit` applied to its text, resolved as if it lay beside the original.
    fn two_rooms(mut edit: impl FnMut(String) -> String) -> Result<Scenario, ScenarioError> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper_two_rooms.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        Scenario::parse(&edit(text), &path)
    }

    #[test]
    fn algorithms_are_read_by_name_and_default_to_sift() {
        let s = two_rooms(|t| t).unwrap();
        assert_eq!(s.merge.algorithms, [Algorithm::Sift, Algorithm::Rmap]);
        let s = two_rooms(|t| t.replace("algorithms = [\"sift\", \"rmap\"]\n", "")).unwrap();
        assert_eq!(s.merge.algorithms, [Algorithm::Sift]);
        let e = two_rooms(|t| t.replace("[\"sift\", \"rmap\"]", "[\"sift\", \"magic\"]")).unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (12, "merge.algorithms"));
        assert_eq!(e.message, "unknown algorithm `magic` (expected one of sift, rmap, correlative, cascade)");
    }

    #[test]
    fn sift_doubles_the_map_images_unless_the_merge_table_says_upscale_false() {
        use crate::runner::merger_for;
        let s = two_rooms(|t| t).unwrap();
        assert!(s.merge.upscale && merger_for(Algorithm::Cascade, &s).sift().sift.upscale);
        let s = two_rooms(|t| t.replace("wall_dilation = 1\n", "wall_dilation = 1\nupscale = false\n")).unwrap();
        assert!(!s.merge.upscale && !merger_for(Algorithm::Cascade, &s).sift().sift.upscale);
        let e = two_rooms(|t| t.replace("wall_dilation = 1\n", "wall_dilation = 1\nupscale = \"no\"\n")).unwrap_err();
        assert_eq!(e.line, 18, "{e}");
        assert!(e.message.contains("expected a boolean"), "{e}");
    }

    #[test]
    fn the_description_is_kept_and_may_be_left_out() {
        let s = two_rooms(|t| t).unwrap();
        assert_eq!(s.description.as_deref(), Some("two heterogeneous robots map two rooms and merge by the door"));
        let s = two_rooms(|t| t.lines().filter(|l| !l.starts_with("description")).collect::<Vec<_>>().join("\n"));
        assert_eq!(s.unwrap().description, None);
    }

    /// The 1-based line of the last line of `text` holding `needle` (for the tests' expectations only).
    fn line_holding(text: &str, needle: &str) -> usize {
        text.lines().enumerate().filter(|(_, l)| l.contains(needle)).last().unwrap().0 + 1
    }

    /// `paper_two_rooms.toml` with `from` replaced by `to` in the second robot's table: the error, and the
    /// line `to` is on.
    fn second_robot(from: &str, to: &str) -> (ScenarioError, usize) {
        let mut text = String::new();
        let e = two_rooms(|t| {
            let (head, second) = t.split_at(t.rfind("[[robots]]").unwrap());
            text = format!("{head}{}", second.replacen(from, to, 1));
            text.clone()
        })
        .unwrap_err();
        let line = line_holding(&text, to);
        (e, line)
    }

    #[test]
    fn errors_name_the_line_of_the_offending_value() {
        // The second robot's speed, not the first's `speed =` line.
        let (e, line) = second_robot("speed = 0.3", "speed = -0.4");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].speed", line), "{e}");
        assert!(line > 30, "{line}");
        // A waypoint outside the world: its robot's route line, not a comment that says "route".
        let (e, line) = second_robot("[9.4, 2.0]", "[94.0, 2.0]");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].route[2]", line), "{e}");
        // A duplicate name: the second `name =` line, not the merge host's.
        let (e, line) = second_robot("name = \"prawn\"", "name = \"experia\"");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].name", line), "{e}");
        assert_eq!(e.message, "robots[0] and robots[1] are both named `experia`", "{e}");
        // A file that cannot be read names no line 0.
        let e = Scenario::from_file(Path::new("/nonexistent/s.toml")).unwrap_err();
        assert!(e.to_string().starts_with("/nonexistent/s.toml: file: "), "{e}");
    }

    #[test]
    fn a_pose_or_a_point_may_be_a_table_as_world_files_write_them() {
        let named = two_rooms(|t| t).unwrap();
        let s = two_rooms(|t| {
            t.replacen("start = \"start_prawn\"", "start = { x = 9.0, y = 2.2, theta = 3.14159265 }", 1).replacen(
                "[9.4, 2.0]",
                "{ x = 9.4, y = 2.0 }",
                1,
            )
        })
        .unwrap();
        assert_eq!(s.robots[1].start, named.robots[1].start);
        assert_eq!(s.robots[1].route, named.robots[1].route);
        // Anything else is refused saying what a pose may be.
        let (e, line) = second_robot("start = \"start_prawn\"", "start = { x = 9.0, north = 2.2 }");
        assert_eq!(e.line, line, "{e}");
        assert!(
            e.message.contains("a named point of the world, [x, y, theta] or { x = .., y = .., theta = .. }"),
            "{e}"
        );
    }

    #[test]
    fn starts_outside_the_world_or_on_the_other_robot_are_refused() {
        let (e, line) = second_robot("start = \"start_prawn\"", "start = [-20.0, 2.5, 0.0]");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].start", line), "{e}");
        assert!(e.message.contains("(-20.00, 2.50), outside the world"), "{e}");
        let (e, line) = second_robot("start = \"start_prawn\"", "start = \"start_experia\"");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].start", line), "{e}");
        assert!(e.message.contains("robot `prawn` would start 0.00 m from robot `experia`"), "{e}");
        let shown = e.to_string();
        assert!(shown.contains(&format!("paper_two_rooms.toml:{line}: robots[1].start: ")), "{shown}");
    }

    #[test]
    fn a_robots_slam_table_picks_a_preset_sets_parameters_by_name_and_the_lidar_caps_the_range() {
        // Without a table: the preset that matches the lidar's reach (Hokuyo 4 m, RpLidar 6 m, SICK 80 m).
        let s = two_rooms(|t| t).unwrap();
        assert_eq!(s.robots[0].slam, {
            let mut p = SlamParams::hokuyo();
            p.map.max_range = p.map.max_range.min(s.robots[0].lidar.range_max);
            p.map.max_urange = p.map.max_urange.min(s.robots[0].lidar.range_max);
            p
        });
        assert!(!s.robots[1].slam.scan_odometry.enabled);
        // A SICK-class 80 m lidar: `slam`'s default for real logs, whose robots carry such lidars.
        let s = two_rooms(|t| t.replace("lidar = \"rplidar_a1\"", "lidar = \"sick_lms\"")).unwrap();
        assert_eq!(s.robots[1].lidar.range_max, 80.0);
        assert!(s.robots[1].slam.scan_odometry.enabled, "the matched preset");
        // A preset and parameters by name; the 80 m preset is capped at the robot's lidar.
        let table =
            "slam = { preset = \"matched\", particles = 12, scan_odometry_reach = 2, linear_update = \"0.4\" }\n";
        let s = two_rooms(|t| {
            let (head, second) = t.split_at(t.rfind("[[robots]]").unwrap());
            format!("{head}{}", second.replacen("[[robots]]\n", &format!("[[robots]]\n{table}"), 1))
        })
        .unwrap();
        let (slam, range) = (&s.robots[1].slam, s.robots[1].lidar.range_max);
        assert!(slam.scan_odometry.enabled, "the matched preset");
        assert_eq!((slam.filter.particles, slam.scan_odometry.reach, slam.filter.linear_update), (12, 2, 0.4));
        assert!(
            slam.map.max_range <= range && slam.map.max_urange <= range,
            "{} {} > {range}",
            slam.map.max_range,
            slam.map.max_urange
        );
        // An unknown parameter or a bad value names the robot's table, the parameter and its line.
        let refused = |table: &str| {
            let mut text = String::new();
            let e = two_rooms(|t| {
                let (head, second) = t.split_at(t.rfind("[[robots]]").unwrap());
                text = format!("{head}{}", second.replacen("[[robots]]\n", &format!("[[robots]]\n{table}\n"), 1));
                text.clone()
            })
            .unwrap_err();
            (e, line_holding(&text, table))
        };
        let (e, line) = refused("slam = { particels = 12 }");
        assert_eq!((e.field.as_str(), e.line), ("robots[1].slam.particels", line), "{e}");
        let (e, _) = refused("slam = { particles = [1, 2] }");
        assert_eq!(e.field, "robots[1].slam.particles", "{e}");
        assert!(e.message.contains("expected a number"), "{e}");
        let (e, _) = refused("slam = { preset = \"fastslam\" }");
        assert!(e.field.starts_with("robots[1].slam"), "{e}");
    }

    /// `paper_two_rooms.toml` with a copy of its last robot's table appended, `edit` applied to the copy.
    fn with_third_robot(edit: impl Fn(&str) -> String) -> (Result<Scenario, ScenarioError>, String) {
        let mut text = String::new();
        let s = two_rooms(|t| {
            let third = edit(&t[t.rfind("[[robots]]").unwrap()..]);
            text = format!("{t}\n{third}");
            text.clone()
        });
        (s, text)
    }

    #[test]
    fn a_scenario_takes_two_robots_or_more_of_distinct_names_and_starts() {
        let (s, _) = with_third_robot(|r| {
            r.replacen("name = \"prawn\"", "name = \"scout\"", 1).replacen(
                "start = \"start_prawn\"",
                "start = [7.0, 3.3, 0.0]",
                1,
            )
        });
        let names: Vec<String> = s.unwrap().robots.iter().map(|r| r.name.clone()).collect();
        assert_eq!(names, ["experia", "prawn", "scout"]);
        // The third robot is named like the second.
        let (e, text) = with_third_robot(|r| r.replacen("start = \"start_prawn\"", "start = [7.0, 3.3, 0.0]", 1));
        let e = e.unwrap_err();
        assert_eq!((e.field.as_str(), e.line), ("robots[2].name", line_holding(&text, "name = \"prawn\"")), "{e}");
        assert_eq!(e.message, "robots[1] and robots[2] are both named `prawn`");
        // The third robot starts on the second.
        let (e, _) = with_third_robot(|r| r.replacen("name = \"prawn\"", "name = \"scout\"", 1));
        let e = e.unwrap_err();
        assert_eq!(e.field, "robots[2].start", "{e}");
        assert!(e.message.contains("robot `scout` would start 0.00 m from robot `prawn`"), "{e}");
        // One robot has nothing to merge with.
        let e = two_rooms(|t| t[..t.rfind("[[robots]]").unwrap()].to_string()).unwrap_err();
        assert_eq!(e.field, "robots", "{e}");
        assert_eq!(e.message, "need at least two robots (a merge takes two maps), found 1");
    }

    #[test]
    fn absurd_times_coordinates_and_names_are_refused_naming_the_line() {
        let refused = |from: &str, to: &str, field: &str, needle: &str| {
            let text = std::cell::RefCell::new(String::new());
            let e = two_rooms(|t| {
                *text.borrow_mut() = t.replacen(from, to, 1);
                text.borrow().clone()
            })
            .unwrap_err();
            let last = to.lines().last().unwrap_or(to);
            assert_eq!((e.field.as_str(), e.line), (field, line_holding(&text.borrow(), last)), "{e}");
            assert!(e.message.contains(needle), "{e}");
            assert!(e.to_string().len() < 300, "{e}");
        };
        refused("duration = 180.0", "duration = 180.0\ndt = 1e-300", "dt", "must lie in [0.0001, 0.1] s");
        refused("duration = 180.0", "duration = 1e300", "duration", "must lie in (0, 1e6] s");
        let start = "start = \"start_prawn\"";
        refused(start, "start = { x = 1e300, y = 2.2, theta = 0.0 }", "robots[1].start", "within 1e7 m of 0");
        refused(start, "start = [1.0, 2.2, inf]", "robots[1].start", "finite number");
        refused("[9.4, 2.0]", "[1e300, 2.0]", "robots[1].route[2]", "within 1e7 m of 0");
        for name in ["truth", "merged_sift", "overlay_rmap", "", "../up", ".hidden"] {
            refused("name = \"prawn\"", &format!("name = \"{name}\""), "robots[1].name", name);
        }
    }

    #[test]
    fn an_idle_robot_needs_no_route() {
        let (s, _) = with_third_robot(|r| {
            let r = r.replacen("name = \"prawn\"", "name = \"watch\"", 1).replacen(
                "start = \"start_prawn\"",
                "start = [7.0, 3.3, 0.0]",
                1,
            );
            let route = r.lines().find(|l| l.starts_with("route")).unwrap().to_string();
            r.replacen(&route, "controller = \"idle\"", 1)
        });
        let s = s.unwrap();
        assert_eq!((s.robots[2].controller, s.robots[2].route.len()), (ControllerKind::Idle, 0));
        let (e, _) = with_third_robot(|r| r.replacen("[[robots]]\n", "[[robots]]\ncontroller = \"drift\"\n", 1));
        let e = e.unwrap_err();
        assert_eq!(e.field, "robots[2].controller", "{e}");
        assert_eq!(e.message, "unknown controller `drift` (expected waypoints, explore or idle)");
    }
}
