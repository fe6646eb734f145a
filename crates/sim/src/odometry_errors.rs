//! Odometry against the truth, per metre driven and per radian turned: the real robot's (a log's odometry against
//! its corrected trajectory) and a simulated robot's driven along the same trajectory, so that the simulator's
//! wheel-slip and encoder models can be compared with a real robot.
//!
//! The path is cut into segments of `segment_m` driven or `segment_rad` turned (by default [`SEGMENT_M`],
//! [`SEGMENT_RAD`]), whichever comes first. For each
//! segment the error `E = T⁻¹·O` of the odometry increment `O` against the true one `T` gives: the translation error
//! per metre (`|E.t| / d`), the distance scale error (`(|O.t| − |T.t|) / d`), and the heading error per metre
//! (straight segments: ended by distance, turned less than [`STRAIGHT_RAD`]) or per radian (segments ended by
//! turning). The mean of each is the systematic part, the standard deviation the random part.

use crate::{EncoderParams, RobotModel, Sim, SimConfig, SimError, SlipParams, World};
use mrslam_core::{Pose2, Xyt};
use std::collections::BTreeMap;

/// Distance that ends a segment by default, metres. Against a reference trajectory with an error of a few
/// centimetres (a SLAM trajectory), short segments measure the reference: 5 m keeps 3 cm under 1 %.
pub const SEGMENT_M: f64 = 5.0;
/// Turn that ends a segment by default, radians.
pub const SEGMENT_RAD: f64 = 2.0;

/// A segment ended by distance that turned less than this per metre is straight, radians per metre: its heading
/// error counts per metre.
pub const STRAIGHT_RAD: f64 = 0.1;

/// Mean (systematic) and standard deviation (random) of one error over the segments.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Spread {
    /// Segments that measured it.
    pub segments: usize,
    /// Mean: the systematic part.
    pub mean: f64,
    /// Population standard deviation: the random part.
    pub std: f64,
    /// Root mean square: both.
    pub rms: f64,
}

impl Spread {
    fn of(v: &[f64]) -> Spread {
        if v.is_empty() {
            return Spread::default();
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
        Spread { segments: v.len(), mean, std: var.sqrt(), rms }
    }
}

/// Odometry errors per metre and per radian.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct OdometryErrors {
    /// Metres driven (true path).
    pub metres: f64,
    /// Radians turned (true headings, summed absolute increments).
    pub radians: f64,
    /// Translation error per metre driven (|E.t| / d), metres per metre.
    pub translation_per_m: Spread,
    /// Distance scale error ((|O.t| − |T.t|) / d), per metre driven.
    pub scale_per_m: Spread,
    /// Heading error per metre driven, radians per metre (straight segments).
    pub heading_per_m: Spread,
    /// Heading error per radian turned (segments ended by turning).
    pub heading_per_rad: Spread,
}

/// The errors of `odom` against `truth` (one pose each per instant, in their own frames), in segments of
/// `segment_m` driven or `segment_rad` turned.
pub fn odometry_errors(truth: &[Pose2], odom: &[Pose2], segment_m: f64, segment_rad: f64) -> OdometryErrors {
    let n = truth.len().min(odom.len());
    let mut e = OdometryErrors::default();
    let (mut trans, mut scale, mut head_m, mut head_rad) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut start, mut d, mut a) = (0, 0.0, 0.0);
    for j in 1..n {
        let step = truth[j - 1].inv_mul(&truth[j]);
        let (sd, sa) = (step.translation.vector.norm(), step.rotation.angle().abs());
        (d, a) = (d + sd, a + sa);
        e.metres += sd;
        e.radians += sa;
        if d < segment_m && a < segment_rad {
            continue;
        }
        let t = truth[start].inv_mul(&truth[j]);
        let o = odom[start].inv_mul(&odom[j]);
        let err = Xyt::from_pose(&t.inv_mul(&o));
        if d >= segment_m {
            trans.push(err.x.hypot(err.y) / d);
            scale.push((o.translation.vector.norm() - t.translation.vector.norm()) / d);
            if a < STRAIGHT_RAD * d {
                head_m.push(err.theta / d);
            }
        }
        if a >= segment_rad {
            head_rad.push(err.theta / a);
        }
        (start, d, a) = (j, 0.0, 0.0);
    }
    e.translation_per_m = Spread::of(&trans);
    e.scale_per_m = Spread::of(&scale);
    e.heading_per_m = Spread::of(&head_m);
    e.heading_per_rad = Spread::of(&head_rad);
    e
}

