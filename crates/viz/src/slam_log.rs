//! What a SLAM run on a recorded log records, and how often (`mrslam slam LOG --rrd`).
//!
//! There is no truth here: the display frame is the SLAM map frame. The odometry is drawn in its own frame,
//! placed so that its first pose sits on the filter's first pose, so that the picture shows the odometry's drift
//! as the gap between the two paths. Timelines as in a run: `step` is the reading's index in the log and
//! `sim_time` the log's time since its first scan.
//!
//! Throttling, so that a 45-minute log stays well under 100 MB: the pose, the particles, the scan and Neff are
//! logged at every processed scan (a few KB each); the paths, redrawn whole, and the map at most at the
//! [`Rates::LOG`] periods of log time (2 s, 10 s). The map is the best particle's own map (hits and seen cells,
//! cheap to take; see `Rbpf::live_map`), in one-byte greys; the output map, rebuilt from every scan, is logged
//! once at the end.

use crate::VizError;
use crate::blueprint::{Layout, ViewKind, query};
use crate::convert::{Rgba, color, lighten, pose_xy, ramp, robot_color, with_alpha};
use crate::metrics::Level;
use crate::paths;
use crate::recorder::{Recorder, RecordingStats};
use crate::run::Rates;
use crate::world::layer;
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use rerun::components::{DrawOrder, Radius};
use rerun::{EntityPath, Points2D};

/// A scan the filter processed, as plain data.
pub struct ProcessedScan<'a, P: Iterator<Item = (Pose2, f64)>> {
    /// The best particle's pose, map frame.
    pub best: &'a Pose2,
    /// The scan's end points, map frame (from the best particle's pose).
    pub points: &'a [Point2<f64>],
    /// Particles (pose in the map frame, normalised weight).
    pub particles: P,
    /// Effective sample size after the update.
    pub neff: f64,
    /// Whether the update resampled.
    pub resampled: bool,
    /// Log time over processing time so far; wall-clock, so the one series that differs between two runs.
    pub realtime_factor: Option<f64>,
}

/// One relation of the benchmark, scored: where and when its second pose lies, and its errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelationMark {
    /// Index in the log of the scan at the relation's second stamp.
    pub index: u64,
    /// Log time of the relation's second stamp, seconds since the first scan.
    pub time: f64,
    /// The trajectory's pose at that stamp, map frame.
    pub at: Pose2,
    /// Translational error, metres.
    pub translation: f64,
    /// Rotational error, radians.
    pub rotation: f64,
}

/// Colour of the loop edges.
const LOOP_EDGE: Rgba = [255, 140, 0, 200];

/// Translational error drawn brightest on the path, metres.
const RELATION_SCALE_M: f64 = 0.2;

/// Records a SLAM run on a log: see the module docs.
#[derive(Debug)]
pub struct SlamLogRecorder {
    rec: Recorder,
    rates: Rates,
    name: String,
    color: Rgba,
    slam_path: Vec<Pose2>,
    odom_path: Vec<Pose2>,
    odom_frame_logged: bool,
    next_path: f64,
    next_map: f64,
    map_dirty: bool,
    resamples: usize,
}

impl SlamLogRecorder {
    /// Wraps an open recording of robot `name` (e.g. the log's file name) and logs what is static and the
    /// layout.
    pub fn new(rec: Recorder, name: &str) -> Self {
        let mut s = SlamLogRecorder {
            rec,
            rates: Rates::LOG,
            name: name.to_string(),
            color: robot_color(0),
            slam_path: Vec::new(),
            odom_path: Vec::new(),
            odom_frame_logged: false,
            next_path: 0.0,
            next_map: 0.0,
            map_dirty: false,
            resamples: 0,
        };
        let (n, c) = (name, s.color);
        s.rec.log_display_frame();
        s.rec.log_series_style(&paths::metric("neff", &[n]), &format!("{n} Neff"), c);
        s.rec.log_series_style(&paths::metric("realtime", &[n]), &format!("{n} real-time factor"), c);
        s.rec.log_series_style(&paths::metric("relations", &[n, "translation"]), "translation (m)", c);
        let light = lighten(c, 0.5);
        s.rec.log_series_style(&paths::metric("relations", &[n, "rotation"]), "rotation (deg)", light);
        s.rec.send_layout(&slam_layout(n));
        s
    }

