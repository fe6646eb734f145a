//! The simulator: a rapier2d world stepping differential-drive robots with slip, encoders and lidars.
//!
//! Each step (fixed `dt`): every robot's wheels advance under its limits (the encoders count this
//! rotation), the slip process turns wheel rotation into ground motion, the body velocity is set from
//! it and rapier steps the world, so contacts stop a robot at a wall. Then the lidars take the beams
//! that fall within the step, each at its own time, from the pose interpolated between the step's
//! start and end. All randomness comes from per-robot ChaCha8 streams derived from (seed, robot name).

use crate::drive::{DiffDrive, Footprint, RobotModel};
use crate::encoder::{EncoderParams, Encoders};
use crate::error::{SimError, bad_param};
use crate::geometry::{Obstacle, ray_circle, ray_segment};
use crate::lidar::LidarModel;
use crate::slip::{SlipParams, SlipState};
use crate::world::World;
use crate::world_file::WorldSpec;
use mrslam_core::pose::interpolate;
use mrslam_core::{LaserScan, Odometry, Pose2, Xyt, pose};
use nalgebra::{Point2, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rapier2d::prelude as rp;
use std::collections::VecDeque;

/// Handle of a robot in a [`Sim`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RobotId(pub usize);

/// How lidar beams are cast.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RayBackend {
    /// Own grid-binned caster over the static geometry, plus the other robots' footprints (fast).
    #[default]
    Grid,
    /// rapier's query pipeline over every collider (f32).
    Rapier,
}

/// Simulator settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Fixed time step, seconds.
    pub dt: f64,
    /// Lidar ray casting backend.
    pub ray_backend: RayBackend,
    /// Published scans kept per robot until taken; older ones are dropped.
    pub scan_queue: usize,
}

impl Default for SimConfig {
    /// 10 ms steps, grid ray casting, up to 8 queued scans.
    fn default() -> Self {
        SimConfig { dt: 0.01, ray_backend: RayBackend::Grid, scan_queue: 8 }
    }
}

/// What happened to one robot during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotStep {
    /// The robot.
    pub id: RobotId,
    /// True when the robot touches an obstacle or another robot after the step.
    pub contact: bool,
    /// Number of colliders the robot touches.
    pub contacts: usize,
    /// True when a scan was completed during the step (see [`Sim::take_scan`]).
    pub scan_ready: bool,
    /// True while a slip event is under way on either wheel.
    pub slipping: bool,
}

/// What happened during a step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepEvents {
    /// Simulated time at the end of the step, seconds.
    pub time: f64,
    /// One entry per robot, in id order.
    pub robots: Vec<RobotStep>,
}

#[derive(Debug, Clone)]
struct ScanState {
    t0: f64,
    next: usize,
    ranges: Vec<f32>,
}

#[derive(Debug)]
struct Robot {
    name: String,
    drive: DiffDrive,
    lidar: LidarModel,
    slip: SlipState,
    enc: Encoders,
    body: rp::RigidBodyHandle,
    collider: rp::ColliderHandle,
    start: Pose2,
    pose: Pose2,
    rng_slip: ChaCha8Rng,
    rng_lidar: ChaCha8Rng,
    scan: ScanState,
    ready: VecDeque<LaserScan>,
    contacts: usize,
}

/// The simulator.
pub struct Sim {
    world: World,
    config: SimConfig,
    seed: u64,
    physics: rp::PhysicsWorld,
    robots: Vec<Robot>,
    steps: u64,
    t_offset: f64,
}

/// FNV-1a hash of a string: a stable stream id for a robot's RNG.
fn stream_id(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// The seeded RNG stream `purpose` of robot `name`.
pub fn robot_rng(seed: u64, name: &str, purpose: &str) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream_id(&format!("{name}/{purpose}")));
    rng
}

fn to_glam(p: &Pose2) -> rp::Pose {
    let Xyt { x, y, theta: t } = Xyt::from_pose(p);
    rp::Pose::new(rp::Vector::new(x as f32, y as f32), t as f32)
}

fn from_glam(p: &rp::Pose) -> Pose2 {
    pose(p.translation.x as f64, p.translation.y as f64, p.rotation.angle() as f64)
}

