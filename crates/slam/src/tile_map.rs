//! A particle's grid map: 32×32-cell tiles shared copy-on-write between particles.
//!
//! GMapping's `HierarchicalArray2D` of `PointAccumulator` patches, in Rust: the map is a growable 2D array of
//! `Option<Arc<Tile>>`; cloning a map clones the array of pointers, not the cells; a write goes through
//! [`Arc::make_mut`], which copies a tile only when another particle still shares it. So N particles cost one
//! map plus the tiles each touched since their lineages split.
//!
//! Cell statistics (GMapping's `PointAccumulator`, as ROS `slam_gmapping` runs it with `generateMap` off):
//! per cell the number of beam end points that fell in it (`hits`) and their mean position. The matcher's
//! score needs exactly these: a cell is "occupied" when it has hits, "free" when it has none, and the
//! distance is measured to the mean of the hits, which is sub-cell accurate. Misses (free space) are not
//! traced per particle, which keeps an update cheap; the output map ([`crate::map_build`]) traces them
//! along the best particle's trajectory. Only the cells with hits hold statistics ([`Tile`]): a building's map
//! is mostly free and unknown cells.
//!
//! Cell `(ix, iy)` covers `[ix·delta, (ix+1)·delta) × [iy·delta, (iy+1)·delta)` of the map frame; indices may be
//! negative.

use std::sync::Arc;

/// Log2 of the tile edge.
pub const TILE_SHIFT: i32 = 5;
/// Tile edge in cells (32).
pub const TILE: i32 = 1 << TILE_SHIFT;
const TILE_MASK: i32 = TILE - 1;
/// Tiles added on each side when the tile array grows.
const GROW_MARGIN: i32 = 4;
/// Largest tile array accepted (tiles): 1024 × 1024 tiles, i.e. 1.6 km × 1.6 km at 5 cm.
const MAX_TILE_SLOTS: usize = 1 << 20;
/// Cell coordinates are clamped to ±this, far beyond any real map, so index arithmetic cannot overflow.
const COORD_LIMIT: f64 = (1u32 << 28) as f64;

/// What one cell with hits holds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellHits {
    /// Mean end point, relative to the cell's lower corner, metres.
    pub mean: [f32; 2],
    /// End points that fell in the cell (saturating).
    pub hits: u16,
    /// Sum of the unit directions of the beams that ended in the cell, ×[`DIR_SCALE`] (saturating): which side
    /// the surface was seen from. Zero when unknown (hits recorded without a direction).
    pub dir: [i16; 2],
}

/// One 32×32 patch of cells: bitmaps of the seen and the hit cells, and the statistics of the hit cells only.
///
/// Most cells of a building's map have no hits (free space and unknown space), so a tile stores the hit cells'
/// statistics in a list, in row-major order, found by counting the bits before them in `occupied`: a tile that
/// is only crossed by beams costs 0.3 KB instead of the 14.6 KB of dense per-cell arrays.
#[derive(Clone)]
pub struct Tile {
    /// Per row (`ly`), bit `lx`: whether a beam's end band (see [`TileMap::mark_seen`]) crossed the cell
    /// (known space).
    pub seen: [u32; TILE as usize],
    /// Per row (`ly`), bit `lx`: whether the cell has hits (lets a scan skip empty cells by the word).
    pub occupied: [u32; TILE as usize],
    /// Per row: the index in `cells` of the row's first hit cell.
    row_start: [u16; TILE as usize],
    /// The hit cells' statistics, row-major.
    cells: Vec<CellHits>,
}

/// Scale of [`CellHits::dir`]'s sums of unit vectors.
pub const DIR_SCALE: f64 = 64.0;

impl Tile {
    fn empty() -> Arc<Tile> {
        Arc::new(Tile {
            seen: [0; TILE as usize],
            occupied: [0; TILE as usize],
            row_start: [0; TILE as usize],
            cells: Vec::new(),
        })
    }

