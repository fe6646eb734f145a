//! What a testbed run records, and how often: the policy between the simulation loop and the [`Recorder`].
//!
//! The runner hands over plain data (poses, scans, grids, points); this module decides what is drawn where and
//! at which rate, keeps the paths, and writes the layout. Frames: the world is the display frame; a robot's
//! odometry is drawn in its odometry frame, placed at its true start; its SLAM estimate in its SLAM map frame,
//! placed where the robot truly was at its first processed scan (what only the evaluator knows). So the picture
//! shows drift as the gap between the true path and the others.

use crate::VizError;
use crate::blueprint::{Layout, ViewKind, query};
use crate::convert::{Rgba, lighten, robot_color, with_alpha};
use crate::maps::{MATCH_BAD, MATCH_GOOD, MATCH_GOOD_M};
use crate::metrics::Level;
use crate::paths;
use crate::recorder::{Recorder, RecordingStats};
use crate::team::{AttemptView, TeamTrack, team_views};
use mrslam_core::{LaserScan, OccupancyGrid, Pose2};
use nalgebra::Point2;
use rerun::{Clear, EntityPath};

/// How often the expensive things are logged, in simulated seconds (for a log, seconds of log time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rates {
    /// Paths (true, odometry, SLAM), redrawn whole.
    pub path_period_s: f64,
    /// Each robot's map (rebuilt from the best particle, so not free); only when the map changed.
    pub map_period_s: f64,
}

impl Rates {
    /// A SLAM run on a recorded log (seconds of log time): paths every 2 s, the growing map every 10 s, so that
    /// a 45-minute log's recording stays well under 100 MB.
    pub const LOG: Rates = Rates { path_period_s: 2.0, map_period_s: 10.0 };
}

impl Default for Rates {
    fn default() -> Self {
        Rates { path_period_s: 0.5, map_period_s: 1.0 }
    }
}

/// A robot as the recording knows it.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotInfo {
    /// Name (entity path part).
    pub name: String,
    /// True start pose in the world: where its odometry frame lies.
    pub start: Pose2,
}

/// A robot's SLAM after an update, as plain data.
pub struct SlamState<'a> {
    /// Scans given to the SLAM so far (nothing is logged when unchanged).
    pub scans: usize,
    /// The best pose estimate, map frame.
    pub best: &'a Pose2,
    /// The pose hypotheses (map frame) with their normalised weights: a particle filter's particles.
    pub hypotheses: &'a [(Pose2, f64)],
    /// How many hypotheses effectively count (a particle filter's Neff), when the SLAM has such a number.
    pub effective: Option<f64>,
    /// Resamplings so far (0 for a SLAM that does not resample).
    pub resamples: usize,
    /// True pose of the SLAM map frame in the world (the robot's true pose at its first processed scan), once
    /// known.
    pub frame: Option<Pose2>,
}

/// One merge's outcome, as plain data.
#[derive(Debug, Clone, Copy)]
pub struct MergeView<'a> {
    /// Algorithm (entity path part).
    pub algorithm: &'a str,
    /// Robot whose map is `a` (the merge's frame).
    pub host: &'a str,
    /// Robot whose map is `b`.
    pub other: &'a str,
    /// Passed verification.
    pub accepted: bool,
    /// Why it was rejected.
    pub reason: Option<&'a str>,
    /// Tentative correspondences.
    pub matches: usize,
    /// Supporting correspondences.
    pub inliers: usize,
    /// Estimated `T_a_b`, when the algorithm produced one.
    pub transform: Option<Pose2>,
    /// Error against the truth (rotation radians, translation metres), when known.
    pub error: Option<(f64, f64)>,
    /// Feature points of map a (its frame).
    pub points_a: &'a [Point2<f64>],
    /// Feature points of map b (its frame).
    pub points_b: &'a [Point2<f64>],
    /// Inlier pairs (index in `points_a`, index in `points_b`).
    pub inlier_pairs: &'a [(usize, usize)],
    /// The merged map (a's frame), when accepted.
    pub merged: Option<&'a OccupancyGrid>,
}

