//! A scenario's robots: body, lidar, odometry, SLAM parameters, start, route and controller, resolved.

use super::error::{Ctx, ScenarioError, apply};
use super::file::{LidarRef, PointRef, PoseRef, RobotFile, SlamFile};
use mrslam_core::map_io;
use mrslam_core::{Pose2, pose};
use mrslam_sim::{EncoderParams, LidarModel, RobotModel, SlipParams, World, WorldSpec, odometry_fit};
use mrslam_slam::SlamParams;
use nalgebra::Point2;

/// How a robot is driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControllerKind {
    /// Pure pursuit along the scripted route (the paper's robots were driven by hand along such routes).
    Waypoints,
    /// Frontier-based exploration on the robot's own SLAM map.
    Explore,
    /// No driving: the robot stays at its start and maps what it sees from there.
    Idle,
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

pub(super) fn resolve_pose(cx: &Ctx, field: &str, r: &PoseRef, world: &WorldSpec) -> Result<Pose2, ScenarioError> {
    let (x, y, t) = match r {
        PoseRef::Named(n) => {
            return world.named_pose(n).ok_or_else(|| cx.err(field, format!("no point named `{n}` in the world")));
        }
        PoseRef::Xyt([x, y, t]) => (*x, *y, *t),
        PoseRef::Table(p) => (p.x, p.y, p.theta),
    };
    check_coordinates(cx, field, &[x, y, t])?;
    Ok(pose(x, y, t))
}

/// Why a robot's `name` cannot name its files in a run's folder (`NAME.yaml`, `.pgm`, `.png`), if it cannot: empty,
/// a path rather than a name, or one of the run's own files (`truth`, `merged_*`, `overlay_*`).
fn check_name(name: &str) -> Result<(), String> {
    if name.trim().is_empty() {
        return Err("a robot needs a name (its map is written as NAME.yaml)".into());
    }
    if name.contains(['/', '\\', '\0']) || name.starts_with('.') {
        return Err(format!("`{name}`: a robot's name is a file name, so it may hold no / or \\ and not start with ."));
    }
    let ours = name == "truth" || name.starts_with("merged_") || name.starts_with("overlay_");
    if ours {
        return Err(format!(
            "`{name}`: the run writes its own files under this name (truth.yaml, merged_ALGORITHM.yaml, \
             overlay_ALGORITHM.png); name the robot otherwise"
        ));
    }
    Ok(())
}

/// Refuses a coordinate that is not a number or lies further than the world reader's bound from 0 (a typo, which
/// would otherwise be printed with hundreds of digits in the error that follows).
fn check_coordinates(cx: &Ctx, field: &str, values: &[f64]) -> Result<(), ScenarioError> {
    let bound = mrslam_sim::MAX_WORLD_COORDINATE;
    match values.iter().find(|v| !(v.is_finite() && v.abs() <= bound)) {
        Some(v) => {
            Err(cx.err(field, format!("{v:e}: every coordinate must be a finite number within {bound:e} m of 0")))
        }
        None => Ok(()),
    }
}

pub(super) fn resolve_robot(
    cx: &Ctx,
    i: usize,
    r: &RobotFile,
    spec: &WorldSpec,
    world: &World,
) -> Result<RobotSetup, ScenarioError> {
    let f = |name: &str| format!("robots[{i}].{name}");
    check_name(&r.name).map_err(|message| cx.err(f("name"), message))?;
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
            PointRef::Table(p) => Point2::new(p.x, p.y),
        };
        check_coordinates(cx, &field, &[p.x, p.y])?;
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
        "idle" => ControllerKind::Idle,
        c => {
            let expected = "expected waypoints, explore or idle";
            return Err(cx.err(f("controller"), format!("unknown controller `{c}` ({expected})")));
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
        // Without a preset, the one made for a lidar of this reach: the simulated Hokuyo (4 m) and RpLidar
        // (6-12 m) robots' presets, and for longer-range scanners (SICK class) `slam`'s default for real logs.
        None if lidar.range_max <= 4.5 => SlamParams::hokuyo(),
        None if lidar.range_max <= 12.0 => SlamParams::rplidar(),
        None => SlamParams::matched(),
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
        p.set(name, &text).map_err(|e| cx.err(format!("{field}.{name}"), e.to_string()))?;
    }
    // The filter sees no farther than the lidar.
    p.map.max_range = p.map.max_range.min(lidar.range_max);
    p.map.max_urange = p.map.max_urange.min(lidar.range_max);
    p.validate().map_err(|e| cx.err(field, e.to_string()))?;
    let bounds = map_io::MIN_RESOLUTION..=map_io::MAX_RESOLUTION;
    if !bounds.contains(&p.map.delta) {
        let (lo, hi) = bounds.into_inner();
        let message = format!("map.delta {}: must be between {lo} and {hi} metres per pixel", p.map.delta);
        return Err(cx.err(field, message));
    }
    Ok(p)
}
