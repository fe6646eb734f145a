//! Robot models and the differential drive: wheel commands, speed and acceleration limits, kinematics.

use crate::error::{SimError, bad_param, check_positive};
use nalgebra::{Point2, Vector2};

/// The shape of a robot on the floor, centred on the wheel axle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Footprint {
    /// A disc of the given radius, metres.
    Circle {
        /// Radius, metres.
        radius: f64,
    },
    /// A rectangle, `length` along the robot's x axis (forward), `width` across, metres.
    Box {
        /// Extent along x, metres.
        length: f64,
        /// Extent along y, metres.
        width: f64,
    },
}

impl Footprint {
    /// Radius of the smallest disc around the axle centre that holds the footprint.
    pub fn bounding_radius(&self) -> f64 {
        match *self {
            Footprint::Circle { radius } => radius,
            Footprint::Box { length, width } => 0.5 * length.hypot(width),
        }
    }

    /// How far the footprint reaches forward of the axle centre, and to either side of it, metres.
    pub fn half_extents(&self) -> (f64, f64) {
        match *self {
            Footprint::Circle { radius } => (radius, radius),
            Footprint::Box { length, width } => (0.5 * length, 0.5 * width),
        }
    }

    /// Outline in the robot frame (counter-clockwise); a circle is approximated by 32 vertices
    /// placed on the circle (inscribed polygon).
    pub fn outline(&self) -> Vec<Point2<f64>> {
        match *self {
            Footprint::Circle { radius } => (0..32)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / 32.0;
                    Point2::new(radius * a.cos(), radius * a.sin())
                })
                .collect(),
            Footprint::Box { length, width } => {
                crate::geometry::box_corners(&Point2::origin(), &Vector2::new(0.5 * length, 0.5 * width), 0.0).to_vec()
            }
        }
    }
}

/// A differential-drive robot's geometry and limits.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    /// Model name, e.g. "experia".
    pub name: String,
    /// Wheel radius, metres.
    pub wheel_radius: f64,
    /// Distance between the wheels' contact points, metres.
    pub wheel_base: f64,
    /// Shape on the floor (collider), centred on the axle.
    pub footprint: Footprint,
    /// Largest forward speed of either wheel's rim, m/s.
    pub max_speed: f64,
    /// Largest rim acceleration of either wheel, m/s².
    pub max_accel: f64,
    /// Mass, kg (only matters when robots push each other).
    pub mass: f64,
}

impl RobotModel {
    /// Experia: the larger robot of the paper (box footprint 0.50 m × 0.42 m, Hokuyo host).
    pub fn experia() -> Self {
        RobotModel {
            name: "experia".into(),
            wheel_radius: 0.075,
            wheel_base: 0.38,
            footprint: Footprint::Box { length: 0.50, width: 0.42 },
            max_speed: 0.8,
            max_accel: 1.0,
            mass: 25.0,
        }
    }

    /// Prawn: the smaller robot of the paper (round, 0.30 m across, RpLidar host).
    pub fn prawn() -> Self {
        RobotModel {
            name: "prawn".into(),
            wheel_radius: 0.035,
            wheel_base: 0.23,
            footprint: Footprint::Circle { radius: 0.15 },
            max_speed: 0.5,
            max_accel: 1.5,
            mass: 4.0,
        }
    }

    /// Pioneer 2-DX class, the robot of the FR079 log: 16.5 cm wheels on a 0.33 m track (the class's nominal
    /// numbers, not the log's: an odometry fit to the log absorbs a different track in its radius and base errors),
    /// the 0.47 m × 0.41 m footprint the log's `robot_length`/`robot_width` give; rim speed up to
    /// 0.75 m/s (the log's `robot_max_t_vel` 0.5 m/s plus a turn at `robot_max_r_vel` 0.78 rad/s, 0.13 m/s at the
    /// rim, with margin), 9 kg.
    pub fn pioneer() -> Self {
        RobotModel {
            name: "pioneer".into(),
            wheel_radius: 0.0825,
            wheel_base: 0.33,
            footprint: Footprint::Box { length: 0.47, width: 0.41 },
            max_speed: 0.75,
            max_accel: 1.0,
            mass: 9.0,
        }
    }

