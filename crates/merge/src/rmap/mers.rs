//! G-map → binary free-space matrix → R-map (Algorithm 1, lines 2-3 and 10-11).
//!
//! The maximal empty rectangles (MERs) of the free matrix are enumerated exactly with the row-histogram
//! stack method: for every row taken as the bottom row, the stack over the column heights emits each
//! rectangle that cannot grow left, right or up, at most one per column, and a prefix count of the next
//! row drops the ones that could still grow down. A binary matrix of W × H cells has at most W · H
//! maximal rectangles, so this is O(W · H) time and memory, whatever the map.
//!
//! **The R-map** is the paper's "integration of the free space into larger simple elements (with the
//! largest area) to reduce the number of map elements": a greedy cover of the free cells by maximal
//! rectangles. By default ([`CoverRule::GreedyGain`]) it is the greedy set cover, each next element the MER
//! that integrates the most free cells not yet covered, listed in that order; the other reading
//! ([`CoverRule::LargestFirst`]) takes MERs by area and keeps each that covers any new cell. Every free cell
//! is covered, every element is a true MER (it cannot grow in any direction), and elements may overlap, as
//! maximal rectangles do. Coverage is tracked with one "next uncovered column" union-find per row, so
//! testing or counting a candidate costs one near-constant lookup per row plus one per uncovered cell.
//!
//! **Connections** (`c(i)` in the paper) of a MER are the MERs touching or overlapping it that stick out
//! past one of its sides: `j` is in `right(i)` when they share at least one row, `j` starts no further left
//! than `i` and no further right than one column past `i` (touching or overlapping), and ends right of
//! `i`'s right edge. `left`, `up` and `down` follow by symmetry, so `j ∈ right(i) ⇔ i ∈ left(j)` and
//! `j ∈ down(i) ⇔ i ∈ up(j)`. "Up" is towards row 0, the matrix's first row, as the paper draws it; a
//! MER's `(x, y)` is its upper-left cell in that drawing. Two MERs that cross (each spans the other in one
//! axis) stick out of no side of each other and are not connected.

use mrslam_core::{CellState, OccupancyGrid};

/// A maximal empty rectangle: columns `x..x + w`, rows `y..y + h` of the free matrix.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Mer {
    /// Left column (the paper's upper-left corner, with row 0 drawn first).
    pub x: usize,
    /// Top row.
    pub y: usize,
    /// Width, cells.
    pub w: usize,
    /// Height, cells.
    pub h: usize,
}

impl Mer {
    /// Area, cells.
    pub fn area(&self) -> usize {
        self.w * self.h
    }
    /// One past the right column.
    pub fn x1(&self) -> usize {
        self.x + self.w
    }
    /// One past the bottom row.
    pub fn y1(&self) -> usize {
        self.y + self.h
    }
    /// Centre in continuous cell coordinates (cell (i, j) covers [i, i+1) × [j, j+1)).
    pub fn center(&self) -> (f64, f64) {
        (self.x as f64 + self.w as f64 / 2.0, self.y as f64 + self.h as f64 / 2.0)
    }
    /// Whether the rectangle holds cell (x, y).
    pub fn contains(&self, x: usize, y: usize) -> bool {
        x >= self.x && x < self.x1() && y >= self.y && y < self.y1()
    }
}

/// The binary matrix of a G-map: which cells are free (1 in the paper), and what the others are.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeMatrix {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// State of every cell, row-major.
    pub states: Vec<CellState>,
}

impl FreeMatrix {
    /// The matrix of an occupancy grid (cell (x, y) of the grid is row y, column x).
    pub fn from_grid(g: &OccupancyGrid) -> Self {
        FreeMatrix {
            width: g.width(),
            height: g.height(),
            states: g.cells().iter().map(|&l| CellState::from_log_odds(l)).collect(),
        }
    }

    /// Whether cell (x, y) is free.
    #[inline]
    pub fn is_free(&self, x: usize, y: usize) -> bool {
        self.states[y * self.width + x] == CellState::Free
    }

    /// State of a cell, Unknown off the matrix.
    #[inline]
    pub fn state_at(&self, x: i64, y: i64) -> CellState {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            CellState::Unknown
        } else {
            self.states[y as usize * self.width + x as usize]
        }
    }

    /// Number of free cells.
    pub fn free_count(&self) -> usize {
        self.states.iter().filter(|&&s| s == CellState::Free).count()
    }
}