    /// Heap bytes of this tile (its `Arc` allocation and its list of hit cells).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Tile>()
            + 2 * std::mem::size_of::<usize>()
            + self.cells.capacity() * std::mem::size_of::<CellHits>()
    }

    /// Where local cell (lx, ly) is or would be in the list of hit cells.
    #[inline]
    fn slot(&self, lx: usize, ly: usize) -> usize {
        self.row_start[ly] as usize + (self.occupied[ly] & ((1u32 << lx) - 1)).count_ones() as usize
    }

    /// The statistics of local cell `l` (index as [`local`] gives it), if it has hits.
    #[inline]
    pub fn cell(&self, l: usize) -> Option<&CellHits> {
        let (lx, ly) = (l & TILE_MASK as usize, l >> TILE_SHIFT);
        if self.occupied[ly] >> lx & 1 == 0 {
            return None;
        }
        Some(&self.cells[self.slot(lx, ly)])
    }

    /// Hits of local cell `l` (0 when none).
    #[inline]
    pub fn hits(&self, l: usize) -> u16 {
        self.cell(l).map_or(0, |c| c.hits)
    }

    /// Whether local cell `l` has hits.
    #[inline]
    pub fn is_hit(&self, l: usize) -> bool {
        self.occupied[l >> TILE_SHIFT] >> (l & TILE_MASK as usize) & 1 != 0
    }

    /// The statistics of local cell (lx, ly), added (empty) when it had no hits.
    fn cell_mut(&mut self, lx: usize, ly: usize) -> &mut CellHits {
        let at = self.slot(lx, ly);
        if self.occupied[ly] >> lx & 1 == 0 {
            self.occupied[ly] |= 1 << lx;
            self.cells.insert(at, CellHits::default());
            for start in &mut self.row_start[ly + 1..] {
                *start += 1;
            }
        }
        &mut self.cells[at]
    }
}

/// A grid of hit statistics made of copy-on-write tiles.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Clone)]
pub struct TileMap {
    delta: f64,
    inv_delta: f64,
    /// Tile coordinates of the array's first slot.
    tx0: i32,
    ty0: i32,
    /// Array size in tiles.
    tw: i32,
    th: i32,
    tiles: Vec<Option<Arc<Tile>>>,
}

impl std::fmt::Debug for TileMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TileMap")
            .field("delta", &self.delta)
            .field("tiles", &(self.tx0, self.ty0, self.tw, self.th))
            .field("allocated", &self.allocated_tiles())
            .finish()
    }
}

/// Error when a hit would grow the tile array past its limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TooLarge;

impl TileMap {
    /// An empty map of `delta` metres per cell.
    pub fn new(delta: f64) -> Self {
        TileMap { delta, inv_delta: 1.0 / delta, tx0: 0, ty0: 0, tw: 0, th: 0, tiles: Vec::new() }
    }

    /// Metres per cell.
    #[inline]
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// The cell a map-frame point falls in.
    #[inline]
    pub fn cell_of(&self, x: f64, y: f64) -> (i32, i32) {
        let cx = (x * self.inv_delta).floor().clamp(-COORD_LIMIT, COORD_LIMIT);
        let cy = (y * self.inv_delta).floor().clamp(-COORD_LIMIT, COORD_LIMIT);
        (cx as i32, cy as i32)
    }

    /// The tile holding tile coordinates (tx, ty), if allocated.
    #[inline]
    pub fn tile(&self, tx: i32, ty: i32) -> Option<&Tile> {
        let (x, y) = (tx.wrapping_sub(self.tx0), ty.wrapping_sub(self.ty0));
        if x < 0 || y < 0 || x >= self.tw || y >= self.th {
            return None;
        }
        self.tiles[(y * self.tw + x) as usize].as_deref()
    }

    /// Hits recorded in cell (ix, iy) (0 off the map).
    #[inline]
    pub fn hits(&self, ix: i32, iy: i32) -> u16 {
        match self.tile(ix >> TILE_SHIFT, iy >> TILE_SHIFT) {
            Some(t) => t.hits(local(ix, iy)),
            None => 0,
        }
    }

    /// Mean end point of cell (ix, iy) in the map frame (the cell's corner when it has no hits).
    #[inline]
    pub fn mean(&self, ix: i32, iy: i32) -> (f64, f64) {
        let m = match self.tile(ix >> TILE_SHIFT, iy >> TILE_SHIFT).and_then(|t| t.cell(local(ix, iy))) {
            Some(c) => c.mean,
            None => [0.0, 0.0],
        };
        (ix as f64 * self.delta + m[0] as f64, iy as f64 * self.delta + m[1] as f64)
    }

    /// Whether cell (ix, iy) was marked seen (false off the map).
    #[inline]
    pub fn seen(&self, ix: i32, iy: i32) -> bool {
        match self.tile(ix >> TILE_SHIFT, iy >> TILE_SHIFT) {
            Some(t) => t.seen[(iy & TILE_MASK) as usize] >> (ix & TILE_MASK) & 1 != 0,
            None => false,
        }
    }

