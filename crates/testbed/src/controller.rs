//! Controllers: pure pursuit along waypoints, frontier exploration on the robot's own map, or none.

use crate::frontier::{Clearance, frontier_path};
use mrslam_core::{LaserScan, OccupancyGrid, Pose2, Xyt};
use nalgebra::Point2;

/// What drives a robot during a run.
#[derive(Debug, Clone)]
pub enum Controller {
    /// Follows a scripted route, steered by the robot's true pose (as an operator would drive it).
    Waypoints(PurePursuit),
    /// Explores frontiers of the robot's own SLAM map, steered by its SLAM pose.
    Explore(Explorer),
    /// Stands still where it started.
    Idle,
}

impl Controller {
    /// True once the route is driven or the exploration is over; always for an idle robot.
    pub fn is_done(&self) -> bool {
        match self {
            Controller::Waypoints(p) => p.is_done(),
            Controller::Explore(e) => e.is_done(),
            Controller::Idle => true,
        }
    }
}

/// Pure pursuit (Coulter 1992) along a polyline of waypoints, with speed and acceleration limits.
#[derive(Debug, Clone)]
pub struct PurePursuit {
    /// Look-ahead distance, metres.
    pub lookahead: f64,
    /// Cruise speed, m/s.
    pub speed: f64,
    /// Largest turn rate, rad/s.
    pub max_turn: f64,
    /// Largest change of forward speed, m/s².
    pub max_accel: f64,
    /// The goal is reached within this distance, metres.
    pub goal_tolerance: f64,
    /// Turn on the spot first when the carrot is more than this far off the heading, radians.
    pub turn_in_place: f64,
    path: Vec<Point2<f64>>,
    segment: usize,
    v: f64,
    done: bool,
}

impl PurePursuit {
    /// Follows `path` from the robot's position at `speed`.
    pub fn new(path: Vec<Point2<f64>>, speed: f64) -> Self {
        PurePursuit {
            lookahead: 0.6,
            speed,
            max_turn: 0.6,
            max_accel: 0.5,
            goal_tolerance: 0.1,
            turn_in_place: 1.0,
            done: path.is_empty(),
            path,
            segment: 0,
            v: 0.0,
        }
    }

    /// True once the last waypoint is reached.
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// Length of the path still to drive from `p`: to the current waypoint, then along the rest, metres.
    pub fn remaining(&self, p: &Point2<f64>) -> f64 {
        if self.done {
            return 0.0;
        }
        let Some(next) = self.path.get(self.segment) else { return 0.0 };
        let rest: f64 = self.path[self.segment..].windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        (next - p).norm() + rest
    }

    /// The last waypoint.
    pub fn goal(&self) -> Option<Point2<f64>> {
        self.path.last().copied()
    }

    /// The whole path it was given, driven or not.
    pub fn path(&self) -> &[Point2<f64>] {
        &self.path
    }

    /// The carrot: the point one look-ahead ahead along the path.
    fn carrot(&mut self, p: &Point2<f64>) -> Point2<f64> {
        // Advance past waypoints already within the look-ahead circle.
        while self.segment + 1 < self.path.len() && (self.path[self.segment] - p).norm() < self.lookahead {
            self.segment += 1;
        }
        let target = self.path[self.segment];
        if self.segment == 0 {
            return target;
        }
        // Intersect the look-ahead circle with the current segment, taking the far intersection.
        let a = self.path[self.segment - 1];
        let d = target - a;
        let f = a - p;
        let (qa, qb, qc) = (d.dot(&d), 2.0 * f.dot(&d), f.dot(&f) - self.lookahead * self.lookahead);
        let disc = qb * qb - 4.0 * qa * qc;
        if qa > 1e-12 && disc >= 0.0 {
            let t = (-qb + disc.sqrt()) / (2.0 * qa);
            if (0.0..=1.0).contains(&t) {
                return a + d * t;
            }
        }
        target
    }

    /// Forward speed (m/s) and turn rate (rad/s) for the robot at `pose`, `dt` seconds after the last call.
    pub fn command(&mut self, pose: &Pose2, dt: f64) -> (f64, f64) {
        if self.done {
            self.v = 0.0;
            return (0.0, 0.0);
        }
        let Xyt { x, y, .. } = Xyt::from_pose(pose);
        let p = Point2::new(x, y);
        let goal = *self.path.last().expect("non-empty path");
        let to_goal = (goal - p).norm();
        let last = self.segment + 1 >= self.path.len();
        if last && to_goal < self.goal_tolerance {
            self.done = true;
            self.v = 0.0;
            return (0.0, 0.0);
        }
        let c = self.carrot(&p);
        let local = pose.inverse_transform_point(&c);
        let bearing = local.y.atan2(local.x);
        if bearing.abs() > self.turn_in_place {
            self.v = 0.0;
            return (0.0, self.max_turn.copysign(bearing));
        }
        // Slow down for the goal and for sharp turns.
        let v_goal = if last { (0.8 * to_goal).max(0.05) } else { self.speed };
        let v_turn = self.speed * (1.0 - 0.7 * bearing.abs() / self.turn_in_place);
        let v_target = self.speed.min(v_goal).min(v_turn);
        self.v = v_target.clamp(self.v - self.max_accel * dt, self.v + self.max_accel * dt);
        let curvature = 2.0 * local.y / local.coords.norm_squared().max(1e-6);
        let w = (self.v.max(0.05) * curvature).clamp(-self.max_turn, self.max_turn);
        (self.v, w)
    }
}

