//! The filter: GMapping's `GridSlamProcessor::processScan` loop over odometry + scans.

use crate::backend::{Correction, Hypotheses, SlamBackend};
use crate::calibration::{CalibrationMatch, OdometryCalibration};
use crate::error::SlamError;
use crate::incremental_map::IncrementalMap;
use crate::loop_closure::LoopClosureReport;
use crate::loop_graph::LoopGraph;
use crate::motion::MotionModel;
use crate::outcome::{Counters, SkipReason, UpdateOutcome, UpdateStats};
use crate::params::SlamParams;
use crate::particle::{Particle, TrajectoryNode, ancestry};
use crate::resample::{normalize, systematic};
use crate::scan_matcher::{Beam, MatchInformation, MatchResult, MotionPrior, PreparedScan, ScanMatcher, Scratch};
use crate::scan_odometry::ScanOdometry;
use crate::tile_map::{Tile, TileMap, TooLarge};
use mrslam_core::{LaserScan, OccupancyGrid, Odometry, Pose2};
use mrslam_core::{Xyt, pose::relative};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::cell::RefCell;
use std::sync::Arc;

/// Odometry farther than this from its frame's origin (metres) is refused as corrupt.
const MAX_ODOM_COORD: f64 = 1e6;
/// Smallest standard deviations (x, y metres; heading radians) of the `motion_prior`: a robot that barely
/// moved still gets a prior the scan can overrule.
const MIN_PRIOR_SIGMA: [f64; 3] = [0.005, 0.005, 0.005];
/// Most beams accepted in one scan.
const MAX_BEAMS: usize = 100_000;

thread_local! {
    /// Each thread's matcher scratch, kept from one update to the next. A scratch per rayon job (`map_init`)
    /// grew its window-sized field buffers afresh at every update: on ACES, 5 million page faults and a
    /// fifth of the CPU time. The field is rebuilt for every match, so results do not depend on which
    /// scratch a particle gets (see [`crate::field`]).
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Memory held by the particles' maps and trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MemoryStats {
    /// Number of particles.
    pub particles: usize,
    /// Distinct tiles across all particles (what is really allocated).
    pub unique_tiles: usize,
    /// Tiles referenced, summed over particles (what N unshared maps would hold).
    pub referenced_tiles: usize,
    /// Bytes of the distinct tiles.
    pub tile_bytes: usize,
    /// Bytes the maps would take without sharing (the referenced tiles' bytes).
    pub unshared_tile_bytes: usize,
    /// Bytes of the particles' tile-pointer arrays.
    pub slot_bytes: usize,
    /// Distinct trajectory nodes.
    pub trajectory_nodes: usize,
    /// Bytes of the distinct trajectory nodes and their scans.
    pub trajectory_bytes: usize,
    /// Bytes of the online loop closure's graph: its nodes and scans, edges and cached submap grids.
    pub loop_graph_bytes: usize,
}

impl MemoryStats {
    /// All bytes counted.
    pub fn total_bytes(&self) -> usize {
        self.tile_bytes + self.slot_bytes + self.trajectory_bytes + self.loop_graph_bytes
    }
}

/// A Rao-Blackwellised particle filter SLAM (GMapping's algorithm).
#[derive(Debug, Clone)]
pub struct Rbpf {
    params: SlamParams,
    laser: Xyt,
    matcher: ScanMatcher,
    motion: MotionModel,
    rng: ChaCha8Rng,
    particles: Vec<Particle>,
    weights: Vec<f64>,
    neff: f64,
    resampled_last: bool,
    odo_pose: Option<Pose2>,
    last_odom_stamp: Option<f64>,
    last_scan_stamp: Option<f64>,
    last_update_stamp: f64,
    linear_distance: f64,
    angular_distance: f64,
    /// Variances (robot frame x, y, heading) the motion model added since the last processed scan.
    motion_var: [f64; 3],
    /// Odometry calibration (see [`crate::FilterParams::odometry_calibration`]).
    calibration: OdometryCalibration,
    /// Scan-matched odometry (see [`SlamParams::scan_odometry`]).
    scan_odometry: Option<ScanOdometry>,
    counters: Counters,
    /// Trajectory poses moved by [`Rbpf::close_loops`] or the online graph, not yet taken
    /// ([`SlamBackend::take_corrections`]).
    corrections: Vec<Correction>,
    /// The online loop closure's pose graph (`loop_closure.enabled` and `loop_closure.online`): the
    /// trajectory and the output map are its; the particles are re-anchored on it when it moves.
    graph: Option<LoopGraph>,
    /// The output map, kept to be extended by the next call of [`Rbpf::map`] while the trajectory only grows.
    map: IncrementalMap,
}