fn obstacle_collider(o: &Obstacle) -> rp::ColliderBuilder {
    let v = |p: &Point2<f64>| rp::Vector::new(p.x as f32, p.y as f32);
    match o {
        Obstacle::Box { center, half, angle } => {
            rp::ColliderBuilder::cuboid(half.x as f32, half.y as f32).position(rp::Pose::new(v(center), *angle as f32))
        }
        Obstacle::Circle { center, radius } => rp::ColliderBuilder::ball(*radius as f32).translation(v(center)),
        Obstacle::Polygon(pts) => {
            let vs: Vec<rp::Vector> = pts.iter().map(v).collect();
            let convex = crate::geometry::is_convex(pts);
            let hull = if convex { rp::ColliderBuilder::convex_polyline(vs.clone()) } else { None };
            hull.unwrap_or_else(|| {
                let n = vs.len() as u32;
                let idx = (0..n).map(|i| [i, (i + 1) % n]).collect();
                rp::ColliderBuilder::polyline(vs, Some(idx))
            })
        }
    }
}

impl Sim {
    /// A simulator of the world `spec` with default settings; `seed` drives every random draw.
    pub fn new(spec: &WorldSpec, seed: u64) -> Result<Sim, SimError> {
        Self::with_config(spec, seed, SimConfig::default())
    }

    /// A simulator with explicit settings.
    pub fn with_config(spec: &WorldSpec, seed: u64, config: SimConfig) -> Result<Sim, SimError> {
        let world = World::from_spec(spec)?;
        Self::from_world(world, seed, config)
    }

    /// A simulator of an already built world.
    pub fn from_world(world: World, seed: u64, config: SimConfig) -> Result<Sim, SimError> {
        crate::error::check_positive("SimConfig.dt", config.dt)?;
        if config.dt > 0.1 {
            return Err(bad_param("SimConfig.dt", "must be at most 0.1 s"));
        }
        let mut physics = rp::PhysicsWorld { gravity: rp::Vector::ZERO, ..Default::default() };
        physics.integration_parameters.dt = config.dt as f32;
        for o in world.obstacles() {
            physics.colliders.insert(obstacle_collider(o).friction(0.3).restitution(0.0));
        }
        // Fill the broad phase now so scene queries work before the first step.
        physics.detect_collisions(&(), &());
        Ok(Sim { world, config, seed, physics, robots: Vec::new(), steps: 0, t_offset: 0.0 })
    }

    /// The static world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The settings.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Simulated time, seconds.
    pub fn time(&self) -> f64 {
        self.t_offset + self.steps as f64 * self.config.dt
    }

    /// Ids of all robots, in order of addition.
    pub fn robot_ids(&self) -> Vec<RobotId> {
        (0..self.robots.len()).map(RobotId).collect()
    }

    /// The robot called `name`.
    pub fn robot_id(&self, name: &str) -> Option<RobotId> {
        self.robots.iter().position(|r| r.name == name).map(RobotId)
    }

    fn robot(&self, id: RobotId) -> Result<&Robot, SimError> {
        self.robots.get(id.0).ok_or(SimError::UnknownRobot(id.0))
    }

    fn robot_mut(&mut self, id: RobotId) -> Result<&mut Robot, SimError> {
        self.robots.get_mut(id.0).ok_or(SimError::UnknownRobot(id.0))
    }

