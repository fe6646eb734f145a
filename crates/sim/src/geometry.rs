//! Planar geometry of obstacles: primitives, containment, overlap and ray intersection (f64, world frame).

use nalgebra::{Point2, Vector2};

/// Tolerance of geometric predicates, metres.
pub const EPS: f64 = 1e-9;

/// One static obstacle in the world frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Obstacle {
    /// An oriented rectangle (wall segment, box, merged bitmap cells).
    Box {
        /// Centre, metres.
        center: Point2<f64>,
        /// Half extents along the box's own x and y axes, metres.
        half: Vector2<f64>,
        /// Orientation, radians.
        angle: f64,
    },
    /// A disc.
    Circle {
        /// Centre, metres.
        center: Point2<f64>,
        /// Radius, metres.
        radius: f64,
    },
    /// A simple polygon (convex or not), counter-clockwise.
    Polygon(Vec<Point2<f64>>),
}

impl Obstacle {
    /// Outline of a box or polygon (counter-clockwise); empty for a circle.
    pub fn outline(&self) -> Vec<Point2<f64>> {
        match self {
            Obstacle::Box { center, half, angle } => box_corners(center, half, *angle).to_vec(),
            Obstacle::Circle { .. } => Vec::new(),
            Obstacle::Polygon(p) => p.clone(),
        }
    }

    /// Axis-aligned bounds `(min, max)`.
    pub fn aabb(&self) -> (Point2<f64>, Point2<f64>) {
        match self {
            Obstacle::Circle { center, radius } => {
                (center - Vector2::new(*radius, *radius), center + Vector2::new(*radius, *radius))
            }
            _ => points_aabb(&self.outline()),
        }
    }

    /// True when `p` lies inside the obstacle (boundary included).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        match self {
            Obstacle::Circle { center, radius } => (p - center).norm() <= *radius + EPS,
            _ => point_in_polygon(p, &self.outline()),
        }
    }

    /// True when the obstacle overlaps the open axis-aligned square `[min, max]` shrunk by `EPS`.
    pub fn overlaps_aabb(&self, min: &Point2<f64>, max: &Point2<f64>) -> bool {
        let (lo, hi) = (min + Vector2::new(EPS, EPS), max - Vector2::new(EPS, EPS));
        match self {
            Obstacle::Circle { center, radius } => {
                let q = Point2::new(center.x.clamp(lo.x, hi.x), center.y.clamp(lo.y, hi.y));
                (q - center).norm() < *radius
            }
            _ => polygon_overlaps_aabb(&self.outline(), &lo, &hi),
        }
    }
}

/// Corners of an oriented box, counter-clockwise.
pub fn box_corners(center: &Point2<f64>, half: &Vector2<f64>, angle: f64) -> [Point2<f64>; 4] {
    let (s, c) = angle.sin_cos();
    let ax = Vector2::new(c, s) * half.x;
    let ay = Vector2::new(-s, c) * half.y;
    [center - ax - ay, center + ax - ay, center + ax + ay, center - ax + ay]
}

