//! N maps from their pairs' merges: a maximum spanning tree of the accepted pairs by confidence (m-explore's
//! approach), each map's transform into map 0's frame composed along the tree, the accepted pairs the tree
//! contradicts, and the maps joined to map 0 fused into one grid in its frame.

use crate::fuse::{FusionRule, fuse};
use crate::report::MergeReport;
use crate::timing::ms;
use mrslam_core::Xyt;
use mrslam_core::{OccupancyGrid, Pose2};
use std::time::Instant;

/// One pair's merge: `report.transform` is `T_a_b` (points of map `b` into map `a`'s frame).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairReport {
    /// Index of the first map (the frame the transform maps into).
    pub a: usize,
    /// Index of the second map, `b > a`.
    pub b: usize,
    /// The two-map pipeline's report, accepted or not, with its reason.
    pub report: MergeReport,
}

/// An edge of the spanning forest, oriented away from its component's root.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TreeEdge {
    /// The map nearer the root.
    pub parent: usize,
    /// The map this edge joins to the tree.
    pub child: usize,
    /// Index of the pair in [`MultiReport::pairs`] that gave the edge.
    pub pair: usize,
    /// The pair's confidence (the edge's weight).
    pub confidence: f64,
    /// `T_parent_child`: points of the child's frame into the parent's.
    pub transform: Xyt,
}

/// An accepted pair the spanning tree contradicts: its transform and the tree's chain between its maps differ by
/// more than [`DISAGREE_M`] or [`DISAGREE_DEG`], so one of the pairs on that cycle is wrong.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Disagreement {
    /// Index of the pair in [`MultiReport::pairs`] (not a tree edge).
    pub pair: usize,
    /// How far the chain's `T_a_b` moves the pair's: translation, metres.
    pub translation_m: f64,
    /// And rotation, degrees.
    pub rotation_deg: f64,
}

/// A pair and the tree's chain between its maps disagree beyond this translation, metres: correct pairs of real
/// SLAM maps are 0.03-0.15 m off the truth (benchmarks/runs/2026-12-02-merge-cascade.md), so a chain of a few of
/// them stays well inside; the wrong answers seen are metres off.
pub const DISAGREE_M: f64 = 1.0;

/// Or beyond this rotation, degrees (correct pairs: below 1°; wrong ones seen: 90° and 180°).
pub const DISAGREE_DEG: f64 = 5.0;

/// What [`crate::merge_many`] reports (also the JSON `mrslam merge` writes for three or more maps).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MultiReport {
    /// Algorithm name.
    pub algorithm: String,
    /// Number of maps merged.
    pub maps: usize,
    /// Every pair (a < b) in order (0,1), (0,2), ..., (1,2), ...: accepted or not, with the reason.
    pub pairs: Vec<PairReport>,
    /// The spanning forest's edges: map 0's tree first (breadth first from map 0), then the other components'.
    pub tree: Vec<TreeEdge>,
    /// `T_0_i` for each map i joined to map 0 by the tree (map 0's own is the identity); None for the rest.
    pub transforms: Vec<Option<Xyt>>,
    /// Connected components of the accepted pairs, each sorted, map 0's first, the rest by smallest member.
    pub components: Vec<Vec<usize>>,
    /// Maps not joined to map 0, ascending (empty when every map is connected).
    pub not_connected: Vec<usize>,
    /// Accepted pairs outside the tree that its chains contradict, in pair order (empty when every cycle closes).
    #[serde(default)]
    pub disagreements: Vec<Disagreement>,
    /// Wall time of all the pairwise merges, the tree and the fusion, milliseconds.
    pub time_ms: f64,
}

impl MultiReport {
    /// Whether every map is joined to map 0.
    pub fn all_connected(&self) -> bool {
        self.not_connected.is_empty()
    }
}

/// Everything [`crate::merge_many`] produced.
#[derive(Debug, Clone)]
pub struct MultiOutcome {
    /// The report.
    pub report: MultiReport,
    /// The maps joined to map 0 fused in map 0's frame and resolution; None when no other map joins map 0
    /// (nothing was merged) or there are no maps.
    pub merged: Option<OccupancyGrid>,
}

/// Union-find over map indices, with path halving; the smaller index becomes the root.
struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind((0..n).collect())
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    /// Joins the sets of `i` and `j`; false when they were one already.
    fn union(&mut self, i: usize, j: usize) -> bool {
        let (ri, rj) = (self.find(i), self.find(j));
        if ri == rj {
            return false;
        }
        let (lo, hi) = (ri.min(rj), ri.max(rj));
        self.0[hi] = lo;
        true
    }
}

/// An accepted pair as a weighted edge of the graph of maps.
#[derive(Debug, Clone, Copy)]
struct Edge {
    /// Index of the pair in [`MultiReport::pairs`].
    pair: usize,
    /// The pair's first map.
    a: usize,
    /// The pair's second map.
    b: usize,
    /// The pair's confidence (the edge's weight).
    confidence: f64,
    /// `T_a_b`: points of b's frame into a's.
    t_a_b: Pose2,
}

