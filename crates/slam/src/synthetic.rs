//! Synthetic data for tests and benchmarks: known maps, known paths, scans ray-cast on the map with
//! noise, and odometry that drifts (systematic scale and heading error plus random noise per step).
//!
//! Nothing here knows about the simulator crate: it uses core's grid ray casting only.

use mrslam_core::sensor::LidarSpec;
use mrslam_core::{LaserScan, OccupancyGrid, Odometry, Pose2, pose};
use mrslam_core::{
    Xyt,
    pose::{normalize_angle, relative},
};
use nalgebra::Point2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Log-odds of the walls of the synthetic maps.
const WALL: f32 = 3.0;
/// Log-odds of the free space of the synthetic maps.
const FREE: f32 = -2.0;

/// A simulated planar lidar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lidar {
    /// Field of view, radians.
    pub fov: f64,
    /// Number of beams.
    pub beams: usize,
    /// Shortest range, metres.
    pub range_min: f32,
    /// Longest range, metres.
    pub range_max: f32,
    /// Range noise standard deviation, metres (the constant part).
    pub sigma: f64,
    /// Range noise growing with the range: standard deviation `sigma + sigma_per_m * range`.
    pub sigma_per_m: f64,
    /// Probability that a beam returns no echo (read as NaN, as the simulator's lidar reports it).
    pub dropout: f64,
}

impl Lidar {
    /// Hokuyo URG-04LX class: 240°, 667 beams (0.36°), 4 m, 1 cm noise.
    pub fn hokuyo() -> Self {
        Lidar {
            fov: 240f64.to_radians(),
            beams: 667,
            range_min: 0.06,
            range_max: 4.0,
            sigma: 0.01,
            sigma_per_m: 0.0,
            dropout: 0.0,
        }
    }

    /// The lidar of a data-sheet specification: its beam pattern, range limits, range noise and dropouts
    /// (angular jitter and scan skew are the simulator's alone).
    pub fn from_spec(spec: &LidarSpec) -> Self {
        let beams = spec.beam_count();
        let fov = if spec.is_full_circle() { spec.fov } else { (beams - 1) as f64 * spec.resolution };
        Lidar {
            fov,
            beams,
            range_min: spec.range_min as f32,
            range_max: spec.range_max as f32,
            sigma: spec.range_noise_const,
            sigma_per_m: spec.range_noise_prop,
            dropout: spec.dropout_prob,
        }
    }

    /// The simulator's Hokuyo ([`LidarSpec::hokuyo_urg_04lx`]): [`Lidar::hokuyo`]'s beams with the data
    /// sheet's noise, 1 cm + 0.5 % of the range, and 0.2 % dropouts. (Its mount, 0.15 m ahead, is the run's
    /// laser offset.)
    pub fn hokuyo_as_simulated() -> Self {
        Self::from_spec(&LidarSpec::hokuyo_urg_04lx())
    }

    /// SICK LMS class, as on the benchmark logs' robots: 180°, 181 beams (1°), 20 m here, 1 cm noise.
    pub fn sick() -> Self {
        Lidar { fov: std::f64::consts::PI, beams: 181, range_max: 20.0, ..Self::hokuyo() }
    }

    /// RpLidar A1 class: 360°, 360 beams, 6 m, 1 cm noise.
    pub fn rplidar() -> Self {
        Lidar {
            fov: 2.0 * std::f64::consts::PI,
            beams: 360,
            range_min: 0.2,
            range_max: 6.0,
            sigma: 0.01,
            sigma_per_m: 0.0,
            dropout: 0.0,
        }
    }

    /// Angle between beams.
    fn increment(&self) -> f64 {
        if self.fov >= 2.0 * std::f64::consts::PI - 1e-9 {
            self.fov / self.beams as f64
        } else {
            self.fov / (self.beams.max(2) - 1) as f64
        }
    }

    /// A scan from `sensor` (map frame) on `map`, with Gaussian range noise (and dropouts) from `rng`.
    pub fn scan<R: Rng>(&self, map: &OccupancyGrid, sensor: &Pose2, stamp: f64, rng: &mut R) -> LaserScan {
        let Xyt { x, y, theta: t } = Xyt::from_pose(sensor);
        let inc = self.increment();
        let angle_min = -self.fov / 2.0;
        let from = Point2::new(x, y);
        let ranges = (0..self.beams)
            .map(|i| {
                let a = t + angle_min + i as f64 * inc;
                // Drawn only when dropouts are modelled, so runs without them keep their noise sequence.
                if self.dropout > 0.0 && rng.random::<f64>() < self.dropout {
                    return f32::NAN;
                }
                match map.cast_ray(&from, a, self.range_max as f64) {
                    Some(r) => {
                        let z: f64 = rng.sample(StandardNormal);
                        let r = (r + z * (self.sigma + self.sigma_per_m * r)).max(0.0) as f32;
                        if r >= self.range_max { self.range_max } else { r }
                    }
                    None => self.range_max,
                }
            })
            .collect();
        LaserScan {
            stamp,
            angle_min,
            angle_increment: inc,
            range_min: self.range_min,
            range_max: self.range_max,
            ranges,
        }
    }
}

