//! A 2D pose graph and its least-squares optimiser: the back end of loop closure.
//!
//! Nodes are poses (x, y, θ); an edge says where node `to` was seen from node `from`, with an information
//! matrix. The optimiser minimises Σ ρ(eᵀ Ω e) over the edges by Gauss-Newton on the poses (node 0 held
//! fixed), with the error of an edge e = t2v(Z⁻¹ · Xᵢ⁻¹ · Xⱼ) as in g2o's SE(2) edges (Kümmerle et al. 2011)
//! and ρ Huber's kernel where the edge asks for it (loop edges: a wrong match is pulled on linearly, not
//! quadratically). The normal equations are sparse (a chain plus the loop edges) and solved by a sparse
//! Cholesky factorisation (`nalgebra-sparse`); in time order the factor fills only within each loop edge's
//! span, so no reordering is needed at the sizes of a log (a node per metre driven).

use crate::Information;
use mrslam_core::Xyt;
use mrslam_core::pose::normalize_angle;
use nalgebra::{DVector, Matrix3, Vector3};
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};

/// A relative-pose constraint between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// The node the measurement was taken from.
    pub from: usize,
    /// The node measured.
    pub to: usize,
    /// Pose of `to` in `from`'s frame.
    pub measured: Xyt,
    /// Information matrix of the error (upper triangle 00 01 02 11 12 22): translation in the frame of
    /// `from ⊕ measured` (i.e. `to`'s own frame), then heading.
    pub information: Information,
    /// Huber's threshold on the edge's Mahalanobis distance √(eᵀ Ω e); infinite for plain least squares.
    pub huber: f64,
}

/// What the optimiser did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// Gauss-Newton iterations run.
    pub iterations: u32,
    /// Σ ρ(eᵀ Ω e) before and after.
    pub cost_before: f64,
    /// See `cost_before`.
    pub cost_after: f64,
}

/// Gauss-Newton stops when no pose moves more than this (metres, and radians).
const STEP_TOLERANCE: f64 = 1e-6;
/// Damping added to the normal matrix's diagonal, relative to it (keeps it positive definite where an edge's
/// information is singular, such as a loop edge along a featureless corridor).
const DAMPING: f64 = 1e-9;

/// The error of `e` at `poses` and its Jacobians with respect to the `from` and `to` poses.
fn linearize(e: &Edge, poses: &[Xyt]) -> ([f64; 3], [[f64; 3]; 3], [[f64; 3]; 3]) {
    let (xi, xj, z) = (&poses[e.from], &poses[e.to], &e.measured);
    let (si, ci) = xi.theta.sin_cos();
    let (sz, cz) = z.theta.sin_cos();
    let (dx, dy) = (xj.x - xi.x, xj.y - xi.y);
    // Rᵢᵀ (tⱼ - tᵢ): where j is in i's frame
    let (ux, uy) = (ci * dx + si * dy, -si * dx + ci * dy);
    // dRᵢᵀ/dθᵢ (tⱼ - tᵢ)
    let (vx, vy) = (-si * dx + ci * dy, -ci * dx - si * dy);
    let rz = |x: f64, y: f64| (cz * x + sz * y, -sz * x + cz * y); // R_zᵀ
    let (ex, ey) = rz(ux - z.x, uy - z.y);
    let et = normalize_angle(xj.theta - xi.theta - z.theta);
    // R_zᵀ Rᵢᵀ columns: the derivative of e_t by tⱼ (and minus that by tᵢ)
    let (a0, a1) = rz(ci, -si);
    let (b0, b1) = rz(si, ci);
    let (g0, g1) = rz(vx, vy);
    let jj = [[a0, b0, 0.0], [a1, b1, 0.0], [0.0, 0.0, 1.0]];
    let ji = [[-a0, -b0, g0], [-a1, -b1, g1], [0.0, 0.0, -1.0]];
    ([ex, ey, et], ji, jj)
}

/// Huber's ρ of a squared distance `d2` with threshold `k`, and its weight ρ'(d2).
fn huber(d2: f64, k: f64) -> (f64, f64) {
    let d = d2.sqrt();
    if d <= k { (d2, 1.0) } else { (2.0 * k * d - k * k, k / d) }
}

/// Σ ρ(eᵀ Ω e).
pub fn cost(poses: &[Xyt], edges: &[Edge]) -> f64 {
    edges.iter().map(|e| huber(e.information.mahalanobis2(&linearize(e, poses).0), e.huber).0).sum()
}