    /// The names of the models, as scenario files give them.
    pub const PRESETS: [&'static str; 3] = ["experia", "prawn", "pioneer"];

    /// The model called `name` (one of [`RobotModel::PRESETS`]).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "experia" => Some(Self::experia()),
            "prawn" => Some(Self::prawn()),
            "pioneer" => Some(Self::pioneer()),
            _ => None,
        }
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), SimError> {
        check_positive("RobotModel.wheel_radius", self.wheel_radius)?;
        check_positive("RobotModel.wheel_base", self.wheel_base)?;
        check_positive("RobotModel.max_speed", self.max_speed)?;
        check_positive("RobotModel.max_accel", self.max_accel)?;
        check_positive("RobotModel.mass", self.mass)?;
        match self.footprint {
            Footprint::Circle { radius } => check_positive("RobotModel.footprint.radius", radius),
            Footprint::Box { length, width } => {
                check_positive("RobotModel.footprint.length", length)?;
                check_positive("RobotModel.footprint.width", width)
            }
        }
    }

    /// Wheel angular speeds (left, right), rad/s, that realise body speeds `v` (m/s) and `w` (rad/s).
    pub fn wheel_speeds(&self, v: f64, w: f64) -> [f64; 2] {
        let h = 0.5 * self.wheel_base * w;
        [(v - h) / self.wheel_radius, (v + h) / self.wheel_radius]
    }

    /// Body speeds `(v, w)` of wheel rim ground speeds `(left, right)` in m/s.
    pub fn body_speeds(&self, ground: [f64; 2]) -> (f64, f64) {
        (0.5 * (ground[0] + ground[1]), (ground[1] - ground[0]) / self.wheel_base)
    }
}

/// The wheels' state: commanded and actual angular speeds under the model's limits.
#[derive(Debug, Clone)]
pub struct DiffDrive {
    model: RobotModel,
    command: [f64; 2],
    speed: [f64; 2],
}

impl DiffDrive {
    /// A drive at rest.
    pub fn new(model: RobotModel) -> Self {
        DiffDrive { model, command: [0.0; 2], speed: [0.0; 2] }
    }

    /// The robot model.
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// Sets the wheel speed command (rad/s). Non-finite values are refused; speeds beyond the model's
    /// limit are scaled down together so the path's curvature is kept.
    pub fn set_command(&mut self, left: f64, right: f64) -> Result<(), SimError> {
        if !(left.is_finite() && right.is_finite()) {
            return Err(bad_param("wheel command", format!("must be finite, got ({left}, {right})")));
        }
        let lim = self.model.max_speed / self.model.wheel_radius;
        let m = left.abs().max(right.abs());
        let k = if m > lim { lim / m } else { 1.0 };
        self.command = [left * k, right * k];
        Ok(())
    }

    /// The (limited) wheel speed command, rad/s.
    pub fn command(&self) -> [f64; 2] {
        self.command
    }

    /// The wheels' current angular speeds, rad/s.
    pub fn wheel_speeds(&self) -> [f64; 2] {
        self.speed
    }

    /// Advances the wheels by `dt` under the acceleration limit; returns the angle each wheel turned.
    pub fn advance(&mut self, dt: f64) -> [f64; 2] {
        let dmax = self.model.max_accel / self.model.wheel_radius * dt;
        let mut dphi = [0.0; 2];
        // Both wheels are slowed by the same factor so the turn rate ramps with the speed.
        let need = [self.command[0] - self.speed[0], self.command[1] - self.speed[1]];
        let m = need[0].abs().max(need[1].abs());
        let k = if m > dmax { dmax / m } else { 1.0 };
        for i in 0..2 {
            let s0 = self.speed[i];
            let s1 = s0 + need[i] * k;
            dphi[i] = 0.5 * (s0 + s1) * dt;
            self.speed[i] = s1;
        }
        dphi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_experia_is_larger() {
        let (e, p) = (RobotModel::experia(), RobotModel::prawn());
        assert!(e.validate().is_ok() && p.validate().is_ok());
        assert!(e.footprint.bounding_radius() > p.footprint.bounding_radius());
        assert_eq!(e.footprint.half_extents(), (0.25, 0.21));
        assert_eq!(p.footprint.half_extents(), (0.15, 0.15));
        for name in RobotModel::PRESETS {
            let m = RobotModel::preset(name).unwrap();
            assert!(m.validate().is_ok() && m.name == name, "{name}");
        }
        assert!(RobotModel::preset("pr2").is_none());
    }

    #[test]
    fn kinematics_round_trip() {
        let m = RobotModel::experia();
        let w = m.wheel_speeds(0.4, 0.5);
        let g = [w[0] * m.wheel_radius, w[1] * m.wheel_radius];
        let (v, om) = m.body_speeds(g);
        assert!((v - 0.4).abs() < 1e-12 && (om - 0.5).abs() < 1e-12);
    }

    #[test]
    fn limits_speed_and_acceleration() {
        let m = RobotModel::prawn();
        let mut d = DiffDrive::new(m.clone());
        d.set_command(100.0, 50.0).unwrap();
        let c = d.command();
        assert!((c[0] * m.wheel_radius - m.max_speed).abs() < 1e-12 && (c[1] / c[0] - 0.5).abs() < 1e-12);
        d.advance(0.01);
        assert!((d.wheel_speeds()[0] * m.wheel_radius - m.max_accel * 0.01).abs() < 1e-12);
        for _ in 0..1000 {
            d.advance(0.01);
        }
        assert_eq!(d.wheel_speeds(), d.command());
        assert!(d.set_command(f64::NAN, 0.0).is_err());
    }
}
