//! The scan matchers: GMapping's (`scanmatcher.cpp`: the score, the likelihood and the hill-climbing
//! optimiser) and the likelihood-field matcher of the presets.
//!
//! **GMapping's** ([`MatcherKind::Gmapping`], the default): for each beam end point the matcher looks, in a
//! (2k+1)² window of cells around it, for an occupied cell whose neighbour one step back along the beam is
//! free (so the beam could have reached it); of those it takes the one whose mean hit position is nearest, at
//! distance d, and adds `exp(-d²/sigma)` to the score and `-d²/lsigma` to the log-likelihood (a beam with no
//! such cell adds `-0.5/lsigma`). "Occupied" means the cell has hits in the particle's [`TileMap`]; "free"
//! means it has none (GMapping with `generateMap` off, where an unknown cell counts as free too). The
//! optimiser climbs from the motion-model pose with steps lstep/astep over six moves (±x, ±y in the map frame,
//! ±θ), halving the steps each time no move improves the score, until `iterations` halvings brought nothing.
//!
//! **The likelihood field** ([`MatcherKind::Field`]): per particle and update a [`Field`] of surfels is built
//! once around the scan; a beam's distance d is then one table read. The pose is the mode of the scan score
//! times the motion model (`motion_prior`): a correlative search over headings (`heading_search`), the hill
//! climb on the field, then Gauss-Newton (iteratively reweighted least squares with the score's own weights
//! exp(-d²/sigma)) to the optimum. The score and likelihood formulas are GMapping's.
//!
//! Here: the types both share, the matcher's settings, [`ScanMatcher::match_scan`] and the searches (heading
//! sweep, hill climb); GMapping's kernel scoring in `kernel.rs`; the field's scoring and the Gauss-Newton
//! refinement in `field_match.rs`.

mod field_match;
mod kernel;
mod params;

pub use params::{MatcherKind, MatcherParams};

use crate::field::Field;
use crate::tile_map::TileMap;
use mrslam_core::{LaserScan, Xyt};
use mrslam_matching::Information;

/// GMapping's `nullLikelihood`: a beam that matches nothing costs `-0.5/lsigma`.
const NULL_LIKELIHOOD: f64 = -0.5;

/// The `field` matcher's heading search scores every this-many-th matched beam.
const SWEEP_STRIDE: usize = 4;
/// The `field` matcher's hill climb scores every this-many-th matched beam.
const CLIMB_STRIDE: usize = 2;

/// One beam in the laser frame: range, unit direction and end point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Range, metres.
    pub r: f64,
    /// cos of the beam angle in the laser frame.
    pub c: f64,
    /// sin of the beam angle in the laser frame.
    pub s: f64,
    /// End point x in the laser frame (`r·c`), metres.
    pub x: f64,
    /// End point y in the laser frame (`r·s`), metres.
    pub y: f64,
}

impl Beam {
    /// The beam of range `r` at angle `a` (laser frame).
    pub fn new(r: f64, a: f64) -> Self {
        let (s, c) = a.sin_cos();
        Beam { r, c, s, x: r * c, y: r * s }
    }
}

/// A scan prepared for matching and mapping.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Default)]
pub struct PreparedScan {
    /// Beams the matcher uses: valid, within the usable range, every (lskip+1)-th.
    pub matched: Vec<Beam>,
    /// Beams whose end point is a hit to record: valid and shorter than the usable range.
    pub hits: Vec<Beam>,
    /// Beams that are not finite, negative or below the sensor's minimum range.
    pub invalid: usize,
}

impl PreparedScan {
    /// Sorts a scan's beams. `max_range` and `max_urange` as in [`crate::MapParams`].
    pub fn new(scan: &LaserScan, max_range: f64, max_urange: f64, lskip: usize) -> Self {
        let mut out = PreparedScan::default();
        for i in 0..scan.len() {
            if !scan.is_valid(i) {
                if !scan.is_max_range(i) {
                    out.invalid += 1;
                }
                continue;
            }
            let r = scan.ranges[i] as f64;
            if r >= max_range || r > max_urange {
                continue;
            }
            let b = Beam::new(r, scan.angle(i));
            if r < max_urange {
                out.hits.push(b);
            }
            if i.is_multiple_of(lskip + 1) {
                out.matched.push(b);
            }
        }
        out
    }
}

