//! Scan-matched odometry: every scan matched against a local map of the scans just before it, so the filter
//! moves its particles by what the laser saw rather than by what the wheels counted.
//!
//! Not in GMapping, which matches only the scans it processes (one per metre by default) and moves the
//! particles between them by raw odometry. On real robots that odometry breaks in ways its Gaussian noise
//! model does not cover: a heading that turns the wrong way while the robot rotates on the spot, wheels
//! that slip, scans stamped a tenth of a second after they were taken. Matching every scan (at 5-40 Hz the
//! increments are centimetres and a degree or two, well inside the matcher's basin) removes those errors
//! before the particle filter sees them, at the cost of one match per scan rather than one per particle.
//!
//! The local map is a pair of overlapping submaps (as Cartographer's local SLAM keeps them): every scan is
//! inserted into both; a submap that has received `2 × submap_scans` scans is replaced by an empty one, so
//! the older of the two always holds between `submap_scans` and `2 × submap_scans` recent scans and is the
//! one matched against. Its frame is the first scan's odometry pose; it drifts slowly over long distances,
//! which is what the particle filter is there to correct.
//!
//! The matcher is the likelihood-field matcher ([`crate::field`]): a heading search, a hill climb and
//! Gauss-Newton refinement of the scan score times a Gaussian prior centred on the raw odometry increment
//! (GMapping's noise model over that increment, with floors; [`ScanOdometryParams::prior`] weighs its
//! translation), so a direction the scan does not observe (along a featureless corridor) keeps the odometry's
//! increment.

use crate::map_build::MapParams;
use crate::motion::MotionModel;
use crate::scan_matcher::MatcherParams;
use crate::scan_matcher::{MotionPrior, PreparedScan, ScanMatcher, Scratch};
use crate::tile_map::TileMap;
use mrslam_core::{LaserScan, Pose2};
use mrslam_core::{Xyt, pose, pose::relative};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;

thread_local! {
    /// Each thread's matcher scratch, kept from one scan to the next (its field's buffers are derived data:
    /// results do not depend on which a match reuses), and out of the odometry so that it stays `Sync`.
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Smallest standard deviations (x, y metres; heading radians) of the prior on an increment: a robot
/// that did not move by its odometry may still have moved a little.
const MIN_PRIOR_SIGMA: [f64; 3] = [0.01, 0.01, 0.01];
/// A match is used only when at least this fraction of the matched beams found a surface at the result.
const MIN_MATCHED_FRACTION: f64 = 0.3;
/// An increment is matched turned round too when it moves at least this far, metres (a shorter one turned
/// round lands within the matcher's reach of the truth either way).
const MIN_TURN_ROUND: f64 = 0.02;
/// The increment is matched turned round only when its match as logged scores less than this per beam (1 on a
/// wall; a match left 4 cm or more from the truth by a reversed increment scores 0.2-0.73 on the Freiburg 079
/// log read without its ODOM lines, good matches 0.8-0.96): the check costs a second match.
const TURN_ROUND_BELOW: f64 = 0.8;
/// The increment turned round is taken when its match scores this many times the increment's as logged: where
/// the scan cannot tell them apart (along a featureless corridor) the odometry's direction stands.
const TURN_ROUND_MARGIN: f64 = 1.2;

/// Scan-matched odometry's settings (not GMapping).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScanOdometryParams {
    /// `scan_odometry`: match every scan against a local map of the scans before it and move the particles by
    /// the matched increments instead of the raw odometry's (see `scan_odometry`). Off (the default): raw
    /// odometry, as GMapping.
    pub enabled: bool,
    /// `scan_odometry_submap`: scans per submap of the local map (it matches against the last `submap` to
    /// 2 × `submap` scans).
    pub submap: usize,
    /// `scan_odometry_range`, metres: beams longer than this (or than `max_urange`) are not used.
    pub range: f64,
    /// `scan_odometry_sigma`: the matcher's score sigma (as the matcher's `sigma`, m²).
    pub sigma: f64,
    /// `scan_odometry_heading_search`, radians: the matcher tries headings within ± this of the odometry's
    /// before it climbs (0: off).
    pub heading_search: f64,
    /// `scan_odometry_reach`, cells: the field reach (as the matcher's `field_reach`). Its increments are
    /// centimetres, so a short reach suffices, and its field is built for every scan.
    pub reach: i32,
    /// `scan_odometry_turn_round`: when an increment's match as logged is doubtful (under 0.8 per beam), also match
    /// it with its translation turned round, and keep that when the scan fits it clearly better (1.2 times the
    /// score). Why: some robots' odometry counts reversing as driving ahead (the speed's magnitude integrated); a
    /// log's ODOM lines can say so by their speed (the reader's reversing repair), its scan lines' own odometry
    /// fields cannot, and the prior on the logged increment then holds every match 2 × the reversed distance from
    /// the truth.
    pub turn_round: bool,
    /// `scan_odometry_line_lag`: a log without an odometry stream (one odometry pose per scan line) has its lag
    /// behind the scans estimated from the scans' matched heading changes and is re-timed by it
    /// ([`crate::odometry_lag`]): a logger that wrote the last reading it had is a fraction of a scan period late.
    pub line_lag: bool,
    /// `scan_odometry_line_lag_s`, seconds: re-time the scan lines' odometry by this lag instead of the
    /// estimated one (positive: the odometry is late), when `line_lag` is on; 0 (the default): estimate it.
    /// For a user who knows the lag, and to measure how a map depends on it.
    pub line_lag_s: f64,
    /// `scan_odometry_prior`: the weight of the prior on the odometry's increment in translation (the variances of
    /// its x and y divided by it; its heading keeps GMapping's noise model). 1 (the default): GMapping's noise model
    /// over the increment, with floors. At 0.5 ACES without its ODOM lines maps 0.0384 -> 0.0371 m, but 4 of 13
    /// forced lags of it break instead of 2 (BENCHMARKS.md).
    pub prior: f64,
}

