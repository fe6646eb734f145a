//! Max-pooled copies of a score field for branch and bound (Hess et al. 2016, precomputation grids).
//!
//! Level `k` holds, at cell (x, y), the largest field value over the `2^k × 2^k` cells `[x, x + 2^k) ×
//! [y, y + 2^k)` (0 for cells off the field). Summed over a scan's points displaced by an offset, it bounds
//! from above the score of every offset in the `2^k × 2^k` block that offset starts.

use crate::field::ScoreField;

/// One level: cells `x ∈ [-(2^k - 1), width)`, same for y, stored from the lowest.
#[derive(Debug, Clone)]
pub struct PooledGrid {
    /// Cells before the field's cell 0, `2^k - 1`.
    pad: i32,
    /// Stored cells along x (field width + pad).
    width: u32,
    /// Stored cells along y.
    height: u32,
    /// Row-major values.
    values: Vec<i16>,
}

impl PooledGrid {
    /// The value at field cell (`x`, `y`): the pooled max of the window starting there; 0 off the stored grid.
    #[inline]
    pub fn get(&self, x: i32, y: i32) -> i16 {
        let (sx, sy) = ((x + self.pad) as u32, (y + self.pad) as u32);
        if sx < self.width && sy < self.height { self.values[(sy * self.width + sx) as usize] } else { 0 }
    }

    /// Heap bytes of the values.
    pub fn bytes(&self) -> usize {
        self.values.capacity() * std::mem::size_of::<i16>()
    }

    /// Sum of the values at `points` displaced by (`ox`, `oy`).
    #[inline]
    pub fn score(&self, points: &[(i32, i32)], ox: i32, oy: i32) -> i64 {
        let (bx, by) = (ox + self.pad, oy + self.pad);
        let mut s = 0i64;
        for &(px, py) in points {
            let (sx, sy) = ((px + bx) as u32, (py + by) as u32);
            if sx < self.width && sy < self.height {
                s += i64::from(self.values[(sy * self.width + sx) as usize]);
            }
        }
        s
    }
}

/// Levels 0 (the field itself) to `depth`.
#[derive(Debug, Clone)]
pub struct Pyramid {
    /// Level k pools windows of `2^k` cells.
    pub levels: Vec<PooledGrid>,
}

impl Pyramid {
    /// Pools `field` up to windows of `2^depth` cells; each level from the one below by the doubling trick.
    pub fn build(field: &ScoreField, depth: usize) -> Self {
        let base =
            PooledGrid { pad: 0, width: field.width as u32, height: field.height as u32, values: field.values.clone() };
        let mut levels = vec![base];
        for k in 1..=depth {
            let below = &levels[k - 1];
            let half = 1i32 << (k - 1);
            let pad = (1i32 << k) - 1;
            let (w, h) = (field.width as i32 + pad, field.height as i32 + pad);
            let mut values = vec![0i16; (w * h) as usize];
            for sy in 0..h {
                let y = sy - pad;
                for sx in 0..w {
                    let x = sx - pad;
                    let m = below
                        .get(x, y)
                        .max(below.get(x + half, y))
                        .max(below.get(x, y + half))
                        .max(below.get(x + half, y + half));
                    values[(sy * w + sx) as usize] = m;
                }
            }
            levels.push(PooledGrid { pad, width: w as u32, height: h as u32, values });
        }
        Pyramid { levels }
    }

    /// Deepest level.
    pub fn depth(&self) -> usize {
        self.levels.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_field(seed: u64) -> ScoreField {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (w, h) = (37, 23);
        let values = (0..w * h).map(|_| rng.random_range(-10i16..=100)).collect();
        ScoreField { width: w, height: h, values }
    }

    #[test]
    fn each_level_is_the_max_over_its_window() {
        let f = random_field(1);
        let p = Pyramid::build(&f, 4);
        for (k, level) in p.levels.iter().enumerate() {
            let n = 1i32 << k;
            for y in -20..30 {
                for x in -20..45 {
                    let want = (0..n).flat_map(|j| (0..n).map(move |i| (i, j))).map(|(i, j)| f.get(x + i, y + j)).max();
                    assert_eq!(level.get(x, y), want.unwrap_or(0), "level {k} at ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn a_coarse_score_bounds_every_offset_of_its_block() {
        let f = random_field(2);
        let p = Pyramid::build(&f, 3);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let points: Vec<(i32, i32)> = (0..60).map(|_| (rng.random_range(-10..40), rng.random_range(-10..30))).collect();
        for k in 1..=3 {
            let n = 1 << k;
            for oy in -12..12 {
                for ox in -12..12 {
                    let bound = p.levels[k].score(&points, ox, oy);
                    for j in 0..n {
                        for i in 0..n {
                            let s = p.levels[0].score(&points, ox + i, oy + j);
                            assert!(s <= bound, "level {k} ({ox}, {oy}) + ({i}, {j}): {s} > {bound}");
                        }
                    }
                }
            }
        }
    }
}