/// A scan matcher: its parameters and the laser mount it matches from.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanMatcher {
    /// Laser mount pose on the robot.
    pub laser: Xyt,
    /// The matcher's parameters.
    pub params: MatcherParams,
    /// Score of a beam ending unmatched in never-seen space; `None`: 0, as GMapping (see
    /// [`MatcherParams::seen_band`]).
    pub unknown_score: Option<f64>,
    /// `field` matcher: report the scan's and the prior's information at the matched pose
    /// (`MatchResult::information`; set for [`crate::FilterParams::odometry_calibration`]).
    pub information: bool,
}

/// A Gaussian prior on a particle's pose for the `field` matcher: the motion model's spread (standard
/// deviations in the robot frame) around the particle's motion-model sample. Matching then finds the
/// mode of the posterior (scan likelihood × motion model) rather than of the scan likelihood alone, so
/// a direction the scan does not observe (along a featureless corridor, say) keeps the motion model's
/// sample instead of drifting with small model errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionPrior {
    /// Standard deviation along the robot's x axis, metres.
    pub sx: f64,
    /// Standard deviation along the robot's y axis, metres.
    pub sy: f64,
    /// Standard deviation of the heading, radians.
    pub st: f64,
}

impl MotionPrior {
    /// The information matrix in the map frame for a robot at heading `t`, scaled by `weight`.
    fn information(&self, t: f64, weight: f64) -> Information {
        let (s, c) = t.sin_cos();
        let (ix, iy) = (weight / (self.sx * self.sx), weight / (self.sy * self.sy));
        Information([
            c * c * ix + s * s * iy,
            c * s * (ix - iy),
            0.0,
            s * s * ix + c * c * iy,
            0.0,
            weight / (self.st * self.st),
        ])
    }
}

/// A Gaussian prior on the pose: information matrix (map frame) and centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PosePrior {
    /// Information matrix.
    pub info: Information,
    /// Centre (the prior's mean).
    pub centre: Xyt,
}

impl PosePrior {
    /// Half the squared Mahalanobis distance of `q` from the centre.
    #[inline]
    pub fn penalty(&self, q: &Xyt) -> f64 {
        let d = self.delta(q);
        let h = &self.info;
        0.5 * (h[0] * d[0] * d[0]
            + 2.0 * h[1] * d[0] * d[1]
            + 2.0 * h[2] * d[0] * d[2]
            + h[3] * d[1] * d[1]
            + 2.0 * h[4] * d[1] * d[2]
            + h[5] * d[2] * d[2])
    }

    #[inline]
    fn delta(&self, q: &Xyt) -> [f64; 3] {
        [q.x - self.centre.x, q.y - self.centre.y, mrslam_core::pose::normalize_angle(q.theta - self.centre.theta)]
    }
}

/// Per-thread working memory of the matcher (the likelihood field), reused between particles.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    /// The field of the particle being matched.
    pub field: Field,
}

/// Outcome of matching one particle's scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchResult {
    /// The pose to keep: the matched pose when its score exceeds the minimum, else the starting pose.
    pub pose: Xyt,
    /// The matched pose's score.
    pub score: f64,
    /// Log-likelihood of the scan at `pose`.
    pub likelihood: f64,
    /// Whether the matched pose was accepted (score > minimum score).
    pub accepted: bool,
    /// Beams of the likelihood that found a surface at `pose`.
    pub matched: usize,
    /// `field` matcher with [`ScanMatcher::information`] on: the scan's information about the pose at `pose`
    /// ([`ScanMatcher::scan_information`]) and the motion prior's (zero without one), map frame.
    pub information: Option<MatchInformation>,
}

/// The information about a matched pose (map frame): the scan's and the motion prior's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchInformation {
    /// The scan's ([`ScanMatcher::scan_information`]).
    pub scan: Information,
    /// The motion prior's (zero without one).
    pub prior: Information,
}

/// Result of evaluating a pose: score, log-likelihood and the number of beams that matched.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Evaluation {
    /// Sum of exp(-d²/sigma) over matched beams.
    pub score: f64,
    /// Log-likelihood.
    pub likelihood: f64,
    /// Beams that found a cell.
    pub matched: usize,
}

/// Samples of exp(-t) per unit of t in [`exp_neg`]'s table.
const EXP_STEPS: f64 = 64.0;
/// Largest t tabulated; exp(-t) is taken as 0 beyond (exp(-16) ≈ 1e-7).
const EXP_MAX: f64 = 16.0;