#[derive(Debug)]
struct Track {
    name: String,
    color: Rgba,
    truth_path: Vec<Pose2>,
    odom_path: Vec<Pose2>,
    slam_path: Vec<Pose2>,
    truth: Option<Pose2>,
    odom: Option<Pose2>,
    start: Pose2,
    frame: Option<Pose2>,
    next_path: f64,
    next_map: f64,
    map_dirty: bool,
    scans: usize,
    resamples: usize,
    steps: u32,
    slip_steps: u32,
    contact: bool,
    /// The path to the exploration goal last drawn (empty: none), and whether a team planner assigned it.
    goal: (Vec<Point2<f64>>, bool),
}

/// Records a testbed run: see the module docs.
#[derive(Debug)]
pub struct RunRecorder {
    rec: Recorder,
    rates: Rates,
    tracks: Vec<Track>,
    step: u64,
    /// The team part, for a run with teams.
    team: Option<TeamTrack>,
}

impl RunRecorder {
    /// Wraps an open recording.
    pub fn new(rec: Recorder) -> Self {
        RunRecorder { rec, rates: Rates::default(), tracks: Vec::new(), step: 0, team: None }
    }

    /// Changes the rates.
    pub fn with_rates(mut self, rates: Rates) -> Self {
        self.rates = rates;
        self
    }

    /// The recording, for anything not covered here.
    pub fn recorder(&mut self) -> &mut Recorder {
        &mut self.rec
    }

    /// Logs what is static (the world's walls and true map, each robot's odometry frame and colours) and the
    /// layout for `robots` and merge `algorithms`; with `team`, the run's robots form teams as they meet (team
    /// maps, merge attempts, coverage: see [`Self::team_map`], [`Self::attempt`], [`Self::coverage`]).
    pub fn begin(
        &mut self,
        walls: &[Vec<Point2<f64>>],
        truth: &OccupancyGrid,
        robots: &[RobotInfo],
        algorithms: &[String],
        team: bool,
    ) {
        self.rec.log_display_frame();
        self.rec.log_walls(walls);
        self.rec.log_truth_map(truth);
        self.tracks = robots
            .iter()
            .enumerate()
            .map(|(i, r)| Track {
                name: r.name.clone(),
                color: robot_color(i),
                truth_path: Vec::new(),
                odom_path: Vec::new(),
                slam_path: Vec::new(),
                truth: None,
                odom: None,
                start: r.start,
                frame: None,
                next_path: 0.0,
                next_map: 0.0,
                map_dirty: false,
                scans: 0,
                resamples: 0,
                steps: 0,
                slip_steps: 0,
                contact: false,
                goal: (Vec::new(), false),
            })
            .collect();
        for t in &self.tracks {
            let n = t.name.as_str();
            self.rec.log_frame(&paths::robot(n, &["odom"]), &t.start, true);
            self.rec.log_series_style(&paths::metric("error", &[n, "slam"]), &format!("{n} SLAM"), t.color);
            let odom_c = lighten(t.color, 0.5);
            self.rec.log_series_style(&paths::metric("error", &[n, "odom"]), &format!("{n} odometry"), odom_c);
            self.rec.log_series_style(&paths::metric("neff", &[n]), &format!("{n} Neff"), t.color);
            self.rec.log_series_style(&paths::metric("slip", &[n]), &format!("{n} slipping"), t.color);
        }
        if team {
            let mut track = TeamTrack::default();
            track.begin(&mut self.rec);
            self.team = Some(track);
        }
        let names: Vec<String> = robots.iter().map(|r| r.name.clone()).collect();
        self.rec.send_layout(&run_layout(&names, algorithms, team));
        self.rec.log_event(Level::Info, &format!("run started: {}", names.join(", ")));
    }

    /// Sets the time of what follows.
    pub fn set_time(&mut self, step: u64, sim_time: f64) {
        self.step = step;
        self.rec.set_time(step, sim_time);
        if let Some(t) = self.team.as_mut() {
            t.tick(&mut self.rec);
        }
    }

    /// One simulation step of robot `i`: whether its wheels slipped and whether it touches an obstacle.
    pub fn robot_step(&mut self, i: usize, slipping: bool, contact: bool) {
        let Some(t) = self.tracks.get_mut(i) else { return };
        t.steps += 1;
        t.slip_steps += slipping as u32;
        if contact != t.contact {
            t.contact = contact;
            let text = if contact {
                format!("{} touches an obstacle", t.name)
            } else {
                format!("{} is clear of obstacles", t.name)
            };
            let level = if contact { Level::Warn } else { Level::Info };
            self.rec.log_event(level, &text);
        }
    }

