//! TRIANGLE(r1, r2) (Algorithm 1, line 12, equation 1) and the bisector comparison of line 13.
//!
//! A triangle is three MERs `(i, j, k)` read as apex `i` and base `j k`, their centres its vertices. Its
//! descriptor is equation (1) read literally:
//! `[A_i / d_jk, A_j / d_jk, A_k / d_jk, α_j, β_k]`, with `A` a MER's area, `d_jk` the distance between
//! the centres of `j` and `k` (the side opposite the apex), and `α_j`, `β_k` the triangle's interior angles
//! at `j` and `k`. Lengths are in metres and angles in radians, the angles weighted by
//! [`TriangleParams::angle_weight`]; the cost of a pair is the Euclidean norm of the descriptors'
//! difference. The descriptor depends on which MER is the apex and on the order of the base, so every
//! ordered triple of map 1 is scored against every unordered triple (taken in one fixed order) of map 2.
//!
//! The descriptor does not change under rotation, and the maps are already laid along their axes, so the
//! relative rotation must be a quarter turn: a pair is only admissible when the angle between the apex
//! bisector vectors (line 13) is within [`TriangleParams::max_bisector_deviation_deg`] of a multiple of
//! 90°, which thereby tries the four rotations 0/90/180/270 at once; and when both triangles turn the same
//! way (a rigid map cannot be mirrored). Triangles with an interior angle below
//! [`TriangleParams::min_angle_deg`] have no reliable bisector or handedness and are skipped.

use std::f64::consts::{FRAC_PI_2, PI};

/// Parameters of the common-triangle search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TriangleParams {
    /// Weight of the two angles (radians) against the three area-over-length terms (metres).
    pub angle_weight: f64,
    /// Largest departure of the bisector angle difference from a quarter turn, degrees.
    pub max_bisector_deviation_deg: f64,
    /// Smallest interior angle of a usable triangle, degrees.
    pub min_angle_deg: f64,
}

impl Default for TriangleParams {
    fn default() -> Self {
        TriangleParams { angle_weight: 1.0, max_bisector_deviation_deg: 10.0, min_angle_deg: 5.0 }
    }
}

/// A MER as a triangle vertex: centre (metres, in the axis-aligned frame) and area (m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Centre x, metres.
    pub x: f64,
    /// Centre y, metres.
    pub y: f64,
    /// Area, square metres.
    pub area: f64,
}

/// One triangle's descriptor, apex bisector direction and handedness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    /// Vertex indices: apex, then base.
    pub v: [usize; 3],
    /// Equation (1)'s vector (angles already weighted).
    pub desc: [f64; 5],
    /// Direction of the apex bisector vector, radians.
    pub bisector: f64,
    /// Counter-clockwise (true) or clockwise.
    pub ccw: bool,
}

fn angle_between(ux: f64, uy: f64, vx: f64, vy: f64) -> f64 {
    (ux * vy - uy * vx).abs().atan2(ux * vx + uy * vy)
}

/// The triangle with apex `i` and base `j k`, None when it is too thin.
pub fn triangle(vs: &[Vertex], i: usize, j: usize, k: usize, p: &TriangleParams) -> Option<Triangle> {
    let (a, b, c) = (vs[i], vs[j], vs[k]);
    let (abx, aby, acx, acy) = (b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y);
    let (lab, lac) = (abx.hypot(aby), acx.hypot(acy));
    let (bcx, bcy) = (c.x - b.x, c.y - b.y);
    let d = bcx.hypot(bcy);
    if lab <= 0.0 || lac <= 0.0 || d <= 0.0 {
        return None;
    }
    let ang_a = angle_between(abx, aby, acx, acy);
    let alpha = angle_between(-abx, -aby, bcx, bcy);
    let beta = angle_between(-acx, -acy, -bcx, -bcy);
    let min = p.min_angle_deg.to_radians();
    if ang_a < min || alpha < min || beta < min {
        return None;
    }
    let bis = (abx / lab + acx / lac, aby / lab + acy / lac);
    let w = p.angle_weight;
    Some(Triangle {
        v: [i, j, k],
        desc: [a.area / d, b.area / d, c.area / d, w * alpha, w * beta],
        bisector: bis.1.atan2(bis.0),
        ccw: abx * acy - aby * acx > 0.0,
    })
}