/// Kruskal's maximum spanning forest: the most confident edges first, ties by pair index.
fn spanning_forest(n: usize, edges: &[Edge]) -> Vec<Edge> {
    let mut order: Vec<&Edge> = edges.iter().filter(|e| e.a < n && e.b < n).collect();
    order.sort_by(|x, y| y.confidence.total_cmp(&x.confidence).then(x.pair.cmp(&y.pair)));
    let mut uf = UnionFind::new(n);
    order.into_iter().filter(|e| uf.union(e.a, e.b)).cloned().collect()
}

/// The forest's components (sorted, by smallest member) and its edges oriented breadth first from each
/// component's smallest map, with `T_root_i` for every map.
fn orient(n: usize, forest: &[Edge]) -> (Vec<Vec<usize>>, Vec<TreeEdge>, Vec<Pose2>) {
    let mut adjacent: Vec<Vec<&Edge>> = vec![Vec::new(); n];
    for e in forest {
        adjacent[e.a].push(e);
        adjacent[e.b].push(e);
    }
    let mut seen = vec![false; n];
    let mut to_root = vec![Pose2::identity(); n];
    let (mut components, mut tree) = (Vec::new(), Vec::new());
    for root in 0..n {
        if seen[root] {
            continue;
        }
        seen[root] = true;
        let mut queue = vec![root];
        let mut k = 0;
        while k < queue.len() {
            let parent = queue[k];
            k += 1;
            for &&Edge { pair, a, b, confidence, t_a_b } in &adjacent[parent] {
                let (child, t_parent_child) = if a == parent { (b, t_a_b) } else { (a, t_a_b.inverse()) };
                if seen[child] {
                    continue;
                }
                seen[child] = true;
                to_root[child] = to_root[parent] * t_parent_child;
                tree.push(TreeEdge { parent, child, pair, confidence, transform: Xyt::from_pose(&t_parent_child) });
                queue.push(child);
            }
        }
        queue.sort_unstable();
        components.push(queue);
    }
    (components, tree, to_root)
}

/// The accepted pairs outside the forest whose transform the forest's chain between their maps contradicts
/// (`to_root`: each map's `T_root_i` within its component).
fn disagreements(edges: &[Edge], forest: &[Edge], components: &[Vec<usize>], to_root: &[Pose2]) -> Vec<Disagreement> {
    let component = |i: usize| components.iter().position(|c| c.contains(&i));
    edges
        .iter()
        .filter(|e| !forest.iter().any(|f| f.pair == e.pair))
        .filter(|e| component(e.a).is_some() && component(e.a) == component(e.b))
        .filter_map(|&Edge { pair, a, b, t_a_b, .. }| {
            let chain = to_root[a].inverse() * to_root[b];
            let d = chain.inverse() * t_a_b;
            let (translation_m, rotation_deg) = (d.translation.vector.norm(), d.rotation.angle().abs().to_degrees());
            (translation_m > DISAGREE_M || rotation_deg > DISAGREE_DEG).then_some(Disagreement {
                pair,
                translation_m,
                rotation_deg,
            })
        })
        .collect()
}

