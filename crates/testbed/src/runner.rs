//! The simulation loop: drive both robots, run their SLAMs, merge their maps, evaluate against truth.

use crate::controller::{Explorer, PurePursuit, blocked_ahead};
use crate::eval::{map_acceptance, rmse, transform_error};
use crate::report::{MergeResult, RobotReport, RunReport};
use crate::scenario::{ControllerKind, MergeWhen, RobotSetup, Scenario};
use mrslam_core::map_io::{self, MapIoError};
use mrslam_core::{CellTraversal, LaserScan, OccupancyGrid, Odometry, Pose2, Xyt};
use mrslam_merge::{Algorithm, MergeOutcome, MergeParams, MergerConfig, merge};
use mrslam_sim::Obstacle;
use mrslam_sim::{RobotId, Sim, SimConfig, SimError, StepEvents};
use mrslam_slam::{Rbpf, SlamError};
use mrslam_viz::{MergeView, RobotInfo, RunRecorder, SlamState};
use nalgebra::Point2;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// What can stop a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The simulator refused something (e.g. a start inside an obstacle).
    #[error("simulator: {0}")]
    Sim(#[from] SimError),
    /// A SLAM filter refused its input or parameters.
    #[error("SLAM of robot `{robot}`: {error}")]
    Slam {
        /// Robot.
        robot: String,
        /// What went wrong.
        error: SlamError,
    },
    /// Writing outputs failed.
    #[error("{0}")]
    Io(#[from] MapIoError),
    /// The scenario is not one a run can take (its fields are public, so it may not come from a file).
    #[error("scenario: {0}")]
    Scenario(String),
}

/// Options of a run that are not part of the scenario.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Merge algorithms to run instead of the scenario's.
    pub algorithms: Option<Vec<Algorithm>>,
    /// Called about once per simulated second with (simulated time, expected end of the run): the merge
    /// time, the duration, or at a rendezvous of routed robots the time their remaining routes take.
    pub progress: Option<Box<dyn FnMut(f64, f64) + 'a>>,
    /// Records the run for the rerun viewer; `None` (the default) records and converts nothing.
    pub viz: Option<&'a mut RunRecorder>,
}

/// Everything a run produced.
pub struct RunOutput {
    /// The report.
    pub report: RunReport,
    /// Each robot's final map (best particle), by robot name, in its own SLAM frame.
    pub maps: BTreeMap<String, OccupancyGrid>,
    /// The true map (world frame).
    pub truth: OccupancyGrid,
    /// Merge outcomes, in algorithm order (with merged maps when accepted).
    pub merges: Vec<MergeOutcome>,
    /// Each robot's SLAM frame in the world (its true pose at its first processed scan), by robot name.
    pub frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM path (the best particle's pose at every processed scan, its own frame), by robot name.
    pub paths: BTreeMap<String, Vec<Pose2>>,
}

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
        ..MergerConfig::new(algorithm, scenario.seed)
    }
}

/// Per-robot state of a run.
struct Agent<'s> {
    setup: &'s RobotSetup,
    id: RobotId,
    slam: Rbpf,
    pursuit: Option<PurePursuit>,
    explorer: Option<Explorer>,
    /// The latest scan, for the explorer's look ahead.
    last_scan: Option<LaserScan>,
    /// (truth, odometry) at each processed scan, in the world and odometry frames.
    processed: Vec<(Pose2, Pose2)>,
    scans: usize,
    distance: f64,
    last: Pose2,
    contact_steps: usize,
    slam_s: f64,
    /// Truth-map cells this robot's beams crossed or hit.
    observed: Vec<bool>,
}

impl Agent<'_> {
    fn finished(&self) -> bool {
        match self.setup.controller {
            ControllerKind::Waypoints => self.pursuit.as_ref().is_none_or(PurePursuit::is_done),
            ControllerKind::Explore => self.explorer.as_ref().is_none_or(Explorer::is_done),
        }
    }

    /// Feeds the scans of this step to SLAM, recording truth and odometry for evaluation.
    fn process(&mut self, scans: Vec<(LaserScan, Odometry, Pose2)>, truth: &OccupancyGrid) -> Result<(), RunError> {
        for (scan, odom, true_pose) in scans {
            self.scans += 1;
            mark_observed(&mut self.observed, truth, &scan, &(true_pose * self.setup.lidar.mount));
            let t = Instant::now();
            let outcome = self
                .slam
                .process(&odom, &scan)
                .map_err(|error| RunError::Slam { robot: self.setup.name.clone(), error })?;
            self.slam_s += t.elapsed().as_secs_f64();
            if outcome.is_processed() {
                self.processed.push((true_pose, odom.pose));
            }
            self.last_scan = Some(scan);
        }
        Ok(())
    }
}