/// Frontier exploration: drive to the nearest reachable frontier of the robot's own map, replan, repeat.
///
/// Works entirely in the SLAM map frame with the SLAM pose, as an autonomous robot must. Frontier cells are
/// free cells next to unknown ones; reachability is a breadth-first search over free cells at least
/// `clearance` from any occupied cell (see [`crate::frontier`]). A team planner may instead hand it the path
/// to follow ([`Self::follow`]) or tell it that nothing is left ([`Self::finish`]).
///
/// When no frontier is reachable it first turns once on the spot, as a navigation stack's rotate recovery
/// does: a lidar that sees less than a full circle, or a map whose specks close the way, may open up; only a
/// plan that fails again after the turn ends the exploration.
#[derive(Debug, Clone)]
pub struct Explorer {
    /// Distance kept from walls when planning, metres.
    pub clearance: Clearance,
    /// Replan period, seconds.
    pub replan_period: f64,
    /// Cruise speed, m/s.
    pub speed: f64,
    follower: Option<PurePursuit>,
    since_plan: f64,
    finished: bool,
    blocked_s: f64,
    abandoned: Vec<Point2<f64>>,
    /// Radians left of the turn on the spot in progress.
    turn_left: f64,
    /// True once it has turned since its last successful plan.
    turned: bool,
}

/// True when a beam of `scan` (taken by a lidar at `mount` on the robot) ends in the corridor the robot is
/// about to drive through: ahead of the axle by at most `reach`, within `half_width` of its centre line.
///
/// The map an explorer plans on holds what was there when it was last updated; this sees what is there now
/// (the other robot, above all).
pub fn blocked_ahead(scan: &LaserScan, mount: &Pose2, reach: f64, half_width: f64) -> bool {
    scan.endpoints(mount).any(|(_, p)| p.x > 0.0 && p.x <= reach && p.y.abs() <= half_width)
}

impl Explorer {
    /// How far ahead of the robot's front the way must be clear, metres (less than [`Self::MARGIN`], so that
    /// walls the planner kept clear of do not stop the robot).
    pub const STOP_DISTANCE: f64 = 0.15;
    /// Blocked this long, the robot gives up its goal, seconds.
    pub const GIVE_UP_S: f64 = 3.0;
    /// Frontiers this close to an abandoned goal are not chosen again, metres.
    pub const ABANDONED_RADIUS: f64 = 0.5;
    /// Distance kept from walls beyond the robot's bounding radius where there is room (the preferred
    /// clearance), metres: the follower cuts the corners of the grid path.
    pub const MARGIN: f64 = 0.2;
    /// Distance kept from walls beyond the robot's half width at the least (the hard clearance), metres: more
    /// than the look-ahead check's 5 cm on each side, so that a robot squeezing through a door is not stopped.
    pub const SQUEEZE_MARGIN: f64 = 0.1;
    /// Look-ahead of the path follower, metres (shorter than the scripted routes': frontier paths bend).
    pub const LOOKAHEAD: f64 = 0.35;
    /// Turn rate of the turn on the spot when no frontier is reachable, rad/s.
    pub const TURN_RATE: f64 = 0.5;

    /// An explorer driving at `speed`, keeping `clearance` from walls.
    pub fn new(speed: f64, clearance: Clearance) -> Self {
        Explorer {
            clearance,
            replan_period: 3.0,
            speed,
            follower: None,
            since_plan: f64::INFINITY,
            finished: false,
            blocked_s: 0.0,
            abandoned: Vec::new(),
            turn_left: 0.0,
            turned: false,
        }
    }

    /// True when no reachable frontier is left.
    pub fn is_done(&self) -> bool {
        self.finished
    }

    /// True when the explorer wants a fresh map to plan on.
    pub fn wants_plan(&self) -> bool {
        !self.finished
            && self.turn_left <= 0.0
            && (self.since_plan >= self.replan_period || self.follower.as_ref().is_none_or(PurePursuit::is_done))
    }