impl Rbpf {
    /// A filter with `params`, a laser mounted at `laser_offset` on the robot, and a seeded RNG.
    pub fn new(params: SlamParams, laser_offset: Pose2, seed: u64) -> Result<Self, SlamError> {
        params.validate().map_err(SlamError::BadParams)?;
        let laser = Xyt::from_pose(&laser_offset);
        if !(laser.x.is_finite() && laser.y.is_finite() && laser.theta.is_finite()) {
            return Err(SlamError::BadLaserOffset);
        }
        let matcher = ScanMatcher::new(params.matcher, laser, params.filter.odometry_calibration > 0.0);
        let motion = params.motion;
        let n = params.filter.particles;
        let graph = (params.loop_closure.enabled && params.loop_closure.online)
            .then(|| LoopGraph::new(params.loop_closure, &params.matcher, params.map, laser));
        let scan_odometry = params
            .scan_odometry
            .enabled
            .then(|| ScanOdometry::new(&params.scan_odometry, &params.matcher, &params.map, params.motion, laser));
        Ok(Rbpf {
            particles: (0..n).map(|_| Particle::new(params.map.delta)).collect(),
            weights: vec![1.0 / n as f64; n],
            neff: n as f64,
            params,
            laser,
            matcher,
            motion,
            rng: ChaCha8Rng::seed_from_u64(seed),
            resampled_last: false,
            odo_pose: None,
            last_odom_stamp: None,
            last_scan_stamp: None,
            last_update_stamp: f64::NEG_INFINITY,
            linear_distance: 0.0,
            angular_distance: 0.0,
            motion_var: [0.0; 3],
            calibration: OdometryCalibration::default(),
            scan_odometry,
            counters: Counters::default(),
            corrections: Vec::new(),
            graph,
            map: IncrementalMap::default(),
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &SlamParams {
        &self.params
    }

    /// The odometry pose of the last reading as the filter used it: the scan-matched one when
    /// `scan_odometry` is on (in its own frame), else the reading's; None until a scan with beams came.
    pub fn odometry_pose(&self) -> Option<Pose2> {
        self.odo_pose
    }

    /// Scans the scan odometry matched, of those the ones matched with their increment turned round, and scans
    /// whose raw increment it kept; zeros when off.
    pub fn scan_odometry_counts(&self) -> (usize, usize, usize) {
        self.scan_odometry.as_ref().map_or((0, 0, 0), |s| {
            let (matched, dead) = s.counts();
            (matched, s.turned_round(), dead)
        })
    }

    /// Feeds one odometry reading and the scan taken with it.
    ///
    /// Every reading moves the particles by the odometry increment (motion model sampling). The scan is
    /// processed (matched, weighted, maybe resampled, mapped) when it is the first, or the robot moved
    /// `linear_update`/`angular_update` since the last processed scan, or `temporal_update` seconds passed.
    ///
    /// Errors (the filter's state is unchanged): non-finite odometry or scan geometry, stamps going
    /// backwards, a map outgrowing its limit. Leniency (counted, not errors): NaN, negative or too-short
    /// beams are ignored ([`Counters::invalid_beams`]); a scan with no beams is skipped.
    pub fn process(&mut self, odom: &Odometry, scan: &LaserScan) -> Result<UpdateOutcome, SlamError> {
        self.validate(odom, scan)?;
        let corrected;
        let odom = match &mut self.scan_odometry {
            Some(so) => {
                corrected = Odometry { pose: so.update(&odom.pose, scan).0, ..*odom };
                &corrected
            }
            None => odom,
        };
        self.last_odom_stamp = Some(odom.stamp);
        self.last_scan_stamp = Some(scan.stamp);
        self.counters.readings += 1;

        let Some(odo_pose) = self.odo_pose else {
            if scan.is_empty() {
                self.counters.skipped_empty += 1;
                return Ok(UpdateOutcome::Skipped(SkipReason::EmptyScan));
            }
            // First scan: it defines the map frame; every particle maps it from the origin.
            self.odo_pose = Some(odom.pose);
            return self.update(scan, true);
        };

        let raw = Xyt::from_pose(&relative(&odo_pose, &odom.pose));
        let Xyt { x: dx, y: dy, theta: dt } = if self.params.filter.odometry_calibration > 0.0 {
            let corrected = self.calibration.correct(raw);
            self.calibration.record(raw, corrected);
            corrected
        } else {
            raw
        };
        for p in &mut self.particles {
            let moved = self.motion.draw_increment(&mut self.rng, &p.pose.to_pose(), dx, dy, dt);
            p.pose = Xyt::from_pose(&moved);
        }
        self.linear_distance += raw.x.hypot(raw.y);
        self.angular_distance += raw.theta.abs();
        let [sx, sy, st] = self.motion.sigmas(dx, dy, dt);
        self.motion_var[0] += sx * sx;
        self.motion_var[1] += sy * sy;
        self.motion_var[2] += st * st;
        self.odo_pose = Some(odom.pose);

        if scan.is_empty() {
            self.counters.skipped_empty += 1;
            return Ok(UpdateOutcome::Skipped(SkipReason::EmptyScan));
        }
        let p = &self.params;
        let due = self.linear_distance >= p.filter.linear_update
            || self.angular_distance >= p.filter.angular_update
            || (p.filter.temporal_update >= 0.0 && scan.stamp - self.last_update_stamp > p.filter.temporal_update);
        if !due {
            self.counters.skipped_not_moved += 1;
            let prepared_invalid = (0..scan.len()).filter(|&i| !scan.is_valid(i) && !scan.is_max_range(i)).count();
            self.counters.invalid_beams += prepared_invalid;
            return Ok(UpdateOutcome::Skipped(SkipReason::NotMoved));
        }
        self.update(scan, false)
    }

    /// Checks a reading before anything changes.
    fn validate(&self, odom: &Odometry, scan: &LaserScan) -> Result<(), SlamError> {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&odom.pose);
        let bad_odom = |message: String| SlamError::BadOdometry { stamp: odom.stamp, message };
        if !odom.stamp.is_finite() {
            return Err(bad_odom("stamp is not finite".into()));
        }
        if !(x.is_finite() && y.is_finite() && t.is_finite()) {
            return Err(bad_odom(format!("pose ({x}, {y}, {t}) is not finite")));
        }
        if x.abs() > MAX_ODOM_COORD || y.abs() > MAX_ODOM_COORD {
            return Err(bad_odom(format!("pose ({x}, {y}) is implausibly far from the origin")));
        }
        let bad_scan = |message: String| SlamError::BadScan { stamp: scan.stamp, message };
        if !scan.stamp.is_finite() {
            return Err(bad_scan("stamp is not finite".into()));
        }
        if !(scan.angle_min.is_finite() && scan.angle_increment.is_finite()) {
            return Err(bad_scan("angle_min or angle_increment is not finite".into()));
        }
        if scan.range_min.is_nan() || scan.range_max.is_nan() || scan.range_max <= 0.0 {
            return Err(bad_scan(format!("range limits [{}, {}] are not usable", scan.range_min, scan.range_max)));
        }
        if scan.len() > MAX_BEAMS {
            return Err(bad_scan(format!("{} beams is more than {MAX_BEAMS}", scan.len())));
        }
        if let Some(prev) = self.last_odom_stamp
            && odom.stamp < prev
        {
            return Err(SlamError::TimeWentBackwards { what: "odometry", previous: prev, got: odom.stamp });
        }
        if let Some(prev) = self.last_scan_stamp
            && scan.stamp < prev
        {
            return Err(SlamError::TimeWentBackwards { what: "scan", previous: prev, got: scan.stamp });
        }
        Ok(())
    }

    /// Matches, weighs, resamples and maps one scan.
    fn update(&mut self, scan: &LaserScan, first: bool) -> Result<UpdateOutcome, SlamError> {
        let p = &self.params;
        let prepared =
            PreparedScan::new(scan, p.map.max_range.min(scan.range_max as f64), p.map.max_urange, p.matcher.lskip);
        self.counters.invalid_beams += prepared.invalid;
        let n = self.particles.len();
        let mut matched_particles = 0;
        let mut score_sum = 0.0;
        let mut resampled = false;
        let mut neff = n as f64;
        if !first {
            let matcher = &self.matcher;
            let prepared = &prepared;
            let v = self.motion_var;
            let prior = MotionPrior {
                sx: v[0].sqrt().max(MIN_PRIOR_SIGMA[0]),
                sy: v[1].sqrt().max(MIN_PRIOR_SIGMA[1]),
                st: v[2].sqrt().max(MIN_PRIOR_SIGMA[2]),
            };
            let prior = &prior;
            // Each particle's match is independent of the others': computed in parallel, collected in order,
            // so results do not depend on the number of threads (the scratch holds only rebuilt data).
            // The calibration learns from where each match started and the information at its end.
            let calibrating = self.params.filter.odometry_calibration > 0.0;
            let starts: Vec<Xyt> =
                if calibrating { self.particles.iter().map(|q| q.pose).collect() } else { Vec::new() };
            let results: Vec<MatchResult> = self
                .particles
                .par_iter()
                .map(|part| {
                    // Taken out for the match rather than borrowed: the field's build joins parallel work,
                    // during which this thread may run another particle's match.
                    let mut scratch = SCRATCH.take();
                    let m = matcher.match_scan(&part.map, &part.pose, prepared, Some(prior), &mut scratch);
                    SCRATCH.set(scratch);
                    m
                })
                .collect();
            let information: Vec<Option<MatchInformation>> =
                if calibrating { results.iter().map(|m| m.information).collect() } else { Vec::new() };
            for (part, m) in self.particles.iter_mut().zip(results) {
                if m.accepted {
                    matched_particles += 1;
                }
                part.pose = m.pose;
                score_sum += m.score;
                part.weight += m.likelihood;
                part.weight_sum += m.likelihood;
            }
            let gain = 1.0 / (self.params.filter.ogain * n as f64);
            let logw: Vec<f64> = self.particles.iter().map(|q| q.weight).collect();
            let (w, ne) = normalize(&logw, gain);
            neff = ne;
            self.weights = w;
            if calibrating {
                self.calibrate(&starts, &information);
            }
            if neff < self.params.filter.resample_threshold * n as f64 {
                let u: f64 = self.rng.random();
                let idx = systematic(&self.weights, n, u);
                let mut next = Vec::with_capacity(n);
                for &i in &idx {
                    let mut q = self.particles[i].clone();
                    q.weight = 0.0;
                    next.push(q);
                }
                self.particles = next;
                self.weights = vec![1.0 / n as f64; n];
                resampled = true;
                self.counters.resamples += 1;
            }
        }
        self.neff = crate::resample::neff(&self.weights);
        self.resampled_last = resampled;

        // Map the scan in every particle and extend its trajectory (in parallel: each particle's map is its
        // own).
        let shared_scan = Arc::new(scan.clone());
        let band = self.params.matcher.seen_band;
        let banded = banded_beams(&prepared, band, self.params.map.delta);
        let matcher = &self.matcher;
        let (hits, banded) = (&prepared.hits, &banded);
        let mapped: Result<(), SlamError> = self.particles.par_iter_mut().try_for_each(|part| {
            draw_scan(&mut part.map, &matcher.laser_pose(&part.pose), hits, banded, band).map_err(|_| {
                SlamError::MapTooLarge(format!(
                    "a particle at ({:.1}, {:.1}) m left the largest map supported",
                    part.pose.x, part.pose.y
                ))
            })?;
            part.node = Some(Arc::new(TrajectoryNode {
                stamp: scan.stamp,
                pose: part.pose,
                scan: shared_scan.clone(),
                parent: part.node.take(),
            }));
            Ok(())
        });
        mapped?;
        self.add_to_graph(scan.stamp, &shared_scan)?;
        self.linear_distance = 0.0;
        self.angular_distance = 0.0;
        self.motion_var = [0.0; 3];
        self.calibration.reset_increments();
        self.last_update_stamp = scan.stamp;
        self.counters.processed += 1;
        Ok(UpdateOutcome::Processed(UpdateStats {
            neff,
            resampled,
            matched_particles,
            mean_score: score_sum / n as f64,
            beams_matched: prepared.matched.len(),
            beams_mapped: prepared.hits.len(),
            invalid_beams: prepared.invalid,
            best: self.best_index(),
        }))
    }

    /// Adds the best particle's new node to the online graph (when there is one) and re-anchors the particles
    /// on the graph when its optimisation moved the trajectory.
    fn add_to_graph(&mut self, stamp: f64, scan: &Arc<LaserScan>) -> Result<(), SlamError> {
        let best = self.best_index();
        let Some(graph) = self.graph.as_mut() else { return Ok(()) };
        let Some(node) = self.particles[best].node.as_ref() else { return Ok(()) };
        let increment = match &node.parent {
            Some(parent) => Xyt::from_pose(&relative(&parent.pose.to_pose(), &node.pose.to_pose())),
            None => node.pose,
        };
        let redraw = graph.add(stamp, increment, scan.clone());
        self.take_graph_corrections();
        if redraw {
            self.reanchor()?;
        }
        Ok(())
    }

    /// Moves the online graph's optimisations made since the last call into [`Rbpf::corrections`].
    fn take_graph_corrections(&mut self) {
        if let Some(g) = self.graph.as_mut() {
            let moved = g.take_moved().into_iter();
            self.corrections.extend(moved.map(|(stamp, before, after)| Correction {
                stamp,
                before: before.to_pose(),
                after: after.to_pose(),
            }));
        }
    }

    /// Redraws the particles' maps from the graph's poses (one map, shared) and moves every particle by the
    /// correction at the newest node, so that the filter goes on in the loop-closed map.
    fn reanchor(&mut self) -> Result<(), SlamError> {
        let best = self.best_index();
        let Some(graph) = self.graph.as_mut() else { return Ok(()) };
        let (Some(node), Some(last)) = (self.particles[best].node.clone(), graph.nodes().last()) else {
            return Ok(());
        };
        let (stamp, pose, scan) = (last.stamp, last.pose, last.scan.clone());
        let shift = pose.to_pose() * node.pose.to_pose().inverse();
        let p = &self.params;
        let band = p.matcher.seen_band;
        let mut map = TileMap::new(p.map.delta);
        for n in graph.nodes() {
            let prepared =
                PreparedScan::new(&n.scan, p.map.max_range.min(n.scan.range_max as f64), p.map.max_urange, 0);
            let banded = banded_beams(&prepared, band, p.map.delta);
            draw_scan(&mut map, &self.matcher.laser_pose(&n.pose), &prepared.hits, &banded, band)
                .map_err(|_| SlamError::MapTooLarge("the loop-closed map left the largest map supported".into()))?;
        }
        graph.mark_drawn();
        let newest = Arc::new(TrajectoryNode { stamp, pose, scan, parent: None });
        for part in &mut self.particles {
            part.pose = Xyt::from_pose(&(shift * part.pose.to_pose()));
            part.map = map.clone();
            part.node = Some(newest.clone());
        }
        self.counters.reanchors += 1;
        Ok(())
    }

    /// One step of the odometry calibration (see [`OdometryCalibration`]) from the matches of this update:
    /// `starts` are the particles' motion-model samples, `information` the matcher's scan and prior
    /// information at each match. Runs once the update's weights are known, before resampling and mapping
    /// (the particles' trajectory nodes still end at the previous update).
    fn calibrate(&mut self, starts: &[Xyt], information: &[Option<MatchInformation>]) {
        let matches = self.particles.iter().zip(starts).zip(information).zip(&self.weights).filter_map(
            |(((part, start), info), &weight)| {
                let (Some(MatchInformation { scan, prior }), Some(node)) = (info, part.node.as_ref()) else {
                    return None;
                };
                Some(CalibrationMatch {
                    matched: part.pose,
                    start: *start,
                    previous: node.pose,
                    scan: *scan,
                    prior: *prior,
                    weight,
                })
            },
        );
        self.calibration.update(matches, self.params.filter.odometry_calibration);
    }

    /// The odometry calibration's current estimate: distance scale error a and heading drift b (rad per metre
    /// driven) by which raw increments (dx, dy, dθ) are corrected to ((1+a)·dx, (1+a)·dy, dθ + b·dx); zeros
    /// when `odometry_calibration` is off.
    pub fn odometry_calibration(&self) -> [f64; 2] {
        self.calibration.kappa()
    }

    /// Index of the best particle: the highest lineage log-likelihood (GMapping's `weightSum`), lowest index
    /// on ties.
    pub fn best_index(&self) -> usize {
        let mut best = 0;
        for (i, p) in self.particles.iter().enumerate() {
            if p.weight_sum > self.particles[best].weight_sum {
                best = i;
            }
        }
        best
    }

    /// Current pose of the best particle (map frame), including motion since the last processed scan; with the
    /// online graph, its move since its last node is carried from the graph's newest node.
    pub fn best_pose(&self) -> Pose2 {
        let part = &self.particles[self.best_index()];
        match (self.graph.as_ref().and_then(|g| g.nodes().last()), part.node.as_ref()) {
            (Some(last), Some(node)) => last.pose.to_pose() * relative(&node.pose.to_pose(), &part.pose.to_pose()),
            _ => part.pose.to_pose(),
        }
    }

    /// The particles' current poses and normalised weights (for visualisation).
    pub fn particles(&self) -> impl Iterator<Item = (Pose2, f64)> + '_ {
        self.particles.iter().zip(&self.weights).map(|(p, &w)| (p.pose.to_pose(), w))
    }

    /// Effective sample size of the current normalised weights (N right after a resampling).
    pub fn neff(&self) -> f64 {
        self.neff
    }

    /// True when the last processed scan resampled the particles.
    pub fn resampled_last_update(&self) -> bool {
        self.resampled_last
    }

    /// Running totals.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// The best particle's path: (stamp, robot pose in the map frame) per processed scan, oldest first; with
    /// the online graph, the graph's optimised poses.
    pub fn trajectory(&self) -> Vec<(f64, Pose2)> {
        match &self.graph {
            Some(g) => g.nodes().iter().map(|n| (n.stamp, n.pose.to_pose())).collect(),
            None => self.particle_trajectory(self.best_index()),
        }
    }

    /// The online graph's loop edges as (older, newer) processed-scan indices; empty without the graph.
    pub fn loop_edges(&self) -> Vec<(usize, usize)> {
        self.graph.as_ref().map_or_else(Vec::new, |g| g.loop_edges().collect())
    }

    /// What loop closure did so far (the online graph's report; the end-of-log closure reports at the end).
    pub fn loop_report(&self) -> Option<LoopClosureReport> {
        self.graph.as_ref().map(|g| g.report())
    }

    /// Particle `i`'s path (see [`Rbpf::trajectory`]); empty when there is no such particle.
    pub fn particle_trajectory(&self, i: usize) -> Vec<(f64, Pose2)> {
        let Some(p) = self.particles.get(i) else { return Vec::new() };
        let mut v: Vec<(f64, Pose2)> = ancestry(&p.node).map(|n| (n.stamp, n.pose.to_pose())).collect();
        v.reverse();
        v
    }

    /// Ends loop closure: with the online graph (`loop_closure.online`), its last optimisation; otherwise smooths
    /// the best particle's trajectory by loop closure (see [`SlamParams::loop_closure`]; runs whether or not that
    /// is set). Returns what loop closure did: the trajectory, [`Rbpf::map`] and [`Rbpf::best_pose`] are
    /// the smoothed ones afterwards.
    ///
    /// Meant for the end of a log: the particles' matching maps are not rebuilt, so a filter that goes on
    /// after it matches against maps that do not fit the smoothed trajectory.
    pub fn close_loops(&mut self) -> LoopClosureReport {
        if let Some(g) = self.graph.as_mut() {
            // The last optimisation; the particles are not redrawn (no reading follows).
            g.finish();
            let report = g.report();
            self.take_graph_corrections();
            return report;
        }
        let best = self.best_index();
        let part = &self.particles[best];
        let mut nodes: Vec<&TrajectoryNode> = ancestry(&part.node).collect();
        nodes.reverse();
        let (poses, report) = crate::loop_closure::close_loops(
            &nodes,
            self.laser,
            &self.params.loop_closure,
            &self.params.matcher,
            &self.params.map,
        );
        if report.closures == 0 {
            return report;
        }
        let last_old = nodes.last().map(|n| n.pose);
        let mut chain: Option<Arc<TrajectoryNode>> = None;
        for (n, p) in nodes.iter().zip(&poses) {
            if n.pose != *p {
                let (before, after) = (n.pose.to_pose(), p.to_pose());
                self.corrections.push(Correction { stamp: n.stamp, before, after });
            }
            chain = Some(Arc::new(TrajectoryNode { stamp: n.stamp, pose: *p, scan: n.scan.clone(), parent: chain }));
        }
        let moved = match (last_old, poses.last()) {
            (Some(old), Some(new)) => Xyt::from_pose(&(new.to_pose() * relative(&old.to_pose(), &part.pose.to_pose()))),
            _ => part.pose,
        };
        let part = &mut self.particles[best];
        part.node = chain;
        part.pose = moved;
        report
    }

    /// Each particle's accumulated log-likelihood over its lineage (GMapping's `weightSum`; the best
    /// particle has the highest).
    pub fn lineage_log_likelihoods(&self) -> Vec<f64> {
        self.particles.iter().map(|p| p.weight_sum).collect()
    }

    /// The best particle's own map as its scan matcher sees it ([`crate::dev::TileMap::to_grid`]): cheap, for
    /// watching the map grow; `None` while empty. [`Rbpf::map`] builds the output map.
    pub fn live_map(&self) -> Option<OccupancyGrid> {
        self.particles[self.best_index()].map.to_grid()
    }

    /// The best particle's map as a log-odds grid (occupied +2, free −2, unknown 0; see `map_build`).
    ///
    /// Drawn from the best particle's trajectory (or the loop graph's) as GMapping's ROS node does every
    /// `map_update_interval`; while that trajectory only grew since the last call, only its new scans are traced
    /// (`incremental_map`), otherwise the whole trajectory is.
    pub fn map(&self) -> Result<OccupancyGrid, SlamError> {
        // Oldest first, so a trajectory that grew since the last call extends the last map.
        let nodes: Vec<&TrajectoryNode> = match &self.graph {
            Some(g) => g.nodes().iter().collect(),
            None => {
                let mut n: Vec<&TrajectoryNode> = ancestry(&self.particles[self.best_index()].node).collect();
                n.reverse();
                n
            }
        };
        self.map
            .map(&nodes, &self.laser, &self.params.map)
            .ok_or_else(|| SlamError::MapTooLarge("the trajectory's map exceeds core's grid size limit".into()))
    }

    /// Memory held by the particles' maps and trajectories and the loop graph, counting shared tiles and nodes once.
    pub fn memory_stats(&self) -> MemoryStats {
        let mut tiles: Vec<(usize, usize)> = Vec::new();
        let mut slots = 0;
        for p in &self.particles {
            slots += p.map.tile_slots();
            tiles.extend(p.map.tiles().map(|t| (t as *const Tile as usize, t.bytes())));
        }
        let (referenced, unshared_tile_bytes) = (tiles.len(), tiles.iter().map(|t| t.1).sum());
        tiles.sort_unstable();
        tiles.dedup();
        let mut nodes = std::collections::BTreeSet::new();
        let mut scans = std::collections::BTreeSet::new();
        let mut scan_bytes = 0;
        for p in &self.particles {
            for n in ancestry(&p.node) {
                if !nodes.insert(n as *const TrajectoryNode as usize) {
                    break;
                }
                if scans.insert(Arc::as_ptr(&n.scan) as usize) {
                    scan_bytes += std::mem::size_of::<LaserScan>() + 4 * n.scan.ranges.capacity();
                }
            }
        }
        MemoryStats {
            particles: self.particles.len(),
            unique_tiles: tiles.len(),
            referenced_tiles: referenced,
            tile_bytes: tiles.iter().map(|t| t.1).sum(),
            unshared_tile_bytes,
            slot_bytes: slots * std::mem::size_of::<Option<Arc<Tile>>>(),
            trajectory_nodes: nodes.len(),
            trajectory_bytes: nodes.len() * std::mem::size_of::<TrajectoryNode>() + scan_bytes,
            loop_graph_bytes: self.graph.as_ref().map_or(0, LoopGraph::bytes),
        }
    }
}

impl SlamBackend for Rbpf {
    fn process(&mut self, odom: &Odometry, scan: &LaserScan) -> Result<UpdateOutcome, SlamError> {
        Rbpf::process(self, odom, scan)
    }

