//! Scenario files: the world, the robots, their routes and sensors, SLAM and merge settings, success criteria.
//!
//! A scenario is TOML (see `scenarios/paper_corridor.toml`); paths inside it are relative to the file.
//! Every error names the file, the line and the field at fault.

use mrslam_core::toml_lines::{TomlLines, line_at};
use mrslam_core::{Pose2, pose};
use mrslam_merge::{Algorithm, Encoding, Model};
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, SlipParams, World, WorldSpec, odometry_fit};
use mrslam_slam::SlamParams;
use nalgebra::Point2;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A scenario error, naming the file, line and field.
#[derive(Debug, thiserror::Error)]
#[error("{}: {field}: {message}", at(path, *line))]
pub struct ScenarioError {
    /// File at fault.
    pub path: PathBuf,
    /// 1-based line (0 when the problem is not tied to one line).
    pub line: usize,
    /// Dotted path of the field, e.g. `robots[1].lidar`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// `file:line`, or the file alone when the problem is not tied to a line.
pub fn at(path: &Path, line: usize) -> String {
    if line == 0 { path.display().to_string() } else { format!("{}:{line}", path.display()) }
}

/// How a robot is driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControllerKind {
    /// Pure pursuit along the scripted route (the paper's robots were driven by hand along such routes).
    Waypoints,
    /// Frontier-based exploration on the robot's own SLAM map.
    Explore,
}

/// When the maps are merged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MergeWhen {
    /// When every robot has finished its route (the paper's common point), or at the duration at the latest.
    Rendezvous,
    /// At the end of the run.
    End,
    /// At this simulated time, seconds; the run ends there.
    At(f64),
}

/// One robot of a scenario, resolved.
#[derive(Debug, Clone)]
pub struct RobotSetup {
    /// Name (also the map's file name and rerun entity).
    pub name: String,
    /// Body and wheels.
    pub model: RobotModel,
    /// Lidar.
    pub lidar: LidarModel,
    /// Wheel slip process.
    pub slip: SlipParams,
    /// Encoders and odometry calibration.
    pub encoder: EncoderParams,
    /// SLAM parameters.
    pub slam: SlamParams,
    /// Start pose in the world (hidden from SLAM and merge; only the evaluator knows it).
    pub start: Pose2,
    /// Waypoints in the world frame.
    pub route: Vec<Point2<f64>>,
    /// Controller.
    pub controller: ControllerKind,
    /// Cruise speed, m/s.
    pub speed: f64,
    /// Look-ahead distance of the waypoint follower, metres (smaller follows corners more tightly).
    pub lookahead: f64,
}