/// Marks the truth cells a scan's beams cross, from the sensor's true pose.
fn mark_observed(observed: &mut [bool], truth: &OccupancyGrid, scan: &LaserScan, sensor: &Pose2) {
    let origin = Point2::new(sensor.translation.x, sensor.translation.y);
    let (x0, y0) = truth.world_to_cell_f(&origin);
    let w = truth.width();
    for i in (0..scan.len()).step_by(2) {
        let r = if scan.is_valid(i) {
            scan.ranges[i] as f64
        } else if scan.is_max_range(i) {
            scan.range_max as f64
        } else {
            continue;
        };
        let (x1, y1) = truth.world_to_cell_f(&scan.point_at(sensor, i, r));
        for (cx, cy) in CellTraversal::new(x0, y0, x1, y1) {
            if truth.contains_cell(cx, cy) {
                observed[cy as usize * w + cx as usize] = true;
            }
        }
    }
}

/// The host robot's name and the other's: a run takes two robots of distinct names, one of them the host.
///
/// [`Scenario::from_file`] checks this; a scenario built or changed in code may not hold to it.
fn merge_pair(scenario: &Scenario) -> Result<(String, String), RunError> {
    let host = &scenario.merge.host;
    match scenario.robots.as_slice() {
        [a, b] if a.name == b.name => Err(RunError::Scenario(format!("the two robots share the name `{}`", a.name))),
        [a, b] if a.name == *host => Ok((a.name.clone(), b.name.clone())),
        [a, b] if b.name == *host => Ok((b.name.clone(), a.name.clone())),
        [_, _] => Err(RunError::Scenario(format!("the merge host `{host}` is not one of the robots"))),
        robots => Err(RunError::Scenario(format!("a run takes two robots, found {}", robots.len()))),
    }
}

/// Runs a scenario end to end: the robots drive and map until the merge time (`drive`), each robot's
/// SLAM is evaluated against the truth (`evaluate_robots`), then the maps are merged by each algorithm and
/// every merge is scored against the true transform (`merge_maps`).
pub fn run(scenario: &Scenario, mut opts: RunOptions) -> Result<RunOutput, RunError> {
    let wall = Instant::now();
    let (host, other) = merge_pair(scenario)?;
    let config = SimConfig { dt: scenario.dt, ..SimConfig::default() };
    let mut sim = Sim::with_config(&scenario.world, scenario.seed, config)?;
    let truth = sim.true_map(scenario.truth_resolution)?;
    let mut agents = add_robots(scenario, &mut sim, &truth)?;
    let algorithms = opts.algorithms.clone().unwrap_or_else(|| scenario.merge.algorithms.clone());
    if let Some(v) = opts.viz.as_deref_mut() {
        viz_begin(v, &sim, &truth, &agents, &algorithms);
    }
    let steps = drive(scenario, &mut sim, &mut agents, &truth, &mut opts)?;
    let merge_at = sim.time();
    if let Some(v) = opts.viz.as_deref_mut() {
        v.set_time(steps, merge_at);
    }
    // A robot whose SLAM parameters ask for loop closure gets it when the drive ends, as `mrslam slam` does
    // at the end of a log (no preset of the simulated robots turns it on).
    for a in agents.iter_mut().filter(|a| a.slam.params().loop_closure) {
        a.slam.close_loops();
    }
    let evaluated = evaluate_robots(&agents, &truth, &mut opts)?;
    let (results, merges) = merge_maps(scenario, &algorithms, &evaluated, (&host, &other), &truth, &mut opts);
    let (oa, ob) = (&agents[0].observed, &agents[1].observed);
    let both = oa.iter().zip(ob).filter(|(x, y)| **x && **y).count();
    let either = oa.iter().zip(ob).filter(|(x, y)| **x || **y).count();
    let report = RunReport {
        scenario: scenario.name.clone(),
        seed: scenario.seed,
        sim_s: merge_at,
        wall_s: wall.elapsed().as_secs_f64(),
        steps,
        merge_at_s: merge_at,
        merge_pair: [host, other],
        robots: evaluated.robots,
        merges: results,
        observed_overlap: if either == 0 { 0.0 } else { both as f64 / either as f64 },
    };
    Ok(RunOutput { report, maps: evaluated.maps, truth, merges, frames: evaluated.frames, paths: evaluated.paths })
}

