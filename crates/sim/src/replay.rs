//! A real log replayed in a simulated world: each real scan against the scan the world gives, noiseless, from
//! the same sensor pose (`mrslam sim replay`), and the lidar noise a model would need to look like it.
//!
//! Per beam the residual is `real range − simulated range` where both returned; a beam that returned in one and
//! not in the other is counted apart (no return where the world has a surface: dark or glass surfaces, people in
//! the way of nothing; a return where the world has none: people, doors, the map's gaps). Residuals are grouped by
//! the simulated range ([`RANGE_BANDS_M`]) and by the angle of incidence on the surface ([`INCIDENCE_BANDS_DEG`],
//! from the real scan's neighbouring end points). A residual beyond [`OUTLIER_M`] is an outlier: kept out of the
//! spread, counted. The spread of each band is robust (1.4826 × the median absolute deviation), and a noise model
//! `σ(r) = a + b·r` is fitted to the bands by weighted least squares: what a simulated lidar needs, together with
//! the map's own quantisation and the trajectory's error, which the residuals also hold.
//!
//! How alike two sets of residuals are is measured by the two-sample Kolmogorov–Smirnov statistic `D` (the largest
//! gap between the two empirical distribution functions): free of any assumption on the residuals' shape (they are
//! not Gaussian: map quantisation is uniform, outliers are heavy), it sees a shifted centre and a wrong spread
//! alike, and it reads directly (0: the same, 1: disjoint). Here the real residuals of a band against residuals
//! drawn from a noise model at the band's simulated ranges.

use crate::World;
use mrslam_core::{LaserScan, Pose2};
use nalgebra::Point2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Lower edges of the range bands, metres (the last band is open).
pub const RANGE_BANDS_M: [f64; 5] = [0.0, 1.0, 3.0, 6.0, 10.0];
/// Lower edges of the incidence bands, degrees (0: the beam meets the surface head-on).
pub const INCIDENCE_BANDS_DEG: [f64; 3] = [0.0, 30.0, 60.0];
/// A residual larger than this is an outlier, metres.
pub const OUTLIER_M: f64 = 0.3;
/// Width of a bin of the residual histograms, metres; they cover ±[`OUTLIER_M`].
pub const HISTOGRAM_BIN_M: f64 = 0.01;

/// Counts of a band's inlier residuals in bins of [`HISTOGRAM_BIN_M`] from −[`OUTLIER_M`] to +[`OUTLIER_M`]: the
/// real ones and those drawn for the KS comparisons.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Histogram {
    /// The real residuals.
    pub real: Vec<usize>,
    /// Drawn from the fitted model plus the band's median.
    pub fitted: Vec<usize>,
    /// Drawn from the lidar model given to the replay.
    pub model: Vec<usize>,
}

/// The counts of `v` in the histogram's bins (values outside ±[`OUTLIER_M`] left out).
fn histogram(v: &[f64]) -> Vec<usize> {
    let bins = (2.0 * OUTLIER_M / HISTOGRAM_BIN_M).round() as usize;
    let mut h = vec![0; bins];
    for x in v {
        let k = ((x + OUTLIER_M) / HISTOGRAM_BIN_M).floor();
        if k >= 0.0 && (k as usize) < bins {
            h[k as usize] += 1;
        }
    }
    h
}

/// The residuals of one band.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct BandStats {
    /// Lower edge of the band (metres or degrees).
    pub from: f64,
    /// Upper edge (infinite for the last band).
    pub to: f64,
    /// Beams that returned in both, outliers included.
    pub beams: usize,
    /// Of which outliers (|residual| > [`OUTLIER_M`]).
    pub outliers: usize,
    /// Median residual (inliers), metres: a bias.
    pub median_m: f64,
    /// Robust spread of the inliers, 1.4826 × median absolute deviation, metres.
    pub sigma_m: f64,
    /// Mean simulated range of the band's inliers, metres.
    pub mean_range_m: f64,
    /// Two-sample KS statistic of the inliers against residuals drawn from the fitted model plus the band's median
    /// (the bias of the world's cells), when there are both.
    pub ks_fitted: Option<f64>,
    /// The same against the lidar model given to the replay (zero-mean, as the simulator draws it).
    pub ks_model: Option<f64>,
    /// The residuals' histograms, real and drawn.
    pub histogram: Histogram,
}