/// The MERs touching one MER on each side.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Connections {
    /// MERs sticking out past the left side.
    pub left: Vec<usize>,
    /// MERs sticking out past the right side.
    pub right: Vec<usize>,
    /// MERs sticking out past the top side (towards row 0).
    pub up: Vec<usize>,
    /// MERs sticking out past the bottom side.
    pub down: Vec<usize>,
}

impl Connections {
    /// All connected MERs (a MER may appear in two lists when it sticks out past two sides).
    pub fn all(&self) -> impl Iterator<Item = usize> + '_ {
        self.left.iter().chain(&self.right).chain(&self.up).chain(&self.down).copied()
    }
}

/// The R-map of a matrix: its MER cover, largest first ([`CoverRule`]), and their connections (`r(i)`
/// and `c(i)`).
#[derive(Debug, Clone, PartialEq)]
pub struct Rmap {
    /// Columns of the matrix.
    pub width: usize,
    /// Rows of the matrix.
    pub height: usize,
    /// The MERs, largest first in the sense of the [`CoverRule`].
    pub mers: Vec<Mer>,
    /// Connections of each MER (same indices).
    pub connections: Vec<Connections>,
}

/// Every maximal empty (all-free) rectangle of the matrix, in no particular order.
pub fn maximal_rectangles(m: &FreeMatrix) -> Vec<Mer> {
    let (w, h) = (m.width, m.height);
    let mut out = Vec::new();
    if w == 0 || h == 0 {
        return out;
    }
    // nonfree[y * (w + 1) + x]: non-free cells in row y before column x.
    let mut nonfree = vec![0u32; h * (w + 1)];
    for y in 0..h {
        let row = &mut nonfree[y * (w + 1)..(y + 1) * (w + 1)];
        for x in 0..w {
            row[x + 1] = row[x] + u32::from(!m.is_free(x, y));
        }
    }
    let row_free = |y: usize, x0: usize, x1: usize| nonfree[y * (w + 1) + x1] == nonfree[y * (w + 1) + x0];
    let mut heights = vec![0usize; w];
    let mut stack: Vec<(usize, usize)> = Vec::with_capacity(w);
    for y in 0..h {
        for (x, ht) in heights.iter_mut().enumerate() {
            *ht = if m.is_free(x, y) { *ht + 1 } else { 0 };
        }
        stack.clear();
        for x in 0..=w {
            let cur = heights.get(x).copied().unwrap_or(0);
            let mut start = x;
            while let Some(&(s, ht)) = stack.last() {
                if ht <= cur {
                    break;
                }
                stack.pop();
                // Columns s..x, rows y+1-ht..=y: blocked left, right and up; keep it if blocked down too.
                if y + 1 == h || !row_free(y + 1, s, x) {
                    out.push(Mer { x: s, y: y + 1 - ht, w: x - s, h: ht });
                }
                start = s;
            }
            if cur > 0 && stack.last().is_none_or(|&(_, ht)| ht < cur) {
                stack.push((start, cur));
            }
        }
    }
    out
}

/// Per-row "next uncovered free column at or after x" (union-find with path halving).
struct Uncovered {
    stride: usize,
    next: Vec<u32>,
}

impl Uncovered {
    fn new(m: &FreeMatrix) -> Self {
        let stride = m.width + 1;
        let mut next = vec![0u32; m.height * stride];
        for y in 0..m.height {
            for x in 0..=m.width {
                let free = x < m.width && m.is_free(x, y);
                next[y * stride + x] = if free { x as u32 } else { (x + 1).min(m.width) as u32 };
            }
        }
        Uncovered { stride, next }
    }

    fn find(&mut self, y: usize, mut x: usize) -> usize {
        let base = y * self.stride;
        loop {
            let n = self.next[base + x] as usize;
            if n == x {
                return x;
            }
            let nn = self.next[base + n] as usize;
            self.next[base + x] = nn as u32;
            x = n;
        }
    }

    fn cover(&mut self, r: &Mer) {
        for y in r.y..r.y1() {
            let mut c = self.find(y, r.x);
            while c < r.x1() {
                self.next[y * self.stride + c] = (c + 1) as u32;
                c = self.find(y, c + 1);
            }
        }
    }

    fn any_uncovered(&mut self, r: &Mer) -> bool {
        (r.y..r.y1()).any(|y| self.find(y, r.x) < r.x1())
    }
}