/// Puts the scenario's robots into the simulator, each with its SLAM filter (seeded by the scenario's seed and
/// the robot's place) and its controller.
fn add_robots<'s>(scenario: &'s Scenario, sim: &mut Sim, truth: &OccupancyGrid) -> Result<Vec<Agent<'s>>, RunError> {
    let mut agents = Vec::new();
    for (k, r) in scenario.robots.iter().enumerate() {
        let id = sim.add_robot(&r.name, r.model.clone(), r.lidar.clone(), r.slip, r.encoder, r.start)?;
        let slam = Rbpf::new(r.slam.clone(), r.lidar.mount, scenario.seed.wrapping_add(1 + k as u64))
            .map_err(|error| RunError::Slam { robot: r.name.clone(), error })?;
        let (pursuit, explorer) = match r.controller {
            ControllerKind::Waypoints => {
                let mut p = PurePursuit::new(r.route.clone(), r.speed);
                p.lookahead = r.lookahead;
                (Some(p), None)
            }
            ControllerKind::Explore => {
                let clearance = r.model.footprint.bounding_radius() + Explorer::MARGIN;
                (None, Some(Explorer::new(r.speed, clearance)))
            }
        };
        agents.push(Agent {
            setup: r,
            id,
            slam,
            pursuit,
            explorer,
            last_scan: None,
            processed: Vec::new(),
            scans: 0,
            distance: 0.0,
            last: r.start,
            contact_steps: 0,
            slam_s: 0.0,
            observed: vec![false; truth.width() * truth.height()],
        });
    }
    Ok(agents)
}

/// Steps the simulation until the scenario's merge time (or its duration): each step, every robot's
/// controller sets its command, the world moves, and the scans that came in are fed to the robots' filters.
/// Returns the number of steps.
fn drive(
    scenario: &Scenario,
    sim: &mut Sim,
    agents: &mut [Agent],
    truth: &OccupancyGrid,
    opts: &mut RunOptions,
) -> Result<u64, RunError> {
    let dt = scenario.dt;
    let mut steps = 0u64;
    let mut next_progress = 0.0;
    loop {
        let t = sim.time();
        if let Some(p) = opts.progress.as_mut()
            && t >= next_progress
        {
            p(t, expected_end(scenario, sim, agents, t));
            next_progress += 1.0;
        }
        let merge_now = match scenario.merge.when {
            MergeWhen::Rendezvous => agents.iter().all(Agent::finished),
            MergeWhen::End => false,
            MergeWhen::At(m) => t >= m - 1e-9,
        };
        if merge_now || t >= scenario.duration - 1e-9 {
            return Ok(steps);
        }
        for a in agents.iter_mut() {
            let true_pose = sim.true_pose(a.id)?;
            let (v, w) = match (&mut a.pursuit, &mut a.explorer) {
                // The scripted route is driven as an operator would: by looking at the robot.
                (Some(p), _) => p.command(&true_pose, dt),
                // Exploration is autonomous: the robot's own map and pose.
                (_, Some(e)) => {
                    let slam_pose = a.slam.best_pose();
                    if e.wants_plan() && !a.processed.is_empty() {
                        let map =
                            a.slam.map().map_err(|error| RunError::Slam { robot: a.setup.name.clone(), error })?;
                        e.plan(&map, &slam_pose);
                    }
                    let (front, half_width) = a.setup.model.footprint.half_extents();
                    let reach = front + Explorer::STOP_DISTANCE;
                    let blocked = a
                        .last_scan
                        .as_ref()
                        .is_some_and(|scan| blocked_ahead(scan, &a.setup.lidar.mount, reach, half_width + 0.05));
                    e.command(&slam_pose, dt, blocked)
                }
                _ => (0.0, 0.0),
            };
            sim.set_velocity_command(a.id, v, w)?;
        }
        let events = sim.step();
        steps += 1;
        let mut batches = Vec::with_capacity(agents.len());
        for (a, ev) in agents.iter_mut().zip(&events.robots) {
            a.contact_steps += ev.contact as usize;
            let pose = sim.true_pose(a.id)?;
            a.distance += (pose.translation.vector - a.last.translation.vector).norm();
            a.last = pose;
            let mut batch = Vec::new();
            while let Some(scan) = sim.take_scan(a.id)? {
                batch.push((scan, sim.odometry(a.id)?, pose));
            }
            batches.push(batch);
        }
        if let Some(v) = opts.viz.as_deref_mut() {
            viz_step(v, steps, sim.time(), agents, &events, &batches);
        }
        // The two filters are independent: update them side by side.
        let (first, rest) = agents.split_at_mut(1);
        let (b0, b1) = {
            let mut it = batches.into_iter();
            (it.next().unwrap_or_default(), it.next().unwrap_or_default())
        };
        let (r0, r1) = rayon::join(|| first[0].process(b0, truth), || rest[0].process(b1, truth));
        r0?;
        r1?;
        if let Some(v) = opts.viz.as_deref_mut() {
            viz_slam(v, agents)?;
        }
    }
}

