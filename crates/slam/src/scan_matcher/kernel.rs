//! GMapping's kernel matcher's parts of [`ScanMatcher`] (`scanmatcher.cpp`): the nearest cell mean in a
//! window around each end point, the score and likelihood, and the hill-climbing optimiser on them.

use super::{Beam, Evaluation, NULL_LIKELIHOOD, ScanMatcher, Xyt};
use crate::tile_map::{TILE, TILE_SHIFT, TileMap, local};

/// |component| of a unit beam direction above which the "one step back" neighbour moves along that axis:
/// GMapping steps back `delta·√2` along the beam, i.e. `round(-√2·d)` cells per axis.
const FREE_STEP_THRESHOLD: f64 = std::f64::consts::SQRT_2 / 4.0;

impl ScanMatcher {
    /// Squared distance from end point (px, py) (beam direction (dx, dy)) to the nearest mean of an
    /// occupied cell with a free cell behind it in the search window, if any.
    #[inline]
    fn nearest(&self, map: &TileMap, px: f64, py: f64, dx: f64, dy: f64) -> Option<f64> {
        let (ix, iy) = map.cell_of(px, py);
        let k = self.params.kernel_size;
        let fx = if dx > FREE_STEP_THRESHOLD {
            -1
        } else if dx < -FREE_STEP_THRESHOLD {
            1
        } else {
            0
        };
        let fy = if dy > FREE_STEP_THRESHOLD {
            -1
        } else if dy < -FREE_STEP_THRESHOLD {
            1
        } else {
            0
        };
        let delta = map.delta();
        let rx = px - ix as f64 * delta;
        let ry = py - iy as f64 * delta;
        let mut best = f64::INFINITY;
        let (lx, ly) = (ix & (TILE - 1), iy & (TILE - 1));
        let reach = k + 1;
        if lx >= reach && ly >= reach && lx < TILE - reach && ly < TILE - reach {
            // Fast path: the window and its free neighbours lie in one tile.
            let tile = map.tile(ix >> TILE_SHIFT, iy >> TILE_SHIFT)?;
            let base = local(ix, iy) as i32;
            let foff = fy * TILE + fx;
            for yy in -k..=k {
                for xx in -k..=k {
                    let i = (base + yy * TILE + xx) as usize;
                    if tile.is_hit(i) && !tile.is_hit((i as i32 + foff) as usize) {
                        let Some(m) = tile.cell(i).map(|c| c.mean) else { continue };
                        let ex = rx - xx as f64 * delta - m[0] as f64;
                        let ey = ry - yy as f64 * delta - m[1] as f64;
                        best = best.min(ex * ex + ey * ey);
                    }
                }
            }
        } else {
            for yy in -k..=k {
                for xx in -k..=k {
                    let (cx, cy) = (ix + xx, iy + yy);
                    if map.hits(cx, cy) > 0 && map.hits(cx + fx, cy + fy) == 0 {
                        let (mx, my) = map.mean(cx, cy);
                        let (ex, ey) = (px - mx, py - my);
                        best = best.min(ex * ex + ey * ey);
                    }
                }
            }
        }
        best.is_finite().then_some(best)
    }

    /// GMapping's `score`: sum over beams of exp(-d²/sigma) at robot pose `p`.
    pub fn score(&self, map: &TileMap, p: &Xyt, beams: &[Beam]) -> f64 {
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        let inv_sigma = 1.0 / self.params.sigma;
        let mut total = 0.0;
        for b in beams {
            let dx = c * b.c - s * b.s;
            let dy = s * b.c + c * b.s;
            let (px, py) = (lp.x + b.r * dx, lp.y + b.r * dy);
            if let Some(d2) = self.nearest(map, px, py, dx, dy) {
                total += (-d2 * inv_sigma).exp();
            } else if let Some(u) = self.unknown_score {
                let (ix, iy) = map.cell_of(px, py);
                if !map.seen(ix, iy) {
                    total += u;
                }
            }
        }
        total
    }

    /// GMapping's `likelihoodAndScore` at robot pose `p`.
    pub fn likelihood_and_score(&self, map: &TileMap, p: &Xyt, beams: &[Beam]) -> Evaluation {
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        let no_hit = NULL_LIKELIHOOD / self.params.lsigma;
        let mut e = Evaluation::default();
        for b in beams {
            let dx = c * b.c - s * b.s;
            let dy = s * b.c + c * b.s;
            let (px, py) = (lp.x + b.r * dx, lp.y + b.r * dy);
            match self.nearest(map, px, py, dx, dy) {
                Some(d2) => {
                    e.score += (-d2 / self.params.sigma).exp();
                    e.likelihood += -d2 / self.params.lsigma;
                    e.matched += 1;
                }
                None => {
                    let unseen = self.unknown_score.is_some() && {
                        let (ix, iy) = map.cell_of(px, py);
                        !map.seen(ix, iy)
                    };
                    if !unseen {
                        e.likelihood += no_hit;
                    }
                }
            }
        }
        e
    }

    /// The beams whose end point, at robot pose `p`, finds an occupied cell in its window.
    ///
    /// Matching only these (the "frontier guard") removes a bias GMapping's score has when the robot drives
    /// into unmapped space: a beam ending just beyond the mapped region scores nothing where it is, but
    /// something once the pose is pulled back by a cell, so every update drags the pose towards the known
    /// map. Chosen once at the start pose of the climb, the set cannot be gamed by moving.
    pub fn beams_in_map(&self, map: &TileMap, p: &Xyt, beams: &[Beam]) -> Vec<Beam> {
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        beams
            .iter()
            .filter(|b| {
                let dx = c * b.c - s * b.s;
                let dy = s * b.c + c * b.s;
                self.nearest(map, lp.x + b.r * dx, lp.y + b.r * dy, dx, dy).is_some()
            })
            .copied()
            .collect()
    }

    /// GMapping's `optimize`: hill-climbs from `init`; returns the best pose and its score.
    pub fn optimize(&self, map: &TileMap, init: &Xyt, beams: &[Beam]) -> (Xyt, f64) {
        self.climb(init, |q| self.score(map, q, beams))
    }
}