    /// Changes the rates.
    pub fn with_rates(mut self, rates: Rates) -> Self {
        self.rates = rates;
        self
    }

    /// Sets the time of what follows: the reading's index and the log time since the first scan.
    pub fn set_time(&mut self, index: u64, log_time: f64) {
        self.rec.set_time(index, log_time);
    }

    /// Logs an event.
    pub fn event(&mut self, level: Level, text: &str) {
        self.rec.log_event(level, text);
    }

    /// A reading's odometry pose (odometry frame); every reading, processed or not. `first_slam` is the filter's
    /// first pose, where the odometry frame is placed (so that the two paths start together).
    pub fn odometry(&mut self, odom: &Pose2, first_slam: Option<&Pose2>) {
        if !self.odom_frame_logged
            && let Some(s) = first_slam
        {
            self.odom_frame_logged = true;
            self.rec.log_frame(&paths::robot(&self.name, &["odom"]), &(s * odom.inverse()), true);
        }
        self.odom_path.push(*odom);
        let c = with_alpha(lighten(self.color, 0.5), 200);
        self.rec.log_pose(&paths::robot(&self.name, &["odom", "pose"]), odom, c, "");
    }

    /// A processed scan: the best pose, the particles, the scan from the best pose, Neff, the real-time factor,
    /// a resampling event.
    pub fn processed<P: Iterator<Item = (Pose2, f64)>>(&mut self, s: ProcessedScan<'_, P>) {
        let name = self.name.clone();
        let c = self.color;
        self.slam_path.push(*s.best);
        self.map_dirty = true;
        self.rec.log_pose(&paths::robot(&name, &["slam", "pose"]), s.best, lighten(c, 0.25), "SLAM");
        let particles: Vec<(Pose2, f64)> = s.particles.collect();
        self.rec.log_particles(&paths::robot(&name, &["slam", "particles"]), &particles);
        self.rec.log_scan_points(&paths::robot(&name, &["scan"]), s.points, with_alpha(lighten(c, 0.3), 220));
        self.rec.log_scalar(&paths::metric("neff", &[&name]), s.neff);
        if let Some(f) = s.realtime_factor {
            self.rec.log_scalar(&paths::metric("realtime", &[&name]), f);
        }
        if s.resampled {
            self.resamples += 1;
            let text = format!("{name}: particles resampled (#{}, Neff {:.1} before)", self.resamples, s.neff);
            self.rec.log_event(Level::Info, &text);
        }
        if self.rec.sim_time() >= self.next_path {
            self.paths(None);
        }
    }

    /// Logs the SLAM and odometry paths now; `slam` replaces the SLAM path first (e.g. after loop closure).
    pub fn paths(&mut self, slam: Option<&[Pose2]>) {
        if let Some(p) = slam {
            self.slam_path = p.to_vec();
        }
        self.next_path = self.rec.sim_time() + self.rates.path_period_s;
        let (name, c) = (self.name.clone(), self.color);
        self.rec.log_path(&paths::robot(&name, &["odom", "path"]), &self.odom_path, with_alpha(lighten(c, 0.5), 200));
        self.rec.log_path(&paths::robot(&name, &["slam", "path"]), &self.slam_path, lighten(c, 0.25));
    }