    /// Adds a robot at `start`; errors if its footprint overlaps an obstacle or another robot, if the
    /// name is taken or a parameter is out of range. Its first scan starts now.
    pub fn add_robot(
        &mut self,
        name: &str,
        model: RobotModel,
        lidar: LidarModel,
        slip: SlipParams,
        encoders: EncoderParams,
        start: Pose2,
    ) -> Result<RobotId, SimError> {
        model.validate()?;
        lidar.validate()?;
        slip.validate()?;
        let Xyt { x: sx, y: sy, theta: st } = Xyt::from_pose(&start);
        if !(sx.is_finite() && sy.is_finite() && st.is_finite()) {
            return Err(bad_param("start", "must be finite"));
        }
        if self.robot_id(name).is_some() {
            return Err(SimError::DuplicateRobot(name.to_string()));
        }
        let in_obstacle = self.world.footprint_collides(&model.footprint, &start)
            || self.robots.iter().any(|r| {
                let d = (r.pose.translation.vector - start.translation.vector).norm();
                d < r.drive.model().footprint.bounding_radius() + model.footprint.bounding_radius()
            });
        if in_obstacle {
            return Err(SimError::StartInObstacle { name: name.to_string(), x: sx, y: sy });
        }
        let enc = Encoders::new(encoders, model.wheel_radius, model.wheel_base, self.time())?;
        let shape = match model.footprint {
            Footprint::Circle { radius } => rp::ColliderBuilder::ball(radius as f32),
            Footprint::Box { length, width } => rp::ColliderBuilder::cuboid(0.5 * length as f32, 0.5 * width as f32),
        };
        let area = match model.footprint {
            Footprint::Circle { radius } => std::f64::consts::PI * radius * radius,
            Footprint::Box { length, width } => length * width,
        };
        let body = rp::RigidBodyBuilder::dynamic()
            .pose(to_glam(&start))
            .ccd_enabled(true)
            .can_sleep(false)
            .linear_damping(0.0)
            .angular_damping(0.0);
        let collider = shape.density((model.mass / area) as f32).friction(0.3).restitution(0.0);
        let (body, collider) = self.physics.insert(body, collider);
        self.physics.detect_collisions(&(), &());
        let n = lidar.beam_count();
        let t0 = self.time();
        self.robots.push(Robot {
            name: name.to_string(),
            drive: DiffDrive::new(model),
            slip: SlipState::new(slip),
            enc,
            body,
            collider,
            start,
            pose: start,
            rng_slip: robot_rng(self.seed, name, "slip"),
            rng_lidar: robot_rng(self.seed, name, "lidar"),
            scan: ScanState { t0, next: 0, ranges: vec![f32::NAN; n] },
            lidar,
            ready: VecDeque::new(),
            contacts: 0,
        });
        Ok(RobotId(self.robots.len() - 1))
    }

    /// Commands wheel angular speeds (rad/s, left and right), limited by the robot's max speed.
    pub fn set_wheel_command(&mut self, id: RobotId, left: f64, right: f64) -> Result<(), SimError> {
        self.robot_mut(id)?.drive.set_command(left, right)
    }

    /// Commands body speeds: `v` forward (m/s) and `w` turn rate (rad/s), through the wheel speeds.
    pub fn set_velocity_command(&mut self, id: RobotId, v: f64, w: f64) -> Result<(), SimError> {
        let r = self.robot_mut(id)?;
        let [l, rr] = r.drive.model().wheel_speeds(v, w);
        r.drive.set_command(l, rr)
    }

    /// Advances the world by one time step.
    pub fn step(&mut self) -> StepEvents {
        let dt = self.config.dt;
        let t_start = self.time();
        let t_end = self.t_offset + (self.steps + 1) as f64 * dt;
        let mut starts = Vec::with_capacity(self.robots.len());
        for r in &mut self.robots {
            let dphi = r.drive.advance(dt);
            let m = r.drive.model();
            let rim = [dphi[0] / dt * m.wheel_radius, dphi[1] / dt * m.wheel_radius];
            let turn = (rim[1] - rim[0]) / m.wheel_base;
            let s = r.slip.step(&mut r.rng_slip, dt, rim, turn);
            let ground = [rim[0] * (1.0 - s[0]), rim[1] * (1.0 - s[1])];
            let (v, w) = m.body_speeds(ground);
            // Exact arc displacement over the step, so rapier's straight-line integration lands on it.
            let dth = w * dt;
            let (dx, dy) = if dth.abs() < 1e-9 {
                (v * dt, 0.0)
            } else {
                let rad = v / w;
                (rad * dth.sin(), rad * (1.0 - dth.cos()))
            };
            let d = r.pose.rotation * Vector2::new(dx, dy) / dt;
            if let Some(b) = self.physics.bodies.get_mut(r.body) {
                b.set_linvel(rp::Vector::new(d.x as f32, d.y as f32), true);
                b.set_angvel(w as f32, true);
            }
            r.enc.advance(dphi, t_end);
            starts.push(r.pose);
        }
        self.physics.step();
        self.steps += 1;
        for r in &mut self.robots {
            if let Some(b) = self.physics.bodies.get(r.body) {
                r.pose = from_glam(b.position());
            }
            r.contacts =
                self.physics.narrow_phase.contact_pairs_with(r.collider).filter(|p| p.has_any_active_contact()).count();
        }
        let shapes = robot_shapes(&self.robots);
        let mut events = Vec::with_capacity(self.robots.len());
        let (world, physics, backend, queue) =
            (&self.world, &self.physics, self.config.ray_backend, self.config.scan_queue);
        for (i, r) in self.robots.iter_mut().enumerate() {
            let caster = BeamCaster { world, physics, backend, own: i, own_body: r.body, robots: &shapes };
            let ready = advance_lidar(r, &caster, &starts[i], t_start, t_end, queue);
            events.push(RobotStep {
                id: RobotId(i),
                contact: r.contacts > 0,
                contacts: r.contacts,
                scan_ready: ready,
                slipping: r.slip.in_event(),
            });
        }
        StepEvents { time: t_end, robots: events }
    }