/// exp(-t) for t ≥ 0 by linear interpolation in a table (relative error below 4e-5): the kernel of the
/// `field` matcher's score, a third of whose time the libm `exp` took. Deterministic on every platform.
#[inline]
pub fn exp_neg(t: f64) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    let table = TABLE
        .get_or_init(|| (0..=(EXP_MAX * EXP_STEPS) as usize + 1).map(|i| (-(i as f64) / EXP_STEPS).exp()).collect());
    if t.is_nan() || t >= EXP_MAX {
        return 0.0;
    }
    let x = t.max(0.0) * EXP_STEPS;
    let i = x as usize;
    let f = x - i as f64;
    table[i] + f * (table[i + 1] - table[i])
}

impl ScanMatcher {
    /// The matcher `params` configure, for a laser mounted at `laser` on the robot; with `information`, the
    /// `field` matcher reports the information at each match.
    pub fn new(params: MatcherParams, laser: Xyt, information: bool) -> Self {
        ScanMatcher {
            laser,
            params,
            unknown_score: (params.seen_band > 0.0).then_some(params.unknown_score),
            information: information && params.kind == MatcherKind::Field,
        }
    }

    /// Matches `scan` on `map` from `init` (the motion model's pose) and computes the likelihood at the
    /// resulting pose (the matched pose when its score exceeds `minimum_score`, else `init`).
    pub fn match_scan(
        &self,
        map: &TileMap,
        init: &Xyt,
        scan: &PreparedScan,
        prior: Option<&MotionPrior>,
        scratch: &mut Scratch,
    ) -> MatchResult {
        let weigh = if self.params.weight_all_beams { &scan.hits } else { &scan.matched };
        match self.params.kind {
            MatcherKind::Gmapping => {
                let (corrected, score) = if self.params.frontier_guard {
                    let guarded = self.beams_in_map(map, init, &scan.matched);
                    self.optimize(map, init, &guarded)
                } else {
                    self.optimize(map, init, &scan.matched)
                };
                let accepted = score > self.params.minimum_score;
                let pose = if accepted { corrected } else { *init };
                let e = self.likelihood_and_score(map, &pose, weigh);
                MatchResult { pose, score, likelihood: e.likelihood, accepted, matched: e.matched, information: None }
            }
            MatcherKind::Field => {
                self.build_field(map, init, scan, &mut scratch.field);
                let f = &scratch.field;
                let prior = prior
                    .filter(|_| self.params.motion_prior > 0.0)
                    .map(|m| PosePrior { info: m.information(init.theta, self.params.motion_prior), centre: *init });
                let penalty = |q: &Xyt| prior.as_ref().map_or(0.0, |p| p.penalty(q));
                let objective = |q: &Xyt| self.field_eval(f, q, &scan.matched).score - penalty(q);
                // The heading search and the climb only pick the basin and approach its optimum, which the
                // Gauss-Newton refinement then reaches on every matched beam: they use fewer beams.
                let sparse: Vec<Beam> = scan.matched.iter().step_by(SWEEP_STRIDE).copied().collect();
                let start = self.sweep_heading(init, |q| self.field_eval(f, q, &sparse).score - penalty(q));
                let coarse: Vec<Beam> = scan.matched.iter().step_by(CLIMB_STRIDE).copied().collect();
                let (mut best, _) = self.climb(&start, |q| self.field_eval(f, q, &coarse).score - penalty(q));
                let mut score = objective(&best);
                if self.params.refine_iterations > 0 {
                    let r = self.refine(f, &best, &scan.matched, prior.as_ref());
                    let sr = self.field_eval(f, &r, &scan.matched).score - penalty(&r);
                    if sr > score {
                        best = r;
                        score = sr;
                    }
                }
                let accepted = score > self.params.minimum_score;
                let pose = if accepted { best } else { *init };
                let e = if self.params.kernel_likelihood {
                    self.likelihood_and_score(map, &pose, weigh)
                } else {
                    self.field_eval(f, &pose, weigh)
                };
                let information = self.information.then(|| MatchInformation {
                    scan: self.scan_information(f, &pose, &scan.matched),
                    prior: prior.as_ref().map_or(Information::ZERO, |p| p.info),
                });
                MatchResult { pose, score, likelihood: e.likelihood, accepted, matched: e.matched, information }
            }
        }
    }

    /// The laser's pose in the map frame for robot pose `p`.
    #[inline]
    pub fn laser_pose(&self, p: &Xyt) -> Xyt {
        let (s, c) = p.theta.sin_cos();
        Xyt {
            x: p.x + c * self.laser.x - s * self.laser.y,
            y: p.y + s * self.laser.x + c * self.laser.y,
            theta: p.theta + self.laser.theta,
        }
    }

