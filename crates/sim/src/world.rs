//! The static world: obstacles built from a [`WorldSpec`], with point, footprint and ray queries.

use crate::drive::Footprint;
use crate::error::SimError;
use crate::geometry::{Obstacle, circle_overlaps_polygon, polygons_overlap, to_isometry_points};
use crate::raycast::RayCaster;
use crate::world_file::{NamedPoint, WorldSpec, to_points};
use mrslam_core::Pose2;
use nalgebra::{Point2, Vector2};
use std::collections::BTreeMap;

/// Cell size of the ray caster's bins, metres.
const CASTER_CELL: f64 = 0.5;

/// The static geometry of a world.
#[derive(Debug, Clone)]
pub struct World {
    name: String,
    obstacles: Vec<Obstacle>,
    caster: RayCaster,
    named_points: BTreeMap<String, NamedPoint>,
}

impl World {
    /// Builds the obstacles of a validated spec: each wall segment becomes a box (square caps of half
    /// the thickness close the corners), bitmap cells become merged rectangles.
    pub fn from_spec(spec: &WorldSpec) -> Result<World, SimError> {
        spec.validate()?;
        let mut obstacles = Vec::new();
        for w in &spec.walls {
            let pts = to_points(&w.points);
            for s in pts.windows(2) {
                let d = s[1] - s[0];
                let len = d.norm();
                obstacles.push(Obstacle::Box {
                    center: nalgebra::center(&s[0], &s[1]),
                    half: Vector2::new(0.5 * (len + w.thickness), 0.5 * w.thickness),
                    angle: d.y.atan2(d.x),
                });
            }
        }
        for b in &spec.boxes {
            obstacles.push(Obstacle::Box {
                center: Point2::new(b.center[0], b.center[1]),
                half: Vector2::new(0.5 * b.size[0], 0.5 * b.size[1]),
                angle: b.angle,
            });
        }
        for c in &spec.circles {
            obstacles.push(Obstacle::Circle { center: Point2::new(c.center[0], c.center[1]), radius: c.radius });
        }
        for p in &spec.polygons {
            let mut pts = to_points(&p.points);
            if crate::geometry::signed_area(&pts) < 0.0 {
                pts.reverse();
            }
            obstacles.push(Obstacle::Polygon(pts));
        }
        if let Some(b) = &spec.bitmap {
            obstacles.extend(crate::bitmap::occupied_obstacles(&b.grid));
        }
        Ok(Self::from_obstacles(spec.name.clone(), obstacles, spec.named_points.clone()))
    }

    /// A world of the given obstacles.
    pub fn from_obstacles(name: String, obstacles: Vec<Obstacle>, named_points: BTreeMap<String, NamedPoint>) -> World {
        let caster = RayCaster::new(&obstacles, CASTER_CELL);
        World { name, obstacles, caster, named_points }
    }

    /// Name of the world.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The static obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Named poses of the world file.
    pub fn named_points(&self) -> &BTreeMap<String, NamedPoint> {
        &self.named_points
    }

    /// The named pose `name`.
    pub fn named_pose(&self, name: &str) -> Option<Pose2> {
        self.named_points.get(name).map(NamedPoint::pose)
    }

    /// Axis-aligned bounds `(min, max)` of all obstacles (a unit square at the origin if there are none).
    pub fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        if self.obstacles.is_empty() {
            return (Point2::origin(), Point2::new(1.0, 1.0));
        }
        self.obstacles.iter().fold(
            (Point2::new(f64::INFINITY, f64::INFINITY), Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY)),
            |(lo, hi), o| {
                let (a, b) = o.aabb();
                (lo.inf(&a), hi.sup(&b))
            },
        )
    }

    /// True when `p` lies inside an obstacle.
    pub fn is_occupied(&self, p: &Point2<f64>) -> bool {
        self.obstacles.iter().any(|o| o.contains(p))
    }

    /// True when a robot footprint at `pose` overlaps an obstacle.
    pub fn footprint_collides(&self, footprint: &Footprint, pose: &Pose2) -> bool {
        let c = Point2::from(pose.translation.vector);
        let br = footprint.bounding_radius();
        let outline = to_isometry_points(pose, &footprint.outline());
        self.obstacles.iter().any(|o| {
            let (lo, hi) = o.aabb();
            if c.x + br < lo.x || c.x - br > hi.x || c.y + br < lo.y || c.y - br > hi.y {
                return false;
            }
            match (o, footprint) {
                (Obstacle::Circle { center, radius }, Footprint::Circle { radius: r }) => {
                    (center - c).norm() < radius + r
                }
                (Obstacle::Circle { center, radius }, Footprint::Box { .. }) => {
                    circle_overlaps_polygon(center, *radius, &outline)
                }
                (_, Footprint::Circle { radius }) => circle_overlaps_polygon(&c, *radius, &o.outline()),
                (_, Footprint::Box { .. }) => polygons_overlap(&outline, &o.outline()),
            }
        })
    }

    /// Distance from `origin` in direction `angle` to the first obstacle within `max_range`
    /// (static geometry only).
    pub fn cast_ray(&self, origin: &Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
        let (s, c) = angle.sin_cos();
        self.caster.cast(origin, &Vector2::new(c, s), max_range)
    }

    /// The ray caster over the static geometry.
    pub fn caster(&self) -> &RayCaster {
        &self.caster
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world_file::{BoxSpec, WallSpec};
    use mrslam_core::pose;

    fn spec() -> WorldSpec {
        WorldSpec {
            walls: vec![WallSpec {
                points: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0], [0.0, 0.0]],
                thickness: 0.2,
            }],
            boxes: vec![BoxSpec { center: [2.0, 1.5], size: [0.4, 0.4], angle: 0.0 }],
            ..WorldSpec::default()
        }
    }

    #[test]
    fn walls_close_their_corners() {
        let w = World::from_spec(&spec()).unwrap();
        assert_eq!(w.obstacles().len(), 5);
        assert!(w.is_occupied(&Point2::new(-0.09, -0.09)));
        assert!(w.is_occupied(&Point2::new(4.09, 3.09)));
        assert!(!w.is_occupied(&Point2::new(1.0, 1.0)));
        let (lo, hi) = w.bounds();
        assert!((lo.x + 0.1).abs() < 1e-12 && (hi.y - 3.1).abs() < 1e-12);
    }

    #[test]
    fn rays_and_footprints() {
        let w = World::from_spec(&spec()).unwrap();
        let t = w.cast_ray(&Point2::new(1.0, 1.5), 0.0, 10.0).unwrap();
        assert!((t - 0.8).abs() < 1e-9);
        let fp = Footprint::Circle { radius: 0.2 };
        assert!(!w.footprint_collides(&fp, &pose(1.0, 1.0, 0.0)));
        assert!(w.footprint_collides(&fp, &pose(0.2, 1.0, 0.0)));
        assert!(w.footprint_collides(&fp, &pose(2.0, 1.5, 0.0)));
        let bx = Footprint::Box { length: 0.5, width: 0.3 };
        assert!(!w.footprint_collides(&bx, &pose(1.0, 1.5, 0.0)));
        assert!(w.footprint_collides(&bx, &pose(1.6, 1.5, 0.0)));
        assert!(!w.footprint_collides(&bx, &pose(1.6, 1.5, std::f64::consts::FRAC_PI_2)));
    }
}