    /// A scan of robot `i`: its true pose, its odometry (odometry frame), the scan and the lidar's mount.
    pub fn scan(&mut self, i: usize, truth: &Pose2, odom: &Pose2, scan: &LaserScan, mount: &Pose2) {
        let Some(t) = self.tracks.get_mut(i) else { return };
        t.truth = Some(*truth);
        t.odom = Some(*odom);
        t.truth_path.push(*truth);
        t.odom_path.push(*odom);
        let (name, c) = (t.name.clone(), t.color);
        let sensor = truth * mount;
        let points: Vec<Point2<f64>> = scan.endpoints(&sensor).map(|(_, p)| p).collect();
        self.rec.log_pose(&paths::robot(&name, &["truth"]), truth, c, &name);
        self.rec.log_pose(&paths::robot(&name, &["odom"]), odom, with_alpha(lighten(c, 0.5), 200), "");
        self.rec.log_scan_points(&paths::robot(&name, &["scan"]), &points, with_alpha(lighten(c, 0.3), 220));
        let odom_world = t.start * odom;
        let err = (odom_world.translation.vector - truth.translation.vector).norm();
        self.rec.log_scalar(&paths::metric("error", &[&name, "odom"]), err);
        let slip = if t.steps > 0 { t.slip_steps as f64 / t.steps as f64 } else { 0.0 };
        (t.steps, t.slip_steps) = (0, 0);
        self.rec.log_scalar(&paths::metric("slip", &[&name]), slip);
    }

    /// Robot `i`'s SLAM after this step's updates; logs nothing when it took no scan since the last call.
    pub fn slam(&mut self, i: usize, s: SlamState<'_>) {
        let Some(t) = self.tracks.get_mut(i) else { return };
        if s.scans == t.scans {
            return;
        }
        t.scans = s.scans;
        let name = t.name.clone();
        if t.frame.is_none()
            && let Some(f) = s.frame
        {
            t.frame = Some(f);
            self.rec.log_frame(&paths::robot(&name, &["slam"]), &f, true);
        }
        if s.resamples > t.resamples {
            t.resamples = s.resamples;
            self.rec.log_event(Level::Info, &format!("{name}: particles resampled (#{})", s.resamples));
        }
        t.map_dirty = true;
        let c = t.color;
        let slam_world = t.frame.map(|f| f * s.best);
        let truth = t.truth;
        self.rec.log_pose(&paths::robot(&name, &["slam", "pose"]), s.best, lighten(c, 0.25), "SLAM");
        self.rec.log_particles(&paths::robot(&name, &["slam", "particles"]), s.hypotheses);
        if let Some(neff) = s.effective {
            self.rec.log_scalar(&paths::metric("neff", &[&name]), neff);
        }
        if let (Some(est), Some(truth)) = (slam_world, truth) {
            let err = (est.translation.vector - truth.translation.vector).norm();
            self.rec.log_scalar(&paths::metric("error", &[&name, "slam"]), err);
        }
    }

    /// True when robot `i`'s paths are due (then call [`Self::paths`] with its SLAM trajectory).
    pub fn paths_due(&self, i: usize) -> bool {
        self.tracks.get(i).is_some_and(|t| self.rec.sim_time() >= t.next_path && !t.truth_path.is_empty())
    }

    /// Logs robot `i`'s true, odometry and SLAM paths (the SLAM path as the best particle has it now, map frame).
    pub fn paths(&mut self, i: usize, slam_trajectory: &[Pose2]) {
        let period = self.rates.path_period_s;
        let now = self.rec.sim_time();
        let Some(t) = self.tracks.get_mut(i) else { return };
        t.next_path = now + period;
        t.slam_path = slam_trajectory.to_vec();
        let (name, c) = (t.name.clone(), t.color);
        let (truth, odom, slam) = (&t.truth_path, &t.odom_path, &t.slam_path);
        self.rec.log_path(&paths::robot(&name, &["truth", "path"]), truth, c);
        self.rec.log_path(&paths::robot(&name, &["odom", "path"]), odom, with_alpha(lighten(c, 0.5), 200));
        if !slam.is_empty() {
            self.rec.log_path(&paths::robot(&name, &["slam", "path"]), slam, lighten(c, 0.25));
        }
    }