    /// Marks the cells of the segment from (x0, y0) to (x1, y1) (map frame, metres) as seen.
    pub fn mark_seen(&mut self, x0: f64, y0: f64, x1: f64, y1: f64) -> Result<(), TooLarge> {
        let clamp = |v: f64| (v * self.inv_delta).clamp(-COORD_LIMIT, COORD_LIMIT);
        let trav = mrslam_core::CellTraversal::new(clamp(x0), clamp(y0), clamp(x1), clamp(y1));
        let mut cached: Option<(i32, i32, usize)> = None;
        for (cx, cy) in trav {
            let (ix, iy) = (cx as i32, cy as i32);
            let (tx, ty) = (ix >> TILE_SHIFT, iy >> TILE_SHIFT);
            let slot = match cached {
                Some((ctx, cty, slot)) if ctx == tx && cty == ty => slot,
                _ => {
                    self.ensure(tx, ty)?;
                    let slot = ((ty - self.ty0) * self.tw + (tx - self.tx0)) as usize;
                    cached = Some((tx, ty, slot));
                    slot
                }
            };
            let (row, bit) = ((iy & TILE_MASK) as usize, 1u32 << (ix & TILE_MASK));
            let t = self.tiles[slot].get_or_insert_with(Tile::empty);
            if t.seen[row] & bit == 0 {
                Arc::make_mut(t).seen[row] |= bit;
            }
        }
        Ok(())
    }

    /// Records a beam end point at map-frame (x, y): one more hit for its cell, running mean updated.
    pub fn add_hit(&mut self, x: f64, y: f64) -> Result<(), TooLarge> {
        self.add_beam_hit(x, y, 0.0, 0.0)
    }

    /// Records the end point (x, y) of a beam travelling along unit direction (dx, dy) (map frame): as
    /// [`TileMap::add_hit`], and the direction is added to the cell's `Tile::dir`.
    pub fn add_beam_hit(&mut self, x: f64, y: f64, dx: f64, dy: f64) -> Result<(), TooLarge> {
        let (ix, iy) = self.cell_of(x, y);
        let (tx, ty) = (ix >> TILE_SHIFT, iy >> TILE_SHIFT);
        self.ensure(tx, ty)?;
        let slot = ((ty - self.ty0) * self.tw + (tx - self.tx0)) as usize;
        let tile = Arc::make_mut(self.tiles[slot].get_or_insert_with(Tile::empty));
        let cell = tile.cell_mut((ix & TILE_MASK) as usize, (iy & TILE_MASK) as usize);
        let n = cell.hits.saturating_add(1);
        cell.hits = n;
        let (ox, oy) = (x - ix as f64 * self.delta, y - iy as f64 * self.delta);
        let m = &mut cell.mean;
        let inv = 1.0 / n as f64;
        m[0] += ((ox - m[0] as f64) * inv) as f32;
        m[1] += ((oy - m[1] as f64) * inv) as f32;
        let d = &mut cell.dir;
        d[0] = d[0].saturating_add((dx * DIR_SCALE).round() as i16);
        d[1] = d[1].saturating_add((dy * DIR_SCALE).round() as i16);
        Ok(())
    }

    /// Grows the tile array (by a margin) so that tile (tx, ty) has a slot.
    fn ensure(&mut self, tx: i32, ty: i32) -> Result<(), TooLarge> {
        let inside = tx >= self.tx0 && ty >= self.ty0 && tx < self.tx0 + self.tw && ty < self.ty0 + self.th;
        if inside {
            return Ok(());
        }
        let (nx0, ny0, nx1, ny1) = if self.tw == 0 {
            (tx - GROW_MARGIN, ty - GROW_MARGIN, tx + GROW_MARGIN + 1, ty + GROW_MARGIN + 1)
        } else {
            (
                if tx < self.tx0 { tx - GROW_MARGIN } else { self.tx0 },
                if ty < self.ty0 { ty - GROW_MARGIN } else { self.ty0 },
                if tx >= self.tx0 + self.tw { tx + GROW_MARGIN + 1 } else { self.tx0 + self.tw },
                if ty >= self.ty0 + self.th { ty + GROW_MARGIN + 1 } else { self.ty0 + self.th },
            )
        };
        let (nw, nh) = ((nx1 - nx0) as usize, (ny1 - ny0) as usize);
        if nw.checked_mul(nh).is_none_or(|n| n > MAX_TILE_SLOTS) {
            return Err(TooLarge);
        }
        let mut tiles = vec![None; nw * nh];
        for y in 0..self.th {
            for x in 0..self.tw {
                let src = (y * self.tw + x) as usize;
                let dst = (y + self.ty0 - ny0) as usize * nw + (x + self.tx0 - nx0) as usize;
                tiles[dst] = self.tiles[src].take();
            }
        }
        self.tiles = tiles;
        self.tx0 = nx0;
        self.ty0 = ny0;
        self.tw = nw as i32;
        self.th = nh as i32;
        Ok(())
    }