/// Each robot's evaluation against the truth, and what the merge needs of it; by robot name.
struct Evaluated {
    /// Report of each robot's SLAM.
    robots: BTreeMap<String, RobotReport>,
    /// Each robot's final map (best particle), in its own SLAM frame.
    maps: BTreeMap<String, OccupancyGrid>,
    /// Each robot's SLAM frame in the world: its true pose at its first processed scan.
    frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM frame placed so that its last SLAM pose is its true pose.
    end_frames: BTreeMap<String, Pose2>,
    /// Each robot's SLAM path in its own frame.
    paths: BTreeMap<String, Vec<Pose2>>,
}

/// Scores each robot's SLAM trajectory and map against the truth and takes its final map.
fn evaluate_robots(agents: &[Agent], truth: &OccupancyGrid, opts: &mut RunOptions) -> Result<Evaluated, RunError> {
    let mut out = Evaluated {
        robots: BTreeMap::new(),
        maps: BTreeMap::new(),
        frames: BTreeMap::new(),
        end_frames: BTreeMap::new(),
        paths: BTreeMap::new(),
    };
    for (k, a) in agents.iter().enumerate() {
        let map = a.slam.map().map_err(|error| RunError::Slam { robot: a.setup.name.clone(), error })?;
        let traj: Vec<Pose2> = a.slam.trajectory().into_iter().map(|(_, p)| p).collect();
        let (t0, o0) = a.processed.first().copied().unwrap_or((a.setup.start, Pose2::identity()));
        let truth_rel: Vec<Pose2> = a.processed.iter().map(|(t, _)| t0.inv_mul(t)).collect();
        let odom_rel: Vec<Pose2> = a.processed.iter().map(|(_, o)| o0.inv_mul(o)).collect();
        let final_err = |est: &[Pose2]| match (est.last(), truth_rel.last()) {
            (Some(e), Some(t)) => (e.translation.vector - t.translation.vector).norm(),
            _ => 0.0,
        };
        let counters = a.slam.counters();
        out.robots.insert(
            a.setup.name.clone(),
            RobotReport {
                slam_rmse_m: rmse(&traj, &truth_rel),
                odom_rmse_m: rmse(&odom_rel, &truth_rel),
                map_acceptance: map_acceptance(truth, &map, &t0),
                slam_final_error_m: final_err(&traj),
                odom_final_error_m: final_err(&odom_rel),
                scans: a.scans,
                processed: counters.processed,
                resamples: counters.resamples,
                final_neff: a.slam.neff(),
                distance_m: a.distance,
                contact_steps: a.contact_steps,
                finished: a.finished(),
                slam_s: a.slam_s,
            },
        );
        if let Some(v) = opts.viz.as_deref_mut() {
            // The maps and paths that are merged and evaluated, whatever the logging rates.
            v.map(k, &map);
            v.paths(k, &traj);
        }
        let end_frame = match (a.processed.last(), traj.last()) {
            (Some((t, _)), Some(e)) => t * e.inverse(),
            _ => t0,
        };
        out.end_frames.insert(a.setup.name.clone(), end_frame);
        out.frames.insert(a.setup.name.clone(), t0);
        out.maps.insert(a.setup.name.clone(), map);
        out.paths.insert(a.setup.name.clone(), traj);
    }
    Ok(out)
}