impl Default for ScanOdometryParams {
    fn default() -> Self {
        ScanOdometryParams {
            enabled: false,
            submap: 60,
            range: 30.0,
            sigma: 0.001,
            heading_search: 0.1,
            reach: 3,
            turn_round: true,
            line_lag: true,
            line_lag_s: 0.0,
            prior: 1.0,
        }
    }
}

/// What scan-matched odometry did with one scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OdometryStep {
    /// The first scan: it starts the local map.
    First,
    /// Matched: the pose is the match's.
    Matched,
    /// Not matched (too few beams found a surface, or none were usable): the raw increment was kept.
    Dead,
    /// Matched with the increment's translation turned round ([`ScanOdometryParams::turn_round`]).
    TurnedRound,
}

/// Scan-matched odometry (see the module documentation).
#[derive(Debug, Clone)]
pub struct ScanOdometry {
    matcher: ScanMatcher,
    delta: f64,
    max_range: f64,
    max_urange: f64,
    submap_scans: usize,
    /// The two submaps and the scans each has received.
    submaps: [(TileMap, usize); 2],
    /// The raw odometry pose of the last scan.
    last_raw: Option<Pose2>,
    /// The corrected pose of the last scan (the local map's frame).
    pose: Xyt,
    /// GMapping's noise model, for the prior.
    noise: MotionModel,
    /// What the prior's translation sigmas are multiplied by: 1/√[`ScanOdometryParams::prior`].
    translation_scale: f64,
    /// Scans inserted so far.
    inserted: usize,
    turn_round: bool,
    matched: usize,
    turned_round: usize,
    dead: usize,
}

impl ScanOdometry {
    /// Scan-matched odometry with settings `so`, its matcher set up from the filter's `matcher` for one scan
    /// alone, on grids and ranges of `map`, its prior from `noise`, for a laser mounted at `laser`.
    pub fn new(
        so: &ScanOdometryParams,
        matcher: &MatcherParams,
        map: &MapParams,
        noise: MotionModel,
        laser: Xyt,
    ) -> Self {
        let matcher_params = MatcherParams {
            sigma: so.sigma,
            heading_search: so.heading_search,
            motion_prior: 1.0,
            field_reach: so.reach,
            ..matcher.alone()
        };
        ScanOdometry {
            matcher: ScanMatcher::new(matcher_params, laser, false),
            delta: map.delta,
            max_range: map.max_range,
            max_urange: so.range.min(map.max_urange),
            submap_scans: so.submap.max(1),
            submaps: [(TileMap::new(map.delta), 0), (TileMap::new(map.delta), 0)],
            last_raw: None,
            pose: Xyt { x: 0.0, y: 0.0, theta: 0.0 },
            noise,
            translation_scale: 1.0 / so.prior.sqrt(),
            inserted: 0,
            turn_round: so.turn_round,
            matched: 0,
            turned_round: 0,
            dead: 0,
        }
    }

