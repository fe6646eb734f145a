//! A likelihood field built from a particle's hit map, for the `field` scan matcher
//! ([`crate::scan_matcher::MatcherKind::Field`]).
//!
//! GMapping's matcher searches, for every beam end point and every pose it tries, a (2k+1)² window of cells
//! for the nearest cell mean. The likelihood field does that search once per cell and update instead: over a
//! window covering the scan, a cell stores the *surface elements* (surfels) nearest to its centre within
//! `reach` cells, so scoring a beam is one table read. A cell is searched when a lookup first reads it, and a
//! surfel computed when a search first needs it: a scan's lookups read about one cell in forty of the window
//! (FR079: 1.1 thousand of 43 thousand per build), so filling every cell up front cost three quarters of the
//! SLAM's time.
//!
//! A surfel is made from an occupied cell: where the means of the occupied cells around it (±2 cells,
//! weighted by their hits) lie on a line, the cell's mean projected onto that line plus the line's normal,
//! and a beam's distance to it is the distance to a segment one cell long each way along the line. This
//! removes two errors of GMapping's point-to-mean distance: the ripple along a wall (the nearest mean is up to
//! half a cell away along it, and which mean is nearest changes as the pose moves), which makes the hill
//! climber stop in spurious optima; and the dead band of a wall lying on a cell boundary, whose hits split
//! between two rows of cells whose means sit on either side of it. Where the neighbourhood holds a second
//! surface (a corner), the line is refitted to the means a candidate line through the cell's own mean
//! supports best; where no line fits, the surfel is the mean point alone.
//!
//! Each cell keeps the nearest surfel of two orientation classes (normals nearer the x axis, nearer the y
//! axis), so that near a corner a beam is measured to both faces and takes the nearer, as GMapping's kernel
//! search takes the nearest mean around the end point itself.
//!
//! The tiles record which side each cell's hits came from ([`crate::tile_map::CellHits::dir`]); a surfel whose
//! beams all came from one side is *oriented*, and a beam can only end on it travelling against its normal.
//! Without this test a surface just coming out of a pillar's shadow gets matched to the pillar's far face.
//!
//! Cells with no surfel within reach keep whether the particle's map has seen them (see
//! [`crate::MatcherParams::seen_band`]). The field is rebuilt for each particle at each update into reused
//! buffers ([`Field::build`]), which are never cleared: slots carry the number of the build that wrote them.
//! It is derived data, never shared or stored; results depend neither on which buffer a build reuses nor on
//! the order of the lookups (a cell's search depends only on the map).

use crate::tile_map::{DIR_SCALE, TILE, TILE_SHIFT, TileMap, local};
use std::cell::Cell;

mod line;

/// A surface element: the nearest occupied cell's mean (window-relative metres), the unit normal of the
/// surface there (×[`NORMAL_SCALE`]), and what kind of surfel it is ([`Surfel::LINE`], [`Surfel::ORIENTED`]
/// flags; [`Surfel::NONE`] for no surfel). 16 bytes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surfel {
    /// Mean hit position (projected on its line for a line surfel), x, metres from the window's origin.
    pub mx: f32,
    /// Mean hit position, y.
    pub my: f32,
    /// Unit normal ×[`NORMAL_SCALE`], x. For an oriented surfel it points to the side the surface was
    /// seen from; for a point surfel it is the mean direction back to the sensors that saw it.
    pub nx: i16,
    /// Unit normal ×[`NORMAL_SCALE`], y.
    pub ny: i16,
    /// Flags.
    pub kind: u8,
    /// The [`Field`] build that wrote this surfel: older ones are stale (the buffer is not cleared).
    stamp: u16,
}

impl Surfel {
    /// Flag: a line surfel (a segment along the line through the neighbouring means); else a point.
    pub const LINE: u8 = 1;
    /// Flag: the side the surface was seen from is known: beams must meet it from the front.
    pub const ORIENTED: u8 = 2;
    /// No surfel.
    pub const NONE: u8 = 0x80;

    /// The unit normal.
    #[inline]
    pub fn normal(&self) -> (f64, f64) {
        (self.nx as f64 * INV_NORMAL_SCALE, self.ny as f64 * INV_NORMAL_SCALE)
    }

    /// Whether this slot holds no surfel of build `stamp`.
    #[inline]
    fn is_none(&self, stamp: u16) -> bool {
        self.stamp != stamp || self.kind & Surfel::NONE != 0
    }
}