/// Optimises `poses` (node 0 fixed) for `edges` by at most `max_iterations` Gauss-Newton steps, each
/// reweighting the Huber edges (iteratively reweighted least squares). Returns `None` (poses unchanged) when
/// an edge names a missing node or the normal matrix cannot be factored.
pub fn optimize(poses: &mut [Xyt], edges: &[Edge], max_iterations: u32) -> Option<Solution> {
    let n = poses.len();
    if edges.iter().any(|e| e.from >= n || e.to >= n || e.from == e.to) {
        return None;
    }
    let cost_before = cost(poses, edges);
    if n < 2 || edges.is_empty() {
        return Some(Solution { iterations: 0, cost_before, cost_after: cost_before });
    }
    let dim = 3 * (n - 1);
    // Node k > 0 owns variables 3·slot[k]..3·slot[k] + 3, in a fill-reducing order.
    let slot = elimination_order(n, edges);
    let mut current = poses.to_vec();
    let mut iterations = 0;
    for _ in 0..max_iterations {
        iterations += 1;
        let mut coo = CooMatrix::<f64>::new(dim, dim);
        let mut b = DVector::<f64>::zeros(dim);
        let mut diag = vec![0.0f64; dim];
        for e in edges {
            let (err, ji, jj) = linearize(e, &current);
            let (_, w) = huber(e.information.mahalanobis2(&err), e.huber);
            let o = e.information.matrix();
            let err = Vector3::from(err);
            let blocks = [(e.from, Matrix3::from(ji).transpose()), (e.to, Matrix3::from(jj).transpose())];
            for &(na, ja) in &blocks {
                let Some(va) = slot[na].map(|k| 3 * k) else { continue };
                let jt_o = ja.transpose() * o; // Jₐᵀ Ω
                let g = jt_o * err * w;
                for r in 0..3 {
                    b[va + r] -= g[r];
                }
                for &(nb, jb) in &blocks {
                    let Some(vb) = slot[nb].map(|k| 3 * k) else { continue };
                    let block = jt_o * jb * w; // Jₐᵀ Ω J_b
                    for ((r, c), &v) in (0..3).flat_map(|c| (0..3).map(move |r| (r, c))).zip(block.iter()) {
                        if v != 0.0 {
                            coo.push(va + r, vb + c, v);
                            if va + r == vb + c {
                                diag[va + r] += v;
                            }
                        }
                    }
                }
            }
        }
        for (k, d) in diag.iter().enumerate() {
            coo.push(k, k, DAMPING * d.max(1.0));
        }
        let h = CscMatrix::from(&coo);
        let chol = CscCholesky::factor(&h).ok()?;
        let step = chol.solve(&b);
        let mut largest: f64 = 0.0;
        for (k, p) in current.iter_mut().enumerate().skip(1) {
            let Some(v) = slot[k].map(|s| 3 * s) else { continue };
            let (dx, dy, dt) = (step[v], step[v + 1], step[v + 2]);
            if !(dx.is_finite() && dy.is_finite() && dt.is_finite()) {
                return None;
            }
            p.x += dx;
            p.y += dy;
            p.theta = normalize_angle(p.theta + dt);
            largest = largest.max(dx.abs().max(dy.abs()).max(dt.abs()));
        }
        if largest < STEP_TOLERANCE {
            break;
        }
    }
    let cost_after = cost(&current, edges);
    poses.copy_from_slice(&current);
    Some(Solution { iterations, cost_before, cost_after })
}

