//! The simulator's odometry errors fitted to a real robot's: encoder calibration and wheel slip chosen so that a
//! simulated robot driven along a real trajectory ([`drive_along`]) shows the real odometry's errors
//! ([`odometry_errors`]), and the presets fitted that way.
//!
//! Where the simulated odometry error comes from, and what each parameter moves:
//! - the odometry's assumed wheel radii ([`EncoderParams`] `left_radius_error`, `right_radius_error`, relative):
//!   their mean is the distance scale error per metre, their difference over the wheel base the heading drift
//!   per metre driven straight (`(e_r − e_l) / B`);
//! - the assumed wheel base (`wheel_base_error`): a turn of θ reads `θ (1 + (e_l + e_r)/2) / (1 + e_b)`, the
//!   error per radian turned, of opposite sign in left and right turns;
//! - wheel slip ([`SlipParams`]): `speed_noise` (each wheel's ground speed error when driving straight, an
//!   Ornstein–Uhlenbeck process of correlation time `noise_correlation_time`) and `turn_noise` (more of it per rad/s
//!   of turn rate) give the random parts; slip events add rare larger losses;
//! - encoder quantisation (`ticks_per_rev`): sub-millimetre, negligible here.
//!
//! The fit ([`fit`]) starts from the closed form of the systematic part (the two radius errors from the real scale
//! error and heading drift) and refines the five parameters `(e_l + e_r)/2`, `e_r − e_l`, `e_b`, `speed_noise`,
//! `turn_noise` by a pattern search (each parameter stepped up and down, the best move kept, the steps halved when
//! none helps) on [`loss`]. Deterministic: the drives use one seed.

use crate::odometry_errors::{OdometryErrors, Spread, drive_along, odometry_errors};
use crate::{EncoderParams, RobotModel, SimError, SlipParams};
use mrslam_core::Pose2;

/// The odometry presets' names, as scenario files give them.
pub const PRESETS: [&str; 1] = ["pioneer_fr079"];

/// The slip and encoder parameters of the odometry preset called `name` (one of [`PRESETS`]).
pub fn preset(name: &str) -> Option<(SlipParams, EncoderParams)> {
    match name {
        "pioneer_fr079" => Some(pioneer_fr079()),
        _ => None,
    }
}

/// FR079's Pioneer (with [`RobotModel::pioneer`]): fitted by [`fit`] to the raw FR079 log's odometry against our
/// SLAM trajectory of it, segments of 5 m / 2 rad, the mean of seeds 0-3, from the defaults
/// (`mrslam sim replay ... --fit-odometry`, benchmarks/runs/2026-12-02-sim-real-fr079.md), then the radius
/// difference scaled so the heading drift's mean over 40 held-out seeds (−0.0133 rad/m with the fit's −0.00207 /
/// −0.00656) meets the log's −0.0167: the odometry reads 0.15 % (left wheel) and 0.71 % (right wheel) short, and
/// the wheels scrub 12 % of their speed (standard deviation) per rad/s of turn rate, 0.1 % when driving straight. The wheel base error stayed at zero: these
/// errors hardly see it (left and right turns cancel in the mean per radian; the spread is the scrubbing's).
/// Slip events and the correlation time keep their defaults.
pub fn pioneer_fr079() -> (SlipParams, EncoderParams) {
    let slip = SlipParams { speed_noise: 0.001, turn_noise: 0.12, ..SlipParams::default() };
    let encoder = EncoderParams::default().with_calibration_error(-0.00150, -0.00713, 0.0);
    (slip, encoder)
}

/// The quantities a fit matches, with the floor under each one's denominator (a real value near zero is matched in
/// absolute terms): scale per metre (mean, std), heading per metre (mean), heading per radian (mean, std).
fn terms(e: &OdometryErrors) -> [f64; 5] {
    [e.scale_per_m.mean, e.scale_per_m.std, e.heading_per_m.mean, e.heading_per_rad.mean, e.heading_per_rad.std]
}

/// Floors of the denominators of [`loss`], in the order of its terms.
const FLOORS: [f64; 5] = [0.002, 0.002, 0.002, 0.005, 0.005];