/// Scale of the surfels' i16 normals.
pub const NORMAL_SCALE: f64 = 32767.0;
const INV_NORMAL_SCALE: f64 = 1.0 / NORMAL_SCALE;
const EMPTY: Surfel = Surfel { mx: 0.0, my: 0.0, nx: 0, ny: 0, kind: Surfel::NONE, stamp: 0 };
/// Largest cosine between a beam and an oriented surfel's outward normal for the beam to end on it:
/// slightly past grazing, so that noise at grazing incidence does not flip the test.
pub const VISIBLE_COS: f64 = 0.1;
/// Fraction of the summed beam directions' lengths their sum must keep, along the normal, for a surface to
/// count as seen from one side (a thin wall seen from both sides has no orientation).
const ORIENTED_FRACTION: f64 = 0.5;
/// Cells on each side of an occupied cell whose means estimate its surface line.
const NORMAL_RADIUS: i32 = 2;
/// Fewest occupied cells (the cell included) in a line fit.
const NORMAL_MIN_CELLS: usize = 3;
/// Largest ratio of the small to the large eigenvalue of the neighbourhood's scatter for a line.
const LINE_RATIO: f64 = 0.03;
/// A point surfel (no line fits) claims a cell only when nearer than a line surfel by this many squared
/// cells: lines are the better model wherever one reaches.
const POINT_PENALTY: f64 = 1.0;
/// Half-length of a line surfel's segment, cells: a beam farther along the surface than this from the
/// cell's mean is measured to the segment's end (beyond a wall's end, the distance grows).
const SEGMENT_HALF_CELLS: f64 = 1.0;
/// Cells from a candidate line beyond which a mean is an outlier (another surface).
const LINE_OUTLIER: f64 = 0.3;
/// Hits beyond which a cell's mean weighs no more in a line fit.
const LINE_WEIGHT_CAP: u32 = 10;

/// What a beam end point finds in the field.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lookup {
    /// A surface within reach, at squared distance d² (m²).
    Hit(f64),
    /// No surface within reach; the cell was seen (known space).
    Seen,
    /// No surface within reach; never seen (or outside the window).
    Unseen,
}

/// The likelihood field of one particle's map over a window of cells, reused between builds.
#[derive(Debug, Clone, Default)]
pub struct Field {
    /// Window origin and size in cells (map cell coordinates).
    x0: i32,
    y0: i32,
    w: i32,
    h: i32,
    delta: f64,
    inv_delta: f64,
    /// Half-length of line segments, metres.
    half: f64,
    /// Number of the current build (mod 2^16, never 0): surfels of other builds are stale.
    stamp: u16,
    /// Per cell the nearest surfel of each of two orientation classes (normal nearer the x axis, nearer the y
    /// axis; point surfels in the first): at a corner, a beam end point is measured to both faces and takes
    /// the nearer, as GMapping's kernel search takes the nearest mean around the point itself. Filled when a
    /// lookup first reads the cell (a scan's lookups read about one cell in forty of its window).
    cells: Vec<Cell<[Surfel; 2]>>,
    /// Seen flags of the window's cells, one bit per cell.
    seen: Vec<u64>,
    /// The padded window's and the blocks' sizes, and the build's reach.
    geometry: Geometry,
    /// Per cell of the padded window, 1 + index into `occupied`: valid where `occ_bits` marks the cell occupied,
    /// stale elsewhere (never cleared).
    occ: Vec<u32>,
    /// The same cells' occupancy, one bit per cell, [`Geometry::words`] words a padded row
    /// (one spare, so that a row's last bits can be read as a pair of words).
    occ_bits: Vec<u64>,
    /// The occupied cells of the padded window: padded x, padded y, mean (metres from the window's
    /// origin), hits, summed beam directions.
    occupied: Vec<(i32, i32, f32, f32, u32, [i16; 2])>,
    /// Per block of [`BLOCK`]² window cells, whether some lookup may need it.
    needed: Vec<bool>,
    /// Build scratch: the points of [`Field::build_near`].
    near: Vec<(f64, f64, f64)>,
    /// Each occupied cell's surfel and the penalty it carries in the contest for the cells around it, computed
    /// when a lookup first needs it ([`Surfel::NONE`] where the cell's block is not needed).
    surfels: Vec<Cell<Option<(Surfel, f32)>>>,
}