/// Axis-aligned bounds of a point set.
pub fn points_aabb(pts: &[Point2<f64>]) -> (Point2<f64>, Point2<f64>) {
    let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in pts {
        lo.x = lo.x.min(p.x);
        lo.y = lo.y.min(p.y);
        hi.x = hi.x.max(p.x);
        hi.y = hi.y.max(p.y);
    }
    (lo, hi)
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn signed_area(pts: &[Point2<f64>]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        * 0.5
}

/// True when the polygon is convex (either orientation).
pub fn is_convex(pts: &[Point2<f64>]) -> bool {
    let n = pts.len();
    let mut sign = 0.0;
    for i in 0..n {
        let (a, b, c) = (pts[i], pts[(i + 1) % n], pts[(i + 2) % n]);
        let cross = (b - a).perp(&(c - b));
        if cross.abs() > EPS {
            if sign == 0.0 {
                sign = cross.signum();
            } else if cross.signum() != sign {
                return false;
            }
        }
    }
    true
}

/// Even-odd point-in-polygon test.
pub fn point_in_polygon(p: &Point2<f64>, pts: &[Point2<f64>]) -> bool {
    let n = pts.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (pts[i], pts[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// True when the closed segments `ab` and `cd` cross at a point interior to both.
pub fn segments_cross(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>, d: &Point2<f64>) -> bool {
    let d1 = (b - a).perp(&(c - a));
    let d2 = (b - a).perp(&(d - a));
    let d3 = (d - c).perp(&(a - c));
    let d4 = (d - c).perp(&(b - c));
    ((d1 > EPS && d2 < -EPS) || (d1 < -EPS && d2 > EPS)) && ((d3 > EPS && d4 < -EPS) || (d3 < -EPS && d4 > EPS))
}

/// True when two non-adjacent edges of the polygon cross.
pub fn polygon_self_intersects(pts: &[Point2<f64>]) -> bool {
    let n = pts.len();
    for i in 0..n {
        for j in (i + 2)..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            if segments_cross(&pts[i], &pts[(i + 1) % n], &pts[j], &pts[(j + 1) % n]) {
                return true;
            }
        }
    }
    false
}

/// True when the segment `ab` passes through the interior of the box `[lo, hi]` (Liang–Barsky clip).
pub fn segment_overlaps_aabb(a: &Point2<f64>, b: &Point2<f64>, lo: &Point2<f64>, hi: &Point2<f64>) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-d.x, a.x - lo.x), (d.x, hi.x - a.x), (-d.y, a.y - lo.y), (d.y, hi.y - a.y)] {
        if p.abs() < 1e-15 {
            if q < 0.0 {
                return false;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// True when a polygon and the box `[lo, hi]` overlap.
pub fn polygon_overlaps_aabb(pts: &[Point2<f64>], lo: &Point2<f64>, hi: &Point2<f64>) -> bool {
    let (plo, phi) = points_aabb(pts);
    if plo.x > hi.x || plo.y > hi.y || phi.x < lo.x || phi.y < lo.y {
        return false;
    }
    let centre = nalgebra::center(lo, hi);
    if point_in_polygon(&centre, pts) {
        return true;
    }
    let n = pts.len();
    (0..n).any(|i| segment_overlaps_aabb(&pts[i], &pts[(i + 1) % n], lo, hi))
}

/// Distance from `p` to the segment `ab`.
pub fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 { ((p - a).dot(&ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
}

/// True when a disc overlaps a polygon (interior contact, not mere touching).
pub fn circle_overlaps_polygon(c: &Point2<f64>, r: f64, pts: &[Point2<f64>]) -> bool {
    if point_in_polygon(c, pts) {
        return true;
    }
    let n = pts.len();
    (0..n).any(|i| point_segment_distance(c, &pts[i], &pts[(i + 1) % n]) < r - EPS)
}

/// True when two polygons overlap.
pub fn polygons_overlap(a: &[Point2<f64>], b: &[Point2<f64>]) -> bool {
    if a.iter().any(|p| point_in_polygon(p, b)) || b.iter().any(|p| point_in_polygon(p, a)) {
        return true;
    }
    let (n, m) = (a.len(), b.len());
    (0..n).any(|i| (0..m).any(|j| segments_cross(&a[i], &a[(i + 1) % n], &b[j], &b[(j + 1) % m])))
}

/// Distance along the ray `o + t d` (|d| = 1) to the segment `ab`, if it hits within `[0, tmax]`.
#[inline]
pub fn ray_segment(o: &Point2<f64>, d: &Vector2<f64>, a: &Point2<f64>, b: &Point2<f64>, tmax: f64) -> Option<f64> {
    let e = b - a;
    let denom = d.perp(&e);
    if denom.abs() < 1e-15 {
        return None;
    }
    let ao = a - o;
    let t = ao.perp(&e) / denom;
    let u = ao.perp(d) / denom;
    (t >= 0.0 && t <= tmax && (-1e-12..=1.0 + 1e-12).contains(&u)).then_some(t)
}

/// Distance along the ray `o + t d` (|d| = 1) to the circle, 0 when `o` is inside, if within `tmax`.
#[inline]
pub fn ray_circle(o: &Point2<f64>, d: &Vector2<f64>, c: &Point2<f64>, r: f64, tmax: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    let cc = oc.norm_squared() - r * r;
    if cc <= 0.0 {
        return Some(0.0);
    }
    let disc = b * b - cc;
    if disc < 0.0 || b > 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t >= 0.0 && t <= tmax).then_some(t)
}

/// Transforms points by a pose.
pub fn to_isometry_points(p: &mrslam_core::Pose2, pts: &[Point2<f64>]) -> Vec<Point2<f64>> {
    pts.iter().map(|q| p * q).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn box_contains_and_overlaps() {
        let b = Obstacle::Box { center: p(1.0, 1.0), half: Vector2::new(1.0, 0.5), angle: std::f64::consts::FRAC_PI_2 };
        assert!(b.contains(&p(1.0, 1.9)));
        assert!(!b.contains(&p(1.9, 1.0)));
        assert!(b.overlaps_aabb(&p(1.4, 0.0), &p(1.6, 0.2)));
        assert!(!b.overlaps_aabb(&p(1.5, 0.0), &p(1.7, 0.2)));
    }

    #[test]
    fn polygon_predicates() {
        let sq = [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)];
        assert!((signed_area(&sq) - 1.0).abs() < 1e-12);
        assert!(is_convex(&sq));
        assert!(!polygon_self_intersects(&sq));
        let bow = [p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 1.0)];
        assert!(polygon_self_intersects(&bow));
        let l = [p(0.0, 0.0), p(2.0, 0.0), p(2.0, 1.0), p(1.0, 1.0), p(1.0, 2.0), p(0.0, 2.0)];
        assert!(!is_convex(&l));
        assert!(!point_in_polygon(&p(1.5, 1.5), &l));
        assert!(point_in_polygon(&p(0.5, 1.5), &l));
    }

    #[test]
    fn rays_hit_segments_and_circles() {
        let o = p(0.0, 0.0);
        let d = Vector2::new(1.0, 0.0);
        let t = ray_segment(&o, &d, &p(2.0, -1.0), &p(2.0, 1.0), 10.0).unwrap();
        assert!((t - 2.0).abs() < 1e-12);
        assert!(ray_segment(&o, &d, &p(2.0, 0.5), &p(2.0, 1.0), 10.0).is_none());
        assert!(ray_segment(&o, &d, &p(2.0, -1.0), &p(2.0, 1.0), 1.5).is_none());
        let t = ray_circle(&o, &d, &p(3.0, 0.0), 0.5, 10.0).unwrap();
        assert!((t - 2.5).abs() < 1e-12);
        assert!(ray_circle(&o, &d, &p(-3.0, 0.0), 0.5, 10.0).is_none());
        assert_eq!(ray_circle(&o, &d, &p(0.1, 0.0), 0.5, 10.0), Some(0.0));
    }

    #[test]
    fn overlap_tests() {
        let sq = [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)];
        assert!(circle_overlaps_polygon(&p(1.2, 0.5), 0.3, &sq));
        assert!(!circle_overlaps_polygon(&p(1.4, 0.5), 0.3, &sq));
        let sq2: Vec<_> = sq.iter().map(|q| q + Vector2::new(0.5, 0.5)).collect();
        assert!(polygons_overlap(&sq, &sq2));
        let sq3: Vec<_> = sq.iter().map(|q| q + Vector2::new(1.5, 0.0)).collect();
        assert!(!polygons_overlap(&sq, &sq3));
    }
}
