//! The pose types: [`Pose2`] (on [`nalgebra::Isometry2<f64>`]), its constructor [`pose`] and its plain-data
//! form [`Xyt`]; re-exported at the crate root.

use nalgebra::{Isometry2, Vector2};

/// A rigid 2D pose or transform: rotation then translation, in metres and radians.
pub type Pose2 = Isometry2<f64>;

/// Builds a pose from x, y (metres) and heading theta (radians).
pub fn pose(x: f64, y: f64, theta: f64) -> Pose2 {
    Isometry2::new(Vector2::new(x, y), theta)
}

/// A pose or transform as its three numbers: x, y (metres) and heading theta (radians).
///
/// The plain-data form of a [`Pose2`]: what matchers iterate on, what reports and files hold.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Xyt {
    /// Translation along x, metres.
    pub x: f64,
    /// Translation along y, metres.
    pub y: f64,
    /// Heading (rotation), radians.
    pub theta: f64,
}

impl Xyt {
    /// The (x, y, theta) of a pose, theta in (-pi, pi].
    #[inline]
    pub fn from_pose(p: &Pose2) -> Self {
        Xyt { x: p.translation.x, y: p.translation.y, theta: p.rotation.angle() }
    }

    /// The pose of (x, y, theta).
    #[inline]
    pub fn to_pose(&self) -> Pose2 {
        pose(self.x, self.y, self.theta)
    }
}