/// The sizes a build works in: the padding around the window (cells), the padded window's width and height,
/// the needed-block grid's columns and rows, the reach (cells, and squared metres from a cell's centre), and
/// whether surfels are lines.
#[derive(Debug, Clone, Copy, Default)]
struct Geometry {
    pad: i32,
    pw: i32,
    ph: i32,
    bw: i32,
    bh: i32,
    reach: i32,
    reach2: f32,
    lines: bool,
    words: usize,
}

/// Side, in cells, of the blocks in which [`Field::build_near`] decides which surfels to compute.
const BLOCK: i32 = 8;

impl Field {
    /// Origin of the window in the map frame, metres: subtract from map-frame points before [`Field::lookup`].
    #[inline]
    pub fn origin(&self) -> (f64, f64) {
        (self.x0 as f64 * self.delta, self.y0 as f64 * self.delta)
    }

    /// Window size in cells.
    pub fn size(&self) -> (i32, i32) {
        (self.w, self.h)
    }

    /// Index of the cell holding window-relative point (u, v), or None outside the window.
    #[inline]
    fn index(&self, u: f64, v: f64) -> Option<usize> {
        let fx = u * self.inv_delta;
        let fy = v * self.inv_delta;
        // NaN fails this test too
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (ix, iy) = (fx as i32, fy as i32);
        if ix >= self.w || iy >= self.h {
            return None;
        }
        Some((iy * self.w + ix) as usize)
    }

    /// Squared distance from (u, v) to surfel `s` for a beam of direction (dx, dy); infinite when there is
    /// no surfel or the beam would meet an oriented surface from behind.
    #[inline]
    fn candidate(&self, s: &Surfel, u: f64, v: f64, dx: f64, dy: f64) -> f64 {
        if s.is_none(self.stamp) {
            return f64::INFINITY;
        }
        let (nx, ny) = s.normal();
        if s.kind & Surfel::ORIENTED != 0 && nx * dx + ny * dy > VISIBLE_COS {
            return f64::INFINITY;
        }
        let ex = u - s.mx as f64;
        let ey = v - s.my as f64;
        if s.kind & Surfel::LINE != 0 {
            let perp = nx * ex + ny * ey;
            let along = ((nx * ey - ny * ex).abs() - self.half).max(0.0);
            perp * perp + along * along
        } else {
            ex * ex + ey * ey
        }
    }

    /// The surfel nearest to window-relative point (u, v) within reach that a beam of unit direction
    /// (dx, dy) can end on, and its squared distance.
    #[inline]
    pub fn nearest(&self, u: f64, v: f64, dx: f64, dy: f64) -> Option<(Surfel, f64)> {
        let [a, b] = self.surfels_at(self.index(u, v)?);
        let da = self.candidate(&a, u, v, dx, dy);
        let db = self.candidate(&b, u, v, dx, dy);
        if da <= db { da.is_finite().then_some((a, da)) } else { Some((b, db)) }
    }

    /// Half-length of a line surfel's segment, metres (0 for a point surfel).
    #[inline]
    pub fn half(&self, s: &Surfel) -> f64 {
        if s.kind & Surfel::LINE != 0 { self.half } else { 0.0 }
    }

    /// What the end point (u, v) (window-relative) of a beam of unit direction (dx, dy) finds: the squared
    /// distance to the nearest surface within reach that the beam can meet from the front, or whether its
    /// cell was seen.
    #[inline]
    pub fn lookup(&self, u: f64, v: f64, dx: f64, dy: f64) -> Lookup {
        let Some(i) = self.index(u, v) else { return Lookup::Unseen };
        let [a, b] = self.surfels_at(i);
        let d = self.candidate(&a, u, v, dx, dy).min(self.candidate(&b, u, v, dx, dy));
        if d.is_finite() {
            Lookup::Hit(d)
        } else if self.seen[i >> 6] >> (i & 63) & 1 != 0 {
            Lookup::Seen
        } else {
            Lookup::Unseen
        }
    }

    /// Rebuilds the field of `map` over cells `[cx0, cx1] × [cy0, cy1]` (inclusive; clipped to the map's
    /// allocated tiles), with surfels within `reach` cells of each cell's centre. `lines` off: every
    /// surfel is a point (the cell mean), as GMapping measures.
    pub fn build(&mut self, map: &TileMap, cells: [i32; 4], reach: i32, lines: bool) {
        self.build_near(map, cells, reach, lines, std::iter::empty());
    }

