//! GMapping's scan matcher: the score, the likelihood and the hill-climbing optimiser (`scanmatcher.cpp`).
//!
//! For each beam end point the matcher looks, in a (2k+1)² window of cells around it, for an occupied cell
//! whose neighbour one step back along the beam is free (so the beam could have reached it); of those it
//! takes the one whose mean hit position is nearest, at distance d, and adds `exp(-d²/sigma)` to the score and
//! `-d²/lsigma` to the log-likelihood (a beam with no such cell adds `-0.5/lsigma`). "Occupied" means the cell
//! has hits in the particle's [`TileMap`]; "free" means it has none (GMapping with `generateMap` off, where an
//! unknown cell counts as free too). The optimiser climbs from the motion-model pose with steps
//! lstep/astep over six moves (±x, ±y in the map frame, ±θ), halving the steps each time no move improves
//! the score, until `iterations` halvings brought nothing.

use crate::tile_map::{TILE, TILE_SHIFT, TileMap, local};
use mrslam_core::LaserScan;

/// |component| of a unit beam direction above which the "one step back" neighbour moves along that axis:
/// GMapping steps back `delta·√2` along the beam, i.e. `round(-√2·d)` cells per axis.
const FREE_STEP_THRESHOLD: f64 = std::f64::consts::SQRT_2 / 4.0;
/// GMapping's `nullLikelihood`: a beam that matches nothing costs `-0.5/lsigma`.
const NULL_LIKELIHOOD: f64 = -0.5;

/// A pose as (x, y, θ), metres and radians: the matcher's working form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Xyt {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub t: f64,
}

/// One beam in the laser frame: range and unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Range, metres.
    pub r: f64,
    /// cos of the beam angle in the laser frame.
    pub c: f64,
    /// sin of the beam angle in the laser frame.
    pub s: f64,
}

/// A scan prepared for matching and mapping.
#[derive(Debug, Clone, Default)]
pub struct PreparedScan {
    /// Beams the matcher uses: valid, within the usable range, every (lskip+1)-th.
    pub matched: Vec<Beam>,
    /// Beams whose end point is a hit to record: valid and shorter than the usable range.
    pub hits: Vec<Beam>,
    /// Beams that are not finite, negative or below the sensor's minimum range.
    pub invalid: usize,
}

impl PreparedScan {
    /// Sorts a scan's beams. `max_range` and `max_urange` as in [`crate::SlamParams`].
    pub fn new(scan: &LaserScan, max_range: f64, max_urange: f64, lskip: usize) -> Self {
        let mut out = PreparedScan::default();
        for i in 0..scan.len() {
            if !scan.is_valid(i) {
                if !scan.is_max_range(i) {
                    out.invalid += 1;
                }
                continue;
            }
            let r = scan.ranges[i] as f64;
            if r >= max_range || r > max_urange {
                continue;
            }
            let a = scan.angle(i);
            let b = Beam { r, c: a.cos(), s: a.sin() };
            if r < max_urange {
                out.hits.push(b);
            }
            if i.is_multiple_of(lskip + 1) {
                out.matched.push(b);
            }
        }
        out
    }
}

/// The scan matcher's settings (see [`crate::SlamParams`] for each).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanMatcher {
    /// Laser mount pose on the robot.
    pub laser: Xyt,
    /// Score sigma.
    pub sigma: f64,
    /// Likelihood sigma.
    pub lsigma: f64,
    /// Search window half-width, cells.
    pub kernel_size: i32,
    /// Initial linear step, metres.
    pub lstep: f64,
    /// Initial angular step, radians.
    pub astep: f64,
    /// Step halvings.
    pub iterations: u32,
    /// Score of a beam ending unmatched in never-seen space; `None`: 0, as GMapping (see
    /// [`crate::SlamParams::seen_band`]).
    pub unknown_score: Option<f64>,
}

/// Result of evaluating a pose: score, log-likelihood and the number of beams that matched.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Evaluation {
    /// Sum of exp(-d²/sigma) over matched beams.
    pub score: f64,
    /// Log-likelihood.
    pub likelihood: f64,
    /// Beams that found a cell.
    pub matched: usize,
}

impl ScanMatcher {
    /// The laser's pose in the map frame for robot pose `p`.
    #[inline]
    pub fn laser_pose(&self, p: &Xyt) -> Xyt {
        let (s, c) = p.t.sin_cos();
        Xyt {
            x: p.x + c * self.laser.x - s * self.laser.y,
            y: p.y + s * self.laser.x + c * self.laser.y,
            t: p.t + self.laser.t,
        }
    }