/// What a replay found.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct ReplayReport {
    /// Scans replayed.
    pub scans: usize,
    /// Beams compared.
    pub beams: usize,
    /// Beams that returned in both.
    pub both: usize,
    /// Beams with no usable return in the real scan where the world has a surface within range.
    pub real_missing: usize,
    /// Beams that returned in the real scan where the world has no surface within range.
    pub real_extra: usize,
    /// Beams with no return in either.
    pub neither: usize,
    /// Residuals by simulated range.
    pub by_range: Vec<BandStats>,
    /// Residuals by incidence angle.
    pub by_incidence: Vec<BandStats>,
    /// Fitted noise model: constant part `a`, metres.
    pub fitted_noise_const_m: f64,
    /// Fitted noise model: proportional part `b`.
    pub fitted_noise_prop: f64,
    /// Largest |residual| of all beams that returned in both, metres.
    pub max_abs_residual_m: f64,
}

/// One beam that returned in both.
#[derive(Debug, Clone, Copy)]
struct Beam {
    sim: f64,
    residual: f64,
    incidence_deg: Option<f64>,
}

/// Replays `scans` (each with the robot's pose in the world's frame) with the sensor at `mount` on the robot,
/// against `world`; the KS statistics compare with noise `σ(r) = model_noise.0 + model_noise.1 · r`, drawn with
/// `seed`.
pub fn replay<'a>(
    world: &World,
    mount: &Pose2,
    scans: impl IntoIterator<Item = (Pose2, &'a LaserScan)>,
    model_noise: (f64, f64),
    seed: u64,
) -> ReplayReport {
    let mut r = ReplayReport::default();
    let mut beams: Vec<Beam> = Vec::new();
    for (robot, scan) in scans {
        r.scans += 1;
        let sensor = robot * mount;
        let origin = Point2::from(sensor.translation.vector);
        let heading = sensor.rotation.angle();
        let max = scan.range_max as f64;
        for i in 0..scan.len() {
            r.beams += 1;
            let sim = world.cast_ray(&origin, heading + scan.angle(i), max).filter(|&d| d < max);
            match (scan.is_valid(i), sim) {
                (true, Some(s)) => {
                    let real = scan.ranges[i] as f64;
                    beams.push(Beam { sim: s, residual: real - s, incidence_deg: incidence(scan, &sensor, i) });
                }
                (false, Some(_)) => r.real_missing += 1,
                (true, None) => r.real_extra += 1,
                (false, None) => r.neither += 1,
            }
        }
    }
    r.both = beams.len();
    r.max_abs_residual_m = beams.iter().map(|b| b.residual.abs()).fold(0.0, f64::max);
    let by_range = group(&beams, &RANGE_BANDS_M, |b| Some(b.sim));
    let by_incidence = group(&beams, &INCIDENCE_BANDS_DEG, |b| b.incidence_deg);
    r.by_range = band_stats(&by_range, &RANGE_BANDS_M);
    r.by_incidence = band_stats(&by_incidence, &INCIDENCE_BANDS_DEG);
    let (a, b) = fit_noise(&r.by_range);
    (r.fitted_noise_const_m, r.fitted_noise_prop) = (a, b);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for (stats, groups) in [(&mut r.by_range, &by_range), (&mut r.by_incidence, &by_incidence)] {
        for (s, members) in stats.iter_mut().zip(groups) {
            let inliers: Vec<&Beam> = members.iter().copied().filter(|b| b.residual.abs() <= OUTLIER_M).collect();
            let real: Vec<f64> = inliers.iter().map(|b| b.residual).collect();
            let bias = s.median_m;
            let mut draw = |(a, b): (f64, f64), bias: f64| -> Vec<f64> {
                inliers
                    .iter()
                    .map(|x| {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        bias + z * (a + b * x.sim)
                    })
                    .collect()
            };
            let (fitted, model) = (draw((a, b), bias), draw(model_noise, 0.0));
            s.ks_fitted = ks_statistic(&real, &fitted);
            s.ks_model = ks_statistic(&real, &model);
            s.histogram = Histogram { real: histogram(&real), fitted: histogram(&fitted), model: histogram(&model) };
        }
    }
    r
}

/// The angle between beam `i` and the normal of the surface it met, degrees, from the end points of the beams
/// on either side (`None` when one of them did not return or they lie more than 0.3 m apart).
fn incidence(scan: &LaserScan, sensor: &Pose2, i: usize) -> Option<f64> {
    if i == 0 || i + 1 >= scan.len() || !scan.is_valid(i - 1) || !scan.is_valid(i + 1) {
        return None;
    }
    let p = |k: usize| scan.point_at(sensor, k, scan.ranges[k] as f64);
    let (a, b, c) = (p(i - 1), p(i), p(i + 1));
    let along = c - a;
    if along.norm() > 0.3 || along.norm() == 0.0 {
        return None;
    }
    let beam = b - Point2::from(sensor.translation.vector);
    // The beam against the surface's direction: 90° is head-on.
    let cos = (beam.dot(&along) / (beam.norm() * along.norm())).clamp(-1.0, 1.0);
    Some(90.0 - cos.acos().to_degrees().min(180.0 - cos.acos().to_degrees()))
}