/// How far `sim` lies from `real`: the sum of the squared relative differences of the scale error per metre (mean
/// and standard deviation), the heading error per metre (mean) and per radian (mean and standard deviation), each
/// relative to `max(|real|, floor)`.
pub fn loss(sim: &OdometryErrors, real: &OdometryErrors) -> f64 {
    let (s, r) = (terms(sim), terms(real));
    (0..5).map(|k| ((s[k] - r[k]) / r[k].abs().max(FLOORS[k])).powi(2)).sum()
}

/// The largest relative difference of the five fitted quantities (as in [`loss`]).
pub fn worst_relative(sim: &OdometryErrors, real: &OdometryErrors) -> f64 {
    let (s, r) = (terms(sim), terms(real));
    (0..5).map(|k| (s[k] - r[k]).abs() / r[k].abs().max(FLOORS[k])).fold(0.0, f64::max)
}

/// First step of each fitted parameter in the pattern search: radius errors 0.2 %, wheel base 2 %, speed noise
/// 0.4 %, turn noise 5 % per rad/s; the search stops when every step is an eighth of this.
const STEPS: [f64; 5] = [0.002, 0.002, 0.02, 0.004, 0.05];

/// What [`fit`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// Fitted slip (events and correlation time as given).
    pub slip: SlipParams,
    /// Fitted encoder calibration errors.
    pub encoder: EncoderParams,
    /// The simulated robot's errors with them.
    pub errors: OdometryErrors,
    /// Their [`loss`] against the real errors.
    pub loss: f64,
    /// Parameter sets tried (each driven once per seed).
    pub evaluations: usize,
}

/// The average of several drives' errors: each spread's mean, standard deviation and rms averaged, segments
/// summed; metres and radians averaged.
pub fn average(errors: &[OdometryErrors]) -> OdometryErrors {
    let n = errors.len().max(1) as f64;
    let spread = |f: fn(&OdometryErrors) -> Spread| Spread {
        segments: errors.iter().map(|e| f(e).segments).sum(),
        mean: errors.iter().map(|e| f(e).mean).sum::<f64>() / n,
        std: errors.iter().map(|e| f(e).std).sum::<f64>() / n,
        rms: errors.iter().map(|e| f(e).rms).sum::<f64>() / n,
    };
    OdometryErrors {
        metres: errors.iter().map(|e| e.metres).sum::<f64>() / n,
        radians: errors.iter().map(|e| e.radians).sum::<f64>() / n,
        translation_per_m: spread(|e| e.translation_per_m),
        scale_per_m: spread(|e| e.scale_per_m),
        heading_per_m: spread(|e| e.heading_per_m),
        heading_per_rad: spread(|e| e.heading_per_rad),
    }
}

