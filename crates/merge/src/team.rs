//! A team's maps as a graph: maps added and updated as their robots map, each pair's merge cached at the two maps'
//! versions, the spanning tree of verified transforms recomputed from the cached pairs. Only the pairs of a map
//! that changed are merged again; [`merge_many`] is the graph used once.

use crate::merge_params::MergeParams;
use crate::merger::{Merger, merge};
use crate::multi::{MultiOutcome, PairReport, assemble};
use crate::report::MergeReport;
use crate::timing::ms;
use mrslam_core::OccupancyGrid;
use rayon::prelude::*;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Instant;

/// A map's place in a [`MapGraph`]: the order it was added in (map 0 is the frame the others are placed in).
pub type MapId = usize;

/// A map id the graph does not hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("no map {0} in the graph")]
pub struct UnknownMap(pub MapId);

/// One pair's merge and the versions of its maps it was computed at.
#[derive(Debug, Clone)]
struct CachedPair {
    versions: (u64, u64),
    report: MergeReport,
}

/// Maps of a team with their versions and every pair's merge, kept up to date incrementally.
///
/// A version names a map's content: a pair is merged again when either map's version differs from the one it was
/// merged at. The cache assumes one merger and one set of [`MergeParams`] for the graph's life.
#[derive(Debug, Clone, Default)]
pub struct MapGraph<'m> {
    maps: Vec<(Cow<'m, OccupancyGrid>, u64)>,
    pairs: BTreeMap<(MapId, MapId), CachedPair>,
}

impl<'m> MapGraph<'m> {
    /// A graph without maps.
    pub fn new() -> Self {
        MapGraph { maps: Vec::new(), pairs: BTreeMap::new() }
    }

    /// Adds a map (owned, or borrowed for the graph's life) at `version`; its id.
    pub fn add(&mut self, map: Cow<'m, OccupancyGrid>, version: u64) -> MapId {
        self.maps.push((map, version));
        self.maps.len() - 1
    }

    /// Replaces map `id` by its `version`; its pairs are merged again at the next [`MapGraph::merge`] unless the
    /// version is the one they were merged at.
    pub fn update(&mut self, id: MapId, map: Cow<'m, OccupancyGrid>, version: u64) -> Result<(), UnknownMap> {
        let slot = self.maps.get_mut(id).ok_or(UnknownMap(id))?;
        *slot = (map, version);
        Ok(())
    }

    /// Number of maps.
    pub fn len(&self) -> usize {
        self.maps.len()
    }

    /// Whether it holds no map.
    pub fn is_empty(&self) -> bool {
        self.maps.is_empty()
    }

    /// Map `id`'s version.
    pub fn version(&self, id: MapId) -> Option<u64> {
        self.maps.get(id).map(|(_, v)| *v)
    }