    /// Cells covered by the tile array, `[x0, y0, x1, y1]` inclusive; None while the map is empty.
    pub fn cell_bounds(&self) -> Option<[i32; 4]> {
        (self.tw > 0).then(|| {
            [
                self.tx0 << TILE_SHIFT,
                self.ty0 << TILE_SHIFT,
                ((self.tx0 + self.tw) << TILE_SHIFT) - 1,
                ((self.ty0 + self.th) << TILE_SHIFT) - 1,
            ]
        })
    }

    /// The map as an occupancy grid, for watching it grow: cells with hits occupied, cells only crossed by a beam's
    /// end band free, the rest unknown (free space is not traced per particle; [`crate::Rbpf::map`] builds the
    /// output map). The grid covers the allocated tiles. `None` while the map is empty or when it exceeds core's
    /// cell limit.
    pub fn to_grid(&self) -> Option<mrslam_core::OccupancyGrid> {
        let allocated = || {
            let tw = self.tw;
            self.tiles
                .iter()
                .enumerate()
                .filter_map(move |(slot, t)| Some((slot as i32 % tw, slot as i32 / tw, t.as_deref()?)))
        };
        let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
        for (tx, ty, _) in allocated() {
            (x0, y0, x1, y1) = (x0.min(tx), y0.min(ty), x1.max(tx), y1.max(ty));
        }
        if x0 > x1 {
            return None;
        }
        let (w, h) = (((x1 - x0 + 1) * TILE) as usize, ((y1 - y0 + 1) * TILE) as usize);
        let (cx0, cy0) = ((self.tx0 + x0) * TILE, (self.ty0 + y0) * TILE);
        let origin = mrslam_core::pose(cx0 as f64 * self.delta, cy0 as f64 * self.delta, 0.0);
        let mut grid = mrslam_core::OccupancyGrid::new(w, h, self.delta, origin).ok()?;
        for (tx, ty, tile) in allocated() {
            let (tx, ty) = (tx - x0, ty - y0);
            for ly in 0..TILE {
                let (seen, occupied) = (tile.seen[ly as usize], tile.occupied[ly as usize]);
                if seen | occupied == 0 {
                    continue;
                }
                for lx in 0..TILE {
                    let l = if occupied >> lx & 1 != 0 {
                        mrslam_core::map_io::ROS_LOGODDS_LIMIT
                    } else if seen >> lx & 1 != 0 {
                        -mrslam_core::map_io::ROS_LOGODDS_LIMIT
                    } else {
                        continue;
                    };
                    grid.set((tx * TILE + lx) as usize, (ty * TILE + ly) as usize, l);
                }
            }
        }
        Some(grid)
    }

    /// Number of tile slots (allocated or not).
    pub fn tile_slots(&self) -> usize {
        self.tiles.len()
    }

    /// Number of allocated tiles (shared or not).
    pub fn allocated_tiles(&self) -> usize {
        self.tiles.iter().filter(|t| t.is_some()).count()
    }

    /// Addresses of the allocated tiles, to count tiles shared between maps.
    pub fn tile_ptrs(&self) -> impl Iterator<Item = *const Tile> + '_ {
        self.tiles.iter().flatten().map(Arc::as_ptr)
    }

    /// The allocated tiles (shared or not).
    pub fn tiles(&self) -> impl Iterator<Item = &Tile> + '_ {
        self.tiles.iter().flatten().map(|t| &**t)
    }
}