    /// As [`Field::build`], but only the surfels that a lookup within `radius` metres of one of the map-frame
    /// points `(x, y, radius)` of `near` can find are computed (all of them when `near` is empty); a lookup
    /// elsewhere finds no surface. Where a scan's end points cover a small part of a large window (a long-range
    /// lidar in a building), that is most of the build's work saved.
    pub fn build_near(
        &mut self,
        map: &TileMap,
        cells: [i32; 4],
        reach: i32,
        lines: bool,
        near: impl IntoIterator<Item = (f64, f64, f64)>,
    ) {
        self.near.clear();
        self.near.extend(near);
        let [mut cx0, mut cy0, mut cx1, mut cy1] = cells;
        if let Some([mx0, my0, mx1, my1]) = map.cell_bounds() {
            cx0 = cx0.max(mx0);
            cy0 = cy0.max(my0);
            cx1 = cx1.min(mx1);
            cy1 = cy1.min(my1);
        } else {
            cx1 = cx0 - 1;
        }
        self.delta = map.delta();
        self.inv_delta = 1.0 / self.delta;
        self.half = SEGMENT_HALF_CELLS * self.delta;
        if cx1 < cx0 || cy1 < cy0 {
            (self.x0, self.y0, self.w, self.h) = (0, 0, 0, 0);
            self.cells.clear();
            self.seen.clear();
            return;
        }
        self.x0 = cx0;
        self.y0 = cy0;
        self.w = cx1 - cx0 + 1;
        self.h = cy1 - cy0 + 1;
        let n = (self.w * self.h) as usize;
        // The buffers keep their contents between builds: a slot is valid when stamped with this build's
        // number, so they need no clearing (half a megabyte per particle and update for a 4 m scan).
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.cells.clear();
            self.stamp = 1;
        }
        if self.cells.len() < n {
            self.cells.resize(n, Cell::new([EMPTY; 2]));
        }
        self.seen.clear();
        self.seen.resize(n.div_ceil(64), 0);

        // Pass 1: occupied cells of the padded window (their means), and the seen flags of the window; both
        // read a tile row's bit mask at a time.
        let pad = reach + NORMAL_RADIUS;
        let (pw, ph) = (self.w + 2 * pad, self.h + 2 * pad);
        // Only read where `occ_bits` marks an occupied cell, so left uncleared (4 bytes a cell of a window that
        // grows with the lidar's range: clearing it was 2-6 % of the SLAM's time).
        if self.occ.len() < (pw * ph) as usize {
            self.occ.resize((pw * ph) as usize, 0);
        }
        let words = pw as usize / 64 + 2;
        self.occ_bits.clear();
        self.occ_bits.resize(words * ph as usize, 0);
        self.occupied.clear();
        let delta = self.delta;
        let (px0, py0) = (cx0 - pad, cy0 - pad);
        let (px1, py1) = (cx1 + pad, cy1 + pad);
        // bits lo..=hi of a tile row (lo, hi in 0..32)
        let span = |lo: i32, hi: i32| -> u32 { (u32::MAX >> (31 - hi)) & (u32::MAX << lo) };
        for ty in (py0 >> TILE_SHIFT)..=(py1 >> TILE_SHIFT) {
            for tx in (px0 >> TILE_SHIFT)..=(px1 >> TILE_SHIFT) {
                let Some(tile) = map.tile(tx, ty) else { continue };
                let (bx, by) = (tx << TILE_SHIFT, ty << TILE_SHIFT);
                let (ya, yb) = (by.max(py0), (by + TILE - 1).min(py1));
                let (xa, xb) = (bx.max(px0), (bx + TILE - 1).min(px1));
                let occ_mask = span(xa - bx, xb - bx);
                let (wa, wb) = (bx.max(cx0), (bx + TILE - 1).min(cx1));
                let seen_mask = if wa <= wb { span(wa - bx, wb - bx) } else { 0 };
                for iy in ya..=yb {
                    let row = (iy - by) as usize;
                    if iy >= cy0 && iy <= cy1 {
                        let mut bits = tile.seen[row] & seen_mask;
                        while bits != 0 {
                            let ix = bx + bits.trailing_zeros() as i32;
                            bits &= bits - 1;
                            let i = ((iy - cy0) * self.w + (ix - cx0)) as usize;
                            self.seen[i >> 6] |= 1 << (i & 63);
                        }
                    }
                    let mut bits = tile.occupied[row] & occ_mask;
                    while bits != 0 {
                        let ix = bx + bits.trailing_zeros() as i32;
                        bits &= bits - 1;
                        let Some(c) = tile.cell(local(ix, iy)) else { continue };
                        let mx = ((ix - cx0) as f64 * delta + c.mean[0] as f64) as f32;
                        let my = ((iy - cy0) as f64 * delta + c.mean[1] as f64) as f32;
                        self.occupied.push((ix - px0, iy - py0, mx, my, c.hits as u32, c.dir));
                        self.occ[((iy - py0) * pw + (ix - px0)) as usize] = self.occupied.len() as u32;
                        let (px, py) = ((ix - px0) as usize, (iy - py0) as usize);
                        self.occ_bits[py * words + px / 64] |= 1 << (px % 64);
                    }
                }
            }
        }