    /// The robot's true pose in the world frame.
    pub fn true_pose(&self, id: RobotId) -> Result<Pose2, SimError> {
        Ok(self.robot(id)?.pose)
    }

    /// The robot's start pose in the world frame (the origin of its odometry frame).
    pub fn start_pose(&self, id: RobotId) -> Result<Pose2, SimError> {
        Ok(self.robot(id)?.start)
    }

    /// The robot's odometry: integrated from encoder ticks, identity at its start.
    pub fn odometry(&self, id: RobotId) -> Result<Odometry, SimError> {
        Ok(self.robot(id)?.enc.odometry())
    }

    /// The robot's encoder tick counts (left, right).
    pub fn encoder_ticks(&self, id: RobotId) -> Result<[i64; 2], SimError> {
        Ok(self.robot(id)?.enc.ticks())
    }

    /// The robot's current wheel angular speeds (left, right), rad/s.
    pub fn wheel_speeds(&self, id: RobotId) -> Result<[f64; 2], SimError> {
        Ok(self.robot(id)?.drive.wheel_speeds())
    }

    /// Number of colliders the robot touched after the last step.
    pub fn contacts(&self, id: RobotId) -> Result<usize, SimError> {
        Ok(self.robot(id)?.contacts)
    }

    /// The robot's name.
    pub fn robot_name(&self, id: RobotId) -> Result<&str, SimError> {
        Ok(&self.robot(id)?.name)
    }

    /// The robot's model.
    pub fn robot_model(&self, id: RobotId) -> Result<&RobotModel, SimError> {
        Ok(self.robot(id)?.drive.model())
    }

    /// The robot's lidar model.
    pub fn lidar_model(&self, id: RobotId) -> Result<&LidarModel, SimError> {
        Ok(&self.robot(id)?.lidar)
    }

    /// The oldest completed scan not yet taken (`None` until a scan period completes).
    pub fn take_scan(&mut self, id: RobotId) -> Result<Option<LaserScan>, SimError> {
        Ok(self.robot_mut(id)?.ready.pop_front())
    }

    /// One scan cast right now from the robot's current pose (no skew), outside the scan schedule.
    /// Draws noise from the robot's lidar stream.
    pub fn scan_now(&mut self, id: RobotId) -> Result<LaserScan, SimError> {
        let shapes = robot_shapes(&self.robots);
        let t = self.time();
        let (world, physics, backend) = (&self.world, &self.physics, self.config.ray_backend);
        let r = self.robots.get_mut(id.0).ok_or(SimError::UnknownRobot(id.0))?;
        let caster = BeamCaster { world, physics, backend, own: id.0, own_body: r.body, robots: &shapes };
        let sensor = r.pose * r.lidar.mount;
        let ranges =
            (0..r.lidar.beam_count()).map(|i| cast_beam(&r.lidar, &mut r.rng_lidar, &caster, &sensor, i)).collect();
        Ok(make_scan(&r.lidar, t, ranges))
    }

    /// The true occupancy grid of the static world at `resolution` metres per cell.
    pub fn true_map(&self, resolution: f64) -> Result<mrslam_core::OccupancyGrid, SimError> {
        self.world.true_map(resolution)
    }
}

/// A robot's footprint at `pose` as an obstacle (for other robots' lidars).
fn robot_obstacle(fp: &Footprint, pose: &Pose2) -> Obstacle {
    let Xyt { x, y, theta: t } = Xyt::from_pose(pose);
    match *fp {
        Footprint::Circle { radius } => Obstacle::Circle { center: Point2::new(x, y), radius },
        Footprint::Box { length, width } => {
            Obstacle::Box { center: Point2::new(x, y), half: Vector2::new(0.5 * length, 0.5 * width), angle: t }
        }
    }
}

/// Everything a beam can hit.
struct BeamCaster<'a> {
    world: &'a World,
    physics: &'a rp::PhysicsWorld,
    backend: RayBackend,
    own: usize,
    own_body: rp::RigidBodyHandle,
    robots: &'a [RobotShape],
}