/// Index of cell (ix, iy) inside its tile.
#[inline]
pub fn local(ix: i32, iy: i32) -> usize {
    (((iy & TILE_MASK) << TILE_SHIFT) | (ix & TILE_MASK)) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_and_means_round_trip_with_negative_cells() {
        let mut m = TileMap::new(0.05);
        m.add_hit(-1.012, 2.031).unwrap();
        m.add_hit(-1.018, 2.039).unwrap();
        let (ix, iy) = m.cell_of(-1.015, 2.035);
        assert_eq!((ix, iy), (-21, 40));
        assert_eq!(m.hits(ix, iy), 2);
        let (mx, my) = m.mean(ix, iy);
        assert!((mx + 1.015).abs() < 1e-6 && (my - 2.035).abs() < 1e-6, "{mx} {my}");
        assert_eq!(m.hits(ix + 1, iy), 0);
        assert_eq!(m.hits(10_000, -10_000), 0);
        m.add_hit(50.0, -40.0).unwrap();
        assert_eq!(m.hits(ix, iy), 2, "growth keeps old cells");
        assert_eq!(m.allocated_tiles(), 2);
    }

    #[test]
    fn the_grid_puts_hits_and_seen_cells_where_the_tiles_have_them() {
        use mrslam_core::CellState;
        let mut m = TileMap::new(0.05);
        assert!(m.to_grid().is_none(), "an empty map has no grid");
        m.mark_seen(-1.0, 0.52, -0.5, 0.52).unwrap();
        m.add_hit(-1.012, 2.031).unwrap();
        let g = m.to_grid().unwrap();
        let state = |x: f64, y: f64| {
            let (ix, iy) = g.world_to_cell(&nalgebra::Point2::new(x, y)).unwrap();
            g.state(ix, iy)
        };
        assert_eq!(state(-1.012, 2.031), CellState::Occupied);
        assert_eq!(state(-0.75, 0.52), CellState::Free);
        assert_eq!(state(-0.75, 1.5), CellState::Unknown);
        let occupied = (0..g.height()).flat_map(|y| (0..g.width()).map(move |x| (x, y)));
        assert_eq!(occupied.filter(|&(x, y)| g.state(x, y) == CellState::Occupied).count(), 1);
    }

    #[test]
    fn clones_share_until_written() {
        let mut a = TileMap::new(0.05);
        a.add_hit(0.1, 0.1).unwrap();
        a.add_hit(5.0, 0.1).unwrap();
        let mut b = a.clone();
        let shared = |a: &TileMap, b: &TileMap| {
            let pa: Vec<_> = a.tile_ptrs().collect();
            b.tile_ptrs().filter(|p| pa.contains(p)).count()
        };
        assert_eq!(shared(&a, &b), 2);
        b.add_hit(0.2, 0.2).unwrap();
        assert_eq!(shared(&a, &b), 1, "the written tile was copied");
        assert_eq!(a.hits(4, 4), 0);
        assert_eq!(b.hits(4, 4), 1);
    }

    #[test]
    fn hit_cells_added_in_any_order_keep_their_own_statistics() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut m = TileMap::new(0.05);
        let mut truth = std::collections::BTreeMap::new();
        for _ in 0..5000 {
            let (ix, iy) = (rng.random_range(-40..40), rng.random_range(-40..40));
            let (fx, fy) = (rng.random_range(0.0..0.05), rng.random_range(0.0..0.05));
            m.add_hit(ix as f64 * 0.05 + fx, iy as f64 * 0.05 + fy).unwrap();
            let e = truth.entry((ix, iy)).or_insert((0u16, 0.0, 0.0));
            e.0 += 1;
            e.1 += (ix as f64 * 0.05 + fx - e.1) / e.0 as f64;
            e.2 += (iy as f64 * 0.05 + fy - e.2) / e.0 as f64;
        }
        for ix in -45..45 {
            for iy in -45..45 {
                let (n, mx, my) = truth.get(&(ix, iy)).copied().unwrap_or((0, 0.0, 0.0));
                assert_eq!(m.hits(ix, iy), n, "cell ({ix}, {iy})");
                if n > 0 {
                    let (ax, ay) = m.mean(ix, iy);
                    assert!((ax - mx).abs() < 1e-5 && (ay - my).abs() < 1e-5, "({ix}, {iy}): {ax} {ay} vs {mx} {my}");
                }
            }
        }
    }

    #[test]
    fn a_tile_stores_only_its_hit_cells() {
        let mut m = TileMap::new(0.05);
        m.mark_seen(0.0, 0.01, 1.5, 0.01).unwrap();
        let seen_only = m.tiles().next().unwrap().bytes();
        assert!(seen_only < 512, "a tile crossed by a beam holds no cell statistics: {seen_only} bytes");
        for i in 0..32 {
            m.add_hit(i as f64 * 0.05 + 0.01, 0.8).unwrap();
        }
        let wall = m.tiles().next().unwrap().bytes();
        assert!(wall < seen_only + 32 * 2 * std::mem::size_of::<CellHits>(), "a wall of 32 cells: {wall} bytes");
    }

    #[test]
    fn absurd_coordinates_are_refused_not_panicking() {
        let mut m = TileMap::new(0.05);
        m.add_hit(0.0, 0.0).unwrap();
        assert_eq!(m.add_hit(1e9, 1e9), Err(TooLarge));
        assert_eq!(m.hits(i32::MAX, i32::MIN), 0);
        let _ = m.cell_of(f64::NAN, f64::INFINITY);
    }
}