    /// Plans a path to the nearest frontier on `map` from `pose` (both in the SLAM frame); without one, turns
    /// once on the spot, then gives up.
    pub fn plan(&mut self, map: &OccupancyGrid, pose: &Pose2) {
        match frontier_path(map, pose, self.clearance, &self.abandoned, Self::ABANDONED_RADIUS) {
            Some(path) => {
                self.turned = false;
                self.follow(path);
            }
            None if !self.turned => {
                self.follower = None;
                self.turned = true;
                self.turn_left = std::f64::consts::TAU;
            }
            None => self.finish(),
        }
    }

    /// True while it turns on the spot to look for a frontier.
    pub fn is_turning(&self) -> bool {
        self.turn_left > 0.0
    }

    /// Follows `path` (the frame of the pose later given to [`Self::command`]) from now on, replacing the goal
    /// it had; the replan period starts again.
    pub fn follow(&mut self, path: Vec<Point2<f64>>) {
        self.since_plan = 0.0;
        self.finished = false;
        self.turn_left = 0.0;
        let mut f = PurePursuit::new(path, self.speed);
        f.lookahead = Self::LOOKAHEAD;
        self.follower = Some(f);
    }

    /// Stops exploring: nothing reachable is left to explore.
    pub fn finish(&mut self) {
        self.since_plan = 0.0;
        self.follower = None;
        self.turn_left = 0.0;
        self.finished = true;
    }

    /// The goal it drives to (the last point of its path), if it has one.
    pub fn goal(&self) -> Option<Point2<f64>> {
        self.follower.as_ref().and_then(PurePursuit::goal)
    }

    /// The path to its goal (ending at the goal), empty when it has none.
    pub fn path(&self) -> &[Point2<f64>] {
        self.follower.as_ref().map_or(&[], PurePursuit::path)
    }

    /// Forward speed and turn rate for the robot at `pose` (SLAM frame); `blocked` when something is in the
    /// way right now (see [`blocked_ahead`]).
    ///
    /// A blocked robot stops (it may still turn on the spot); blocked for [`Self::GIVE_UP_S`], it abandons its
    /// goal, as an exploration stack abandons a goal it cannot reach, and plans to another frontier.
    pub fn command(&mut self, pose: &Pose2, dt: f64, blocked: bool) -> (f64, f64) {
        self.since_plan += dt;
        if self.turn_left > 0.0 {
            self.turn_left -= Self::TURN_RATE * dt;
            return (0.0, Self::TURN_RATE);
        }
        let Some(f) = &mut self.follower else { return (0.0, 0.0) };
        let (v, w) = f.command(pose, dt);
        if !(blocked && v > 0.0) {
            self.blocked_s = 0.0;
            return (v, w);
        }
        self.blocked_s += dt;
        if self.blocked_s >= Self::GIVE_UP_S {
            self.blocked_s = 0.0;
            self.abandoned.extend(f.goal());
            self.follower = None;
        }
        (0.0, 0.0)
    }

