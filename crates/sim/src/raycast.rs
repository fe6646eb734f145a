//! A fast ray caster over static geometry: obstacle edges and discs binned in a uniform grid,
//! traversed cell by cell (Amanatides & Woo) so a beam only tests what lies along it.

use crate::geometry::{Obstacle, ray_circle, ray_segment, segment_overlaps_aabb};
use nalgebra::{Point2, Vector2};

/// Static geometry prepared for ray casting.
#[derive(Debug, Clone)]
pub struct RayCaster {
    origin: Point2<f64>,
    cell: f64,
    inv_cell: f64,
    nx: usize,
    ny: usize,
    /// Items of cell `i` are `items[starts[i]..starts[i + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Segments `(a, b)`; item ids below `segs.len()`.
    segs: Vec<(Point2<f64>, Point2<f64>)>,
    /// Discs `(centre, radius)`; item ids from `segs.len()`.
    discs: Vec<(Point2<f64>, f64)>,
}

impl RayCaster {
    /// Bins the obstacles' outlines into cells of about `cell` metres.
    pub fn new(obstacles: &[Obstacle], cell: f64) -> Self {
        let mut segs = Vec::new();
        let mut discs = Vec::new();
        for o in obstacles {
            match o {
                Obstacle::Circle { center, radius } => discs.push((*center, *radius)),
                _ => {
                    let pts = o.outline();
                    for i in 0..pts.len() {
                        segs.push((pts[i], pts[(i + 1) % pts.len()]));
                    }
                }
            }
        }
        let (mut lo, mut hi) =
            (Point2::new(f64::INFINITY, f64::INFINITY), Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY));
        for o in obstacles {
            let (a, b) = o.aabb();
            lo = lo.inf(&a);
            hi = hi.sup(&b);
        }
        if obstacles.is_empty() {
            lo = Point2::origin();
            hi = Point2::new(1.0, 1.0);
        }
        let mut cell = cell.max(1e-3);
        // keep the grid small for huge, sparse worlds
        // Counted as the grid is built (rounded up, plus the margin), so a world long and thin (1e16 m by 1 m)
        // cannot slip past the bound.
        let cells = |cell: f64| (((hi.x - lo.x) / cell).ceil() + 2.0) * (((hi.y - lo.y) / cell).ceil() + 2.0);
        while cells(cell) > 4e6 && cell.is_finite() {
            cell *= 2.0;
        }
        let margin = Vector2::new(cell, cell);
        let origin = lo - margin;
        let nx = (((hi.x - lo.x) / cell).ceil() as usize + 2).max(1);
        let ny = (((hi.y - lo.y) / cell).ceil() as usize + 2).max(1);
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        let cell_range = |a: f64, b: f64, o: f64, n: usize| {
            let i0 = (((a - o) / cell).floor().max(0.0) as usize).min(n - 1);
            let i1 = (((b - o) / cell).floor().max(0.0) as usize).min(n - 1);
            i0..=i1
        };
        let grow = 1e-6;
        for (k, (a, b)) in segs.iter().enumerate() {
            let (x0, x1) = (a.x.min(b.x) - grow, a.x.max(b.x) + grow);
            let (y0, y1) = (a.y.min(b.y) - grow, a.y.max(b.y) + grow);
            for iy in cell_range(y0, y1, origin.y, ny) {
                for ix in cell_range(x0, x1, origin.x, nx) {
                    let clo = origin + Vector2::new(ix as f64 * cell - grow, iy as f64 * cell - grow);
                    let chi = clo + Vector2::new(cell + 2.0 * grow, cell + 2.0 * grow);
                    if segment_overlaps_aabb(a, b, &clo, &chi) {
                        bins[iy * nx + ix].push(k as u32);
                    }
                }
            }
        }
        for (k, (c, r)) in discs.iter().enumerate() {
            for iy in cell_range(c.y - r, c.y + r, origin.y, ny) {
                for ix in cell_range(c.x - r, c.x + r, origin.x, nx) {
                    bins[iy * nx + ix].push((segs.len() + k) as u32);
                }
            }
        }
        let mut starts = Vec::with_capacity(nx * ny + 1);
        let mut items = Vec::new();
        for b in &bins {
            starts.push(items.len() as u32);
            items.extend_from_slice(b);
        }
        starts.push(items.len() as u32);
        RayCaster { origin, cell, inv_cell: 1.0 / cell, nx, ny, starts, items, segs, discs }
    }

    /// Number of edges and discs held.
    pub fn primitive_count(&self) -> usize {
        self.segs.len() + self.discs.len()
    }

    #[inline]
    fn test_cell(&self, i: usize, o: &Point2<f64>, d: &Vector2<f64>, best: &mut f64) {
        let (s, e) = (self.starts[i] as usize, self.starts[i + 1] as usize);
        let nseg = self.segs.len();
        for &it in &self.items[s..e] {
            let it = it as usize;
            let t = if it < nseg {
                let (a, b) = &self.segs[it];
                ray_segment(o, d, a, b, *best)
            } else {
                let (c, r) = &self.discs[it - nseg];
                ray_circle(o, d, c, *r, *best)
            };
            if let Some(t) = t {
                *best = t;
            }
        }
    }

    /// Distance from `o` along the unit direction `d` to the first obstacle edge within `tmax`.
    pub fn cast(&self, o: &Point2<f64>, d: &Vector2<f64>, tmax: f64) -> Option<f64> {
        // Clip the ray to the grid's bounds.
        let w = self.nx as f64 * self.cell;
        let h = self.ny as f64 * self.cell;
        let rel = o - self.origin;
        let (mut t0, mut t1) = (0.0f64, tmax);
        for (p, dd, size) in [(rel.x, d.x, w), (rel.y, d.y, h)] {
            if dd.abs() < 1e-15 {
                if p < 0.0 || p > size {
                    return None;
                }
            } else {
                let (a, b) = ((0.0 - p) / dd, (size - p) / dd);
                let (a, b) = if a < b { (a, b) } else { (b, a) };
                t0 = t0.max(a);
                t1 = t1.min(b);
            }
        }
        if t0 > t1 {
            return None;
        }
        let start = rel + d * t0;
        let mut ix = ((start.x * self.inv_cell).floor() as i64).clamp(0, self.nx as i64 - 1);
        let mut iy = ((start.y * self.inv_cell).floor() as i64).clamp(0, self.ny as i64 - 1);
        let axis = |p: f64, dd: f64, i: i64| -> (i64, f64, f64) {
            if dd > 0.0 {
                (1, self.cell / dd, ((i + 1) as f64 * self.cell - p) / dd)
            } else if dd < 0.0 {
                (-1, -self.cell / dd, (i as f64 * self.cell - p) / dd)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (sx, dtx, mut tmx) = axis(rel.x, d.x, ix);
        let (sy, dty, mut tmy) = axis(rel.y, d.y, iy);
        let mut best = tmax;
        let mut hit = false;
        loop {
            let before = best;
            self.test_cell(iy as usize * self.nx + ix as usize, o, d, &mut best);
            hit |= best < before;
            let exit = tmx.min(tmy);
            if (hit && best <= exit) || exit > t1 {
                break;
            }
            if tmx < tmy {
                ix += sx;
                tmx += dtx;
            } else {
                iy += sy;
                tmy += dty;
            }
            if ix < 0 || iy < 0 || ix >= self.nx as i64 || iy >= self.ny as i64 {
                break;
            }
        }
        hit.then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room() -> Vec<Obstacle> {
        vec![
            Obstacle::Box { center: Point2::new(2.0, 0.0), half: Vector2::new(2.1, 0.1), angle: 0.0 },
            Obstacle::Box { center: Point2::new(2.0, 3.0), half: Vector2::new(2.1, 0.1), angle: 0.0 },
            Obstacle::Box { center: Point2::new(0.0, 1.5), half: Vector2::new(0.1, 1.6), angle: 0.0 },
            Obstacle::Box { center: Point2::new(4.0, 1.5), half: Vector2::new(0.1, 1.6), angle: 0.0 },
            Obstacle::Circle { center: Point2::new(3.0, 1.5), radius: 0.2 },
        ]
    }

    fn brute(obs: &[Obstacle], o: &Point2<f64>, d: &Vector2<f64>, tmax: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        for ob in obs {
            let t = match ob {
                Obstacle::Circle { center, radius } => ray_circle(o, d, center, *radius, tmax),
                _ => {
                    let p = ob.outline();
                    (0..p.len())
                        .filter_map(|i| ray_segment(o, d, &p[i], &p[(i + 1) % p.len()], tmax))
                        .min_by(f64::total_cmp)
                }
            };
            if let Some(t) = t {
                best = Some(best.map_or(t, |b: f64| b.min(t)));
            }
        }
        best
    }

    #[test]
    fn matches_brute_force_in_every_direction() {
        let obs = room();
        for cell in [0.1, 0.37, 1.0, 10.0] {
            let c = RayCaster::new(&obs, cell);
            for (ox, oy) in [(1.0, 1.0), (2.5, 2.2), (3.5, 0.5), (-3.0, 1.5), (1.0, -5.0)] {
                let o = Point2::new(ox, oy);
                for k in 0..720 {
                    let a = k as f64 * std::f64::consts::TAU / 720.0;
                    let d = Vector2::new(a.cos(), a.sin());
                    for tmax in [1.0, 4.0, 30.0] {
                        let (x, y) = (c.cast(&o, &d, tmax), brute(&obs, &o, &d, tmax));
                        match (x, y) {
                            (Some(x), Some(y)) => {
                                assert!((x - y).abs() < 1e-9, "{cell} {ox},{oy} {a}: {x} vs {y}")
                            }
                            (None, None) => {}
                            _ => panic!("{cell} {ox},{oy} {a} {tmax}: {x:?} vs {y:?}"),
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn axis_aligned_rays_hit_walls() {
        let c = RayCaster::new(&room(), 0.5);
        let o = Point2::new(1.0, 1.0);
        let t = c.cast(&o, &Vector2::new(0.0, 1.0), 10.0).unwrap();
        assert!((t - 1.9).abs() < 1e-12);
        let t = c.cast(&o, &Vector2::new(-1.0, 0.0), 10.0).unwrap();
        assert!((t - 0.9).abs() < 1e-12);
        assert!(c.cast(&o, &Vector2::new(-1.0, 0.0), 0.5).is_none());
    }

    #[test]
    fn obstacles_at_absurd_coordinates_build_a_small_grid_without_overflow() {
        for far in [1e300, -1e300, 1e308, 1e100] {
            let obs = vec![
                Obstacle::Box { center: Point2::new(2.0, 0.0), half: Vector2::new(2.1, 0.1), angle: 0.0 },
                Obstacle::Box { center: Point2::new(far, 0.0), half: Vector2::new(0.1, 0.1), angle: 0.0 },
                Obstacle::Circle { center: Point2::new(0.0, far), radius: 1.0 },
            ];
            let c = RayCaster::new(&obs, 0.5);
            assert!(c.nx * c.ny <= 4_000_000, "{far}: {} x {}", c.nx, c.ny);
            let _ = c.cast(&Point2::new(1.0, 1.0), &Vector2::new(0.0, -1.0), 10.0);
        }
    }
}