    /// The pairs (a < b, in order) whose merge is missing or was computed at other versions of their maps.
    pub fn stale_pairs(&self) -> Vec<(MapId, MapId)> {
        let n = self.maps.len();
        (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .filter(|&(a, b)| self.pairs.get(&(a, b)).is_none_or(|c| c.versions != (self.maps[a].1, self.maps[b].1)))
            .collect()
    }

    /// Merges the stale pairs (in parallel) and caches their reports; the number merged.
    pub fn refresh(&mut self, merger: &dyn Merger, params: &MergeParams) -> usize {
        let stale = self.stale_pairs();
        let maps = &self.maps;
        let merged: Vec<((MapId, MapId), CachedPair)> = stale
            .par_iter()
            .map(|&(a, b)| {
                let report = merge(merger, &maps[a].0, &maps[b].0, params).report;
                ((a, b), CachedPair { versions: (maps[a].1, maps[b].1), report })
            })
            .collect();
        self.pairs.extend(merged);
        stale.len()
    }

    /// Brings the pairs up to date ([`MapGraph::refresh`]), then the spanning tree of the accepted pairs by
    /// confidence rooted at map 0, each map's transform into map 0's frame, and the maps joined to map 0 fused in
    /// its frame with `params.fusion`.
    pub fn merge(&mut self, merger: &dyn Merger, params: &MergeParams) -> MultiOutcome {
        let start = Instant::now();
        self.refresh(merger, params);
        let n = self.maps.len();
        let pairs: Vec<PairReport> = (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .map(|(a, b)| PairReport { a, b, report: self.pairs[&(a, b)].report.clone() })
            .collect();
        let maps: Vec<&OccupancyGrid> = self.maps.iter().map(|(m, _)| m.as_ref()).collect();
        assemble(&maps, pairs, merger.name(), params.fusion, start)
    }
}

/// Merges N maps at once: a [`MapGraph`] of them, every pair through [`merge`] (in parallel, reported in pair
/// order), a maximum spanning tree of the accepted pairs by confidence rooted at map 0, each map's transform into
/// map 0's frame along the tree, and the maps joined to map 0 fused one by one (tree order) onto map 0 with
/// `params.fusion`.
///
/// Maps of different resolution are handled as [`merge`] handles them; the fused grid has map 0's.
pub fn merge_many(merger: &dyn Merger, maps: &[OccupancyGrid], params: &MergeParams) -> MultiOutcome {
    let start = Instant::now();
    let mut graph = MapGraph::new();
    for m in maps {
        graph.add(Cow::Borrowed(m), 0);
    }
    let mut out = graph.merge(merger, params);
    out.report.time_ms = ms(start);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::alignment::{Alignment, Evidence, NoAlignment};
    use mrslam_core::{Pose2, Xyt, pose};
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn close(p: &Pose2, q: &Pose2) -> bool {
        let d = p.inverse() * q;
        d.translation.vector.norm() < 1e-9 && d.rotation.angle().abs() < 1e-9
    }

    /// Answers with known transforms between "maps" told apart by their width: width 10 + k is map k, placed
    /// at `poses[k]` in a common world; pairs listed in `refuse` get no transform.
    struct Known {
        poses: Vec<Pose2>,
        refuse: Vec<(usize, usize)>,
    }

    impl Merger for Known {
        fn name(&self) -> &'static str {
            "known"
        }
        fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
            let (i, j) = (a.width() - 10, b.width() - 10);
            if self.refuse.contains(&(i, j)) || self.refuse.contains(&(j, i)) {
                return Err(Box::new(NoAlignment {
                    reason: "nothing in common".into(),
                    matches: 0,
                    timings_ms: BTreeMap::new(),
                    evidence: Evidence::default(),
                }));
            }
            Ok(Alignment {
                transform: self.poses[i].inverse() * self.poses[j],
                scale: 1.0,
                matches: 40,
                matched_features: 40,
                inliers: 30 + i + j,
                timings_ms: BTreeMap::new(),
                evidence: Evidence::default(),
                alternatives: Vec::new(),
                alternatives_are_rivals: false,
            })
        }
    }