/// Odometry error model: applied to each true increment and integrated, so drift accumulates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drift {
    /// Relative scale error of travelled distance (0.02 = odometry reports 2 % more).
    pub scale: f64,
    /// Systematic heading error per metre travelled, rad/m.
    pub heading_per_m: f64,
    /// Random translation noise, standard deviation per metre of the step.
    pub sigma_trans: f64,
    /// Random rotation noise, standard deviation in radians per metre and per radian of the step.
    pub sigma_rot: f64,
}

impl Drift {
    /// No error.
    pub fn none() -> Self {
        Drift { scale: 0.0, heading_per_m: 0.0, sigma_trans: 0.0, sigma_rot: 0.0 }
    }

    /// A drifting odometry increment for the true increment (dx, dy, dθ).
    pub fn apply<R: Rng>(&self, rng: &mut R, dx: f64, dy: f64, dt: f64) -> Pose2 {
        let d = dx.hypot(dy);
        let z: [f64; 3] = [rng.sample(StandardNormal), rng.sample(StandardNormal), rng.sample(StandardNormal)];
        let nx = dx * (1.0 + self.scale) + z[0] * self.sigma_trans * d;
        let ny = dy * (1.0 + self.scale) + z[1] * self.sigma_trans * d;
        let nt = dt + self.heading_per_m * d + z[2] * self.sigma_rot * (d + dt.abs());
        pose(nx, ny, nt)
    }
}

/// Re-integrates odometry readings with `drift` applied to every increment (seeded): the drift injection
/// used to test that the filter corrects odometry, e.g. on a log whose odometry is already corrected.
pub fn inject_drift(odometry: &mut [Odometry], drift: &Drift, seed: u64) {
    let Some(first) = odometry.first().map(|o| o.pose) else {
        return;
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut prev_raw, mut cur) = (first, first);
    for o in odometry.iter_mut() {
        let Xyt { x: dx, y: dy, theta: dt } = Xyt::from_pose(&relative(&prev_raw, &o.pose));
        prev_raw = o.pose;
        cur *= drift.apply(&mut rng, dx, dy, dt);
        o.pose = cur;
    }
}

/// A simulated run: truth, odometry and scans, one per step.
#[derive(Debug, Clone)]
pub struct SyntheticRun {
    /// The map the scans were cast on.
    pub truth_map: OccupancyGrid,
    /// True robot poses in the map's frame, with stamps.
    pub truth: Vec<(f64, Pose2)>,
    /// Odometry readings (frame: the true start pose's, so odometry starts equal to the truth).
    pub odometry: Vec<Odometry>,
    /// Scans, one per pose.
    pub scans: Vec<LaserScan>,
    /// Laser mount pose on the robot.
    pub laser_offset: Pose2,
}

/// Simulates a robot following `path` (one pose per step, `dt` seconds apart).
pub fn simulate(
    map: &OccupancyGrid,
    path: &[Pose2],
    dt: f64,
    lidar: &Lidar,
    laser_offset: Pose2,
    drift: &Drift,
    seed: u64,
) -> SyntheticRun {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut odo = path.first().copied().unwrap_or_else(|| pose(0.0, 0.0, 0.0));
    let mut out = SyntheticRun {
        truth_map: map.clone(),
        truth: Vec::with_capacity(path.len()),
        odometry: Vec::with_capacity(path.len()),
        scans: Vec::with_capacity(path.len()),
        laser_offset,
    };
    for (i, p) in path.iter().enumerate() {
        let stamp = i as f64 * dt;
        if i > 0 {
            let Xyt { x: dx, y: dy, theta: dth } = Xyt::from_pose(&relative(&path[i - 1], p));
            odo *= drift.apply(&mut rng, dx, dy, dth);
        }
        out.truth.push((stamp, *p));
        out.odometry.push(Odometry { stamp, pose: odo });
        out.scans.push(lidar.scan(map, &(p * laser_offset), stamp, &mut rng));
    }
    out
}

