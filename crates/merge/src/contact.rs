//! Two robots known to be near each other when their maps are merged: a bound on the transform between the maps.
//!
//! Robots that exchange maps over a radio of range r are at most r apart at that moment (two robots in contact,
//! Dudek-style rendezvous). Each knows its own pose in its own map, so an answer `T_a_b` that puts b's robot
//! farther than r (plus the robots' localisation error) from a's is not where the maps meet: the gate refuses
//! it, and, when asked ([`Contact::search_within`]), the correlative search does not look there. `mrslam merge`
//! of two files knows no contact unless `--contact` gives one.

use mrslam_core::Pose2;
use nalgebra::{Point2, Rotation2};

/// Where two robots in contact were, each in its own map's frame, and how far apart they can have been.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Robot of map a, in a's frame, metres.
    pub a: Point2<f64>,
    /// Robot of map b, in b's frame, metres.
    pub b: Point2<f64>,
    /// Largest distance between them, metres: the link's range plus the error of the robots' poses.
    pub within_m: f64,
    /// Whether the correlative searches keep to the translations within reach (faster), or search every one
    /// and leave the bound to the gate. Off by default where it is offered: a search kept within reach no
    /// longer sees the answers elsewhere that tell a self-similar pair is ambiguous, and in the FR079 team
    /// study one such pair merged 178° wrong within reach (the gate alone refused it).
    pub search_within: bool,
}

impl Contact {
    /// The same contact seen from b: for merging b with a.
    pub fn swapped(&self) -> Contact {
        Contact { a: self.b, b: self.a, ..*self }
    }

    /// How far apart `t_a_b` puts the two robots, metres.
    pub fn distance(&self, t_a_b: &Pose2) -> f64 {
        (t_a_b * self.b - self.a).norm()
    }

    /// Why `t_a_b` cannot be the transform: it puts the robots farther apart than they were.
    pub fn refusal(&self, t_a_b: &Pose2) -> Option<String> {
        let d = self.distance(t_a_b);
        (d > self.within_m).then(|| {
            format!(
                "the answer puts the robots {d:.1} m apart, and they were in contact (within {:.1} m)",
                self.within_m
            )
        })
    }

    /// The translations a scan search may try at rotation `theta`, as a box of offsets in cells of `cell`
    /// metres, `[x0, x1, y0, y1]`.
    ///
    /// The scan is b's points about their centroid `centroid` (b's frame) turned by `theta`, placed so the
    /// centroid lands at `cell * (offset + 0.5)` in a's grid frame, whose pose in a's frame is `origin_a`
    /// (as the correlative search discretises it).
    pub fn offsets(&self, origin_a: &Pose2, centroid: &Point2<f64>, theta: f64, cell: f64) -> [i32; 4] {
        let robot_a = origin_a.inverse() * self.a;
        // Where the centroid must land for b's robot to land on a's: robot_a - R(theta) (b - centroid).
        let centre = robot_a - Rotation2::new(theta) * (self.b - centroid);
        let lo = |v: f64| ((v - self.within_m) / cell - 0.5).floor() as i32;
        let hi = |v: f64| ((v + self.within_m) / cell - 0.5).ceil() as i32;
        [lo(centre.x), hi(centre.x), lo(centre.y), hi(centre.y)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn a_transform_that_puts_the_robots_apart_is_refused() {
        let c = Contact { a: Point2::new(1.0, 2.0), b: Point2::new(0.0, 0.0), within_m: 5.0, search_within: true };
        assert!(c.refusal(&pose(1.0, 2.0, 0.7)).is_none());
        assert!(c.refusal(&pose(5.0, 2.0, 0.0)).is_none());
        let far = c.refusal(&pose(7.0, 2.0, 0.0)).unwrap();
        assert!(far.contains("6.0 m apart") && far.contains("within 5.0 m"), "{far}");
        // Seen from b the distance is the same.
        let t = pose(3.0, -1.0, 1.1);
        assert!((c.swapped().distance(&t.inverse()) - c.distance(&t)).abs() < 1e-9);
    }

    #[test]
    fn the_offsets_hold_every_translation_that_keeps_the_robots_in_range() {
        let origin_a = pose(-3.0, 4.0, 0.3);
        let centroid = Point2::new(2.0, -1.0);
        let c = Contact { a: Point2::new(1.5, 0.5), b: Point2::new(4.0, 2.0), within_m: 3.0, search_within: true };
        let cell = 0.2;
        for theta in [0.0, 0.8, -2.5] {
            let [x0, x1, y0, y1] = c.offsets(&origin_a, &centroid, theta, cell);
            // Every offset of a 0.1-cell lattice over a wide square: inside the box if the robots are in range.
            for i in -400..=400 {
                for j in -400..=400 {
                    let (ox, oy) = (f64::from(i) * 0.25, f64::from(j) * 0.25);
                    let t = Point2::new(cell * (ox + 0.5), cell * (oy + 0.5));
                    // The scan pose (theta, t) as T_a_b: b's centroid turned by theta lands at t in a's grid.
                    let rc = Rotation2::new(theta) * centroid.coords;
                    let t_a_b = origin_a * pose(t.x - rc.x, t.y - rc.y, theta);
                    if c.distance(&t_a_b) <= c.within_m {
                        let inside =
                            ox >= f64::from(x0) && ox <= f64::from(x1) && oy >= f64::from(y0) && oy <= f64::from(y1);
                        assert!(
                            inside,
                            "theta {theta}: offset ({ox}, {oy}) keeps them in range, box {x0}..{x1} {y0}..{y1}"
                        );
                    }
                }
            }
            // And the box is not much larger than the disc: 2 r / cell plus a cell or two each way.
            assert!(x1 - x0 <= (2.0 * c.within_m / cell) as i32 + 2 && y1 - y0 <= (2.0 * c.within_m / cell) as i32 + 2);
        }
    }
}