    #[test]
    fn a_map_joined_to_nothing_is_reported_and_the_rest_placed() {
        let poses = vec![pose(0.0, 0.0, 0.0), pose(2.0, 1.0, 0.5), pose(-1.0, 3.0, -2.0), pose(0.0, 0.0, 0.0)];
        let refuse = vec![(0, 3), (1, 3), (2, 3)];
        let maps: Vec<OccupancyGrid> =
            (0..4).map(|k| OccupancyGrid::new(10 + k, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap()).collect();
        let mut p = MergeParams { verify_enabled: false, ..MergeParams::default() };
        p.refine.enabled = false;
        let out = merge_many(&Known { poses: poses.clone(), refuse }, &maps, &p);
        let r = &out.report;
        assert_eq!(r.pairs.len(), 6);
        assert_eq!(r.pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>()[..3], [(0, 1), (0, 2), (0, 3)]);
        assert!(!r.pairs[2].report.accepted && r.pairs[2].report.reason.as_deref() == Some("nothing in common"));
        assert_eq!(r.components, vec![vec![0, 1, 2], vec![3]]);
        assert_eq!(r.not_connected, vec![3]);
        assert!(!r.all_connected());
        assert_eq!(r.tree.len(), 2);
        for (i, (t, truth)) in r.transforms.iter().zip(&poses).take(3).enumerate() {
            assert!(close(&t.unwrap().to_pose(), truth), "map {i}: {t:?}");
        }
        assert!(r.transforms[3].is_none());
        assert!(out.merged.is_some());
        // Two maps that join each other but not map 0 form their own component.
        let out = merge_many(&Known { poses, refuse: vec![(0, 2), (0, 3), (1, 2), (1, 3)] }, &maps, &p);
        assert_eq!(out.report.components, vec![vec![0, 1], vec![2, 3]]);
        assert_eq!(out.report.not_connected, vec![2, 3]);
        assert_eq!(out.report.tree.iter().map(|e| (e.parent, e.child)).collect::<Vec<_>>(), vec![(0, 1), (2, 3)]);
    }

    #[test]
    fn no_maps_and_one_map_give_nothing_merged() {
        let known = Known { poses: vec![Pose2::identity()], refuse: Vec::new() };
        let out = merge_many(&known, &[], &MergeParams::default());
        assert!(out.merged.is_none() && out.report.components.is_empty() && out.report.pairs.is_empty());
        let one = [OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap()];
        let out = merge_many(&known, &one, &MergeParams::default());
        assert!(out.merged.is_none() && out.report.all_connected());
        assert_eq!(out.report.transforms, vec![Some(Xyt::from_pose(&Pose2::identity()))]);
    }

    /// [`Known`], counting its calls.
    struct Counting(Known, AtomicUsize);

    impl Merger for Counting {
        fn name(&self) -> &'static str {
            "counting"
        }
        fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
            self.1.fetch_add(1, Ordering::SeqCst);
            self.0.align(a, b)
        }
    }

    /// Map k of [`Known`]'s world.
    fn map(k: usize) -> OccupancyGrid {
        OccupancyGrid::new(10 + k, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap()
    }

    /// The pipeline without the gate and the refinement (the maps are blank).
    fn unchecked() -> MergeParams {
        let mut p = MergeParams { verify_enabled: false, ..MergeParams::default() };
        p.refine.enabled = false;
        p
    }

    /// The parts of an N-map report that do not depend on wall time.
    fn timeless(mut out: MultiOutcome) -> (crate::MultiReport, Option<OccupancyGrid>) {
        out.report.time_ms = 0.0;
        for p in &mut out.report.pairs {
            p.report.time_ms = 0.0;
            p.report.timings_ms.clear();
        }
        (out.report, out.merged)
    }

    #[test]
    fn a_new_map_merges_only_its_pairs_and_an_update_only_the_updated_maps() {
        let poses = vec![pose(0.0, 0.0, 0.0), pose(2.0, 1.0, 0.5), pose(-1.0, 3.0, -2.0)];
        let counting = Counting(Known { poses, refuse: Vec::new() }, AtomicUsize::new(0));
        let calls = || counting.1.swap(0, Ordering::SeqCst);
        let p = unchecked();
        let mut g = MapGraph::new();
        g.add(Cow::Owned(map(0)), 0);
        g.add(Cow::Owned(map(1)), 0);
        g.merge(&counting, &p);
        assert_eq!(calls(), 1);
        g.add(Cow::Owned(map(2)), 0);
        assert_eq!(g.stale_pairs(), [(0, 2), (1, 2)]);
        let out = g.merge(&counting, &p);
        assert_eq!(calls(), 2, "only the new map's pairs");
        assert!(out.report.all_connected());
        // Nothing changed: nothing merged.
        g.merge(&counting, &p);
        assert_eq!(calls(), 0);
        // Map 1 mapped further: its two pairs again; the same version again: nothing.
        g.update(1, Cow::Owned(map(1)), 1).unwrap();
        assert_eq!(g.stale_pairs(), [(0, 1), (1, 2)]);
        g.merge(&counting, &p);
        assert_eq!(calls(), 2);
        g.update(1, Cow::Owned(map(1)), 1).unwrap();
        assert_eq!(g.refresh(&counting, &p), 0);
        assert_eq!(g.update(7, Cow::Owned(map(1)), 1), Err(UnknownMap(7)));
    }

    #[test]
    fn the_graph_built_step_by_step_gives_the_tree_merge_many_gives() {
        let poses = vec![pose(0.0, 0.0, 0.0), pose(2.0, 1.0, 0.5), pose(-1.0, 3.0, -2.0), pose(1.0, -1.0, 1.0)];
        let known = Known { poses, refuse: vec![(0, 3), (1, 2)] };
        let p = unchecked();
        let maps: Vec<OccupancyGrid> = (0..4).map(map).collect();
        let mut g = MapGraph::new();
        for (k, m) in maps.iter().enumerate() {
            g.add(Cow::Borrowed(m), 0);
            g.merge(&known, &p);
            if k == 2 {
                g.update(1, Cow::Borrowed(&maps[1]), 5).unwrap();
            }
        }
        let (step, merged_step) = timeless(g.merge(&known, &p));
        let (once, merged_once) = timeless(merge_many(&known, &maps, &p));
        assert_eq!(step, once);
        assert_eq!(merged_step.map(|m| m.cells().to_vec()), merged_once.map(|m| m.cells().to_vec()));
        assert_eq!(step.tree.len(), 3);
    }
}