/// Poses along straight segments between waypoints, `ds` metres apart, turning on the spot in steps of
/// at most `dtheta` radians at each waypoint (a differential-drive robot).
pub fn waypoint_path(waypoints: &[(f64, f64)], ds: f64, dtheta: f64) -> Vec<Pose2> {
    let mut out = Vec::new();
    let Some(&(mut x, mut y)) = waypoints.first() else {
        return out;
    };
    let mut heading = match waypoints.get(1) {
        Some(&(x1, y1)) => (y1 - y).atan2(x1 - x),
        None => 0.0,
    };
    out.push(pose(x, y, heading));
    for &(wx, wy) in &waypoints[1..] {
        let target = (wy - y).atan2(wx - x);
        let turn = normalize_angle(target - heading);
        let steps = (turn.abs() / dtheta).ceil() as usize;
        for k in 1..=steps {
            out.push(pose(x, y, heading + turn * k as f64 / steps as f64));
        }
        heading = target;
        let len = (wx - x).hypot(wy - y);
        let steps = (len / ds).ceil().max(1.0) as usize;
        let (x0, y0) = (x, y);
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            out.push(pose(x0 + (wx - x0) * f, y0 + (wy - y0) * f, heading));
        }
        x = wx;
        y = wy;
    }
    out
}

/// Paints the rectangle [x0, x1) × [y0, y1) (metres) with log-odds `v`.
fn fill(g: &mut OccupancyGrid, x0: f64, y0: f64, x1: f64, y1: f64, v: f32) {
    let r = g.resolution();
    let (cx0, cy0) = ((x0 / r).round().max(0.0) as usize, (y0 / r).round().max(0.0) as usize);
    let cx1 = ((x1 / r).round() as usize).min(g.width());
    let cy1 = ((y1 / r).round() as usize).min(g.height());
    for iy in cy0..cy1 {
        for ix in cx0..cx1 {
            g.set(ix, iy, v);
        }
    }
}

/// A grid of `w × h` metres at 5 cm, free inside walls `t` thick.
fn walled(w: f64, h: f64, t: f64) -> OccupancyGrid {
    let r = 0.05;
    let mut g = OccupancyGrid::new((w / r).round() as usize, (h / r).round() as usize, r, pose(0.0, 0.0, 0.0))
        .expect("a small synthetic grid");
    fill(&mut g, 0.0, 0.0, w, h, WALL);
    fill(&mut g, t, t, w - t, h - t, FREE);
    g
}

/// A 24 m × 14 m office floor: a ring corridor about 4 m wide around a central 16 m × 6 m block with
/// niches, pillars and boxes every few metres so no stretch of corridor looks like another.
pub fn office_map() -> OccupancyGrid {
    let mut g = walled(24.0, 14.0, 0.15);
    // central block
    fill(&mut g, 4.0, 4.0, 20.0, 10.0, WALL);
    // niches cut into the block (free), irregularly spaced
    for &(x0, y0, x1, y1) in &[
        (5.0, 4.0, 5.8, 4.6),
        (8.3, 4.0, 9.5, 4.4),
        (13.1, 4.0, 13.6, 4.8),
        (16.5, 4.0, 18.0, 4.5),
        (19.4, 5.0, 20.0, 6.2),
        (19.5, 8.0, 20.0, 8.6),
        (17.2, 9.3, 18.0, 10.0),
        (12.0, 9.5, 13.5, 10.0),
        (7.4, 9.2, 8.0, 10.0),
        (4.0, 7.5, 4.6, 8.8),
        (4.0, 5.0, 4.4, 5.6),
    ] {
        fill(&mut g, x0, y0, x1, y1, FREE);
    }
    // pillars and boxes along the outer walls and in the corridors (off the robot's path)
    for &(x0, y0, x1, y1) in &[
        (3.0, 0.15, 3.6, 0.7),
        (6.9, 0.15, 7.2, 1.1),
        (10.5, 3.3, 10.9, 3.7),
        (12.0, 0.15, 13.4, 0.5),
        (15.3, 0.6, 15.6, 0.9),
        (18.7, 0.15, 19.0, 0.8),
        (23.3, 2.5, 23.85, 3.4),
        (20.6, 6.8, 20.9, 7.1),
        (23.4, 9.0, 23.85, 10.4),
        (21.0, 13.3, 22.2, 13.85),
        (16.0, 13.4, 16.4, 13.85),
        (14.2, 10.6, 14.5, 10.9),
        (9.8, 13.1, 10.9, 13.85),
        (6.0, 13.5, 6.3, 13.85),
        (2.6, 13.2, 3.4, 13.85),
        (0.15, 10.0, 0.6, 10.5),
        (3.2, 6.7, 3.5, 7.0),
        (0.15, 4.8, 0.8, 5.3),
    ] {
        fill(&mut g, x0, y0, x1, y1, WALL);
    }
    g
}