    /// True when robot `i`'s map is due (changed, and the period has passed since the last one).
    pub fn map_due(&self, i: usize) -> bool {
        self.tracks.get(i).is_some_and(|t| t.map_dirty && t.frame.is_some() && self.rec.sim_time() >= t.next_map)
    }

    /// Logs robot `i`'s map (its SLAM map frame) at `maps/<name>`.
    pub fn map(&mut self, i: usize, grid: &OccupancyGrid) {
        let period = self.rates.map_period_s;
        let now = self.rec.sim_time();
        let Some(t) = self.tracks.get_mut(i) else { return };
        let Some(frame) = t.frame else { return };
        t.next_map = now + period;
        t.map_dirty = false;
        let (name, c) = (t.name.clone(), t.color);
        self.rec.log_map(&paths::map(&name), grid, &frame, c);
    }

    /// Robot `i`'s exploration goal now: the path to it (its SLAM map frame; the goal is the last point, none when
    /// empty), and whether its team's planner `assigned` it (else the robot chose it on its own map). Logs
    /// `robots/<name>/slam/goal` and `.../goal/path` only when they changed; clears them when the goal is gone.
    pub fn goal(&mut self, i: usize, path: &[Point2<f64>], assigned: bool) {
        let Some(t) = self.tracks.get_mut(i) else { return };
        if t.goal.0 == path && t.goal.1 == assigned {
            return;
        }
        t.goal = (path.to_vec(), assigned);
        let (name, c) = (t.name.clone(), t.color);
        let entity = paths::robot(&name, &["slam", "goal"]);
        let Some(goal) = path.last() else {
            self.rec.log(&entity, &Clear::recursive());
            return;
        };
        let label = if assigned { format!("{name}: team goal") } else { format!("{name}: goal") };
        self.rec.log_goal(&entity, goal, c, &label);
        self.rec.log_plan(&paths::robot(&name, &["slam", "goal", "path"]), path, with_alpha(c, 170));
    }

    /// Logs the map of the team whose root is robot `i` (the root's SLAM map frame, placed where the root truly
    /// was at its first processed scan) at `team/maps/<name>`; call it when the team's map changed. Nothing for a
    /// run without teams.
    pub fn team_map(&mut self, i: usize, grid: &OccupancyGrid) {
        let (Some(team), Some(t)) = (self.team.as_mut(), self.tracks.get(i)) else { return };
        let Some(frame) = t.frame else { return };
        team.map(&mut self.rec, &t.name, grid, &frame, t.color);
    }

    /// Logs a merge attempt between two teams at `team/attempts` (a line between the robots), `team/events` (what
    /// and why) and `metrics/merges/...` (the counts). Nothing for a run without teams.
    pub fn attempt(&mut self, a: &AttemptView<'_>) {
        if let Some(team) = self.team.as_mut() {
            team.attempt(&mut self.rec, a);
        }
    }

    /// Logs a coverage sample at `metrics/coverage/{mapped,redundancy}`: the share of the reachable free area some
    /// robot's map marks free, and of the area the robots' beams crossed the share more than one crossed. Nothing
    /// for a run without teams.
    pub fn coverage(&mut self, mapped: f64, redundancy: f64) {
        if let Some(team) = self.team.as_mut() {
            team.coverage(&mut self.rec, mapped, redundancy);
        }
    }

    /// Logs an event.
    pub fn event(&mut self, level: Level, text: &str) {
        self.rec.log_event(level, text);
    }

    /// Logs a merge between the maps of robots `m.host` (a) and `m.other` (b), placed by the truth.
    pub fn merge(&mut self, m: &MergeView<'_>) {
        let frame = |n: &str| self.tracks.iter().find(|t| t.name == n).map(|t| (t.frame, t.color));
        let (Some((Some(fa), ca)), Some((Some(fb), cb))) = (frame(m.host), frame(m.other)) else {
            self.rec.log_event(Level::Warn, &format!("merge {}: a map frame is unknown, not drawn", m.algorithm));
            return;
        };
        record_merge(&mut self.rec, m, (&fa, ca), (&fb, cb), true);
    }

    /// Flushes and closes the recording.
    pub fn finish(self) -> Result<RecordingStats, VizError> {
        self.rec.finish()
    }
}