/// Drives a simulated robot (`model`, `slip`, `encoders`, seeded) along `trajectory` (stamp, pose) in an empty
/// world, commanding each interval's forward speed and turn rate; returns its true poses and its odometry poses at
/// the trajectory's stamps. Intervals longer than a second are driven in a second.
pub fn drive_along(
    model: RobotModel,
    slip: SlipParams,
    encoders: EncoderParams,
    trajectory: &[(f64, Pose2)],
    seed: u64,
) -> Result<(Vec<Pose2>, Vec<Pose2>), SimError> {
    let Some(&(_, start)) = trajectory.first() else { return Ok((Vec::new(), Vec::new())) };
    let world = World::from_obstacles("empty".into(), Vec::new(), BTreeMap::new());
    let config = SimConfig::default();
    let mut sim = Sim::from_world(world, seed, config)?;
    let lidar = crate::LidarModel::hokuyo_urg_04lx().noiseless();
    let id = sim.add_robot("replayed", model, lidar, slip, encoders, start)?;
    let (mut truth, mut odom) = (vec![sim.true_pose(id)?], vec![sim.odometry(id)?.pose]);
    for w in trajectory.windows(2) {
        let dt = (w[1].0 - w[0].0).clamp(config.dt, 1.0);
        let inc = Xyt::from_pose(&w[0].1.inv_mul(&w[1].1));
        sim.set_velocity_command(id, inc.x / dt, inc.theta / dt)?;
        for _ in 0..(dt / config.dt).round().max(1.0) as usize {
            sim.step();
        }
        truth.push(sim.true_pose(id)?);
        odom.push(sim.odometry(id)?.pose);
    }
    Ok((truth, odom))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    /// A square loop of 4 m sides, turning on the spot at the corners, one pose every 0.1 s at 0.4 m/s.
    fn square() -> Vec<(f64, Pose2)> {
        let mut out = Vec::new();
        let mut p = pose(0.0, 0.0, 0.0);
        let mut t = 0.0;
        for _ in 0..4 {
            for _ in 0..100 {
                out.push((t, p));
                p *= pose(0.04, 0.0, 0.0);
                t += 0.1;
            }
            for _ in 0..20 {
                out.push((t, p));
                p *= pose(0.0, 0.0, std::f64::consts::FRAC_PI_2 / 20.0);
                t += 0.1;
            }
        }
        out
    }

    #[test]
    fn a_known_scale_and_heading_error_is_measured_per_metre_and_per_radian() {
        let truth: Vec<Pose2> = square().into_iter().map(|(_, p)| p).collect();
        // Odometry reading 3 % long and turning 2 % too little, built increment by increment.
        let mut odom = vec![truth[0]];
        for w in truth.windows(2) {
            let inc = Xyt::from_pose(&w[0].inv_mul(&w[1]));
            let last = *odom.last().unwrap();
            odom.push(last * pose(inc.x * 1.03, inc.y * 1.03, inc.theta * 0.98));
        }
        let e = odometry_errors(&truth, &odom, 1.0, 1.0);
        assert!((e.metres - 16.0).abs() < 1e-6 && e.radians > 6.0, "{e:?}");
        assert!((e.scale_per_m.mean - 0.03).abs() < 1e-6 && e.scale_per_m.std < 1e-6, "{e:?}");
        assert!((e.heading_per_rad.mean + 0.02).abs() < 1e-6, "{e:?}");
        assert!(e.heading_per_m.mean.abs() < 1e-9, "no heading error while driving straight: {e:?}");
    }

    #[test]
    fn perfect_encoders_without_slip_follow_the_truth_and_slip_shows() {
        let traj = square();
        let none = SlipParams { speed_noise: 0.0, turn_noise: 0.0, event_rate: 0.0, ..SlipParams::default() };
        let (truth, odom) = drive_along(RobotModel::experia(), none, EncoderParams::default(), &traj, 1).unwrap();
        assert_eq!(truth.len(), traj.len());
        let clean = odometry_errors(&truth, &odom, 1.0, 1.0);
        assert!(clean.metres > 14.0, "the robot drove the square: {clean:?}");
        assert!(clean.translation_per_m.rms < 0.01 && clean.heading_per_rad.rms < 0.01, "{clean:?}");
        let biased = EncoderParams::default().with_calibration_error(0.02, 0.0, 0.0);
        let (truth, odom) = drive_along(RobotModel::experia(), none, biased, &traj, 1).unwrap();
        let e = odometry_errors(&truth, &odom, 1.0, 1.0);
        assert!(e.heading_per_m.mean.abs() > 0.02, "a 2 % wheel radius error turns the odometry: {e:?}");
    }
}
