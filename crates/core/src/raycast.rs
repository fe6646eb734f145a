//! Grid ray traversal (Amanatides & Woo): the cells a segment passes through, in order.
//!
//! Coordinates here are continuous cell coordinates: cell `(i, j)` covers `[i, i+1) × [j, j+1)`.

/// Iterator over the cells a segment passes through, from the start cell to the end cell inclusive.
///
/// Cells the segment only grazes at a corner (an intersection of zero length) are not visited; when the
/// segment passes exactly through a corner, the x step is taken first.
#[derive(Debug, Clone)]
pub struct CellTraversal {
    ix: i64,
    iy: i64,
    end_x: i64,
    end_y: i64,
    step_x: i64,
    step_y: i64,
    t_max_x: f64,
    t_max_y: f64,
    t_delta_x: f64,
    t_delta_y: f64,
    remaining: u64,
    done: bool,
}

impl CellTraversal {
    /// Traverses the segment from `(x0, y0)` to `(x1, y1)`, both in cell coordinates.
    pub fn new(x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        let ix = x0.floor() as i64;
        let iy = y0.floor() as i64;
        let end_x = x1.floor() as i64;
        let end_y = y1.floor() as i64;
        let dx = x1 - x0;
        let dy = y1 - y0;
        let (step_x, t_delta_x, t_max_x) = axis_setup(x0, dx);
        let (step_y, t_delta_y, t_max_y) = axis_setup(y0, dy);
        let remaining = (end_x - ix).unsigned_abs() + (end_y - iy).unsigned_abs();
        CellTraversal {
            ix,
            iy,
            end_x,
            end_y,
            step_x,
            step_y,
            t_max_x,
            t_max_y,
            t_delta_x,
            t_delta_y,
            remaining,
            done: false,
        }
    }

    /// The cell the traversal ends in.
    pub fn end_cell(&self) -> (i64, i64) {
        (self.end_x, self.end_y)
    }
}

/// Step direction, parametric cell width and parametric distance to the first boundary along one axis.
fn axis_setup(p0: f64, d: f64) -> (i64, f64, f64) {
    if d > 0.0 {
        (1, 1.0 / d, (p0.floor() + 1.0 - p0) / d)
    } else if d < 0.0 {
        (-1, -1.0 / d, (p0 - p0.floor()) / -d)
    } else {
        (0, f64::INFINITY, f64::INFINITY)
    }
}

impl Iterator for CellTraversal {
    type Item = (i64, i64);

    fn next(&mut self) -> Option<(i64, i64)> {
        if self.done {
            return None;
        }
        let cell = (self.ix, self.iy);
        if self.remaining == 0 {
            self.done = true;
            return Some(cell);
        }
        // Step across the nearer boundary, but never beyond the end cell on an axis: with floating-point
        // rounding the parametric boundaries can disagree with floor() of the end point by one ulp.
        let x_left = self.ix != self.end_x;
        let y_left = self.iy != self.end_y;
        if x_left && (!y_left || self.t_max_x <= self.t_max_y) {
            self.ix += self.step_x;
            self.t_max_x += self.t_delta_x;
        } else {
            self.iy += self.step_y;
            self.t_max_y += self.t_delta_y;
        }
        self.remaining -= 1;
        Some(cell)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = if self.done { 0 } else { self.remaining as usize + 1 };
        (n, Some(n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::BTreeSet;

    /// Length of the parametric interval of the segment inside the closed unit cell `(i, j)`.
    fn overlap(x0: f64, y0: f64, x1: f64, y1: f64, i: i64, j: i64) -> f64 {
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, d, lo) in [(x0, x1 - x0, i as f64), (y0, y1 - y0, j as f64)] {
            let hi = lo + 1.0;
            if d == 0.0 {
                if p < lo || p > hi {
                    return -1.0;
                }
            } else {
                let (a, b) = ((lo - p) / d, (hi - p) / d);
                let (a, b) = if a < b { (a, b) } else { (b, a) };
                t0 = t0.max(a);
                t1 = t1.min(b);
            }
        }
        t1 - t0
    }

    #[test]
    fn horizontal_and_diagonal() {
        let v: Vec<_> = CellTraversal::new(0.5, 0.5, 3.5, 0.5).collect();
        assert_eq!(v, [(0, 0), (1, 0), (2, 0), (3, 0)]);
        let v: Vec<_> = CellTraversal::new(0.5, 0.2, 2.5, 1.7).collect();
        assert_eq!(v.first(), Some(&(0, 0)));
        assert_eq!(v.last(), Some(&(2, 1)));
        assert_eq!(v.len(), 4);
        let v: Vec<_> = CellTraversal::new(-0.5, 2.5, -0.5, 0.5).collect();
        assert_eq!(v, [(-1, 2), (-1, 1), (-1, 0)]);
    }

    #[test]
    fn single_cell_segment() {
        let v: Vec<_> = CellTraversal::new(4.1, 4.2, 4.9, 4.8).collect();
        assert_eq!(v, [(4, 4)]);
    }

    proptest! {
        /// The traversal visits every cell the segment crosses with positive length, no cell it misses,
        /// each once, as a 4-connected chain from start to end.
        #[test]
        fn traversal_matches_brute_force(x0 in -20.0f64..20.0, y0 in -20.0f64..20.0,
                                         x1 in -20.0f64..20.0, y1 in -20.0f64..20.0) {
            let visited: Vec<(i64, i64)> = CellTraversal::new(x0, y0, x1, y1).collect();
            let set: BTreeSet<_> = visited.iter().copied().collect();
            prop_assert_eq!(set.len(), visited.len(), "a cell was visited twice");
            prop_assert_eq!(visited[0], (x0.floor() as i64, y0.floor() as i64));
            prop_assert_eq!(*visited.last().unwrap(), (x1.floor() as i64, y1.floor() as i64));
            for w in visited.windows(2) {
                prop_assert_eq!((w[0].0 - w[1].0).abs() + (w[0].1 - w[1].1).abs(), 1);
            }
            let eps = 1e-9;
            for i in (x0.min(x1).floor() as i64)..=(x0.max(x1).floor() as i64) {
                for j in (y0.min(y1).floor() as i64)..=(y0.max(y1).floor() as i64) {
                    let len = overlap(x0, y0, x1, y1, i, j);
                    if len > eps {
                        prop_assert!(set.contains(&(i, j)), "missed cell {:?} (overlap {})", (i, j), len);
                    }
                    if set.contains(&(i, j)) {
                        prop_assert!(len >= -eps, "visited cell {:?} the segment misses", (i, j));
                    }
                }
            }
        }
    }
}
