//! How fast a robot moves at most: odometry faster than this was not stamped when it was measured, or the robot
//! was carried or reset.

use mrslam_core::Pose2;

/// Fastest a robot drives, m/s: odometry readings whose stamps imply more were not stamped when they were
/// measured (a logger that stamps a buffered burst on arrival), or the robot was carried or reset.
pub const MAX_SPEED: f64 = 5.0;
/// Fastest a robot turns, rad/s (see [`MAX_SPEED`]).
pub const MAX_TURN_RATE: f64 = 10.0;

/// Whether going from `a` to `b` in `seconds` is faster than a robot drives or turns ([`MAX_SPEED`],
/// [`MAX_TURN_RATE`]).
pub fn faster_than_a_robot(a: &Pose2, b: &Pose2, seconds: f64) -> bool {
    let step = a.inv_mul(b);
    let (distance, turn) = (step.translation.vector.norm(), step.rotation.angle().abs());
    distance > MAX_SPEED * seconds || turn > MAX_TURN_RATE * seconds
}