/// The N-map outcome of the pairs' reports (every pair a < b of `maps`, in order (0,1), (0,2), ..., (1,2), ...): a
/// maximum spanning tree of the accepted pairs by confidence rooted at map 0, each map's transform into map 0's
/// frame along the tree, and the maps joined to map 0 fused one by one (tree order) onto map 0 with `fusion`. Its
/// `time_ms` counts from `start`.
pub(crate) fn assemble(
    maps: &[&OccupancyGrid],
    pairs: Vec<PairReport>,
    algorithm: &str,
    fusion: FusionRule,
    start: Instant,
) -> MultiOutcome {
    let n = maps.len();
    let edges: Vec<Edge> = pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| p.report.accepted)
        .filter_map(|(pair, p)| {
            let t_a_b = p.report.transform?.to_pose();
            Some(Edge { pair, a: p.a, b: p.b, confidence: p.report.confidence, t_a_b })
        })
        .collect();
    let forest = spanning_forest(n, &edges);
    let (components, tree, to_root) = orient(n, &forest);
    let joined: &[usize] = components.first().map_or(&[], |c| c.as_slice());
    let transforms: Vec<Option<Xyt>> =
        (0..n).map(|i| joined.contains(&i).then(|| Xyt::from_pose(&to_root[i]))).collect();
    let not_connected: Vec<usize> = (0..n).filter(|i| !joined.contains(i)).collect();
    let disagreements = disagreements(&edges, &forest, &components, &to_root);
    // Fused in tree order (breadth first from map 0): each map lands next to maps already in.
    let merged = (joined.len() > 1).then(|| {
        tree.iter()
            .filter(|e| joined.contains(&e.child))
            .fold(maps[0].clone(), |acc, e| fuse(&acc, maps[e.child], &to_root[e.child], fusion))
    });
    let report = MultiReport {
        algorithm: algorithm.to_string(),
        maps: n,
        pairs,
        tree,
        transforms,
        components,
        not_connected,
        disagreements,
        time_ms: ms(start),
    };
    MultiOutcome { report, merged }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    /// An edge from its parts, in [`Edge`]'s order.
    fn e(pair: usize, a: usize, b: usize, confidence: f64, t_a_b: Pose2) -> Edge {
        Edge { pair, a, b, confidence, t_a_b }
    }

    fn close(p: &Pose2, q: &Pose2) -> bool {
        let d = p.inverse() * q;
        d.translation.vector.norm() < 1e-9 && d.rotation.angle().abs() < 1e-9
    }

    #[test]
    fn the_forest_takes_the_most_confident_edges() {
        let t = Pose2::identity();
        // A triangle 0-1-2 and a weak 2-3: the weakest triangle edge (0-2) closes a cycle and is dropped.
        let edges = vec![e(0, 0, 1, 0.9, t), e(1, 0, 2, 0.2, t), e(3, 1, 2, 0.5, t), e(5, 2, 3, 0.1, t)];
        let kept: Vec<usize> = spanning_forest(4, &edges).iter().map(|e| e.pair).collect();
        assert_eq!(kept, vec![0, 3, 5]);
        // Equal confidence: the lower pair index wins.
        let tie = vec![e(4, 1, 2, 0.5, t), e(0, 0, 1, 0.5, t), e(2, 0, 2, 0.5, t)];
        let kept: Vec<usize> = spanning_forest(3, &tie).iter().map(|e| e.pair).collect();
        assert_eq!(kept, vec![0, 2]);
    }

    #[test]
    fn an_accepted_pair_the_tree_contradicts_is_reported() {
        let (t01, t12) = (pose(1.0, 2.0, 0.3), pose(-0.5, 1.5, -1.1));
        let t02 = t01 * t12;
        // A triangle whose weakest edge (0-2) agrees with the chain 0-1-2, then one that is a half turn off.
        for (t, off) in [(t02, false), (t02 * pose(0.3, -0.2, std::f64::consts::PI), true)] {
            let edges = vec![e(0, 0, 1, 0.9, t01), e(1, 0, 2, 0.2, t), e(2, 1, 2, 0.8, t12)];
            let forest = spanning_forest(3, &edges);
            let (components, _, to_root) = orient(3, &forest);
            let d = disagreements(&edges, &forest, &components, &to_root);
            if off {
                assert_eq!(d.len(), 1, "{d:?}");
                assert_eq!(d[0].pair, 1);
                assert!((d[0].rotation_deg - 180.0).abs() < 1e-6, "{d:?}");
            } else {
                assert!(d.is_empty(), "{d:?}");
            }
        }
        // Pairs in different components are not compared (no chain joins them).
        let edges = vec![e(0, 0, 1, 0.9, t01), e(1, 2, 3, 0.5, t12)];
        let forest = spanning_forest(4, &edges);
        let (components, _, to_root) = orient(4, &forest);
        assert!(disagreements(&edges, &forest, &components, &to_root).is_empty());
    }

    #[test]
    fn transforms_compose_along_the_tree_whichever_way_edges_point() {
        let t01 = pose(1.0, 2.0, 0.3);
        let t21 = pose(-0.5, 1.5, -1.1); // the pair (1, 2) gives T_1_2; store it that way
        let t12 = t21.inverse();
        let t13 = pose(3.0, -1.0, 2.0);
        let forest = vec![e(0, 0, 1, 0.9, t01), e(3, 1, 2, 0.8, t12), e(4, 1, 3, 0.7, t13)];
        let (components, tree, to_root) = orient(4, &forest);
        assert_eq!(components, vec![vec![0, 1, 2, 3]]);
        assert!(close(&to_root[1], &t01));
        assert!(close(&to_root[2], &(t01 * t12)));
        assert!(close(&to_root[3], &(t01 * t13)));
        // A chain stored against the tree's direction: the pair (0, 1) rooted at 1 still gives T_0_1.
        let (_, tree2, to_root2) = orient(3, &[e(1, 1, 2, 0.5, t12), e(0, 0, 2, 0.4, t21.inverse() * t01)]);
        assert_eq!((tree2[0].parent, tree2[0].child), (0, 2));
        assert!(close(&to_root2[2], &(t21.inverse() * t01)));
        assert!(close(&to_root2[1], &(t21.inverse() * t01 * t12.inverse())));
        assert_eq!(tree.iter().map(|e| (e.parent, e.child)).collect::<Vec<_>>(), vec![(0, 1), (1, 2), (1, 3)]);
    }
}
