//! The score field of map a: how well a point of b's walls fits where it lands, one value per cell.
//!
//! Walls of a are blurred with a Gaussian of their distance (Olson 2009's likelihood field), known free
//! cells far from any wall score a penalty (a wall of b laid across a's free space is evidence against the
//! pose), unknown cells and everything off the grid score 0. Free space can be made to count only where it is
//! dense: a single ray's line of free cells beyond a wall left unknown ([`BlockStates::keep_dense_free`]).

use mrslam_core::{CellState, OccupancyGrid};

/// Score of a point exactly on a wall of a: the field's scale.
pub const HIT: i16 = 100;

/// A map's states on a grid of `factor × factor` blocks of its cells: a block is occupied when one of its
/// cells is, free when one is free and none occupied, unknown otherwise.
#[derive(Debug, Clone)]
pub struct BlockStates {
    /// Blocks along x.
    pub width: usize,
    /// Blocks along y.
    pub height: usize,
    /// Cells per block side.
    pub factor: usize,
    /// Row-major states.
    pub states: Vec<CellState>,
}

impl BlockStates {
    /// Pools `g` into blocks of `factor × factor` cells (`factor` at least 1).
    pub fn of(g: &OccupancyGrid, factor: usize) -> Self {
        let cells = Self::cells(g);
        if factor <= 1 { cells } else { cells.pooled(factor) }
    }

    /// `g`'s own cells as blocks of one cell.
    pub fn cells(g: &OccupancyGrid) -> Self {
        let states = g.cells().iter().map(|&l| CellState::from_log_odds(l)).collect();
        BlockStates { width: g.width(), height: g.height(), factor: 1, states }
    }

    /// These blocks pooled again into blocks of `factor × factor` of them (`factor` at least 1).
    pub fn pooled(&self, factor: usize) -> Self {
        let f = factor.max(1);
        if f == 1 {
            return self.clone();
        }
        let (w, h) = (self.width.div_ceil(f), self.height.div_ceil(f));
        let mut states = vec![CellState::Unknown; w * h];
        for (iy, row) in self.states.chunks_exact(self.width.max(1)).enumerate() {
            let out = &mut states[(iy / f) * w..(iy / f + 1) * w];
            for (ix, &s) in row.iter().enumerate() {
                let o = &mut out[ix / f];
                *o = match (*o, s) {
                    (CellState::Occupied, _) | (_, CellState::Occupied) => CellState::Occupied,
                    (CellState::Free, _) | (_, CellState::Free) => CellState::Free,
                    _ => CellState::Unknown,
                };
            }
        }
        BlockStates { width: w, height: h, factor: self.factor * f, states }
    }

    /// Leaves free only the free blocks with at least `share` of the `side × side` blocks centred on them free
    /// (`side` odd; the grid's edge counts as not free): one stray ray through a room's wall marks a line of
    /// free cells that a wall of the other map should not be penalised for.
    pub fn keep_dense_free(&mut self, side: usize, share: f64) {
        let (w, h) = (self.width, self.height);
        if share <= 0.0 || w == 0 || h == 0 {
            return;
        }
        let r = side / 2;
        let needed = ((share.min(1.0) * ((2 * r + 1) * (2 * r + 1)) as f64).ceil() as u32).max(1);
        // Summed-area table of free blocks, (w + 1) × (h + 1).
        let mut sum = vec![0u32; (w + 1) * (h + 1)];
        for y in 0..h {
            let mut row = 0u32;
            for x in 0..w {
                row += u32::from(self.states[y * w + x] == CellState::Free);
                sum[(y + 1) * (w + 1) + x + 1] = sum[y * (w + 1) + x + 1] + row;
            }
        }
        for y in 0..h {
            let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(h));
            for x in 0..w {
                if self.states[y * w + x] != CellState::Free {
                    continue;
                }
                let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(w));
                let free =
                    sum[y1 * (w + 1) + x1] + sum[y0 * (w + 1) + x0] - sum[y0 * (w + 1) + x1] - sum[y1 * (w + 1) + x0];
                if free < needed {
                    self.states[y * w + x] = CellState::Unknown;
                }
            }
        }
    }
}

/// The score of every cell of a grid, row-major, `i16` so the sums stay cheap.
#[derive(Debug, Clone)]
pub struct ScoreField {
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Row-major scores.
    pub values: Vec<i16>,
}