/// The loop through [`office_map`]'s ring corridor, starting and ending near (2, 2), plus a revisit of the
/// first corridor.
pub fn office_loop() -> Vec<(f64, f64)> {
    vec![(2.0, 2.0), (22.0, 2.0), (22.0, 12.0), (2.0, 12.0), (2.0, 2.0), (10.0, 2.0)]
}

/// A building `w × h` metres whose corridor, `corridor` metres wide, runs round a solid core: a loop of about
/// 2(w + h) - 4·corridor metres. Boxes (cabinets, pillars) and niches are placed along both walls at irregular
/// spacings drawn from `seed`, so that no stretch looks like another, but many look alike at a glance.
pub fn ring_building(w: f64, h: f64, corridor: f64, seed: u64) -> OccupancyGrid {
    let t = 0.15;
    let mut g = walled(w, h, t);
    let inner = t + corridor;
    fill(&mut g, inner, inner, w - inner, h - inner, WALL);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Walk each wall of the ring (outer and inner face of each side) and place a feature every 2-6 m.
    let sides: [(f64, f64, f64, f64, bool); 4] = [
        (t, t, w - t, inner, true),          // bottom corridor: x varies
        (t, h - inner, w - t, h - t, true),  // top
        (t, t, inner, h - t, false),         // left: y varies
        (w - inner, t, w - t, h - t, false), // right
    ];
    for (x0, y0, x1, y1, along_x) in sides {
        let (from, to) = if along_x { (x0 + inner, x1 - inner) } else { (y0 + inner, y1 - inner) };
        let mut u = from + rng.random_range(1.0..3.0);
        while u < to - 1.0 {
            let len = rng.random_range(0.3..1.4);
            let depth = rng.random_range(0.2..0.6_f64).min(0.25 * corridor);
            let outer_face = rng.random_bool(0.5);
            let niche = rng.random_bool(0.3);
            let (a, b) = (u, (u + len).min(to));
            let rect = match (along_x, outer_face) {
                (true, true) if y0 <= t => (a, y0, b, y0 + depth),
                (true, false) if y0 <= t => (a, y1 - depth, b, y1),
                (true, true) => (a, y1 - depth, b, y1),
                (true, false) => (a, y0, b, y0 + depth),
                (false, true) if x0 <= t => (x0, a, x0 + depth, b),
                (false, false) if x0 <= t => (x1 - depth, a, x1, b),
                (false, true) => (x1 - depth, a, x1, b),
                (false, false) => (x0, a, x0 + depth, b),
            };
            if niche {
                // cut into the wall behind the face instead
                let (rx0, ry0, rx1, ry1) = rect;
                let (dx, dy) = if along_x {
                    (0.0, if ry0 <= y0 { -depth } else { depth })
                } else {
                    (if rx0 <= x0 { -depth } else { depth }, 0.0)
                };
                fill(&mut g, rx0 + dx, ry0 + dy, rx1 + dx, ry1 + dy, FREE);
            } else {
                fill(&mut g, rect.0, rect.1, rect.2, rect.3, WALL);
            }
            u = b + rng.random_range(2.0..6.0);
        }
    }
    g
}

/// The centre line of [`ring_building`]'s corridor once round, from the bottom-left corner anticlockwise, then
/// `beyond` metres along the bottom corridor again.
pub fn ring_loop(w: f64, h: f64, corridor: f64, beyond: f64) -> Vec<(f64, f64)> {
    let c = 0.15 + 0.5 * corridor;
    vec![(c, c), (w - c, c), (w - c, h - c), (c, h - c), (c, c), (c + beyond, c)]
}

/// A corridor `length` metres long and 5 m wide, with protrusions (a table, a water cooler, a fence, a
/// staircase: boxes along the walls) every few metres, as in the paper's first experiment.
pub fn corridor_map(length: f64) -> OccupancyGrid {
    let w = 5.0;
    let mut g = walled(length, w, 0.15);
    let mut x = 1.5;
    let mut k = 0u32;
    while x < length - 2.0 {
        // alternate sides, vary size, irregular spacing
        let (dx, dy) = (0.4 + 0.3 * (k % 3) as f64, 0.4 + 0.25 * (k % 4) as f64);
        if k.is_multiple_of(2) {
            fill(&mut g, x, 0.15, x + dx, 0.15 + dy, WALL);
        } else {
            fill(&mut g, x, w - 0.15 - dy, x + dx, w - 0.15, WALL);
        }
        x += 1.7 + 0.6 * ((k * 7) % 5) as f64;
        k += 1;
    }
    g
}