    /// The correlative heading search: scores `init` turned by every multiple of `heading_step` within
    /// ±`heading_search` and returns the best (the smallest turn on ties); `init` when the search is off.
    pub fn sweep_heading(&self, init: &Xyt, score: impl Fn(&Xyt) -> f64) -> Xyt {
        if !(self.params.heading_search > 0.0 && self.params.heading_step > 0.0) {
            return *init;
        }
        let k = (self.params.heading_search / self.params.heading_step).floor() as i32;
        let mut best = (score(init), *init);
        for i in 1..=k {
            for sign in [-1.0, 1.0] {
                let q = Xyt { theta: init.theta + sign * i as f64 * self.params.heading_step, ..*init };
                let s = score(&q);
                if s > best.0 {
                    best = (s, q);
                }
            }
        }
        best.1
    }

    /// GMapping's hill climbing on any score: from `init`, steps lstep/astep over six moves (±x, ±y in the
    /// map frame, ±θ), halving the steps each time no move improves the score, until `iterations` halvings
    /// brought nothing. Returns the best pose and its score.
    pub fn climb(&self, init: &Xyt, score: impl Fn(&Xyt) -> f64) -> (Xyt, f64) {
        let mut best_score = -1.0;
        let mut current = *init;
        let mut current_score = score(&current);
        let (mut ldelta, mut adelta) = (self.params.lstep, self.params.astep);
        let mut refinement = 0;
        // Bounded like GMapping's loop is in practice: each round improves the score or halves the steps.
        let mut rounds = 0;
        loop {
            if best_score >= current_score {
                refinement += 1;
                ldelta *= 0.5;
                adelta *= 0.5;
            }
            best_score = current_score;
            let mut best_local = current;
            for m in 0..6 {
                let mut q = current;
                match m {
                    0 => q.x += ldelta,
                    1 => q.x -= ldelta,
                    2 => q.y -= ldelta,
                    3 => q.y += ldelta,
                    4 => q.theta += adelta,
                    _ => q.theta -= adelta,
                }
                let s = score(&q);
                if s > current_score {
                    current_score = s;
                    best_local = q;
                }
            }
            current = best_local;
            rounds += 1;
            if !(current_score > best_score || refinement < self.params.iterations) || rounds > 1000 {
                break;
            }
        }
        (current, best_score.max(current_score))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matcher() -> ScanMatcher {
        ScanMatcher::new(MatcherParams::default(), Xyt { x: 0.0, y: 0.0, theta: 0.0 }, false)
    }

    /// A square room 4 m across around the origin, mapped as hits from the true pose.
    fn room(beams: &[Beam]) -> TileMap {
        let mut m = TileMap::new(0.05);
        for b in beams {
            m.add_hit(b.r * b.c, b.r * b.s).unwrap();
        }
        m
    }

    fn room_beams() -> Vec<Beam> {
        (0..720)
            .map(|i| {
                let a = -std::f64::consts::PI + i as f64 * std::f64::consts::PI / 360.0;
                let (c, s) = (a.cos(), a.sin());
                // distance to the walls of a 4 m x 3 m box centred near the origin, not symmetric
                let tx = if c > 1e-9 {
                    2.3 / c
                } else if c < -1e-9 {
                    -1.7 / c
                } else {
                    f64::INFINITY
                };
                let ty = if s > 1e-9 {
                    1.2 / s
                } else if s < -1e-9 {
                    -1.8 / s
                } else {
                    f64::INFINITY
                };
                Beam { r: tx.min(ty), c, s, x: tx.min(ty) * c, y: tx.min(ty) * s }
            })
            .collect()
    }

    #[test]
    fn optimiser_recovers_an_offset() {
        let beams = room_beams();
        let map = room(&beams);
        let m = matcher();
        let at_truth = m.score(&map, &Xyt { x: 0.0, y: 0.0, theta: 0.0 }, &beams);
        assert!(at_truth > 0.9 * beams.len() as f64, "{at_truth}");
        let (p, s) = m.optimize(&map, &Xyt { x: 0.06, y: -0.04, theta: 0.03 }, &beams);
        assert!(p.x.abs() < 0.01 && p.y.abs() < 0.01 && p.theta.abs() < 0.005, "{p:?}");
        assert!(s > 0.9 * at_truth);
        let e_truth = m.likelihood_and_score(&map, &Xyt { x: 0.0, y: 0.0, theta: 0.0 }, &beams);
        let e_off = m.likelihood_and_score(&map, &Xyt { x: 0.2, y: 0.0, theta: 0.0 }, &beams);
        assert!(e_truth.likelihood > e_off.likelihood);
        assert_eq!(e_truth.matched, beams.len());
    }

    #[test]
    fn prepared_scan_sorts_beams() {
        let scan = LaserScan {
            stamp: 0.0,
            angle_min: 0.0,
            angle_increment: 0.1,
            range_min: 0.1,
            range_max: 4.0,
            ranges: vec![1.0, f32::NAN, -1.0, 4.0, 3.9, 0.05, f32::INFINITY, 2.0],
        };
        let p = PreparedScan::new(&scan, 4.0, 3.0, 1);
        assert_eq!(p.invalid, 3, "NaN, negative and below range_min");
        assert_eq!(p.hits.len(), 2, "1.0 and 2.0; 3.9 is beyond the usable range");
        assert_eq!(p.matched.len(), 1, "beam 0 only (beam 7 is skipped by lskip)");
    }

    #[test]
    fn the_proposal_concentrates_motion_samples_where_the_score_peaks() {
        // GMapping's proposal moves each particle's motion-model sample to the matcher's optimum on its map.
        // Mapped: the office from ten true poses along its first corridor; matched: the scan at the next true
        // pose, from 100 samples spread as a motion model spreads them.
        use crate::synthetic::{self, Lidar};
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let office = synthetic::office_map();
        let lidar = Lidar::sick();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let at = |x: f64| mrslam_core::pose(x, 2.0, 0.02);
        // GMapping's hill climber has a narrow basin (its first steps are 5 cm and 0.05 rad) and stops at a
        // few centimetres; the matched preset's field matcher searches ±0.05 rad and refines to the optimum.
        // Headings are spread by 0.03 rad, what the motion model adds over a metre of matched odometry.
        for (params, spread, turn, shrink, bound) in [
            (MatcherParams::default(), 0.03, 0.03, 2.0, 0.025),
            (crate::SlamParams::matched().matcher, 0.1, 0.03, 4.0, 0.03),
        ] {
            let m = ScanMatcher::new(params, Xyt { x: 0.0, y: 0.0, theta: 0.0 }, false);
            let mut map = TileMap::new(0.05);
            for k in 0..10 {
                let p = at(3.0 + 0.5 * k as f64);
                let scan = PreparedScan::new(&lidar.scan(&office, &p, 0.0, &mut rng), 20.0, 20.0, 0);
                let Xyt { x, y, theta: t } = Xyt::from_pose(&p);
                let (sn, cs) = t.sin_cos();
                for b in &scan.hits {
                    let (dx, dy) = (cs * b.c - sn * b.s, sn * b.c + cs * b.s);
                    map.add_beam_hit(x + b.r * dx, y + b.r * dy, dx, dy).unwrap();
                }
            }
            let truth = Xyt { x: 8.3, y: 2.0, theta: 0.02 };
            let scan = lidar.scan(&office, &at(truth.x), 0.0, &mut rng);
            let scan = PreparedScan::new(&scan, 20.0, 20.0, params.lskip);
            let (nxy, nt) = (Normal::new(0.0, spread).unwrap(), Normal::new(0.0, turn).unwrap());
            let prior = MotionPrior { sx: spread, sy: spread, st: turn };
            let mut scratch = Scratch::default();
            let (mut before, mut after, mut heading) = (0.0, 0.0, 0.0);
            let n = 100;
            for _ in 0..n {
                let init = Xyt {
                    x: truth.x + nxy.sample(&mut rng),
                    y: truth.y + nxy.sample(&mut rng),
                    theta: truth.theta + nt.sample(&mut rng),
                };
                let r = m.match_scan(&map, &init, &scan, Some(&prior), &mut scratch);
                before += (init.x - truth.x).powi(2) + (init.y - truth.y).powi(2);
                after += (r.pose.x - truth.x).powi(2) + (r.pose.y - truth.y).powi(2);
                heading += (r.pose.theta - truth.theta).powi(2);
            }
            let (before, after, heading) =
                ((before / n as f64).sqrt(), (after / n as f64).sqrt(), (heading / n as f64).sqrt());
            assert!(
                after <= bound && after * shrink <= before && heading <= 0.5f64.to_radians(),
                "{:?}: samples {before} m from the truth, proposal {after} m and {heading} rad",
                params.kind
            );
        }
    }
}