/// Every ordered triangle of the first `n` vertices (all six orders of each triple).
pub fn ordered_triangles(vs: &[Vertex], n: usize, p: &TriangleParams) -> Vec<Triangle> {
    let n = n.min(vs.len());
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                if i != j && j != k && i != k {
                    out.extend(triangle(vs, i, j, k, p));
                }
            }
        }
    }
    out
}

/// Every triple of the first `n` vertices in one order (apex the largest).
pub fn unordered_triangles(vs: &[Vertex], n: usize, p: &TriangleParams) -> Vec<Triangle> {
    let n = n.min(vs.len());
    let mut out = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                out.extend(triangle(vs, i, j, k, p));
            }
        }
    }
    out
}

/// The common triangles: the admissible pair with the least equation-(1) cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleMatch {
    /// Triangle of map 1 (vertex indices apex, base).
    pub a: Triangle,
    /// Triangle of map 2, vertex for vertex.
    pub b: Triangle,
    /// Its cost.
    pub cost: f64,
    /// Rotation taking map 2 onto map 1, quarter turns counter-clockwise (0..4).
    pub quarter_turns: u8,
    /// Pairs of triangles scored.
    pub scored: usize,
}

/// Quarter turns nearest to an angle and the departure from them.
pub fn nearest_quarter(phi: f64) -> (u8, f64) {
    let q = (phi / FRAC_PI_2).round();
    let dev = phi - q * FRAC_PI_2;
    ((q as i64).rem_euclid(4) as u8, dev.abs())
}

/// The least-cost admissible pair of triangles, with the number of pairs scored (also when none is).
pub fn best_pair(ta: &[Triangle], tb: &[Triangle], p: &TriangleParams) -> (Option<TriangleMatch>, usize) {
    let max_dev = p.max_bisector_deviation_deg.to_radians();
    let mut best: Option<TriangleMatch> = None;
    let mut best_cost2 = f64::INFINITY;
    let mut scored = 0usize;
    for a in ta {
        for b in tb {
            if a.ccw != b.ccw {
                continue;
            }
            scored += 1;
            let mut c2 = 0.0;
            for (x, y) in a.desc.iter().zip(&b.desc) {
                c2 += (x - y) * (x - y);
            }
            if c2 >= best_cost2 {
                continue;
            }
            let phi = (a.bisector - b.bisector + PI).rem_euclid(2.0 * PI) - PI;
            let (q, dev) = nearest_quarter(phi);
            if dev > max_dev {
                continue;
            }
            best_cost2 = c2;
            best = Some(TriangleMatch { a: *a, b: *b, cost: c2.sqrt(), quarter_turns: q, scored: 0 });
        }
    }
    (best.map(|m| TriangleMatch { scored, ..m }), scored)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rotated_copy_matches_itself_with_its_quarter_turn() {
        let vs = [
            Vertex { x: 0.0, y: 0.0, area: 30.0 },
            Vertex { x: 6.0, y: 1.0, area: 12.0 },
            Vertex { x: 2.0, y: 5.0, area: 8.0 },
            Vertex { x: -4.0, y: 3.0, area: 5.0 },
        ];
        // map 2 is map 1 turned by 90 degrees and shifted; its vertices listed in another order
        let rot: Vec<Vertex> = [3, 1, 0, 2]
            .iter()
            .map(|&i| {
                let v: Vertex = vs[i];
                Vertex { x: -v.y + 10.0, y: v.x - 3.0, area: v.area }
            })
            .collect();
        let p = TriangleParams::default();
        let (m, scored) = best_pair(&ordered_triangles(&vs, 4, &p), &unordered_triangles(&rot, 4, &p), &p);
        let m = m.unwrap();
        assert!(scored > 0);
        assert!(m.cost < 1e-9);
        // map-1 turned by +90 gives map 2, so map 2 onto map 1 is -90 = 3 quarter turns
        assert_eq!(m.quarter_turns, 3);
        let order = [3, 1, 0, 2];
        for t in 0..3 {
            assert_eq!(m.a.v[t], order[m.b.v[t]]);
        }
    }
}