    /// Takes one scan with its raw odometry pose; returns the corrected odometry pose (the local map's
    /// frame) and what was done.
    pub fn update(&mut self, raw: &Pose2, scan: &LaserScan) -> (Pose2, OdometryStep) {
        let prepared = PreparedScan::new(scan, self.max_range.min(scan.range_max as f64), self.max_urange, 0);
        let step = match self.last_raw {
            None => {
                self.pose = Xyt::from_pose(raw);
                OdometryStep::First
            }
            Some(last) => {
                let Xyt { x: dx, y: dy, theta: dt } = Xyt::from_pose(&relative(&last, raw));
                let older = if self.submaps[0].1 >= self.submaps[1].1 { 0 } else { 1 };
                let logged = self.match_increment(older, (dx, dy, dt), &prepared);
                let doubtful = logged.is_none_or(|l| l.score < TURN_ROUND_BELOW * prepared.matched.len() as f64);
                let turned = (self.turn_round && doubtful && dx.hypot(dy) >= MIN_TURN_ROUND)
                    .then(|| self.match_increment(older, (-dx, -dy, dt), &prepared))
                    .flatten()
                    .filter(|t| logged.is_none_or(|l| t.score > TURN_ROUND_MARGIN * l.score));
                if let Some(m) = turned {
                    self.pose = m.pose;
                    self.turned_round += 1;
                    OdometryStep::TurnedRound
                } else if let Some(m) = logged {
                    self.pose = m.pose;
                    self.matched += 1;
                    OdometryStep::Matched
                } else {
                    self.pose = self.predict((dx, dy, dt));
                    self.dead += 1;
                    OdometryStep::Dead
                }
            }
        };
        self.last_raw = Some(*raw);
        self.insert(&prepared);
        (self.pose.to_pose(), step)
    }

    /// Matches the scan against submap `older` from the last pose moved by `increment` (robot frame), with the
    /// motion prior centred there; `None` when the match is not accepted or too few beams found a surface.
    fn match_increment(
        &mut self,
        older: usize,
        (dx, dy, dt): (f64, f64, f64),
        prepared: &PreparedScan,
    ) -> Option<crate::scan_matcher::MatchResult> {
        if prepared.matched.is_empty() {
            return None;
        }
        let predicted = self.predict((dx, dy, dt));
        let [sx, sy, st] = self.noise.sigmas(dx, dy, dt);
        let prior = MotionPrior {
            sx: sx.max(MIN_PRIOR_SIGMA[0]) * self.translation_scale,
            sy: sy.max(MIN_PRIOR_SIGMA[1]) * self.translation_scale,
            st: st.max(MIN_PRIOR_SIGMA[2]),
        };
        let mut scratch = SCRATCH.take();
        let m = self.matcher.match_scan(&self.submaps[older].0, &predicted, prepared, Some(&prior), &mut scratch);
        SCRATCH.set(scratch);
        (m.accepted && m.matched as f64 >= MIN_MATCHED_FRACTION * prepared.matched.len() as f64).then_some(m)
    }

    /// The last pose moved by `increment` (robot frame).
    fn predict(&self, (dx, dy, dt): (f64, f64, f64)) -> Xyt {
        Xyt::from_pose(&(self.pose.to_pose() * pose(dx, dy, dt)))
    }

    /// Inserts the scan's hits at the current pose into the submaps, replacing a full one by an empty one.
    fn insert(&mut self, prepared: &PreparedScan) {
        let (i, n) = (self.inserted, self.submap_scans);
        if i % (2 * n) == 0 {
            self.submaps[0] = (TileMap::new(self.delta), 0);
        }
        // The second submap starts `n` scans after the first, so the two always overlap by half.
        if i >= n && (i - n) % (2 * n) == 0 {
            self.submaps[1] = (TileMap::new(self.delta), 0);
        }
        let lp = self.matcher.laser_pose(&self.pose);
        let (s, c) = lp.theta.sin_cos();
        for (map, count) in self.submaps.iter_mut().take(if i >= n { 2 } else { 1 }) {
            for b in &prepared.hits {
                let (dx, dy) = (c * b.c - s * b.s, s * b.c + c * b.s);
                // A hit outside the largest map is dropped: the local map only needs the scans near it.
                let _ = map.add_beam_hit(lp.x + b.r * dx, lp.y + b.r * dy, dx, dy);
            }
            *count += 1;
        }
        self.inserted += 1;
    }

    /// Scans matched and scans whose raw increment was kept.
    pub fn counts(&self) -> (usize, usize) {
        (self.matched + self.turned_round, self.dead)
    }