    /// Goals given up on so far (SLAM frame): frontiers within [`Self::ABANDONED_RADIUS`] of them are skipped.
    pub fn abandoned(&self) -> &[Point2<f64>] {
        &self.abandoned
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn pure_pursuit_drives_a_kinematic_robot_to_the_goal() {
        let path = vec![Point2::new(2.0, 0.0), Point2::new(2.0, 2.0), Point2::new(0.0, 2.0)];
        let mut pp = PurePursuit::new(path, 0.5);
        let mut p = pose(0.0, 0.0, 0.0);
        let dt = 0.02;
        let mut t = 0.0;
        while !pp.is_done() && t < 60.0 {
            let (v, w) = pp.command(&p, dt);
            let Xyt { x, y, theta: th } = Xyt::from_pose(&p);
            p = pose(x + v * th.cos() * dt, y + v * th.sin() * dt, th + w * dt);
            t += dt;
            assert!(x > -0.3 && x < 2.3 && y > -0.3 && y < 2.3, "left the route at ({x}, {y})");
        }
        assert!(pp.is_done(), "did not arrive in 60 s");
        let Xyt { x, y, .. } = Xyt::from_pose(&p);
        assert!(x.hypot(y - 2.0) < 0.1);
    }

    fn scan_with_one_hit(bearing: f64, range: f32) -> LaserScan {
        let n = 360;
        let inc = std::f64::consts::TAU / n as f64;
        let mut ranges = vec![f32::INFINITY; n];
        ranges[((bearing + std::f64::consts::PI) / inc).round() as usize % n] = range;
        LaserScan {
            stamp: 0.0,
            angle_min: -std::f64::consts::PI,
            angle_increment: inc,
            range_min: 0.1,
            range_max: 6.0,
            ranges,
        }
    }

    #[test]
    fn only_what_lies_in_the_way_blocks() {
        let mount = pose(0.1, 0.0, 0.0);
        assert!(blocked_ahead(&scan_with_one_hit(0.0, 0.3), &mount, 0.45, 0.25), "0.4 m straight ahead");
        assert!(!blocked_ahead(&scan_with_one_hit(0.0, 0.5), &mount, 0.45, 0.25), "0.6 m ahead: beyond reach");
        assert!(!blocked_ahead(&scan_with_one_hit(1.2, 0.5), &mount, 0.45, 0.25), "off to the side");
        assert!(!blocked_ahead(&scan_with_one_hit(std::f64::consts::PI, 0.2), &mount, 0.45, 0.25), "behind");
        let mut nothing = scan_with_one_hit(0.0, 0.3);
        nothing.ranges.fill(f32::INFINITY);
        assert!(!blocked_ahead(&nothing, &mount, 0.45, 0.25), "max-range readings are no obstacle");
    }

    #[test]
    fn a_robot_blocked_for_long_gives_up_its_goal_and_picks_another() {
        // An open 4 m x 2 m room, known all around the robot, with two unseen alcoves: east and west.
        let mut g = OccupancyGrid::new(80, 40, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..40 {
            for ix in 0..80 {
                let wall = iy == 0 || iy == 39 || ((ix == 0 || ix == 79) && !(15..25).contains(&iy));
                let unseen = !(3..=76).contains(&ix) && (15..25).contains(&iy);
                if wall {
                    g.set(ix, iy, 2.0);
                } else if !unseen {
                    g.set(ix, iy, -2.0);
                }
            }
        }
        let start = pose(2.6, 1.0, 0.0);
        let mut e = Explorer::new(0.3, Clearance::uniform(0.2));
        e.plan(&g, &start);
        let first = e.follower.as_ref().and_then(PurePursuit::goal).unwrap();
        assert!(first.x > 3.5, "the nearer, east alcove first: {first:?}");
        let dt = 0.1;
        for _ in 0..100 {
            let (v, _) = e.command(&start, dt, true);
            assert_eq!(v, 0.0, "a blocked robot does not drive on");
        }
        assert_eq!(e.abandoned(), &[first]);
        assert!(e.wants_plan());
        e.plan(&g, &start);
        let second = e.follower.as_ref().and_then(PurePursuit::goal).unwrap();
        assert!(second.x < 0.5, "then the west one: {second:?}");
    }

    #[test]
    fn a_robot_with_no_reachable_frontier_turns_once_on_the_spot_before_it_gives_up() {
        // A closed, fully known room: nothing to explore.
        let mut g = OccupancyGrid::new(40, 40, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..40 {
            for ix in 0..40 {
                let wall = ix == 0 || iy == 0 || ix == 39 || iy == 39;
                g.set(ix, iy, if wall { 2.0 } else { -2.0 });
            }
        }
        let start = pose(1.0, 1.0, 0.0);
        let mut e = Explorer::new(0.3, Clearance::uniform(0.2));
        e.plan(&g, &start);
        assert!(e.is_turning() && !e.is_done() && !e.wants_plan());
        let dt = 0.1;
        let mut turned = 0.0;
        while e.is_turning() {
            let (v, w) = e.command(&start, dt, false);
            assert_eq!(v, 0.0, "it turns on the spot");
            turned += w * dt;
            assert!(turned < 7.0, "the turn ends");
        }
        assert!((turned - std::f64::consts::TAU).abs() <= Explorer::TURN_RATE * dt + 1e-9, "one full turn: {turned}");
        assert!(e.wants_plan(), "then it plans again");
        e.plan(&g, &start);
        assert!(e.is_done(), "still nothing after the turn: done");
    }

    #[test]
    fn an_explorer_follows_the_path_a_team_planner_gives_and_stops_when_told() {
        let mut e = Explorer::new(0.3, Clearance::uniform(0.2));
        assert!(e.wants_plan() && e.goal().is_none());
        e.follow(vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0)]);
        assert_eq!(e.goal(), Some(Point2::new(1.0, 0.0)));
        assert!(!e.wants_plan(), "a fresh path: no replan before the period");
        let (v, _) = e.command(&pose(0.0, 0.0, 0.0), 0.1, false);
        assert!(v > 0.0, "it drives along the path");
        for _ in 0..30 {
            e.command(&pose(0.0, 0.0, 0.0), 0.1, false);
        }
        assert!(e.wants_plan(), "the replan period is over");
        e.follow(vec![Point2::new(0.0, 0.0), Point2::new(0.0, 2.0)]);
        assert_eq!(e.goal(), Some(Point2::new(0.0, 2.0)), "the new path replaces the old");
        assert!(!e.wants_plan());
        e.finish();
        assert!(e.is_done() && !e.wants_plan() && e.goal().is_none());
        assert_eq!(e.command(&pose(0.0, 0.0, 0.0), 0.1, false), (0.0, 0.0));
    }
}