/// Merges the other robot's map into the host's with each algorithm and scores each merge against the true
/// transform between the two SLAM frames (and against the one at the end of the run).
fn merge_maps(
    scenario: &Scenario,
    algorithms: &[Algorithm],
    evaluated: &Evaluated,
    (host, other): (&str, &str),
    truth: &OccupancyGrid,
    opts: &mut RunOptions,
) -> (Vec<MergeResult>, Vec<MergeOutcome>) {
    let true_t = evaluated.frames[host].inv_mul(&evaluated.frames[other]);
    let end_t = evaluated.end_frames[host].inv_mul(&evaluated.end_frames[other]);
    let mut merges = Vec::new();
    let mut results = Vec::new();
    for &algorithm in algorithms {
        let merger = merger_for(algorithm, scenario).build();
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

/// When the run is expected to end, simulated seconds: a fixed merge time or the duration; at a rendezvous
/// of robots on routes, now plus the longest time a robot's remaining route takes at its cruise speed.
fn expected_end(scenario: &Scenario, sim: &Sim, agents: &[Agent], t: f64) -> f64 {
    let to_go = |a: &Agent| -> Option<f64> {
        let p = a.pursuit.as_ref()?;
        let pose = sim.true_pose(a.id).ok()?;
        Some(p.remaining(&Point2::from(pose.translation.vector)) / p.speed.max(1e-3))
    };
    match scenario.merge.when {
        MergeWhen::At(m) => m.min(scenario.duration),
        MergeWhen::End => scenario.duration,
        MergeWhen::Rendezvous => agents
            .iter()
            .map(to_go)
            .try_fold(0.0f64, |longest, s| s.map(|s| longest.max(s)))
            .map_or(scenario.duration, |s| (t + s).min(scenario.duration)),
    }
}

/// The picture of a merge: the true map in grey, the first robot's map (blue) at its true frame, the second's
/// (orange) placed by the merge's estimate `t_a_b` from there, each with its SLAM path: where the estimate is
/// right, both robots' walls lie on the truth's.
pub fn merge_overlay(out: &RunOutput, t_a_b: &Pose2) -> image::RgbImage {
    let [host, other] = &out.report.merge_pair;
    let frame = out.frames.get(host).copied().unwrap_or_else(Pose2::identity);
    let layer = |name: &String, placement: Pose2, colour: [u8; 3]| {
        out.maps.get(name).map(|map| map_io::OverlayLayer {
            map,
            placement,
            path: out.paths.get(name).map_or(&[][..], Vec::as_slice),
            colour,
        })
    };
    let layers: Vec<map_io::OverlayLayer> =
        [layer(host, frame, [30, 90, 220]), layer(other, frame * t_a_b, [235, 120, 20])]
            .into_iter()
            .flatten()
            .collect();
    map_io::overlay(&out.truth, &layers)
}

/// Writes a run's maps (YAML+PGM, each with a PNG preview), the true map, merged maps with a picture of each
/// accepted merge over the truth (`overlay_<algorithm>.png`, see [`merge_overlay`]) and `report.json` (last)
/// into `dir`.
pub fn write_outputs(out: &RunOutput, dir: &Path) -> Result<(), RunError> {
    std::fs::create_dir_all(dir).map_err(|cause| MapIoError::Io { path: dir.to_path_buf(), cause })?;
    for (name, map) in &out.maps {
        map_io::write_ros_map_with_preview(map, &dir.join(format!("{name}.yaml")))?;
    }
    map_io::write_ros_map_with_preview(&out.truth, &dir.join("truth.yaml"))?;
    for m in &out.merges {
        let path = dir.join(format!("merged_{}.yaml", m.report.algorithm));
        let picture = dir.join(format!("overlay_{}.png", m.report.algorithm));
        match &m.merged {
            Some(g) => {
                map_io::write_ros_map_with_preview(g, &path)?;
                if let Some(t) = m.report.transform {
                    map_io::write_rgb_png(&merge_overlay(out, &t.to_pose()), &picture)?;
                }
            }
            None => {
                // A rejected merge leaves no map, not even a stale one from an earlier run.
                let _ = std::fs::remove_file(&path);
                let _ = std::fs::remove_file(path.with_extension("pgm"));
                let _ = std::fs::remove_file(map_io::preview_path(&path));
                let _ = std::fs::remove_file(&picture);
            }
        }
    }
    let json = serde_json::to_vec_pretty(&out.report).expect("reports serialise");
    map_io::write_file_atomic(&dir.join("report.json"), &json)?;
    Ok(())
}

// ---- rerun hooks: called only when `RunOptions::viz` is set; they hand plain data to mrslam-viz. ----

/// What the rerun recording shows of a merge of `host`'s map (a) and `other`'s (b); `error` against the truth
/// (rotation radians, translation metres) when known.
pub fn merge_view<'a>(
    out: &'a MergeOutcome,
    host: &'a str,
    other: &'a str,
    error: Option<(f64, f64)>,
) -> MergeView<'a> {
    MergeView {
        algorithm: &out.report.algorithm,
        host,
        other,
        accepted: out.report.accepted,
        reason: out.report.reason.as_deref(),
        matches: out.report.matches,
        inliers: out.report.inliers,
        transform: out.report.transform.map(|t| t.to_pose()),
        error,
        points_a: &out.evidence.points_a,
        points_b: &out.evidence.points_b,
        inlier_pairs: &out.evidence.inlier_pairs,
        merged: out.merged.as_ref(),
    }
}