/// The beams in each band of `edges` (lower edges, the last open) by `key`, in beam order; beams without a key in
/// none.
fn group<'a>(beams: &'a [Beam], edges: &[f64], key: impl Fn(&Beam) -> Option<f64>) -> Vec<Vec<&'a Beam>> {
    let mut groups = vec![Vec::new(); edges.len()];
    for b in beams {
        if let Some(v) = key(b) {
            groups[edges.iter().rposition(|&e| v >= e).unwrap_or(0)].push(b);
        }
    }
    groups
}

/// Each band's statistics (KS left for the caller).
fn band_stats(groups: &[Vec<&Beam>], edges: &[f64]) -> Vec<BandStats> {
    groups
        .iter()
        .enumerate()
        .map(|(k, members)| {
            let mut inl: Vec<f64> = members.iter().map(|b| b.residual).filter(|r| r.abs() <= OUTLIER_M).collect();
            let ranges: Vec<f64> = members.iter().filter(|b| b.residual.abs() <= OUTLIER_M).map(|b| b.sim).collect();
            let centre = median(&mut inl);
            let mut dev: Vec<f64> = inl.iter().map(|r| (r - centre).abs()).collect();
            BandStats {
                from: edges[k],
                to: edges.get(k + 1).copied().unwrap_or(f64::INFINITY),
                beams: members.len(),
                outliers: members.len() - inl.len(),
                median_m: centre,
                sigma_m: 1.4826 * median(&mut dev),
                mean_range_m: if ranges.is_empty() { 0.0 } else { ranges.iter().sum::<f64>() / ranges.len() as f64 },
                ks_fitted: None,
                ks_model: None,
                histogram: Histogram::default(),
            }
        })
        .collect()
}

/// Median of `v` (sorted in place); 0 when empty.
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// `σ(r) = a + b·r` through the bands' (mean range, spread), weighted by their inlier counts; `b` kept ≥ 0 and `a`
/// ≥ 0 (a band-only constant when the slope would be negative).
fn fit_noise(bands: &[BandStats]) -> (f64, f64) {
    let pts: Vec<(f64, f64, f64)> = bands
        .iter()
        .filter(|b| b.beams - b.outliers >= 10)
        .map(|b| (b.mean_range_m, b.sigma_m, (b.beams - b.outliers) as f64))
        .collect();
    let w: f64 = pts.iter().map(|p| p.2).sum();
    if w == 0.0 {
        return (0.0, 0.0);
    }
    let mx = pts.iter().map(|p| p.0 * p.2).sum::<f64>() / w;
    let my = pts.iter().map(|p| p.1 * p.2).sum::<f64>() / w;
    let sxx: f64 = pts.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| p.2 * (p.0 - mx) * (p.1 - my)).sum();
    let b = if sxx > 0.0 { (sxy / sxx).max(0.0) } else { 0.0 };
    let a = (my - b * mx).max(0.0);
    (a, b)
}