/// Merge settings.
#[derive(Debug, Clone)]
pub struct MergeSetup {
    /// When to merge.
    pub when: MergeWhen,
    /// Algorithms to run on the same maps, in order.
    pub algorithms: Vec<Algorithm>,
    /// Transform model of the SIFT merger.
    pub model: Model,
    /// Lowe's ratio.
    pub ratio: f32,
    /// Map-to-image encoding.
    pub encoding: Encoding,
    /// Descriptor candidates per feature (1: nearest neighbour with the ratio test, as the paper).
    pub candidates: usize,
    /// Transforms handed to verification (1: the paper's single answer).
    pub hypotheses: usize,
    /// Cells by which walls grow before SIFT.
    pub wall_dilation: usize,
    /// Robot that hosts the merge (the paper: Experia); the other's map is merged into its frame.
    pub host: String,
}

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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: Option<String>,
    description: Option<String>,
    world: String,
    seed: u64,
    duration: f64,
    dt: Option<f64>,
    truth_resolution: Option<f64>,
    robots: Vec<RobotFile>,
    #[serde(default)]
    merge: MergeFile,
    #[serde(default)]
    success: SuccessFile,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PoseRef {
    Named(String),
    Xyt([f64; 3]),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PointRef {
    Named(String),
    Xy([f64; 2]),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum LidarRef {
    Preset(String),
    Table(LidarFile),
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LidarFile {
    preset: Option<String>,
    fov_deg: Option<f64>,
    resolution_deg: Option<f64>,
    range_min: Option<f64>,
    range_max: Option<f64>,
    scan_period: Option<f64>,
    range_noise_const: Option<f64>,
    range_noise_prop: Option<f64>,
    angular_jitter_deg: Option<f64>,
    dropout_prob: Option<f64>,
    mount: Option<[f64; 3]>,
    skew: Option<bool>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SlipFile {
    none: Option<bool>,
    speed_noise: Option<f64>,
    turn_noise: Option<f64>,
    noise_correlation_time: Option<f64>,
    event_rate: Option<f64>,
    event_turn_gain: Option<f64>,
    event_duration: Option<f64>,
    event_magnitude: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct EncoderFile {
    ticks_per_rev: Option<u32>,
    left_radius_error: Option<f64>,
    right_radius_error: Option<f64>,
    wheel_base_error: Option<f64>,
}

/// A robot's `slam` table: an optional `preset`, then any parameter of [`SlamParams::set`] by name.
#[derive(Deserialize, Default)]
struct SlamFile {
    preset: Option<String>,
    #[serde(flatten)]
    params: BTreeMap<String, toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    model: String,
    lidar: LidarRef,
    start: PoseRef,
    #[serde(default)]
    route: Vec<PointRef>,
    controller: Option<String>,
    speed: Option<f64>,
    lookahead: Option<f64>,
    odometry: Option<String>,
    #[serde(default)]
    slip: SlipFile,
    #[serde(default)]
    encoder: EncoderFile,
    #[serde(default)]
    slam: SlamFile,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct MergeFile {
    when: Option<toml::Value>,
    algorithms: Option<Vec<String>>,
    model: Option<String>,
    ratio: Option<f32>,
    encoding: Option<String>,
    candidates: Option<usize>,
    hypotheses: Option<usize>,
    wall_dilation: Option<usize>,
    host: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SuccessFile {
    rotation_deg: Option<f64>,
    translation_m: Option<f64>,
}

struct Ctx<'a> {
    path: &'a Path,
    lines: TomlLines<'a>,
}

impl Ctx<'_> {
    /// An error on `field` (a dotted path such as `robots[1].speed`), located at the line where the field is
    /// written, or where its table is when the field was left out.
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> ScenarioError {
        let field = field.into();
        ScenarioError { path: self.path.to_path_buf(), line: self.lines.line(&field), field, message: message.into() }
    }
}

/// Overwrites each destination with its source value when one is given.
fn apply<T: Copy>(pairs: &mut [(&mut T, Option<T>)]) {
    for (dst, src) in pairs.iter_mut() {
        if let Some(v) = *src {
            **dst = v;
        }
    }
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
        if !(file.duration.is_finite() && file.duration > 0.0) {
            return Err(cx.err("duration", format!("must be positive, got {}", file.duration)));
        }
        let dt = file.dt.unwrap_or(0.01);
        if !(dt > 0.0 && dt <= 0.1) {
            return Err(cx.err("dt", format!("must lie in (0, 0.1] s, got {dt}")));
        }
        let truth_resolution = file.truth_resolution.unwrap_or(0.05);
        if !(truth_resolution > 0.0 && truth_resolution.is_finite()) {
            return Err(cx.err("truth_resolution", "must be positive"));
        }
        if file.robots.len() != 2 {
            return Err(cx.err("robots", format!("need two robots, found {}", file.robots.len())));
        }
        let robots = file
            .robots
            .iter()
            .enumerate()
            .map(|(i, r)| resolve_robot(&cx, i, r, &world, &built))
            .collect::<Result<Vec<_>, _>>()?;
        if robots[0].name == robots[1].name {
            return Err(cx.err("robots[1].name", format!("both robots are named `{}`", robots[1].name)));
        }
        let (a, b) = (&robots[0], &robots[1]);
        let apart = (a.start.translation.vector - b.start.translation.vector).norm();
        let need = a.model.footprint.bounding_radius() + b.model.footprint.bounding_radius();
        if apart < need {
            return Err(cx.err(
                "robots[1].start",
                format!(
                    "robot `{}` would start {apart:.2} m from robot `{}`, so their bodies overlap; starts must lie \
                     at least {need:.2} m apart",
                    b.name, a.name
                ),
            ));
        }
        let merge = resolve_merge(&cx, &file.merge, &robots, file.duration)?;
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
        })
    }
}

fn resolve_pose(cx: &Ctx, field: &str, r: &PoseRef, world: &WorldSpec) -> Result<Pose2, ScenarioError> {
    match r {
        PoseRef::Named(n) => {
            world.named_pose(n).ok_or_else(|| cx.err(field, format!("no point named `{n}` in the world")))
        }
        PoseRef::Xyt([x, y, t]) => Ok(pose(*x, *y, *t)),
    }
}

fn resolve_robot(
    cx: &Ctx,
    i: usize,
    r: &RobotFile,
    spec: &WorldSpec,
    world: &World,
) -> Result<RobotSetup, ScenarioError> {
    let f = |name: &str| format!("robots[{i}].{name}");
    let model = RobotModel::preset(&r.model).ok_or_else(|| {
        let names = RobotModel::PRESETS.join(", ");
        cx.err(f("model"), format!("unknown robot model `{}` (expected one of {names})", r.model))
    })?;
    let lidar = resolve_lidar(cx, &f("lidar"), &r.lidar)?;
    // An odometry preset gives the slip and encoder parameters the tables below start from.
    let (base_slip, base_encoder) = match &r.odometry {
        None => (SlipParams::default(), EncoderParams::default()),
        Some(name) => odometry_fit::preset(name).ok_or_else(|| {
            let names = odometry_fit::PRESETS.join(", ");
            cx.err(f("odometry"), format!("unknown odometry preset `{name}` (expected one of {names})"))
        })?,
    };
    let mut slip = if r.slip.none == Some(true) { SlipParams::none() } else { base_slip };
    let s = &r.slip;
    apply(&mut [
        (&mut slip.speed_noise, s.speed_noise),
        (&mut slip.turn_noise, s.turn_noise),
        (&mut slip.noise_correlation_time, s.noise_correlation_time),
        (&mut slip.event_rate, s.event_rate),
        (&mut slip.event_turn_gain, s.event_turn_gain),
        (&mut slip.event_duration, s.event_duration),
        (&mut slip.event_magnitude, s.event_magnitude),
    ]);
    slip.validate().map_err(|e| cx.err(f("slip"), e.to_string()))?;
    let mut encoder = base_encoder;
    let e = &r.encoder;
    apply(&mut [(&mut encoder.ticks_per_rev, e.ticks_per_rev)]);
    apply(&mut [
        (&mut encoder.left_radius_error, e.left_radius_error),
        (&mut encoder.right_radius_error, e.right_radius_error),
        (&mut encoder.wheel_base_error, e.wheel_base_error),
    ]);
    encoder.validate().map_err(|er| cx.err(f("encoder"), er.to_string()))?;
    let slam = resolve_slam(cx, &f("slam"), &r.slam, &lidar)?;
    let start = resolve_pose(cx, &f("start"), &r.start, spec)?;
    let (lo, hi) = world.bounds();
    let outside = |p: &Point2<f64>| !(p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y);
    let bounds = format!("{:.1}..{:.1} x {:.1}..{:.1}", lo.x, hi.x, lo.y, hi.y);
    if outside(&Point2::from(start.translation.vector)) {
        let (x, y) = (start.translation.x, start.translation.y);
        return Err(cx.err(
            f("start"),
            format!("robot `{}` would start at ({x:.2}, {y:.2}), outside the world ({bounds})", r.name),
        ));
    }
    if world.footprint_collides(&model.footprint, &start) {
        let (x, y) = (start.translation.x, start.translation.y);
        return Err(
            cx.err(f("start"), format!("robot `{}` would start inside an obstacle at ({x:.2}, {y:.2})", r.name))
        );
    }
    let mut route = Vec::new();
    for (k, w) in r.route.iter().enumerate() {
        let field = format!("robots[{i}].route[{k}]");
        let p = match w {
            PointRef::Named(n) => {
                let p =
                    spec.named_pose(n).ok_or_else(|| cx.err(&field, format!("no point named `{n}` in the world")))?;
                Point2::new(p.translation.x, p.translation.y)
            }
            PointRef::Xy([x, y]) => Point2::new(*x, *y),
        };
        if outside(&p) {
            return Err(cx.err(&field, format!("waypoint ({:.2}, {:.2}) lies outside the world ({bounds})", p.x, p.y)));
        }
        if world.footprint_collides(&model.footprint, &pose(p.x, p.y, 0.0)) {
            return Err(cx.err(
                &field,
                format!("the robot cannot stand at waypoint ({:.2}, {:.2}): it overlaps an obstacle", p.x, p.y),
            ));
        }
        route.push(p);
    }
    let controller = match r.controller.as_deref().unwrap_or("waypoints") {
        "waypoints" => ControllerKind::Waypoints,
        "explore" => ControllerKind::Explore,
        c => {
            return Err(cx.err(f("controller"), format!("unknown controller `{c}` (expected waypoints or explore)")));
        }
    };
    if controller == ControllerKind::Waypoints && route.is_empty() {
        return Err(cx.err(f("route"), "the waypoint controller needs a route"));
    }
    let speed = r.speed.unwrap_or(0.4);
    if !(speed > 0.0 && speed <= model.max_speed) {
        return Err(cx.err(f("speed"), format!("must lie in (0, {}] m/s for this robot, got {speed}", model.max_speed)));
    }
    let lookahead = r.lookahead.unwrap_or(0.35);
    if !(lookahead > 0.05 && lookahead <= 5.0) {
        return Err(cx.err(f("lookahead"), format!("must lie in (0.05, 5] m, got {lookahead}")));
    }
    Ok(RobotSetup {
        name: r.name.clone(),
        model,
        lidar,
        slip,
        encoder,
        slam,
        start,
        route,
        controller,
        speed,
        lookahead,
    })
}

fn resolve_lidar(cx: &Ctx, field: &str, r: &LidarRef) -> Result<LidarModel, ScenarioError> {
    let preset = |name: &str| {
        LidarModel::preset(name).ok_or_else(|| {
            let names = LidarModel::PRESETS.join(" or ");
            cx.err(field, format!("unknown lidar preset `{name}` (expected {names})"))
        })
    };
    let lidar = match r {
        LidarRef::Preset(name) => preset(name)?,
        LidarRef::Table(t) => {
            let mut l = match &t.preset {
                Some(p) => preset(p)?,
                None => LidarModel::hokuyo_urg_04lx(),
            };
            apply(&mut [
                (&mut l.fov, t.fov_deg.map(f64::to_radians)),
                (&mut l.resolution, t.resolution_deg.map(f64::to_radians)),
                (&mut l.angular_jitter, t.angular_jitter_deg.map(f64::to_radians)),
                (&mut l.range_min, t.range_min),
                (&mut l.range_max, t.range_max),
                (&mut l.scan_period, t.scan_period),
                (&mut l.range_noise_const, t.range_noise_const),
                (&mut l.range_noise_prop, t.range_noise_prop),
                (&mut l.dropout_prob, t.dropout_prob),
            ]);
            if let Some([x, y, th]) = t.mount {
                l.mount = pose(x, y, th);
            }
            apply(&mut [(&mut l.skew, t.skew)]);
            l
        }
    };
    lidar.validate().map_err(|e| cx.err(field, e.to_string()))?;
    Ok(lidar)
}

fn resolve_slam(cx: &Ctx, field: &str, s: &SlamFile, lidar: &LidarModel) -> Result<SlamParams, ScenarioError> {
    let mut p = match s.preset.as_deref() {
        Some(name) => name.parse::<mrslam_slam::Preset>().map_err(|e| cx.err(field, e))?.params(),
        // Without a preset, the one matching the lidar's reach.
        None if lidar.range_max <= 4.5 => SlamParams::hokuyo(),
        None => SlamParams::rplidar(),
    };
    // Each name sets its own field, so the (sorted) order of application does not matter.
    for (name, value) in &s.params {
        let text = match value {
            toml::Value::String(t) => t.clone(),
            toml::Value::Integer(_) | toml::Value::Float(_) | toml::Value::Boolean(_) => value.to_string(),
            other => {
                return Err(
                    cx.err(format!("{field}.{name}"), format!("expected a number, boolean or string, got {other}"))
                );
            }
        };
        p.set(name, &text).map_err(|e| cx.err(format!("{field}.{name}"), e))?;
    }
    // The filter sees no farther than the lidar.
    p.max_range = p.max_range.min(lidar.range_max);
    p.max_urange = p.max_urange.min(lidar.range_max);
    p.validate().map_err(|e| cx.err(field, e))?;
    Ok(p)
}

fn resolve_merge(cx: &Ctx, m: &MergeFile, robots: &[RobotSetup], duration: f64) -> Result<MergeSetup, ScenarioError> {
    let when = match &m.when {
        None => MergeWhen::Rendezvous,
        Some(toml::Value::String(s)) if s == "rendezvous" => MergeWhen::Rendezvous,
        Some(toml::Value::String(s)) if s == "end" => MergeWhen::End,
        Some(toml::Value::Float(t)) => MergeWhen::At(*t),
        Some(toml::Value::Integer(t)) => MergeWhen::At(*t as f64),
        Some(v) => {
            return Err(cx.err("merge.when", format!("expected \"rendezvous\", \"end\" or a time in seconds, got {v}")));
        }
    };
    if let MergeWhen::At(t) = when {
        if t.is_nan() || t <= 0.0 {
            return Err(cx.err("merge.when", format!("merge time must be positive, got {t}")));
        }
        if t > duration {
            return Err(cx.err("merge.when", format!("merge time {t} s is after the end of the run ({duration} s)")));
        }
    }
    let algorithms = match &m.algorithms {
        None => vec![Algorithm::Sift],
        Some(names) => names
            .iter()
            .map(|a| a.parse::<Algorithm>().map_err(|e| cx.err("merge.algorithms", e.to_string())))
            .collect::<Result<_, _>>()?,
    };
    let model = match &m.model {
        None => Model::Rigid,
        Some(s) => s.parse().map_err(|e: String| cx.err("merge.model", e))?,
    };
    let ratio = m.ratio.unwrap_or(0.75);
    if !(ratio > 0.0 && ratio <= 1.0) {
        return Err(cx.err("merge.ratio", format!("must lie in (0, 1], got {ratio}")));
    }
    let encoding = match &m.encoding {
        None => Encoding::default(),
        Some(s) => s.parse().map_err(|e: String| cx.err("merge.encoding", e))?,
    };
    let host = m.host.clone().unwrap_or_else(|| robots[0].name.clone());
    if !robots.iter().any(|r| r.name == host) {
        return Err(cx.err("merge.host", format!("no robot named `{host}`")));
    }
    let in_range = |field: &str, v: Option<usize>, lo: usize, hi: usize, default: usize| match v {
        Some(x) if !(lo..=hi).contains(&x) => Err(cx.err(field, format!("must lie in {lo}..={hi}, got {x}"))),
        v => Ok(v.unwrap_or(default)),
    };
    let candidates = in_range("merge.candidates", m.candidates, 1, 16, 1)?;
    let hypotheses = in_range("merge.hypotheses", m.hypotheses, 1, 16, 1)?;
    let wall_dilation = in_range("merge.wall_dilation", m.wall_dilation, 0, 4, 0)?;
    Ok(MergeSetup { when, algorithms, model, ratio, encoding, candidates, hypotheses, wall_dilation, host })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(e.message.contains("both robots are named `experia`"), "{e}");
        // A file that cannot be read names no line 0.
        let e = Scenario::from_file(Path::new("/nonexistent/s.toml")).unwrap_err();
        assert!(e.to_string().starts_with("/nonexistent/s.toml: file: "), "{e}");
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
        // Without a table: the preset that matches the lidar's reach (Hokuyo 4 m, RpLidar 6 m).
        let s = two_rooms(|t| t).unwrap();
        assert_eq!(s.robots[0].slam, {
            let mut p = SlamParams::hokuyo();
            p.max_range = p.max_range.min(s.robots[0].lidar.range_max);
            p.max_urange = p.max_urange.min(s.robots[0].lidar.range_max);
            p
        });
        assert!(!s.robots[1].slam.scan_odometry);
        // A preset and parameters by name; the 80 m preset is capped at the robot's lidar.
        let table =
            "slam = { preset = \"matched\", particles = 12, scan_odometry_reach = 2, linear_update = \"0.4\" }\n";
        let s = two_rooms(|t| {
            let (head, second) = t.split_at(t.rfind("[[robots]]").unwrap());
            format!("{head}{}", second.replacen("[[robots]]\n", &format!("[[robots]]\n{table}"), 1))
        })
        .unwrap();
        let (slam, range) = (&s.robots[1].slam, s.robots[1].lidar.range_max);
        assert!(slam.scan_odometry, "the matched preset");
        assert_eq!((slam.particles, slam.scan_odometry_reach, slam.linear_update), (12, 2, 0.4));
        assert!(
            slam.max_range <= range && slam.max_urange <= range,
            "{} {} > {range}",
            slam.max_range,
            slam.max_urange
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
}
