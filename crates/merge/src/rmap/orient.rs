//! ANGLE(r, c) (Algorithm 1, lines 4-5): the rotation that lays a map's walls along its axes.
//!
//! Points on the edges of free space come from the R-map: every cell on a MER's side whose outward
//! neighbour is not covered by a connected MER is a boundary cell of free space (a MER cannot grow past it,
//! so the neighbour is not free), and the midpoint of the cell edge facing that neighbour is an edge point.
//! Which neighbours count is a parameter: by default only occupied ones (walls), because the border between
//! free and unknown follows the sensor's range or, in cut test pairs, a straight cut at a random angle, not
//! the building. Because every free cell lies in some MER and a MER stops at every non-free neighbour, this
//! is exactly the set of free/blocked cell edges, found by walking MER sides.
//!
//! RANSAC then finds the dominant wall line: each hypothesis is the line through an edge point and another
//! edge point a few cells away (drawn from nearby buckets, so both usually lie on one wall), scored by the
//! edge points within a tolerance of it. The best line's inliers are refitted by total least squares, and
//! its direction modulo 90° is the map's orientation in [-45°, 45°).

use super::mers::{FreeMatrix, Rmap};
use mrslam_core::CellState;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters of the orientation search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OrientParams {
    /// Free space bordering unknown also yields edge points (otherwise only free space bordering walls).
    pub edges_at_unknown: bool,
    /// RANSAC hypotheses.
    pub iterations: usize,
    /// Largest distance of an inlier edge point from the line, cells.
    pub inlier_cells: f64,
    /// Fewest cells between the two points of a hypothesis.
    pub min_pair_cells: f64,
    /// Most edge points scored per hypothesis (an even subsample beyond that).
    pub max_scored_points: usize,
    /// Angles closer than this to an axis are taken as exactly on it (no resampling), degrees.
    pub snap_deg: f64,
    /// Seed of the hypothesis draws.
    pub seed: u64,
}

impl Default for OrientParams {
    fn default() -> Self {
        OrientParams {
            edges_at_unknown: false,
            iterations: 300,
            inlier_cells: 1.0,
            min_pair_cells: 6.0,
            max_scored_points: 4000,
            snap_deg: 0.5,
            seed: 0,
        }
    }
}

/// Edge points of free space in continuous cell coordinates, walked from the MER sides.
pub fn edge_points(m: &FreeMatrix, r: &Rmap, edges_at_unknown: bool) -> Vec<(f64, f64)> {
    let blocked = |x: i64, y: i64| match m.state_at(x, y) {
        CellState::Occupied => true,
        CellState::Unknown => edges_at_unknown,
        CellState::Free => false,
    };
    let n = m.width * m.height;
    // One "seen" flag per cell and side (left, right, top, bottom).
    let mut seen = vec![0u8; n];
    let mut out = Vec::new();
    let mut visit = |x: usize, y: usize, side: u8, out: &mut Vec<(f64, f64)>| {
        let (dx, dy, px, py) = match side {
            0 => (-1, 0, 0.0, 0.5),
            1 => (1, 0, 1.0, 0.5),
            2 => (0, -1, 0.5, 0.0),
            _ => (0, 1, 0.5, 1.0),
        };
        let i = y * m.width + x;
        if seen[i] & (1 << side) == 0 && blocked(x as i64 + dx, y as i64 + dy) {
            seen[i] |= 1 << side;
            out.push((x as f64 + px, y as f64 + py));
        }
    };
    for mer in &r.mers {
        for y in mer.y..mer.y1() {
            visit(mer.x, y, 0, &mut out);
            visit(mer.x1() - 1, y, 1, &mut out);
        }
        for x in mer.x..mer.x1() {
            visit(x, mer.y, 2, &mut out);
            visit(x, mer.y1() - 1, 3, &mut out);
        }
    }
    out
}

/// Wraps an angle into [-45°, 45°).
pub fn mod_quarter(a: f64) -> f64 {
    let q = std::f64::consts::FRAC_PI_2;
    (a + q / 2.0).rem_euclid(q) - q / 2.0
}