/// Each node's place in the elimination order (node 0, held fixed, has none): greedy minimum degree on the
/// graph of the edges (Tinney's scheme 2, the idea behind AMD). In time order a loop edge fills the factor
/// across its whole span, and a log full of loops factors nearly dense; eliminating the least connected node
/// first keeps the factor of a chain with loops sparse.
fn elimination_order(n: usize, edges: &[Edge]) -> Vec<Option<usize>> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
    for e in edges {
        if e.from != 0 && e.to != 0 {
            adjacent[e.from].push(e.to);
            adjacent[e.to].push(e.from);
        }
    }
    for a in &mut adjacent {
        a.sort_unstable();
        a.dedup();
    }
    let mut slot = vec![None; n];
    let mut heap: BinaryHeap<Reverse<(usize, usize)>> = (1..n).map(|k| Reverse((adjacent[k].len(), k))).collect();
    let mut next = 0;
    while let Some(Reverse((degree, v))) = heap.pop() {
        if slot[v].is_some() || degree != adjacent[v].len() {
            continue;
        }
        slot[v] = Some(next);
        next += 1;
        // Eliminating v joins its neighbours into a clique.
        let neighbours = std::mem::take(&mut adjacent[v]);
        for &u in &neighbours {
            let a = &mut adjacent[u];
            a.retain(|&w| w != v);
            a.extend(neighbours.iter().copied().filter(|&w| w != u));
            a.sort_unstable();
            a.dedup();
            heap.push(Reverse((a.len(), u)));
        }
    }
    slot
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose::relative;

    fn xyt(x: f64, y: f64, theta: f64) -> Xyt {
        Xyt { x, y, theta }
    }

    fn between(a: &Xyt, b: &Xyt) -> Xyt {
        Xyt::from_pose(&relative(&a.to_pose(), &b.to_pose()))
    }

    const INFO: Information = Information([100.0, 0.0, 0.0, 100.0, 0.0, 400.0]);

    /// A square loop of 4 m sides, a node every metre, ending where it started.
    fn square() -> Vec<Xyt> {
        let mut v = Vec::new();
        for side in 0..4 {
            let t = side as f64 * std::f64::consts::FRAC_PI_2;
            let (s, c) = t.sin_cos();
            let (ox, oy) = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)][side];
            for k in 0..4 {
                v.push(xyt(ox + c * k as f64, oy + s * k as f64, t));
            }
        }
        v
    }

    #[test]
    fn the_jacobians_match_finite_differences() {
        let poses = [xyt(0.3, -0.2, 0.4), xyt(1.7, 0.9, 1.9)];
        let e = Edge { from: 0, to: 1, measured: xyt(1.1, 0.5, 1.2), information: INFO, huber: f64::INFINITY };
        let (_, ji, jj) = linearize(&e, &poses);
        let h = 1e-6;
        for (node, jac) in [(0, ji), (1, jj)] {
            for c in 0..3 {
                let mut p = poses;
                match c {
                    0 => p[node].x += h,
                    1 => p[node].y += h,
                    _ => p[node].theta += h,
                }
                let (plus, _, _) = linearize(&e, &p);
                let (base, _, _) = linearize(&e, &poses);
                for (r, row) in jac.iter().enumerate() {
                    let numeric = (plus[r] - base[r]) / h;
                    assert!((numeric - row[c]).abs() < 1e-5, "node {node} d e{r}/d x{c}: {numeric} vs {}", row[c]);
                }
            }
        }
    }

    #[test]
    fn a_loop_edge_pulls_a_drifted_square_back_onto_the_truth() {
        let truth = square();
        // Odometry edges measured with a heading bias of 0.02 rad per step: the chain ends 1 m off.
        let mut drifted = vec![truth[0]];
        let mut edges = Vec::new();
        for k in 1..truth.len() {
            let mut z = between(&truth[k - 1], &truth[k]);
            z.theta += 0.02;
            let p = Xyt::from_pose(&(drifted[k - 1].to_pose() * z.to_pose()));
            drifted.push(p);
            edges.push(Edge { from: k - 1, to: k, measured: z, information: INFO, huber: f64::INFINITY });
        }
        let last = truth.len() - 1;
        let before = (drifted[last].x - truth[last].x).hypot(drifted[last].y - truth[last].y);
        assert!(before > 0.5, "the chain drifted {before} m");
        // The loop edge: the last node seen from the first, as it truly is, stiffer than the chain.
        let z = between(&truth[0], &truth[last]);
        let stiff = Information([1e4, 0.0, 0.0, 1e4, 0.0, 1e4]);
        edges.push(Edge { from: 0, to: last, measured: z, information: stiff, huber: 3.0 });
        let mut poses = drifted.clone();
        let s = optimize(&mut poses, &edges, 50).unwrap();
        assert!(s.cost_after < 0.01 * s.cost_before, "{s:?}");
        let after = (poses[last].x - truth[last].x).hypot(poses[last].y - truth[last].y);
        assert!(after < 0.05, "the loop closed to {after} m (was {before} m)");
        // Every node is closer to the truth than the drifted chain put it.
        let worst = truth.iter().zip(&poses).map(|(t, p)| (t.x - p.x).hypot(t.y - p.y)).fold(0.0, f64::max);
        assert!(worst < 0.15, "worst node {worst} m from the truth");
        assert_eq!(poses[0], truth[0], "node 0 is fixed");
    }

    #[test]
    fn a_wrong_loop_edge_under_huber_moves_the_chain_far_less_than_under_least_squares() {
        let truth = square();
        let stiff = Information([1e4, 0.0, 0.0, 1e4, 0.0, 1e4]);
        let mut edges: Vec<Edge> = (1..truth.len())
            .map(|k| Edge {
                from: k - 1,
                to: k,
                measured: between(&truth[k - 1], &truth[k]),
                information: stiff,
                huber: f64::INFINITY,
            })
            .collect();
        // A loop edge 2 m wrong, less stiff than the chain.
        let mut z = between(&truth[0], &truth[8]);
        z.x += 2.0;
        edges.push(Edge { from: 0, to: 8, measured: z, information: INFO, huber: 1.0 });
        let mut robust = truth.clone();
        optimize(&mut robust, &edges, 50).unwrap();
        edges.last_mut().unwrap().huber = f64::INFINITY;
        let mut plain = truth.clone();
        optimize(&mut plain, &edges, 50).unwrap();
        let moved = |p: &[Xyt]| truth.iter().zip(p).map(|(t, q)| (t.x - q.x).hypot(t.y - q.y)).fold(0.0, f64::max);
        eprintln!("robust {} m, plain {} m", moved(&robust), moved(&plain));
        assert!(moved(&robust) < 0.25 * moved(&plain), "robust {} m, plain {} m", moved(&robust), moved(&plain));
    }

    #[test]
    fn bad_edges_are_refused() {
        let mut poses = vec![xyt(0.0, 0.0, 0.0), xyt(1.0, 0.0, 0.0)];
        let e = Edge { from: 0, to: 2, measured: xyt(1.0, 0.0, 0.0), information: INFO, huber: 1.0 };
        assert!(optimize(&mut poses, &[e], 10).is_none());
        let e = Edge { from: 1, to: 1, ..e };
        assert!(optimize(&mut poses, &[e], 10).is_none());
    }
}