    /// Scans matched with their increment turned round ([`ScanOdometryParams::turn_round`]).
    pub fn turned_round(&self) -> usize {
        self.turned_round
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{self, Drift, Lidar};
    use mrslam_core::pose::normalize_angle;

    /// (translation m, rotation rad) of the error of the end pose relative to the start pose.
    fn end_error(est: &[Pose2], truth: &[Pose2]) -> (f64, f64) {
        let e = relative(&relative(&est[0], &est[est.len() - 1]), &relative(&truth[0], &truth[truth.len() - 1]));
        let Xyt { x, y, theta: t } = Xyt::from_pose(&e);
        (x.hypot(y), normalize_angle(t).abs())
    }

    #[test]
    fn matched_increments_undo_slipping_wheels_and_a_heading_that_turns_the_wrong_way() {
        let path: Vec<Pose2> =
            synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.05).into_iter().take(500).collect();
        let drift = Drift { scale: 0.05, heading_per_m: 0.05, sigma_trans: 0.05, sigma_rot: 0.05 };
        let mut run =
            synthetic::simulate(&synthetic::office_map(), &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &drift, 7);
        // The heading glitch of a real log (Freiburg 079 at 1380 s): while the robot turns on the spot at the
        // first corner, the odometry's heading lags the truth by 0.03 rad per scan for 30 scans.
        let turn = (1..path.len())
            .find(|&i| {
                let Xyt { x: dx, y: dy, theta: dt } = Xyt::from_pose(&relative(&path[i - 1], &path[i]));
                dt.abs() > 0.01 && dx.hypot(dy) < 1e-6
            })
            .expect("the path turns");
        let mut wrong = Pose2::identity();
        for i in turn..path.len() {
            if i < turn + 30 {
                wrong *= pose(0.0, 0.0, -0.03);
            }
            run.odometry[i].pose *= wrong;
        }
        let params = crate::SlamParams::default();
        let laser = Xyt { x: 0.1, y: 0.0, theta: 0.0 };
        let mut so = ScanOdometry::new(&params.scan_odometry, &params.matcher, &params.map, params.motion, laser);
        let mut corrected = Vec::new();
        let mut steps = Vec::new();
        for (o, s) in run.odometry.iter().zip(&run.scans) {
            let (p, step) = so.update(&o.pose, s);
            corrected.push(p);
            steps.push(step);
        }
        assert_eq!(steps[0], OdometryStep::First);
        assert_eq!(so.counts(), (path.len() - 1, 0), "every scan after the first is matched");
        let raw: Vec<Pose2> = run.odometry.iter().map(|o| o.pose).collect();
        let (raw_t, raw_r) = end_error(&raw, &path);
        let (t, r) = end_error(&corrected, &path);
        assert!(
            raw_t > 1.0 && raw_r > 0.15,
            "the odometry must be bad for this test to mean anything: {raw_t} m {raw_r} rad"
        );
        assert!(t < 0.1 && r < 0.01, "scan odometry's end pose error {t} m {r} rad");
        // Every increment, not just the end: no step is off by more than 2 cm or 0.5°.
        for i in 1..path.len() {
            let e = relative(&relative(&corrected[i - 1], &corrected[i]), &relative(&path[i - 1], &path[i]));
            let Xyt { x, y, theta: th } = Xyt::from_pose(&e);
            assert!(x.hypot(y) < 0.02 && th.abs() < 0.5f64.to_radians(), "step {i}: {x} {y} {th}");
        }
    }

    #[test]
    fn an_odometry_that_counts_reversing_as_driving_ahead_is_turned_round_by_the_scans() {
        // Along the office's first corridor: 2.5 m ahead, 2 m back (heading unchanged), 2.5 m ahead, 5 cm a scan.
        let ahead: Vec<Pose2> =
            synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.05).into_iter().take(51).collect();
        let straight = ahead.windows(2).all(|w| Xyt::from_pose(&relative(&w[0], &w[1])).theta.abs() < 1e-9);
        assert!(straight, "the office's first 2.5 m must be straight");
        let mut path = ahead.clone();
        path.extend(ahead[10..50].iter().rev());
        path.extend(&ahead[11..]);
        let mut run = synthetic::simulate(
            &synthetic::office_map(),
            &path,
            0.1,
            &Lidar::sick(),
            pose(0.1, 0.0, 0.0),
            &Drift::none(),
            3,
        );
        // The odometry integrates the speed's magnitude: backing up reads as driving ahead.
        let mut odo = run.odometry[0].pose;
        for i in 1..path.len() {
            let Xyt { x, y, theta } = Xyt::from_pose(&relative(&path[i - 1], &path[i]));
            odo *= pose(x.abs(), y, theta);
            run.odometry[i].pose = odo;
        }
        let run_with = |turn_round: bool| {
            let mut params = crate::SlamParams::matched();
            params.scan_odometry.turn_round = turn_round;
            let laser = Xyt { x: 0.1, y: 0.0, theta: 0.0 };
            let mut so = ScanOdometry::new(&params.scan_odometry, &params.matcher, &params.map, params.motion, laser);
            let poses: Vec<Pose2> = run.odometry.iter().zip(&run.scans).map(|(o, s)| so.update(&o.pose, s).0).collect();
            (end_error(&poses, &path).0, so.turned_round())
        };
        let (error, turned) = run_with(true);
        let (error_without, _) = run_with(false);
        assert!(error_without > 1.0, "the reversing must break the match without turning round: {error_without} m");
        assert!(error < 0.05, "end pose {error} m from the truth (without turning round: {error_without} m)");
        assert_eq!(turned, 40, "the 40 steps backing up, and only they, turned round");
    }
}