/// Fits slip and encoder parameters of `model` so that, driven along `trajectory` once per seed of `seeds`, its
/// odometry errors averaged over the drives ([`average`]; segments `segment_m` / `segment_rad`) match `real`;
/// `base` gives the parameters not fitted (slip events, correlation time, ticks). At most `max_evaluations`
/// parameter sets are tried.
pub fn fit(
    model: &RobotModel,
    base: (SlipParams, EncoderParams),
    trajectory: &[(f64, Pose2)],
    real: &OdometryErrors,
    segments: (f64, f64),
    seeds: &[u64],
    max_evaluations: usize,
) -> Result<Fitted, SimError> {
    let b = model.wheel_base;
    // x = [(e_l + e_r)/2, e_r − e_l, e_b, speed_noise, turn_noise]
    let params = |x: &[f64; 5]| {
        let slip = SlipParams { speed_noise: x[3], turn_noise: x[4], ..base.0 };
        let encoder = EncoderParams {
            left_radius_error: x[0] - 0.5 * x[1],
            right_radius_error: x[0] + 0.5 * x[1],
            wheel_base_error: x[2],
            ..base.1
        };
        (slip, encoder)
    };
    let evaluations = std::cell::Cell::new(0);
    let evaluate = |x: &[f64; 5]| -> Result<(f64, OdometryErrors), SimError> {
        let (slip, encoder) = params(x);
        slip.validate()?;
        encoder.validate()?;
        let mut drives = Vec::new();
        for &seed in seeds {
            let (t, o) = drive_along(model.clone(), slip, encoder, trajectory, seed)?;
            drives.push(odometry_errors(&t, &o, segments.0, segments.1));
        }
        evaluations.set(evaluations.get() + 1);
        let e = average(&drives);
        Ok((loss(&e, real), e))
    };
    // Closed form of the systematic part: scale = mean radius error, heading per metre = difference / base.
    let mut x = [
        real.scale_per_m.mean,
        real.heading_per_m.mean * b,
        base.1.wheel_base_error,
        base.0.speed_noise,
        base.0.turn_noise,
    ];
    let mut step = STEPS;
    let (mut best, mut errors) = evaluate(&x)?;
    while evaluations.get() + 2 <= max_evaluations && step.iter().zip(&STEPS).any(|(s, s0)| *s > s0 / 8.0) {
        let mut moved = None;
        for k in 0..5 {
            for sign in [1.0, -1.0] {
                if evaluations.get() >= max_evaluations {
                    break;
                }
                let mut y = x;
                y[k] += sign * step[k];
                if k >= 3 && y[k] < 0.0 {
                    continue;
                }
                let Ok((l, e)) = evaluate(&y) else { continue };
                if l < best {
                    (best, errors) = (l, e);
                    moved = Some(y);
                }
            }
        }
        match moved {
            Some(y) => x = y,
            None => step.iter_mut().for_each(|s| *s *= 0.5),
        }
    }
    let (slip, encoder) = params(&x);
    Ok(Fitted { slip, encoder, errors, loss: best, evaluations: evaluations.get() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    /// A figure-of-eight-ish path: straights of 3 m and turns both ways, one pose every 0.1 s.
    fn path() -> Vec<(f64, Pose2)> {
        let mut out = Vec::new();
        let mut p = pose(0.0, 0.0, 0.0);
        let mut t = 0.0;
        for lap in 0..6 {
            let turn = if lap % 2 == 0 { 1.0 } else { -1.0 };
            for _ in 0..75 {
                out.push((t, p));
                p *= pose(0.04, 0.0, 0.0);
                t += 0.1;
            }
            for _ in 0..30 {
                out.push((t, p));
                p *= pose(0.01, 0.0, turn * 0.1);
                t += 0.1;
            }
        }
        out
    }

    #[test]
    fn the_fit_recovers_a_known_calibration_error() {
        let model = RobotModel::pioneer();
        let traj = path();
        let quiet = SlipParams { event_rate: 0.0, ..SlipParams::default() };
        let truth_enc = EncoderParams::default().with_calibration_error(0.004, -0.006, 0.03);
        let (t, o) = drive_along(model.clone(), quiet, truth_enc, &traj, 3).unwrap();
        let real = odometry_errors(&t, &o, 3.0, 2.0);
        assert!(real.heading_per_m.segments > 0 && real.heading_per_rad.segments > 0, "{real:?}");
        let start = (SlipParams { speed_noise: 0.01, turn_noise: 0.05, ..quiet }, EncoderParams::default());
        let f = fit(&model, start, &traj, &real, (3.0, 2.0), &[3], 150).unwrap();
        assert!(f.evaluations <= 150);
        let e = f.encoder;
        assert!((e.right_radius_error - e.left_radius_error + 0.01).abs() < 0.002, "{f:?}");
        assert!(((e.left_radius_error + e.right_radius_error) / 2.0 + 0.001).abs() < 0.002, "{f:?}");
        assert!(worst_relative(&f.errors, &real) < 0.2, "{f:?}");
    }

    #[test]
    fn the_presets_are_valid_and_named() {
        for name in PRESETS {
            let (s, e) = preset(name).unwrap();
            assert!(s.validate().is_ok() && e.validate().is_ok(), "{name}");
        }
        assert!(preset("pioneer").is_none());
    }
}