/// The world's obstacles as closed outlines (circles as 24-gons).
fn viz_walls(sim: &Sim) -> Vec<Vec<Point2<f64>>> {
    sim.world()
        .obstacles()
        .iter()
        .map(|o| match o {
            Obstacle::Circle { center, radius } => (0..24)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 24.0;
                    Point2::new(center.x + radius * a.cos(), center.y + radius * a.sin())
                })
                .collect(),
            other => other.outline(),
        })
        .collect()
}

/// Static content and layout.
fn viz_begin(v: &mut RunRecorder, sim: &Sim, truth: &OccupancyGrid, agents: &[Agent], algorithms: &[Algorithm]) {
    let robots: Vec<RobotInfo> =
        agents.iter().map(|a| RobotInfo { name: a.setup.name.clone(), start: a.setup.start }).collect();
    let algorithms: Vec<String> = algorithms.iter().map(Algorithm::to_string).collect();
    v.set_time(0, sim.time());
    v.begin(&viz_walls(sim), truth, &robots, &algorithms);
}

/// A step: slip and contacts, and this step's scans with the true and odometry poses they were taken at.
fn viz_step(
    v: &mut RunRecorder,
    step: u64,
    time: f64,
    agents: &[Agent],
    events: &StepEvents,
    batches: &[Vec<(LaserScan, Odometry, Pose2)>],
) {
    v.set_time(step, time);
    for (k, ((a, ev), batch)) in agents.iter().zip(&events.robots).zip(batches).enumerate() {
        v.robot_step(k, ev.slipping, ev.contact);
        for (scan, odom, pose) in batch {
            v.scan(k, pose, &odom.pose, scan, &a.setup.lidar.mount);
        }
    }
}

/// The filters after this step's updates: best pose, particles, Neff; paths and maps when due.
fn viz_slam(v: &mut RunRecorder, agents: &[Agent]) -> Result<(), RunError> {
    for (k, a) in agents.iter().enumerate() {
        let state = SlamState {
            scans: a.scans,
            best: &a.slam.best_pose(),
            particles: a.slam.particles(),
            neff: a.slam.neff(),
            resamples: a.slam.counters().resamples,
            frame: a.processed.first().map(|p| p.0),
        };
        v.slam(k, state);
        if v.paths_due(k) {
            let traj: Vec<Pose2> = a.slam.trajectory().into_iter().map(|(_, p)| p).collect();
            v.paths(k, &traj);
        }
        if v.map_due(k) {
            let map = a.slam.map().map_err(|error| RunError::Slam { robot: a.setup.name.clone(), error })?;
            v.map(k, &map);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_rooms() -> Scenario {
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
        assert_eq!(refused(&s), "a run takes two robots, found 1");
        let mut s = two_rooms();
        s.merge.host = "nobody".into();
        assert_eq!(refused(&s), "the merge host `nobody` is not one of the robots");
        let mut s = two_rooms();
        s.robots[1].name = s.robots[0].name.clone();
        assert!(refused(&s).contains("share the name"));
    }

    #[test]
    fn the_host_comes_first_in_the_merge_pair() {
        let mut s = two_rooms();
        let (a, b) = (s.robots[0].name.clone(), s.robots[1].name.clone());
        assert_eq!(merge_pair(&s).unwrap(), (a.clone(), b.clone()));
        s.merge.host = b.clone();
        assert_eq!(merge_pair(&s).unwrap(), (b, a));
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