/// Logs a merge with map a's frame placed at `a.0` and b's at `b.0` in the display frame. With `truth`, a match
/// is good when its two ends fall within [`MATCH_GOOD_M`] of each other in the display frame (the placement is
/// the true one); without, when the estimated transform carries b's end onto a's.
pub(crate) fn record_merge(rec: &mut Recorder, m: &MergeView<'_>, a: (&Pose2, Rgba), b: (&Pose2, Rgba), truth: bool) {
    let alg = m.algorithm;
    rec.log_keypoints(&paths::merge(alg, &["keypoints", m.host]), m.points_a, a.0, a.1);
    rec.log_keypoints(&paths::merge(alg, &["keypoints", m.other]), m.points_b, b.0, b.1);
    let mut segments = Vec::with_capacity(m.inlier_pairs.len());
    let mut colors = Vec::with_capacity(m.inlier_pairs.len());
    for &(i, j) in m.inlier_pairs {
        let (Some(pa), Some(pb)) = (m.points_a.get(i), m.points_b.get(j)) else { continue };
        let (wa, wb) = (a.0 * pa, b.0 * pb);
        let good = if truth {
            (wa - wb).norm() <= MATCH_GOOD_M
        } else {
            m.transform.is_some_and(|t| (pa - t * pb).norm() <= MATCH_GOOD_M)
        };
        segments.push((wa, wb));
        colors.push(if good { MATCH_GOOD } else { MATCH_BAD });
    }
    rec.log_matches(&paths::merge(alg, &["matches"]), &segments, &colors);
    if let Some(g) = m.merged {
        rec.log_merged_map(&paths::merge(alg, &["merged"]), g, a.0);
    }
    let text = match (m.accepted, m.reason) {
        (true, _) => format!("merge {alg}: ACCEPTED, {} inliers of {} matches", m.inliers, m.matches),
        (false, Some(r)) => format!("merge {alg}: REJECTED, {} inliers of {} matches: {r}", m.inliers, m.matches),
        (false, None) => format!("merge {alg}: REJECTED, {} inliers of {} matches", m.inliers, m.matches),
    };
    let text = match m.error {
        Some((rot, tr)) => format!("{text} (error vs truth {:.2} deg, {tr:.3} m)", rot.to_degrees()),
        None => text,
    };
    rec.log_event(if m.accepted { Level::Info } else { Level::Warn }, &text);
}

