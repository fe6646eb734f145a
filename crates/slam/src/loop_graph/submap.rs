//! A submap: a run of consecutive graph nodes whose scans, drawn in the frame of its first node (the anchor),
//! a new scan is searched against when the robot comes back.
//!
//! Only the node range is stored; the grids a search needs (the field matcher's tile map and the branch and
//! bound's score pyramid) are built when the submap is searched and kept in a small cache, so that memory
//! does not grow with the submaps of a two-hour log.

use crate::scan_matcher::{PreparedScan, ScanMatcher};
use crate::tile_map::TileMap;
use mrslam_core::Xyt;
use mrslam_core::pose::relative;
use mrslam_matching::{BlockStates, Pyramid, ScoreField};
use std::sync::Arc;

/// A run of consecutive nodes, `first..=last`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Submap {
    /// Its first node: the frame its grids are drawn in.
    pub first: usize,
    /// Its last node.
    pub last: usize,
}

/// What a search needs of a submap: its scans' hits in the anchor's frame as the field matcher's map, and a
/// score pyramid of them on a coarser grid for branch and bound.
#[derive(Debug)]
pub struct SubmapGrids {
    /// The hits as a tile map (anchor frame, the filter's cell size).
    pub tiles: TileMap,
    /// Max-pooled score fields of the coarse grid.
    pub pyramid: Pyramid,
    /// The coarse grid's cell (0, 0) corner, anchor frame, metres.
    pub origin: (f64, f64),
    /// The coarse grid's cell size, metres.
    pub cell: f64,
}

/// Cells of the filter's grid per coarse cell of the branch and bound.
pub const COARSE: usize = 2;
/// Standard deviation of the coarse score field's blur, coarse cells.
const BLUR_CELLS: f64 = 1.0;

impl SubmapGrids {
    /// Draws the hits of `scans` (each with its robot pose in the anchor's frame) and builds the pyramid to
    /// `depth` levels. `None` when nothing was hit or a grid would be too large.
    pub fn build(scans: &[(Xyt, &PreparedScan)], matcher: &ScanMatcher, delta: f64, depth: usize) -> Option<Self> {
        let mut tiles = TileMap::new(delta);
        for (pose, scan) in scans {
            let lp = matcher.laser_pose(pose);
            let (s, c) = lp.theta.sin_cos();
            for b in &scan.hits {
                let (dx, dy) = (c * b.c - s * b.s, s * b.c + c * b.s);
                tiles.add_beam_hit(lp.x + b.r * dx, lp.y + b.r * dy, dx, dy).ok()?;
            }
        }
        let grid = tiles.to_grid()?;
        let blocks = BlockStates::of(&grid, COARSE);
        let field = ScoreField::build(&blocks, BLUR_CELLS, 0);
        let pyramid = Pyramid::build(&field, depth);
        let o = grid.origin().translation.vector;
        Some(SubmapGrids { tiles, pyramid, origin: (o.x, o.y), cell: delta * COARSE as f64 })
    }
}

impl SubmapGrids {
    /// Heap bytes of the grids.
    pub fn bytes(&self) -> usize {
        let tiles: usize = self.tiles.tiles().map(|t| t.bytes()).sum();
        tiles + self.pyramid.levels.iter().map(|l| l.bytes()).sum::<usize>()
    }
}

/// The last few submaps' grids, by submap index and the graph's version when they were built (an optimisation
/// moves the nodes within a submap, so a grid built before it is rebuilt).
#[derive(Debug, Clone, Default)]
pub struct GridCache {
    entries: Vec<(usize, u64, Arc<SubmapGrids>)>,
}

/// Grids kept at most.
const CACHE_SIZE: usize = 12;

impl GridCache {
    /// The grids of submap `index` at graph version `version`, if cached.
    pub fn get(&mut self, index: usize, version: u64) -> Option<Arc<SubmapGrids>> {
        let at = self.entries.iter().position(|e| e.0 == index && e.1 == version)?;
        let e = self.entries.remove(at);
        let grids = e.2.clone();
        self.entries.push(e);
        Some(grids)
    }

    /// Heap bytes of the cached grids.
    pub fn bytes(&self) -> usize {
        self.entries.iter().map(|e| e.2.bytes()).sum()
    }

    /// Keeps `grids`, dropping the least recently used beyond the cache's size.
    pub fn put(&mut self, index: usize, version: u64, grids: Arc<SubmapGrids>) {
        self.entries.retain(|e| e.0 != index);
        self.entries.push((index, version, grids));
        if self.entries.len() > CACHE_SIZE {
            self.entries.remove(0);
        }
    }
}

/// Robot poses of `nodes` (map frame) in the frame of `anchor`.
pub fn in_anchor_frame(anchor: &Xyt, nodes: &[Xyt]) -> Vec<Xyt> {
    let a = anchor.to_pose();
    nodes.iter().map(|p| Xyt::from_pose(&relative(&a, &p.to_pose()))).collect()
}