/// The dominant wall direction modulo 90°, radians in [-π/4, π/4), and the inliers of its line; None
/// with fewer than two edge points.
pub fn dominant_angle(points: &[(f64, f64)], p: &OrientParams) -> Option<(f64, usize)> {
    if points.len() < 2 {
        return None;
    }
    // Buckets of 16 cells, so the second point of a hypothesis is drawn near the first.
    const B: f64 = 16.0;
    let (mut bx, mut by) = (0usize, 0usize);
    for &(x, y) in points {
        bx = bx.max((x / B) as usize + 1);
        by = by.max((y / B) as usize + 1);
    }
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); bx * by];
    for (i, &(x, y)) in points.iter().enumerate() {
        buckets[(y / B) as usize * bx + (x / B) as usize].push(i as u32);
    }
    let stride = points.len().div_ceil(p.max_scored_points.max(1)).max(1);
    let scored: Vec<(f64, f64)> = points.iter().step_by(stride).copied().collect();
    let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
    // (inliers, line normal, point on the line)
    type Line = (usize, (f64, f64), (f64, f64));
    let mut best: Option<Line> = None;
    let mut near = Vec::new();
    for _ in 0..p.iterations {
        let a = points[rng.random_range(0..points.len())];
        let (cx, cy) = ((a.0 / B) as i64, (a.1 / B) as i64);
        near.clear();
        for yy in cy - 1..=cy + 1 {
            for xx in cx - 1..=cx + 1 {
                if xx >= 0 && yy >= 0 && (xx as usize) < bx && (yy as usize) < by {
                    near.extend_from_slice(&buckets[yy as usize * bx + xx as usize]);
                }
            }
        }
        let b = points[near[rng.random_range(0..near.len())] as usize];
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy);
        if len < p.min_pair_cells {
            continue;
        }
        let (nx, ny) = (-dy / len, dx / len);
        let c = nx * a.0 + ny * a.1;
        let count = scored.iter().filter(|q| (nx * q.0 + ny * q.1 - c).abs() <= p.inlier_cells).count();
        if best.as_ref().is_none_or(|bst| count > bst.0) {
            best = Some((count, (nx, ny), a));
        }
    }
    let (_, (nx, ny), a) = best?;
    let c = nx * a.0 + ny * a.1;
    let inl: Vec<(f64, f64)> =
        points.iter().filter(|q| (nx * q.0 + ny * q.1 - c).abs() <= p.inlier_cells).copied().collect();
    // Total least squares: the principal direction of the inliers.
    let n = inl.len() as f64;
    let (mx, my) = (inl.iter().map(|q| q.0).sum::<f64>() / n, inl.iter().map(|q| q.1).sum::<f64>() / n);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for q in &inl {
        let (u, v) = (q.0 - mx, q.1 - my);
        sxx += u * u;
        syy += v * v;
        sxy += u * v;
    }
    let dir = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mut ang = mod_quarter(dir);
    if ang.abs() < p.snap_deg.to_radians() {
        ang = 0.0;
    }
    Some((ang, inl.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilted_staircase_line_gives_its_angle() {
        // points on a 20 degree line, rounded to half cells like a rasterised wall, plus a few far off
        let t = 20f64.to_radians();
        let mut pts: Vec<(f64, f64)> = (0..200)
            .map(|i| {
                let s = i as f64 * 0.7;
                (((10.0 + s * t.cos()) * 2.0).round() / 2.0, ((10.0 + s * t.sin()) * 2.0).round() / 2.0)
            })
            .collect();
        pts.extend([(3.0, 90.0), (50.0, 2.0), (70.0, 70.0)]);
        let (a, n) = dominant_angle(&pts, &OrientParams::default()).unwrap();
        assert!((a - t).abs() < 0.5f64.to_radians(), "{} deg", a.to_degrees());
        assert!(n >= 190);
        // and modulo 90: the same wall seen rotated by a quarter turn
        let rot: Vec<(f64, f64)> = pts.iter().map(|&(x, y)| (200.0 - y, x)).collect();
        let (b, _) = dominant_angle(&rot, &OrientParams::default()).unwrap();
        assert!((b - t).abs() < 0.5f64.to_radians(), "{} deg", b.to_degrees());
    }

    #[test]
    fn quarter_wrap() {
        assert!((mod_quarter(100f64.to_radians()) - 10f64.to_radians()).abs() < 1e-12);
        assert!((mod_quarter(-50f64.to_radians()) - 40f64.to_radians()).abs() < 1e-12);
    }
}
