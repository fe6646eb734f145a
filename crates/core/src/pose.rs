//! SE(2) helpers on [`Pose2`] (a [`nalgebra::Isometry2<f64>`]): composition, inverse, relative pose, angle
//! arithmetic, interpolation.

use crate::se2::{Pose2, Xyt, pose};

use nalgebra::Point2;
use std::f64::consts::PI;

/// Composes `a ⊕ b`: the pose `b`, expressed in frame `a`, taken to `a`'s parent frame.
pub fn compose(a: &Pose2, b: &Pose2) -> Pose2 {
    a * b
}

/// The inverse transform of `p`.
pub fn inverse(p: &Pose2) -> Pose2 {
    p.inverse()
}

/// The pose of `b` seen from `a` (`a⁻¹ ⊕ b`), e.g. an odometry increment.
pub fn relative(a: &Pose2, b: &Pose2) -> Pose2 {
    a.inv_mul(b)
}

/// Wraps an angle into (-pi, pi].
pub fn normalize_angle(a: f64) -> f64 {
    let mut r = a % (2.0 * PI);
    if r <= -PI {
        r += 2.0 * PI;
    } else if r > PI {
        r -= 2.0 * PI;
    }
    r
}

/// Smallest signed difference `a - b` of two angles, in (-pi, pi].
pub fn angle_diff(a: f64, b: f64) -> f64 {
    normalize_angle(a - b)
}

/// The pose a fraction `s` of the way from `a` to `b`: linear in x and y, the short way round in heading.
pub fn interpolate(a: &Pose2, b: &Pose2, s: f64) -> Pose2 {
    let Xyt { x: ax, y: ay, theta: at } = Xyt::from_pose(a);
    let Xyt { x: bx, y: by, theta: bt } = Xyt::from_pose(b);
    pose(ax + s * (bx - ax), ay + s * (by - ay), at + s * angle_diff(bt, at))
}

/// Transforms a point by a pose.
pub fn transform_point(p: &Pose2, x: f64, y: f64) -> Point2<f64> {
    p * Point2::new(x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_wraps_into_half_open_interval() {
        assert!((normalize_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((normalize_angle(-PI) - PI).abs() < 1e-12);
        assert!((normalize_angle(0.5 + 4.0 * PI) - 0.5).abs() < 1e-12);
        assert!((normalize_angle(-0.5 - 4.0 * PI) + 0.5).abs() < 1e-12);
    }

    #[test]
    fn relative_undoes_compose() {
        let a = pose(1.0, -2.0, 0.7);
        let d = pose(0.3, 0.1, -0.2);
        let b = compose(&a, &d);
        let r = relative(&a, &b);
        let Xyt { x, y, theta: t } = Xyt::from_pose(&r);
        assert!((x - 0.3).abs() < 1e-12 && (y - 0.1).abs() < 1e-12 && (t + 0.2).abs() < 1e-12);
        let id = compose(&inverse(&a), &a);
        assert!(Xyt::from_pose(&id).x.abs() < 1e-12 && Xyt::from_pose(&id).theta.abs() < 1e-12);
    }

    #[test]
    fn transform_point_rotates_then_translates() {
        let p = transform_point(&pose(1.0, 0.0, PI / 2.0), 1.0, 0.0);
        assert!((p.x - 1.0).abs() < 1e-12 && (p.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn angle_diff_takes_short_way() {
        assert!((angle_diff(PI - 0.1, -PI + 0.1) + 0.2).abs() < 1e-12);
    }
}