    fn finish(&mut self) -> Option<LoopClosureReport> {
        self.params.loop_closure.enabled.then(|| self.close_loops())
    }

    fn map(&self) -> Result<OccupancyGrid, SlamError> {
        Rbpf::map(self)
    }

    fn live_map(&self) -> Option<OccupancyGrid> {
        Rbpf::live_map(self)
    }

    fn best_pose(&self) -> Pose2 {
        Rbpf::best_pose(self)
    }

    fn trajectory(&self) -> Vec<(f64, Pose2)> {
        Rbpf::trajectory(self)
    }

    fn take_corrections(&mut self) -> Vec<Correction> {
        std::mem::take(&mut self.corrections)
    }

    fn odometry_pose(&self) -> Option<Pose2> {
        Rbpf::odometry_pose(self)
    }

    fn hypotheses(&self) -> Hypotheses {
        Hypotheses { poses: self.particles().collect(), effective: Some(self.neff) }
    }

    fn counters(&self) -> Counters {
        self.counters
    }
}

/// Which of a scan's hits also mark their seen band: a beam whose end point lies within half a cell of the last
/// banded beam's adds nothing at this resolution and is skipped (the same beams for every particle).
fn banded_beams(prepared: &PreparedScan, band: f64, delta: f64) -> Vec<bool> {
    let mut banded = vec![false; prepared.hits.len()];
    if band > 0.0 {
        let gap = 0.5 * delta;
        let mut last: Option<(f64, f64)> = None;
        for (flag, b) in banded.iter_mut().zip(&prepared.hits) {
            if last.is_none_or(|(x, y)| (b.x - x) * (b.x - x) + (b.y - y) * (b.y - y) >= gap * gap) {
                *flag = true;
                last = Some((b.x, b.y));
            }
        }
    }
    banded
}

/// Draws a scan's `hits` from laser pose `lp` into `map`: each end point, and the seen band of the `banded` ones.
fn draw_scan(map: &mut TileMap, lp: &Xyt, hits: &[Beam], banded: &[bool], band: f64) -> Result<(), TooLarge> {
    let (s, c) = lp.theta.sin_cos();
    for (b, &band_it) in hits.iter().zip(banded) {
        let (dx, dy) = (c * b.c - s * b.s, s * b.c + c * b.s);
        let (ex, ey) = (lp.x + b.r * dx, lp.y + b.r * dy);
        if band_it {
            let r0 = (b.r - band).max(0.0);
            let (x0, y0) = (lp.x + r0 * dx, lp.y + r0 * dy);
            map.mark_seen(x0, y0, ex + band * dx, ey + band * dy)?;
        }
        map.add_beam_hit(ex, ey, dx, dy)?;
    }
    Ok(())
}