/// The office loop seen by a SICK-class lidar from the true poses, one keyframe every metre or quarter turn: the
/// true poses, their scans and the laser mount (test data for loop closure).
pub fn office_keyframes() -> (Vec<Pose2>, Vec<std::sync::Arc<LaserScan>>, Xyt) {
    let path = waypoint_path(&office_loop(), 0.05, 0.1);
    let run = simulate(&office_map(), &path, 0.1, &Lidar::sick(), pose(0.1, 0.0, 0.0), &Drift::none(), 3);
    let (mut truth, mut scans) = (Vec::new(), Vec::new());
    let mut last: Option<Pose2> = None;
    for ((_, p), s) in run.truth.iter().zip(&run.scans) {
        let due = last.is_none_or(|l| {
            let d = Xyt::from_pose(&relative(&l, p));
            d.x.hypot(d.y) >= 1.0 || d.theta.abs() >= 0.25
        });
        if due {
            truth.push(*p);
            scans.push(std::sync::Arc::new(s.clone()));
            last = Some(*p);
        }
    }
    (truth, scans, Xyt::from_pose(&run.laser_offset))
}

/// The largest and the last distance between `truth` and `poses` (paired in order).
pub fn error_to(truth: &[Pose2], poses: &[Xyt]) -> (f64, f64) {
    let e: Vec<f64> =
        truth.iter().zip(poses).map(|(t, p)| (t.translation.x - p.x).hypot(t.translation.y - p.y)).collect();
    (e.iter().copied().fold(0.0, f64::max), e.last().copied().unwrap_or(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scans_see_the_walls() {
        let g = office_map();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let s = Lidar::hokuyo().scan(&g, &pose(2.0, 2.0, 0.0), 0.0, &mut rng);
        assert_eq!(s.len(), 667);
        // straight down: the outer wall's inner face at y = 0.15, 1.85 m away
        let i = (0..s.len())
            .min_by(|&a, &b| {
                (s.angle(a) + std::f64::consts::FRAC_PI_2)
                    .abs()
                    .total_cmp(&(s.angle(b) + std::f64::consts::FRAC_PI_2).abs())
            })
            .unwrap();
        assert!((s.ranges[i] as f64 - 1.85).abs() < 0.05, "{}", s.ranges[i]);
        let path = waypoint_path(&office_loop(), 0.05, 0.1);
        assert!(path.len() > 1200);
        for p in &path {
            let c = g.world_to_cell(&Point2::new(p.translation.x, p.translation.y)).unwrap();
            assert!(g.get(c.0, c.1) < 0.0, "the path stays in free space");
        }
    }

    #[test]
    fn simulated_noise_grows_with_range_and_drops_beams() {
        let g = office_map();
        let at = pose(2.0, 2.0, 0.3);
        let clean = Lidar { sigma: 0.0, ..Lidar::hokuyo() }.scan(&g, &at, 0.0, &mut ChaCha8Rng::seed_from_u64(1));
        let noisy = Lidar { dropout: 0.1, ..Lidar::hokuyo_as_simulated() };
        // (near, far) sums of squared errors and counts, and the dropouts.
        let (mut near, mut far, mut dropped, mut beams) = ((0.0, 0usize), (0.0, 0usize), 0usize, 0usize);
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for _ in 0..40 {
            let s = noisy.scan(&g, &at, 0.0, &mut rng);
            for (r, c) in s.ranges.iter().zip(&clean.ranges) {
                beams += 1;
                if r.is_nan() {
                    dropped += 1;
                } else if *c < 3.9 {
                    let e = ((r - c) as f64).powi(2);
                    let bin = if *c < 2.5 { &mut near } else { &mut far };
                    bin.0 += e;
                    bin.1 += 1;
                }
            }
        }
        let rate = dropped as f64 / beams as f64;
        assert!((rate - 0.1).abs() < 0.01, "dropout rate {rate}");
        let (sn, sf) = ((near.0 / near.1 as f64).sqrt(), (far.0 / far.1 as f64).sqrt());
        assert!(near.1 > 1000 && far.1 > 1000, "{near:?} {far:?}");
        // 1 cm + 0.5 % of the range: about 2 cm near (< 2.5 m), more far.
        assert!(sn > 0.018 && sn < 0.0225 && sf > sn * 1.1 && sf < 0.03, "near {sn}, far {sf}");
    }
}