    /// The online loop closure moved the trajectory: the SLAM path is replaced by `path` at once, the loop edges
    /// (older node, newer node) are drawn as segments, and an event says what changed.
    pub fn loops_closed(&mut self, path: &[Pose2], edges: &[(Pose2, Pose2)], text: &str) {
        let name = self.name.clone();
        self.paths(Some(path));
        let segments: Vec<(Point2<f64>, Point2<f64>)> =
            edges.iter().map(|(a, b)| (a.translation.vector.into(), b.translation.vector.into())).collect();
        let colors = vec![LOOP_EDGE; segments.len()];
        self.rec.log_matches(&paths::robot(&name, &["slam", "loop_edges"]), &segments, &colors);
        self.rec.log_event(Level::Info, text);
        self.map_dirty = true;
        self.next_map = self.rec.sim_time();
    }

    /// True when the growing map is due (processed scans since the last one, and the period has passed).
    pub fn map_due(&self) -> bool {
        self.map_dirty && self.rec.sim_time() >= self.next_map
    }

    /// Logs the map (map frame) at `maps/<name>`, in map_server's greys.
    pub fn map(&mut self, grid: &OccupancyGrid) {
        self.next_map = self.rec.sim_time() + self.rates.map_period_s;
        self.map_dirty = false;
        let name = self.name.clone();
        self.rec.log_grey_map(&paths::map(&name), grid, &Pose2::identity());
    }

    /// Logs the relations' errors: as time series at each relation's second stamp, and as dots on the path at
    /// its pose there, brighter for larger errors (full at 0.2 m).
    pub fn relations(&mut self, marks: &[RelationMark]) {
        let name = self.name.clone();
        let (now, step) = (self.rec.sim_time(), self.rec.step());
        let mut sorted: Vec<&RelationMark> = marks.iter().collect();
        sorted.sort_by(|a, b| a.time.total_cmp(&b.time));
        for m in sorted {
            self.rec.set_time(m.index, m.time);
            self.rec.log_scalar(&paths::metric("relations", &[&name, "translation"]), m.translation);
            self.rec.log_scalar(&paths::metric("relations", &[&name, "rotation"]), m.rotation.to_degrees());
        }
        self.rec.set_time(step, now);
        let tone = |m: &RelationMark| ramp((m.translation / RELATION_SCALE_M).clamp(0.0, 1.0));
        let arch = Points2D::new(marks.iter().map(|m| pose_xy(&m.at)))
            .with_colors(marks.iter().map(|m| color(tone(m))))
            .with_radii([Radius::new_ui_points(3.0)])
            .with_labels(marks.iter().map(|m| format!("{:.3} m, {:.2} deg", m.translation, m.rotation.to_degrees())))
            .with_show_labels(false)
            .with_draw_order(DrawOrder::from(layer::POINTS));
        self.rec.log(&paths::robot(&name, &["relations"]), &arch);
    }

    /// Flushes and closes the recording.
    pub fn finish(self) -> Result<RecordingStats, VizError> {
        self.rec.finish()
    }
}

/// The layout of a SLAM run on a log: the map with the paths, particles and scan on the left; Neff, the
/// real-time factor, the relations' errors and the events on the right.
pub fn slam_layout(name: &str) -> Layout {
    let map = Layout::view(
        ViewKind::Spatial2D,
        &format!("{name}: map, paths, particles, scan"),
        EntityPath::root(),
        &[query('+', &paths::root("maps"), true), query('+', &paths::root("robots"), true)],
    );
    let series = |group: &str, title: &str| {
        let origin = paths::metric(group, &[]);
        Layout::view(ViewKind::TimeSeries, title, origin.clone(), &[query('+', &origin, true)])
    };
    let events = Layout::view(ViewKind::TextLog, "events", paths::events(), &[query('+', &paths::events(), false)]);
    let side = Layout::Vertical(
        vec![
            series("neff", "Neff"),
            series("realtime", "real-time factor"),
            series("relations", "relation errors"),
            events,
        ],
        vec![],
    );
    Layout::Horizontal(vec![map, side], vec![3.0, 1.5])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_names_every_view() {
        let names = slam_layout("fr079").view_names();
        for want in ["fr079: map, paths, particles, scan", "Neff", "real-time factor", "relation errors", "events"] {
            assert!(names.iter().any(|n| n == want), "{want}: {names:?}");
        }
    }
}