/// How the R-map picks its elements from the maximal rectangles (both cover every free cell).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum CoverRule {
    /// Greedy set cover: repeatedly the MER covering the most free cells not yet covered (ties: larger
    /// area, then top row, left column); the R-map lists them in that order. Fewest, largest elements.
    #[default]
    GreedyGain,
    /// Largest area first, each MER kept when it covers any cell not yet covered; listed by area. Along a
    /// staircase boundary this keeps runs of near-identical large MERs that each add a few cells.
    LargestFirst,
}

impl Uncovered {
    /// Uncovered free cells inside a rectangle.
    fn count(&mut self, r: &Mer) -> usize {
        let mut n = 0;
        for y in r.y..r.y1() {
            let mut c = self.find(y, r.x);
            while c < r.x1() {
                n += 1;
                c = self.find(y, c + 1);
            }
        }
        n
    }
}

/// The cover of the free cells by maximal rectangles (see the module docs and [`CoverRule`]).
pub fn mer_cover(m: &FreeMatrix, rule: CoverRule) -> Vec<Mer> {
    let mut cands = maximal_rectangles(m);
    cands.sort_unstable_by(|a, b| b.area().cmp(&a.area()).then(a.y.cmp(&b.y)).then(a.x.cmp(&b.x)).then(a.w.cmp(&b.w)));
    let mut unc = Uncovered::new(m);
    let mut out = Vec::new();
    match rule {
        CoverRule::LargestFirst => {
            for r in cands {
                if unc.any_uncovered(&r) {
                    unc.cover(&r);
                    out.push(r);
                }
            }
        }
        CoverRule::GreedyGain => {
            // Lazy greedy: gains only shrink, so a popped candidate whose refreshed gain still tops the
            // heap is the best one.
            use std::cmp::Reverse;
            use std::collections::BinaryHeap;
            let mut heap: BinaryHeap<(usize, Reverse<usize>)> =
                cands.iter().enumerate().map(|(i, r)| (r.area(), Reverse(i))).collect();
            while let Some((gain, Reverse(i))) = heap.pop() {
                let fresh = unc.count(&cands[i]);
                if fresh == 0 {
                    continue;
                }
                if fresh == gain || heap.peek().is_none_or(|top| (fresh, Reverse(i)) >= *top) {
                    unc.cover(&cands[i]);
                    out.push(cands[i]);
                } else {
                    heap.push((fresh, Reverse(i)));
                }
            }
        }
    }
    out
}

/// Whether half-open ranges [a0, a1) and [b0, b1) share a cell.
#[inline]
fn share(a0: usize, a1: usize, b0: usize, b1: usize) -> bool {
    a0 < b1 && b0 < a1
}

/// `j` sticks out past `i`'s far side along one axis (see the module docs): starts no earlier than `i`,
/// no later than just past `i`'s end, and ends after `i` ends.
#[inline]
fn after(i0: usize, i1: usize, j0: usize, j1: usize) -> bool {
    i0 <= j0 && j0 <= i1 && j1 > i1
}

/// Connections of every MER (see the module docs), found through a coarse bucket grid.
pub fn connections(width: usize, height: usize, mers: &[Mer]) -> Vec<Connections> {
    const B: usize = 32;
    let (bw, bh) = (width / B + 1, height / B + 1);
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); bw * bh];
    let span = |r: &Mer| {
        let (x0, y0) = (r.x.saturating_sub(1) / B, r.y.saturating_sub(1) / B);
        let (x1, y1) = (r.x1().min(width.saturating_sub(1)) / B, r.y1().min(height.saturating_sub(1)) / B);
        (x0, y0, x1.min(bw - 1), y1.min(bh - 1))
    };
    for (i, r) in mers.iter().enumerate() {
        let (x0, y0, x1, y1) = span(r);
        for by in y0..=y1 {
            for bx in x0..=x1 {
                buckets[by * bw + bx].push(i as u32);
            }
        }
    }
    let mut conn = vec![Connections::default(); mers.len()];
    let mut seen = vec![usize::MAX; mers.len()];
    for (i, a) in mers.iter().enumerate() {
        let (x0, y0, x1, y1) = span(a);
        for by in y0..=y1 {
            for bx in x0..=x1 {
                for &j in &buckets[by * bw + bx] {
                    let j = j as usize;
                    if j <= i || seen[j] == i {
                        continue;
                    }
                    seen[j] = i;
                    let b = &mers[j];
                    if share(a.y, a.y1(), b.y, b.y1()) {
                        if after(a.x, a.x1(), b.x, b.x1()) {
                            conn[i].right.push(j);
                            conn[j].left.push(i);
                        } else if after(b.x, b.x1(), a.x, a.x1()) {
                            conn[i].left.push(j);
                            conn[j].right.push(i);
                        }
                    }
                    if share(a.x, a.x1(), b.x, b.x1()) {
                        if after(a.y, a.y1(), b.y, b.y1()) {
                            conn[i].down.push(j);
                            conn[j].up.push(i);
                        } else if after(b.y, b.y1(), a.y, a.y1()) {
                            conn[i].up.push(j);
                            conn[j].down.push(i);
                        }
                    }
                }
            }
        }
    }
    for c in &mut conn {
        for v in [&mut c.left, &mut c.right, &mut c.up, &mut c.down] {
            v.sort_unstable();
        }
    }
    conn
}