        // The blocks whose occupied cells can reach a lookup near one of the points.
        let (bw, bh) = ((self.w + BLOCK - 1) / BLOCK, (self.h + BLOCK - 1) / BLOCK);
        self.needed.clear();
        self.needed.resize((bw * bh) as usize, self.near.is_empty());
        for &(x, y, r) in &self.near {
            let (u, v) = (x * self.inv_delta - cx0 as f64, y * self.inv_delta - cy0 as f64);
            let rc = r * self.inv_delta + (reach + 1) as f64;
            let lo = |c: f64, n: i32| (((c - rc).floor() as i32).div_euclid(BLOCK)).clamp(0, n - 1);
            let hi = |c: f64, n: i32| (((c + rc).ceil() as i32).div_euclid(BLOCK)).clamp(0, n - 1);
            if u + rc < 0.0 || v + rc < 0.0 || u - rc >= self.w as f64 || v - rc >= self.h as f64 {
                continue;
            }
            for by in lo(v, bh)..=hi(v, bh) {
                let row = (by * bw) as usize;
                self.needed[row + lo(u, bw) as usize..=row + hi(u, bw) as usize].fill(true);
            }
        }

        // The surfels and the cells' nearest surfels are computed when a lookup first needs them.
        self.surfels.clear();
        self.surfels.resize(self.occupied.len(), Cell::new(None));
        let reach2 = ((reach as f64 + 0.5) * delta).powi(2) as f32;
        self.geometry = Geometry { pad, pw, ph, bw, bh, reach, reach2, lines, words };
    }

    /// The nearest surfels of window cell `i`, found on the first call of this build.
    #[inline]
    fn surfels_at(&self, i: usize) -> [Surfel; 2] {
        let pair = self.cells[i].get();
        if pair[0].stamp == self.stamp {
            return pair;
        }
        let pair = self.nearest_surfels(i);
        self.cells[i].set(pair);
        pair
    }

    /// Of the surfels whose occupied cell lies within reach of window cell `i` (its mean within reach of the
    /// cell's centre), the nearest of each orientation class, counting the point penalty; on a tie, the first
    /// occupied cell in the order of the build's pass over the tiles. Empty classes hold a [`Surfel::NONE`]
    /// stamped with the build, so that the cell counts as found.
    fn nearest_surfels(&self, i: usize) -> [Surfel; 2] {
        let g = self.geometry;
        let w = self.w as usize;
        let (x, y) = ((i % w) as i32, (i / w) as i32);
        let d32 = self.delta as f32;
        let (cx, cy) = ((x as f32 + 0.5) * d32, (y as f32 + 0.5) * d32);
        let none = Surfel { stamp: self.stamp, ..EMPTY };
        // per class: penalised squared distance, occupied index, surfel
        let mut best = [(f32::INFINITY, u32::MAX, none); 2];
        // the occupied cells of each padded row from xa to xa + 2 reach, read as a bit mask
        let xa = (x + g.pad - g.reach) as usize;
        let (word, shift) = (xa / 64, xa % 64);
        let span = u64::MAX >> (63 - 2 * g.reach);
        for py in y + g.pad - g.reach..=y + g.pad + g.reach {
            let (bits, row) = (&self.occ_bits[py as usize * g.words + word..], py as usize * g.pw as usize + xa);
            let mut mask = (bits[0] >> shift | if shift > 0 { bits[1] << (64 - shift) } else { 0 }) & span;
            while mask != 0 {
                let k = self.occ[row + mask.trailing_zeros() as usize];
                mask &= mask - 1;
                let (_, _, mx, my, _, _) = self.occupied[k as usize - 1];
                let (ex, ey) = (cx - mx, cy - my);
                let d2 = ex * ex + ey * ey;
                if d2 > g.reach2 {
                    continue;
                }
                let (s, penalty) = self.surfel(k as usize - 1);
                if s.kind & Surfel::NONE != 0 {
                    continue;
                }
                let class = usize::from(s.kind & Surfel::LINE != 0 && s.ny.unsigned_abs() > s.nx.unsigned_abs());
                let d = d2 + penalty;
                let b = &mut best[class];
                if d < b.0 || (d == b.0 && k < b.1) {
                    *b = (d, k, s);
                }
            }
        }
        [best[0].2, best[1].2]
    }

    /// The surfel of occupied cell `k` and its penalty, computed on the first call of this build.
    #[inline]
    fn surfel(&self, k: usize) -> (Surfel, f32) {
        if let Some(found) = self.surfels[k].get() {
            return found;
        }
        let found = self.surfel_of(k);
        self.surfels[k].set(Some(found));
        found
    }

    /// The surfel of occupied cell `k` and the penalty it carries in the contest for the cells around it
    /// (a [`Surfel::NONE`] where the cell's block is not needed).
    fn surfel_of(&self, k: usize) -> (Surfel, f32) {
        let Geometry { pad, pw, ph, bw, bh, lines, .. } = self.geometry;
        let (ox, oy, mx, my, hits, dir) = self.occupied[k];
        let (bx, by) = (((ox - pad) / BLOCK).clamp(0, bw - 1), ((oy - pad) / BLOCK).clamp(0, bh - 1));
        if !self.needed[(by * bw + bx) as usize] {
            return (EMPTY, 0.0);
        }
        let mut s = Surfel { mx, my, nx: 0, ny: 0, kind: 0, stamp: self.stamp };
        // a point surfel's normal: the mean direction back to the sensors that saw it
        let (ddx, ddy) = (dir[0] as f64, dir[1] as f64);
        let dlen = (ddx * ddx + ddy * ddy).sqrt();
        if dlen > ORIENTED_FRACTION * hits as f64 * DIR_SCALE {
            s.nx = (-ddx / dlen * NORMAL_SCALE).round() as i16;
            s.ny = (-ddy / dlen * NORMAL_SCALE).round() as i16;
            s.kind = Surfel::ORIENTED;
        }
        if !lines {
            return (s, 0.0);
        }
        let Some((nx, ny, c, oriented)) =
            self.line(ox, oy, pw, ph, NORMAL_RADIUS).or_else(|| self.line(ox, oy, pw, ph, 1))
        else {
            return (s, (POINT_PENALTY * self.delta * self.delta) as f32);
        };
        // the cell's mean projected onto the line
        let off = nx * mx as f64 + ny * my as f64 - c;
        let line = Surfel {
            mx: (mx as f64 - off * nx) as f32,
            my: (my as f64 - off * ny) as f32,
            nx: (nx * NORMAL_SCALE).round() as i16,
            ny: (ny * NORMAL_SCALE).round() as i16,
            kind: Surfel::LINE | if oriented { Surfel::ORIENTED } else { 0 },
            stamp: self.stamp,
        };
        (line, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An occupied cell's surfel placed in the window, for the eager reference build of the tests: the cell (window
    /// coordinates) and its mean (metres from the window's origin), the surfel, and its penalty.
    #[derive(Debug, Clone, Copy)]
    struct Placed {
        wx: i32,
        wy: i32,
        mx: f32,
        my: f32,
        surfel: Surfel,
        penalty: f32,
    }

    /// The eager build's view of a window, kept as the tests' reference: its size, the reach (cells, and squared
    /// metres), the cell size.
    #[derive(Debug, Clone, Copy)]
    struct Band {
        w: i32,
        reach: i32,
        reach2: f32,
        delta: f32,
        stamp: u16,
    }

    impl Band {
        /// Splats `surfels` onto the window's rows from `row0` on, whose cells and best distances are `cells` and
        /// `best`: each cell within reach of a surfel's mean keeps the nearest of each orientation class.
        fn splat(&self, surfels: &[Placed], row0: i32, cells: &mut [[Surfel; 2]], best: &mut [[f32; 2]]) {
            let w = self.w as usize;
            let row1 = row0 + (cells.len() / w.max(1)) as i32 - 1;
            let d32 = self.delta;
            for p in surfels {
                let s = p.surfel;
                if s.kind & Surfel::NONE != 0 {
                    continue;
                }
                let (ya, yb) = ((p.wy - self.reach).max(row0), (p.wy + self.reach).min(row1));
                if ya > yb {
                    continue;
                }
                let class = usize::from(s.kind & Surfel::LINE != 0 && s.ny.unsigned_abs() > s.nx.unsigned_abs());
                let (mx, my) = (p.mx, p.my);
                let (xa, xb) = ((p.wx - self.reach).max(0), (p.wx + self.reach).min(self.w - 1));
                for y in ya..=yb {
                    let cy = (y as f32 + 0.5) * d32 - my;
                    let row = (y - row0) as usize * w;
                    // the row's cells within reach: |cx| <= sqrt(reach² - cy²), rounded out by a cell
                    let half = (self.reach2 - cy * cy).max(0.0).sqrt() / d32;
                    let mxc = mx / d32 - 0.5;
                    let (xa, xb) = (xa.max((mxc - half).floor() as i32), xb.min((mxc + half).ceil() as i32));
                    for x in xa..=xb {
                        let cx = (x as f32 + 0.5) * d32 - mx;
                        let d2 = cx * cx + cy * cy;
                        let i = row + x as usize;
                        let slot = &mut cells[i][class];
                        let b = &mut best[i][class];
                        if d2 <= self.reach2 && (slot.stamp != self.stamp || d2 + p.penalty < *b) {
                            *b = d2 + p.penalty;
                            *slot = s;
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_wall_gives_line_surfels_and_seen_cells() {
        let mut m = TileMap::new(0.05);
        // a wall along y = 1.02, x in [0, 2], seen from below (beams travelling +y)
        for i in 0..200 {
            m.add_beam_hit(i as f64 * 0.01, 1.02, 0.0, 1.0).unwrap();
        }
        m.mark_seen(1.0, 0.0, 1.0, 0.9).unwrap();
        let mut f = Field::default();
        f.build(&m, [-10, -10, 50, 50], 3, true);
        let (ox, oy) = f.origin();
        let up = |f: &Field, x: f64, y: f64| f.lookup(x - ox, y - oy, 0.0, 1.0);
        // a point 3 cm below the wall, between two cell means: distance to the segment is the perpendicular
        match up(&f, 1.013, 0.99) {
            Lookup::Hit(d2) => assert!((d2.sqrt() - 0.03).abs() < 1e-4, "{}", d2.sqrt()),
            other => panic!("{other:?}"),
        }
        // a beam meeting the wall from behind (travelling -y) does not end on it
        assert!(!matches!(f.lookup(1.013 - ox, 0.99 - oy, 0.0, -1.0), Lookup::Hit(_)));
        // without lines, the distance to the nearest mean includes the offset along the wall
        let mut g = Field::default();
        g.build(&m, [-10, -10, 50, 50], 3, false);
        match up(&g, 1.013, 0.99) {
            Lookup::Hit(d2) => assert!(d2.sqrt() > 0.03 + 1e-4, "{}", d2.sqrt()),
            other => panic!("{other:?}"),
        }
        // beyond reach: seen below the wall where marked, unseen elsewhere
        assert_eq!(up(&f, 1.01, 0.3), Lookup::Seen);
        assert_eq!(up(&f, 0.5, 0.3), Lookup::Unseen);
        assert_eq!(f.lookup(-100.0, 0.0, 0.0, 1.0), Lookup::Unseen);
        // beyond the wall's end the segment distance grows
        match up(&f, 2.12, 1.02) {
            Lookup::Hit(d2) => assert!(d2.sqrt() > 0.05, "{}", d2.sqrt()),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_corner_keeps_both_faces() {
        // an L: a wall along y = 1 for x in [0, 1], and one along x = 1 for y in [0, 1]
        let mut m = TileMap::new(0.05);
        for i in 0..100 {
            let t = i as f64 * 0.01;
            m.add_beam_hit(t, 1.0, 0.0, 1.0).unwrap();
            m.add_beam_hit(1.0, t, 1.0, 0.0).unwrap();
        }
        let mut f = Field::default();
        f.build(&m, [-10, -10, 40, 40], 3, true);
        let (ox, oy) = f.origin();
        // near the corner, a point on each face is on that face's line
        for (x, y, dx, dy) in [(0.96, 0.995, 0.0, 1.0), (0.995, 0.96, 1.0, 0.0)] {
            match f.lookup(x - ox, y - oy, dx, dy) {
                Lookup::Hit(d2) => assert!(d2.sqrt() < 0.01, "({x}, {y}): {}", d2.sqrt()),
                other => panic!("{other:?}"),
            }
        }
    }

    /// A room with slanted walls and clutter, hit from inside.
    fn cluttered_room() -> TileMap {
        let mut m = TileMap::new(0.05);
        for i in 0..400 {
            let t = i as f64 * 0.01;
            m.add_beam_hit(t, 0.0, 0.0, -1.0).unwrap();
            m.add_beam_hit(t, 3.0 + 0.2 * t, 0.0, 1.0).unwrap();
            m.add_beam_hit(0.0, t * 0.75, -1.0, 0.0).unwrap();
            m.add_beam_hit(4.0, t * 0.8, 1.0, 0.0).unwrap();
            m.add_beam_hit(1.5 + 0.3 * (t * 7.0).sin(), 1.5 + 0.3 * (t * 7.0).cos(), 1.0, 0.0).unwrap();
        }
        m
    }

    #[test]
    fn the_lazy_field_equals_the_eager_splat_and_a_reused_field_equals_a_fresh_one() {
        let m = cluttered_room();
        let mut reused = Field::default();
        reused.build(&cluttered_room_other(), [-20, -20, 90, 90], 4, true);
        reused.build(&m, [-10, -10, 90, 90], 4, true);
        let mut fresh = Field::default();
        fresh.build(&m, [-10, -10, 90, 90], 4, true);
        assert_equals_eager_splat(&fresh);
        // and where only the surfels near some points are computed
        let mut near = Field::default();
        near.build_near(&m, [-10, -10, 90, 90], 4, true, [(0.5, 0.2, 0.5), (3.5, 2.0, 0.3)]);
        assert_equals_eager_splat(&near);
        // the reused buffers give the same lookups as fresh ones
        let (ox, oy) = fresh.origin();
        assert_eq!(reused.origin(), (ox, oy));
        for k in 0..2000 {
            let (x, y) = (-0.3 + (k % 50) as f64 * 0.1, -0.3 + (k / 50) as f64 * 0.1);
            let (dx, dy) = ((k as f64).cos(), (k as f64).sin());
            assert_eq!(reused.lookup(x - ox, y - oy, dx, dy), fresh.lookup(x - ox, y - oy, dx, dy), "({x}, {y})");
        }
    }

    /// Asserts that every cell of `f`, looked up lazily, finds what the eager splat of every occupied cell's
    /// surfel onto the cells within reach of its mean (the build before lookups were lazy) puts there.
    fn assert_equals_eager_splat(f: &Field) {
        let n = (f.w * f.h) as usize;
        let g = f.geometry;
        let placed: Vec<Placed> = (0..f.occupied.len())
            .map(|k| {
                let (ox, oy, mx, my, _, _) = f.occupied[k];
                let (surfel, penalty) = f.surfel_of(k);
                Placed { wx: ox - g.pad, wy: oy - g.pad, mx, my, surfel, penalty }
            })
            .collect();
        let mut cells = vec![[EMPTY; 2]; n];
        let mut best = vec![[f32::INFINITY; 2]; n];
        let band = Band { w: f.w, reach: g.reach, reach2: g.reach2, delta: f.delta as f32, stamp: f.stamp };
        band.splat(&placed, 0, &mut cells, &mut best);
        let found = |pair: [Surfel; 2]| pair.map(|s| (!s.is_none(f.stamp)).then_some(s));
        for (i, eager) in cells.iter().enumerate() {
            assert_eq!(found(f.surfels_at(i)), found(*eager), "cell {i}");
        }
        assert!(cells.iter().flatten().any(|s| !s.is_none(f.stamp) && s.kind & Surfel::LINE != 0));
        assert!(cells.iter().flatten().any(|s| s.is_none(f.stamp)));
    }

    /// Another map, so that a reused field holds stale surfels where the next build has none.
    fn cluttered_room_other() -> TileMap {
        let mut m = TileMap::new(0.05);
        for i in 0..300 {
            let t = i as f64 * 0.01;
            m.add_beam_hit(t + 0.5, 2.0 - 0.5 * t, 0.0, 1.0).unwrap();
        }
        m
    }
}