    /// Squared distance from end point (px, py) (beam direction (dx, dy)) to the nearest mean of an
    /// occupied cell with a free cell behind it in the search window, if any.
    #[inline]
    fn nearest(&self, map: &TileMap, px: f64, py: f64, dx: f64, dy: f64) -> Option<f64> {
        let (ix, iy) = map.cell_of(px, py);
        let k = self.kernel_size;
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
                    if tile.hits[i] > 0 && tile.hits[(i as i32 + foff) as usize] == 0 {
                        let m = tile.mean[i];
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
        let (s, c) = lp.t.sin_cos();
        let inv_sigma = 1.0 / self.sigma;
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
        let (s, c) = lp.t.sin_cos();
        let no_hit = NULL_LIKELIHOOD / self.lsigma;
        let mut e = Evaluation::default();
        for b in beams {
            let dx = c * b.c - s * b.s;
            let dy = s * b.c + c * b.s;
            let (px, py) = (lp.x + b.r * dx, lp.y + b.r * dy);
            match self.nearest(map, px, py, dx, dy) {
                Some(d2) => {
                    e.score += (-d2 / self.sigma).exp();
                    e.likelihood += -d2 / self.lsigma;
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
        let (s, c) = lp.t.sin_cos();
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
        let mut best_score = -1.0;
        let mut current = *init;
        let mut current_score = self.score(map, &current, beams);
        let (mut ldelta, mut adelta) = (self.lstep, self.astep);
        let mut refinement = 0;
        // Bounded like GMapping's loop is in practice: each round improves the score or halves the steps.
        let mut rounds = 0;
        loop {
            if best_score >= current_score {
                refinement += 1;
                ldelta *= 0.5;
                adelta *= 0.5;
            }
            best_score = current_score;
            let mut best_local = current;
            for m in 0..6 {
                let mut q = current;
                match m {
                    0 => q.x += ldelta,
                    1 => q.x -= ldelta,
                    2 => q.y -= ldelta,
                    3 => q.y += ldelta,
                    4 => q.t += adelta,
                    _ => q.t -= adelta,
                }
                let s = self.score(map, &q, beams);
                if s > current_score {
                    current_score = s;
                    best_local = q;
                }
            }
            current = best_local;
            rounds += 1;
            if !(current_score > best_score || refinement < self.iterations) || rounds > 1000 {
                break;
            }
        }
        (current, best_score.max(current_score))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matcher() -> ScanMatcher {
        ScanMatcher {
            laser: Xyt { x: 0.0, y: 0.0, t: 0.0 },
            sigma: 0.05,
            lsigma: 0.075,
            kernel_size: 1,
            lstep: 0.05,
            astep: 0.05,
            iterations: 5,
            unknown_score: None,
        }
    }

    /// A square room 4 m across around the origin, mapped as hits from the true pose.
    fn room(beams: &[Beam]) -> TileMap {
        let mut m = TileMap::new(0.05);
        for b in beams {
            m.add_hit(b.r * b.c, b.r * b.s).unwrap();
        }
        m
    }

    fn room_beams() -> Vec<Beam> {
        (0..720)
            .map(|i| {
                let a = -std::f64::consts::PI + i as f64 * std::f64::consts::PI / 360.0;
                let (c, s) = (a.cos(), a.sin());
                // distance to the walls of a 4 m x 3 m box centred near the origin, not symmetric
                let tx = if c > 1e-9 {
                    2.3 / c
                } else if c < -1e-9 {
                    -1.7 / c
                } else {
                    f64::INFINITY
                };
                let ty = if s > 1e-9 {
                    1.2 / s
                } else if s < -1e-9 {
                    -1.8 / s
                } else {
                    f64::INFINITY
                };
                Beam { r: tx.min(ty), c, s }
            })
            .collect()
    }

    #[test]
    fn optimiser_recovers_an_offset() {
        let beams = room_beams();
        let map = room(&beams);
        let m = matcher();
        let at_truth = m.score(&map, &Xyt { x: 0.0, y: 0.0, t: 0.0 }, &beams);
        assert!(at_truth > 0.9 * beams.len() as f64, "{at_truth}");
        let (p, s) = m.optimize(&map, &Xyt { x: 0.06, y: -0.04, t: 0.03 }, &beams);
        assert!(p.x.abs() < 0.01 && p.y.abs() < 0.01 && p.t.abs() < 0.005, "{p:?}");
        assert!(s > 0.9 * at_truth);
        let e_truth = m.likelihood_and_score(&map, &Xyt { x: 0.0, y: 0.0, t: 0.0 }, &beams);
        let e_off = m.likelihood_and_score(&map, &Xyt { x: 0.2, y: 0.0, t: 0.0 }, &beams);
        assert!(e_truth.likelihood > e_off.likelihood);
        assert_eq!(e_truth.matched, beams.len());
    }

    #[test]
    fn prepared_scan_sorts_beams() {
        let scan = LaserScan {
            stamp: 0.0,
            angle_min: 0.0,
            angle_increment: 0.1,
            range_min: 0.1,
            range_max: 4.0,
            ranges: vec![1.0, f32::NAN, -1.0, 4.0, 3.9, 0.05, f32::INFINITY, 2.0],
        };
        let p = PreparedScan::new(&scan, 4.0, 3.0, 1);
        assert_eq!(p.invalid, 3, "NaN, negative and below range_min");
        assert_eq!(p.hits.len(), 2, "1.0 and 2.0; 3.9 is beyond the usable range");
        assert_eq!(p.matched.len(), 1, "beam 0 only (beam 7 is skipped by lskip)");
    }
}