/// The two-sample Kolmogorov–Smirnov statistic: the largest gap between the empirical distribution functions of
/// `x` and `y`; `None` when either is empty.
pub fn ks_statistic(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.is_empty() || y.is_empty() {
        return None;
    }
    let (mut a, mut b) = (x.to_vec(), y.to_vec());
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (mut i, mut j, mut d) = (0, 0, 0.0_f64);
    while i < a.len() && j < b.len() {
        let v = a[i].min(b[j]);
        while i < a.len() && a[i] <= v {
            i += 1;
        }
        while j < b.len() && b[j] <= v {
            j += 1;
        }
        d = d.max((i as f64 / a.len() as f64 - j as f64 / b.len() as f64).abs());
    }
    Some(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EncoderParams, LidarModel, RobotModel, Sim, SimConfig, SlipParams, WorldSpec};
    use mrslam_core::pose;

    const ROOM: &str = r#"
name = "replay room"
[[walls]]
points = [[0, 0], [8, 0], [8, 5], [0, 5], [0, 0]]
[[boxes]]
center = [5, 3]
size = [1.0, 0.6]
angle = 0.4
[[circles]]
center = [2, 1.5]
radius = 0.3
"#;

    #[test]
    fn the_simulators_own_noiseless_scans_replay_with_no_residual() {
        let spec = WorldSpec::from_toml_str(ROOM, std::path::Path::new("room.toml")).unwrap();
        let mut sim = Sim::with_config(&spec, 1, SimConfig::default()).unwrap();
        let mut lidar = LidarModel::hokuyo_urg_04lx().noiseless();
        lidar.skew = false;
        let mount = lidar.mount;
        let id = sim
            .add_robot(
                "r",
                RobotModel::experia(),
                lidar,
                SlipParams::default(),
                EncoderParams::default(),
                pose(1.0, 3.5, -0.3),
            )
            .unwrap();
        sim.set_velocity_command(id, 0.3, 0.2).unwrap();
        let mut taken = Vec::new();
        for step in 0..400 {
            sim.step();
            if step % 40 == 0 {
                taken.push((sim.true_pose(id).unwrap(), sim.scan_now(id).unwrap()));
            }
        }
        let r = replay(sim.world(), &mount, taken.iter().map(|(p, s)| (*p, s)), (0.0, 0.0), 7);
        assert_eq!(r.scans, 10);
        // Every beam agrees on whether it returned (the Hokuyo's 5.6 m leaves part of the 8 m room unseen).
        assert_eq!((r.real_missing, r.real_extra, r.both + r.neither), (0, 0, r.beams), "{r:?}");
        assert!(r.both > r.beams / 2, "{r:?}");
        assert!(r.max_abs_residual_m < 1e-4, "{}", r.max_abs_residual_m);
        assert!(r.fitted_noise_const_m < 1e-4 && r.fitted_noise_prop < 1e-4, "{r:?}");
    }

    #[test]
    fn the_fit_recovers_a_known_noise_and_ks_tells_models_apart() {
        // Scans of the room with Gaussian noise 0.01 + 0.02 r, the world replayed against them.
        let spec = WorldSpec::from_toml_str(ROOM, std::path::Path::new("room.toml")).unwrap();
        let world = World::from_spec(&spec).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut scans = Vec::new();
        for k in 0..40 {
            let robot = pose(1.0 + 0.15 * k as f64, 3.8 - 0.05 * k as f64, 0.1 * k as f64);
            let ranges: Vec<f32> = (0..361)
                .map(|i| {
                    let a = robot.rotation.angle() - 1.5 + i as f64 * 3.0 / 360.0;
                    let o = Point2::from(robot.translation.vector);
                    match world.cast_ray(&o, a, 20.0) {
                        Some(d) => {
                            let z: f64 = StandardNormal.sample(&mut rng);
                            (d + z * (0.01 + 0.02 * d)) as f32
                        }
                        None => f32::INFINITY,
                    }
                })
                .collect();
            let scan = LaserScan {
                stamp: k as f64,
                angle_min: -1.5,
                angle_increment: 3.0 / 360.0,
                range_min: 0.02,
                range_max: 20.0,
                ranges,
            };
            scans.push((robot, scan));
        }
        let r = replay(&world, &Pose2::identity(), scans.iter().map(|(p, s)| (*p, s)), (0.01, 0.0), 5);
        assert!((r.fitted_noise_const_m - 0.01).abs() < 0.006, "{r:?}");
        assert!((r.fitted_noise_prop - 0.02).abs() < 0.006, "{r:?}");
        let far = r.by_range.iter().find(|b| b.from == 3.0).unwrap();
        assert!(far.ks_fitted.unwrap() < 0.1, "the fitted model's residuals look like the real ones: {far:?}");
        assert!(far.ks_model.unwrap() > 0.3, "a model without the proportional noise does not: {far:?}");
        // The histograms hold every inlier, real and drawn alike (none falls outside ±OUTLIER_M by construction).
        let h = &far.histogram;
        assert_eq!(h.real.len(), 60);
        let inliers = far.beams - far.outliers;
        assert_eq!(h.real.iter().sum::<usize>(), inliers);
        let drawn: usize = h.fitted.iter().sum();
        assert!(drawn <= inliers && drawn + inliers / 50 >= inliers, "{drawn} of {inliers}");
    }

    #[test]
    fn ks_statistic_of_known_samples() {
        assert_eq!(ks_statistic(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]), Some(0.0));
        assert_eq!(ks_statistic(&[1.0, 2.0], &[3.0, 4.0]), Some(1.0));
        assert_eq!(ks_statistic(&[1.0, 3.0], &[2.0, 4.0]), Some(0.5));
        assert_eq!(ks_statistic(&[], &[1.0]), None);
    }
}