/// A robot's footprint as other robots' lidars see it: index, shape and outline (empty for a disc).
type RobotShape = (usize, Obstacle, Vec<Point2<f64>>);

fn robot_shapes(robots: &[Robot]) -> Vec<RobotShape> {
    robots
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let o = robot_obstacle(&r.drive.model().footprint, &r.pose);
            let outline = o.outline();
            (i, o, outline)
        })
        .collect()
}

impl BeamCaster<'_> {
    /// Distance to the first hit from `o` along unit `d` within `tmax`.
    fn cast(&self, o: &Point2<f64>, d: &Vector2<f64>, tmax: f64) -> Option<f64> {
        match self.backend {
            RayBackend::Grid => {
                let mut best = self.world.caster().cast(o, d, tmax);
                let mut lim = best.unwrap_or(tmax);
                for (i, ob, p) in self.robots {
                    if *i == self.own {
                        continue;
                    }
                    let t = match ob {
                        Obstacle::Circle { center, radius } => ray_circle(o, d, center, *radius, lim),
                        _ => (0..p.len())
                            .filter_map(|k| ray_segment(o, d, &p[k], &p[(k + 1) % p.len()], lim))
                            .min_by(f64::total_cmp),
                    };
                    if let Some(t) = t {
                        best = Some(t);
                        lim = t;
                    }
                }
                best
            }
            RayBackend::Rapier => {
                let filter = rp::QueryFilter::default().exclude_rigid_body(self.own_body);
                let qp = self.physics.query_pipeline_with_filter(filter);
                let ray =
                    rp::Ray::new(rp::Vector::new(o.x as f32, o.y as f32), rp::Vector::new(d.x as f32, d.y as f32));
                qp.cast_ray(&ray, tmax as f32, true).map(|(_, t)| t as f64)
            }
        }
    }
}

fn cast_beam(lidar: &LidarModel, rng: &mut ChaCha8Rng, caster: &BeamCaster, sensor: &Pose2, i: usize) -> f32 {
    let a = sensor.rotation.angle() + lidar.beam_direction(i, rng);
    let o = Point2::from(sensor.translation.vector);
    let d = Vector2::new(a.cos(), a.sin());
    // Cast a little beyond range_max so noise can decide readings near the limit.
    let t = caster.cast(&o, &d, lidar.range_max * 1.05 + 0.1);
    lidar.measure(t, rng)
}

fn make_scan(lidar: &LidarModel, stamp: f64, ranges: Vec<f32>) -> LaserScan {
    LaserScan {
        stamp,
        angle_min: lidar.angle_min(),
        angle_increment: lidar.resolution,
        range_min: lidar.range_min as f32,
        range_max: lidar.range_max as f32,
        ranges,
    }
}

/// Takes the beams of `r`'s lidar due in `[t_start, t_end)`; returns true when a scan was published.
fn advance_lidar(
    r: &mut Robot,
    caster: &BeamCaster,
    pose_start: &Pose2,
    t_start: f64,
    t_end: f64,
    queue: usize,
) -> bool {
    let n = r.lidar.beam_count();
    let inc = if r.lidar.skew { r.lidar.time_increment() } else { 0.0 };
    let dt = t_end - t_start;
    let mut published = false;
    loop {
        while r.scan.next < n {
            let tb = r.scan.t0 + r.scan.next as f64 * inc;
            if tb >= t_end - 1e-9 {
                break;
            }
            let s = ((tb - t_start) / dt).clamp(0.0, 1.0);
            let sensor = interpolate(pose_start, &r.pose, s) * r.lidar.mount;
            let i = r.scan.next;
            r.scan.ranges[i] = cast_beam(&r.lidar, &mut r.rng_lidar, caster, &sensor, i);
            r.scan.next += 1;
        }
        if r.scan.next == n && r.scan.t0 + r.lidar.scan_period <= t_end + 1e-9 {
            let ranges = std::mem::replace(&mut r.scan.ranges, vec![f32::NAN; n]);
            r.ready.push_back(make_scan(&r.lidar, r.scan.t0, ranges));
            while r.ready.len() > queue.max(1) {
                r.ready.pop_front();
            }
            r.scan.t0 += r.lidar.scan_period;
            r.scan.next = 0;
            published = true;
        } else {
            return published;
        }
    }
}