/// The layout of a run: the world on top (with `team`, the teams' view beside it), each robot's map in its own
/// frame, then the merges, the metrics (with `team`, coverage and merge counts) and the events.
pub fn run_layout(robots: &[String], algorithms: &[String], team: bool) -> Layout {
    let root = EntityPath::root();
    let world = Layout::view(
        ViewKind::Spatial2D,
        "world (truth, odometry, SLAM, scans)",
        root.clone(),
        &[query('+', &paths::root("world"), true), query('+', &paths::root("robots"), true)],
    );
    let maps = robots
        .iter()
        .map(|r| {
            let mut contents = vec![query('+', &paths::map(r), false), query('+', &paths::robot(r, &["slam"]), true)];
            contents.extend(algorithms.iter().map(|a| query('+', &paths::merge(a, &["keypoints", r]), false)));
            Layout::view(ViewKind::Spatial2D, &format!("{r}: SLAM map"), paths::map(r), &contents)
        })
        .collect();
    let merges: Vec<Layout> = algorithms
        .iter()
        .map(|a| {
            let contents = [
                query('+', &paths::walls(), false),
                query('+', &paths::root("maps"), true),
                query('+', &paths::merge(a, &[]), true),
            ];
            Layout::view(ViewKind::Spatial2D, &format!("merge: {a}"), root.clone(), &contents)
        })
        .collect();
    let series = |group: &str, title: &str| {
        let origin = paths::metric(group, &[]);
        Layout::view(ViewKind::TimeSeries, title, origin.clone(), &[query('+', &origin, true)])
    };
    let mut metrics = vec![
        series("error", "trajectory error (m)"),
        series("neff", "Neff"),
        series("slip", "slipping (share of steps)"),
    ];
    let mut events = vec![query('+', &paths::events(), false)];
    let top = if team {
        let (view, series) = team_views(robots);
        metrics.splice(0..0, series);
        events.push(query('+', &paths::team(&["events"]), false));
        Layout::Horizontal(vec![world, view], vec![])
    } else {
        world
    };
    let events = Layout::view(ViewKind::TextLog, "events", paths::events(), &events);
    let bottom =
        Layout::Horizontal(vec![Layout::Tabs(merges), Layout::Vertical(metrics, vec![]), events], vec![2.0, 1.5, 1.5]);
    Layout::Vertical(vec![top, Layout::Horizontal(maps, vec![]), bottom], vec![3.0, 2.0, 3.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_names_every_view() {
        let robots = ["experia".to_string(), "prawn".to_string()];
        let l = run_layout(&robots, &["sift".into(), "rmap".into()], false);
        let names = l.view_names();
        assert!(names.iter().any(|n| n.starts_with("world")));
        assert!(names.contains(&"experia: SLAM map".to_string()));
        assert!(names.contains(&"merge: rmap".to_string()));
        assert!(names.contains(&"events".to_string()));
        assert!(!names.iter().any(|n| n.starts_with("team") || n.starts_with("coverage")), "{names:?}");
        let team = run_layout(&robots, &["cascade".into()], true).view_names();
        for view in ["team (team maps, merge attempts, goals)", "coverage (share)", "online merges (count)"] {
            assert!(team.contains(&view.to_string()), "{view}: {team:?}");
        }
    }

    #[test]
    fn a_team_run_records_goals_attempts_team_maps_and_coverage_when_they_change() {
        use crate::team::AttemptOutcome;
        use mrslam_core::pose;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("team.rrd");
        let rec = Recorder::open(&[crate::Target::File(path.clone())], "team", "team").unwrap();
        let mut v = RunRecorder::new(rec);
        let robots = [
            RobotInfo { name: "a".into(), start: pose(0.0, 0.0, 0.0) },
            RobotInfo { name: "b".into(), start: pose(5.0, 0.0, 0.0) },
        ];
        let grid = OccupancyGrid::new(10, 10, 0.1, Pose2::identity()).unwrap();
        v.begin(&[], &grid, &robots, &[], true);
        for (i, r) in robots.iter().enumerate() {
            let state = SlamState {
                scans: 1,
                best: &r.start,
                hypotheses: &[],
                effective: None,
                resamples: 0,
                frame: Some(r.start),
            };
            v.slam(i, state);
        }
        let p = |x: f64| Point2::new(x, 0.0);
        v.set_time(1, 0.1);
        v.goal(0, &[p(1.0), p(2.0)], false);
        v.goal(0, &[p(1.0), p(2.0)], false); // unchanged: nothing logged
        v.set_time(2, 0.2);
        v.goal(0, &[p(1.0), p(2.0)], true); // now the team's: logged again
        v.goal(0, &[], true); // gone: cleared
        let (ta, tb) = (["a".to_string()], ["b".to_string()]);
        let refused = AttemptView {
            robots: ["a", "b"],
            at: [p(0.0), p(5.0)],
            teams: [&ta, &tb],
            outcome: AttemptOutcome::Refused,
            stage: None,
            reason: Some("too few inliers"),
            error: None,
        };
        v.attempt(&refused);
        v.set_time(3, 0.2 + crate::team::ATTEMPT_SHOW_S); // the line is cleared
        v.attempt(&AttemptView { outcome: AttemptOutcome::Correct, reason: None, error: Some((0.5, 0.02)), ..refused });
        v.team_map(0, &grid);
        v.coverage(0.5, 0.1);
        v.finish().unwrap();

        let s = crate::inspect::summarize(&path).unwrap();
        let at = |e: &str| s.rows_at(e) - s.static_rows.get(e).copied().unwrap_or(0);
        assert_eq!(at("/robots/a/slam/goal"), 3, "{:?}", s.rows);
        assert_eq!(at("/robots/a/slam/goal/path"), 2);
        assert_eq!(at("/robots/b/slam/goal"), 0);
        assert_eq!(at("/team/events"), 2);
        assert_eq!(at("/team/attempts"), 3, "a line, its clearing, a line");
        assert_eq!(at("/team/maps/a"), 1);
        assert_eq!((at("/metrics/coverage/mapped"), at("/metrics/coverage/redundancy")), (1, 1));
        // A zero at the start, one value per attempt (two when it changed: a step), one per coverage sample.
        assert_eq!(at("/metrics/merges/accepted"), 1 + 1 + 2 + 1);
        assert_eq!(at("/metrics/merges/refused"), 1 + 2 + 1 + 1);
        assert_eq!(at("/metrics/merges/false"), 1 + 1 + 1 + 1);
    }
}