impl ScoreField {
    /// The field of `blocks`: [`HIT`] `· exp(-d² / 2σ²)` at distance `d` cells from the nearest wall (σ =
    /// `sigma_cells`, cut where it rounds to 0), `-free_penalty` on free cells with no wall that near, 0 elsewhere.
    pub fn build(blocks: &BlockStates, sigma_cells: f64, free_penalty: i16) -> Self {
        let (w, h) = (blocks.width, blocks.height);
        let mut values: Vec<i16> =
            blocks.states.iter().map(|s| if *s == CellState::Free { -free_penalty.max(0) } else { 0 }).collect();
        let kernel = Kernel::gaussian(sigma_cells);
        let r = kernel.radius as i64;
        for iy in 0..h {
            for ix in 0..w {
                if blocks.states[iy * w + ix] != CellState::Occupied {
                    continue;
                }
                let (y0, y1) = ((iy as i64 - r).max(0) as usize, (iy as i64 + r).min(h as i64 - 1) as usize);
                let (x0, x1) = ((ix as i64 - r).max(0) as usize, (ix as i64 + r).min(w as i64 - 1) as usize);
                for y in y0..=y1 {
                    let krow = kernel.row(y as i64 - iy as i64);
                    let out = &mut values[y * w + x0..=y * w + x1];
                    let k = &krow[(x0 as i64 - ix as i64 + r) as usize..=(x1 as i64 - ix as i64 + r) as usize];
                    for (o, &kv) in out.iter_mut().zip(k) {
                        if kv > 0 && kv > *o {
                            *o = kv;
                        }
                    }
                }
            }
        }
        ScoreField { width: w, height: h, values }
    }

    /// The score of cell (`x`, `y`); 0 off the grid.
    #[cfg(test)]
    #[inline]
    pub fn get(&self, x: i32, y: i32) -> i16 {
        if (x as u32) < self.width as u32 && (y as u32) < self.height as u32 {
            self.values[y as usize * self.width + x as usize]
        } else {
            0
        }
    }
}

/// A square table of the blur, `2 radius + 1` cells a side.
struct Kernel {
    radius: usize,
    values: Vec<i16>,
}

impl Kernel {
    fn gaussian(sigma: f64) -> Self {
        let sigma = sigma.max(1e-3);
        let value = |d2: f64| (f64::from(HIT) * (-d2 / (2.0 * sigma * sigma)).exp()).round() as i16;
        let mut radius = 0;
        while radius < 64 && value(((radius + 1) * (radius + 1)) as f64) > 0 {
            radius += 1;
        }
        let n = 2 * radius + 1;
        let mut values = vec![0; n * n];
        for y in 0..n {
            for x in 0..n {
                let (dx, dy) = (x as f64 - radius as f64, y as f64 - radius as f64);
                values[y * n + x] = value(dx * dx + dy * dy);
            }
        }
        Kernel { radius, values }
    }

    /// Row `dy` (from `-radius` to `radius`).
    fn row(&self, dy: i64) -> &[i16] {
        let n = 2 * self.radius + 1;
        let y = (dy + self.radius as i64) as usize;
        &self.values[y * n..(y + 1) * n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    #[test]
    fn walls_score_highest_free_space_is_penalised_unknown_is_neutral() {
        let mut g = OccupancyGrid::new(12, 10, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..10 {
            for ix in 0..8 {
                g.set(ix, iy, if ix == 2 { 2.0 } else { -2.0 });
            }
        }
        let f = ScoreField::build(&BlockStates::of(&g, 1), 1.0, 7);
        assert_eq!(f.get(2, 5), HIT);
        assert!(f.get(3, 5) > 50 && f.get(3, 5) < HIT, "{}", f.get(3, 5));
        assert!(f.get(1, 5) == f.get(3, 5));
        assert_eq!(f.get(7, 5), -7);
        assert_eq!(f.get(10, 5), 0);
        assert_eq!(f.get(-1, 5), 0);
        assert_eq!(f.get(3, 10), 0);
    }

    #[test]
    fn a_ray_of_free_cells_is_not_dense_free_space_a_room_is() {
        let mut g = OccupancyGrid::new(30, 20, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..10 {
            for ix in 0..10 {
                g.set(ix, iy, -2.0); // a room
            }
        }
        for ix in 10..30 {
            g.set(ix, 15, -2.0); // a ray through nothing else known
        }
        let mut b = BlockStates::of(&g, 1);
        b.keep_dense_free(5, 0.5);
        let at = |x: usize, y: usize| b.states[y * b.width + x];
        assert_eq!(at(5, 5), CellState::Free);
        assert_eq!(at(0, 0), CellState::Unknown, "a corner sees 9 of 25 free cells");
        assert_eq!(at(2, 2), CellState::Free);
        assert_eq!(at(20, 15), CellState::Unknown);
        assert_eq!(at(25, 5), CellState::Unknown);
        let mut unchanged = BlockStates::of(&g, 1);
        unchanged.keep_dense_free(5, 0.0);
        assert_eq!(unchanged.states, BlockStates::of(&g, 1).states);
    }

    #[test]
    fn blocks_keep_any_wall_then_any_free_cell() {
        let mut g = OccupancyGrid::new(5, 3, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        g.set(0, 0, 2.0);
        g.set(1, 1, -2.0);
        g.set(2, 0, -2.0);
        let b = BlockStates::of(&g, 2);
        assert_eq!((b.width, b.height), (3, 2));
        assert_eq!(b.states[0], CellState::Occupied);
        assert_eq!(b.states[1], CellState::Free);
        assert_eq!(b.states[2], CellState::Unknown);
    }
}