/// RMAP(map): the R-map of a free matrix.
pub fn rmap(m: &FreeMatrix, rule: CoverRule) -> Rmap {
    let mers = mer_cover(m, rule);
    let connections = connections(m.width, m.height, &mers);
    Rmap { width: m.width, height: m.height, mers, connections }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(rows: &[&str]) -> FreeMatrix {
        let states = rows
            .iter()
            .flat_map(|r| r.chars().map(|c| if c == '.' { CellState::Free } else { CellState::Occupied }))
            .collect();
        FreeMatrix { width: rows[0].len(), height: rows.len(), states }
    }

    #[test]
    fn l_shape_has_two_maximal_rectangles_that_connect() {
        let m = matrix(&["...#", "...#", "....", "#..."]);
        let mut all = maximal_rectangles(&m);
        all.sort();
        // the 3x3 block, the full row 2, the 2-wide column band rows 0..4, the 3x2 lower right
        assert!(all.contains(&Mer { x: 0, y: 0, w: 3, h: 3 }));
        assert!(all.contains(&Mer { x: 0, y: 2, w: 4, h: 1 }));
        assert!(all.contains(&Mer { x: 1, y: 0, w: 2, h: 4 }));
        assert!(all.contains(&Mer { x: 1, y: 2, w: 3, h: 2 }));
        assert_eq!(all.len(), 4);
        let r = rmap(&m, CoverRule::GreedyGain);
        // after the 3x3 block, the lower-right 3x2 adds the most (4 cells) and completes the cover
        assert_eq!(r.mers, vec![Mer { x: 0, y: 0, w: 3, h: 3 }, Mer { x: 1, y: 2, w: 3, h: 2 }]);
        assert_eq!(r.connections[0], Connections { left: vec![], right: vec![1], up: vec![], down: vec![1] });
        assert_eq!(r.connections[1], Connections { left: vec![0], right: vec![], up: vec![0], down: vec![] });
        let r = rmap(&m, CoverRule::LargestFirst);
        // largest first; the column band still covers row 3's cells 1-2, the lower right cell (3, 3)
        assert_eq!(
            r.mers,
            vec![Mer { x: 0, y: 0, w: 3, h: 3 }, Mer { x: 1, y: 0, w: 2, h: 4 }, Mer { x: 1, y: 2, w: 3, h: 2 }]
        );
        assert_eq!(r.connections[0], Connections { left: vec![], right: vec![2], up: vec![], down: vec![1, 2] });
        assert_eq!(r.connections[1], Connections { left: vec![], right: vec![2], up: vec![0], down: vec![] });
        assert_eq!(r.connections[2], Connections { left: vec![0, 1], right: vec![], up: vec![0], down: vec![] });
    }

    #[test]
    fn empty_and_full_matrices() {
        for rule in [CoverRule::GreedyGain, CoverRule::LargestFirst] {
            assert!(rmap(&FreeMatrix { width: 0, height: 0, states: vec![] }, rule).mers.is_empty());
            let full = matrix(&["....", "...."]);
            assert_eq!(rmap(&full, rule).mers, vec![Mer { x: 0, y: 0, w: 4, h: 2 }]);
            let none = matrix(&["##", "##"]);
            assert!(rmap(&none, rule).mers.is_empty());
        }
    }
}
