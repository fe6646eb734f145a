//! Branch and bound over the translations of one rotated scan (Hess et al. 2016, algorithm 3).
//!
//! Candidates are integer cell offsets of the scan's points. The root level tiles the offset range with
//! blocks of `2^depth` offsets scored on the deepest pooled level (an upper bound of every offset in the
//! block); blocks are split into four, best first, and a branch is dropped as soon as its bound cannot beat
//! the weakest of the answers kept. The leaves are exact scores on the field itself.

use crate::pyramid::Pyramid;

/// An offset and its score.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Candidate {
    /// Sum of the field over the displaced points.
    pub score: i64,
    /// Offset along x, cells.
    pub ox: i32,
    /// Offset along y, cells.
    pub oy: i32,
}

/// Offsets searched: `[x0, x1] × [y0, y1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// Lowest x offset.
    pub x0: i32,
    /// Highest x offset.
    pub x1: i32,
    /// Lowest y offset.
    pub y0: i32,
    /// Highest y offset.
    pub y1: i32,
}

/// The best distinct answers found so far, best first.
#[derive(Debug, Clone)]
pub struct Best {
    /// At most `keep` candidates, best first.
    pub found: Vec<Candidate>,
    keep: usize,
    /// Candidates nearer than this (cells, along either axis) are the same answer.
    separation: i32,
    /// Scores below this are never kept.
    floor: i64,
}

impl Best {
    /// Room for `keep` answers at least `separation` cells apart that score at least `floor`.
    pub fn new(keep: usize, separation: i32, floor: i64) -> Self {
        Best { found: Vec::with_capacity(keep + 1), keep: keep.max(1), separation, floor }
    }

    /// Whether a branch bounded by `bound` cannot change the answers: below the floor, or no better than the
    /// weakest of a full list.
    #[inline]
    fn prunes(&self, bound: i64) -> bool {
        bound < self.floor || (self.found.len() >= self.keep && self.found.last().is_some_and(|c| bound <= c.score))
    }

    /// Offers a leaf: it replaces a weaker answer near it, or joins the list when it is far from all.
    fn offer(&mut self, c: Candidate) {
        if self.prunes(c.score) {
            return;
        }
        let near = |o: &Candidate| (o.ox - c.ox).abs() < self.separation && (o.oy - c.oy).abs() < self.separation;
        if let Some(i) = self.found.iter().position(near) {
            if self.found[i].score >= c.score {
                return;
            }
            self.found.remove(i);
        }
        let at = self.found.iter().position(|o| o.score < c.score).unwrap_or(self.found.len());
        self.found.insert(at, c);
        self.found.truncate(self.keep);
    }
}

/// Branch and bound of `points` over the offsets of `window` on `pyramid`: the best distinct offsets.
///
/// `scratch` holds the root blocks between calls (no allocation once it has grown).
pub fn branch_and_bound(
    pyramid: &Pyramid,
    points: &[(i32, i32)],
    window: Window,
    best: &mut Best,
    scratch: &mut Vec<Candidate>,
) {
    let depth = pyramid.depth();
    let step = 1i32 << depth;
    scratch.clear();
    let top = &pyramid.levels[depth];
    let mut oy = window.y0;
    while oy <= window.y1 {
        let mut ox = window.x0;
        while ox <= window.x1 {
            scratch.push(Candidate { score: top.score(points, ox, oy), ox, oy });
            ox += step;
        }
        oy += step;
    }
    scratch.sort_unstable_by(|a, b| b.score.cmp(&a.score).then(a.oy.cmp(&b.oy)).then(a.ox.cmp(&b.ox)));
    for &c in scratch.iter() {
        if best.prunes(c.score) {
            break;
        }
        descend(pyramid, points, window, depth, c, best);
    }
}

/// Splits block `c` of level `k` (k ≥ 1) into its four children, best first; offers leaves.
fn descend(pyramid: &Pyramid, points: &[(i32, i32)], window: Window, k: usize, c: Candidate, best: &mut Best) {
    if k == 0 {
        best.offer(c);
        return;
    }
    let half = 1i32 << (k - 1);
    let level = &pyramid.levels[k - 1];
    let mut children = [Candidate { score: i64::MIN, ox: 0, oy: 0 }; 4];
    let mut n = 0;
    for (dx, dy) in [(0, 0), (half, 0), (0, half), (half, half)] {
        let (ox, oy) = (c.ox + dx, c.oy + dy);
        if ox <= window.x1 && oy <= window.y1 {
            children[n] = Candidate { score: level.score(points, ox, oy), ox, oy };
            n += 1;
        }
    }
    let children = &mut children[..n];
    children.sort_unstable_by(|a, b| b.score.cmp(&a.score).then(a.oy.cmp(&b.oy)).then(a.ox.cmp(&b.ox)));
    for &child in children.iter() {
        if best.prunes(child.score) {
            break;
        }
        descend(pyramid, points, window, k - 1, child, best);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::ScoreField;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn branch_and_bound_finds_the_exhaustive_best() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for trial in 0..20 {
            let (w, h) = (50, 40);
            let values = (0..w * h).map(|_| rng.random_range(-5i16..=100)).collect();
            let field = ScoreField { width: w, height: h, values };
            let points: Vec<(i32, i32)> = (0..30).map(|_| (rng.random_range(0..20), rng.random_range(0..20))).collect();
            let window = Window { x0: -15, x1: 45, y0: -15, y1: 35 };
            let mut exhaustive = Candidate { score: i64::MIN, ox: 0, oy: 0 };
            let flat = Pyramid::build(&field, 0);
            for oy in window.y0..=window.y1 {
                for ox in window.x0..=window.x1 {
                    let s = Candidate { score: flat.levels[0].score(&points, ox, oy), ox, oy };
                    if s.score > exhaustive.score {
                        exhaustive = s;
                    }
                }
            }
            let pyramid = Pyramid::build(&field, 1 + trial % 5);
            let mut best = Best::new(3, 3, i64::MIN);
            branch_and_bound(&pyramid, &points, window, &mut best, &mut Vec::new());
            assert_eq!(best.found[0].score, exhaustive.score, "trial {trial}");
            assert!(best.found.windows(2).all(|p| p[0].score >= p[1].score));
            for (i, c) in best.found.iter().enumerate() {
                for d in &best.found[i + 1..] {
                    assert!((c.ox - d.ox).abs() >= 3 || (c.oy - d.oy).abs() >= 3, "{c:?} {d:?}");
                }
            }
        }
    }
}
