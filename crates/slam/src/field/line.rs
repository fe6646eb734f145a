//! The surface lines of the likelihood field's surfels: the line through the means of an occupied cell's
//! neighbours, refitted to one face where the neighbourhood holds two, and turned towards the side it was seen from.

use super::{Field, LINE_OUTLIER, LINE_RATIO, LINE_WEIGHT_CAP, NORMAL_MIN_CELLS, NORMAL_RADIUS, ORIENTED_FRACTION};
use crate::tile_map::DIR_SCALE;

impl Field {
    /// The line through the means of the occupied cells within [`NORMAL_RADIUS`] of padded cell (ox, oy),
    /// weighted by their hits (up to [`LINE_WEIGHT_CAP`]), when they lie on a line: its unit normal n and
    /// offset c (points x on the line have n·x = c).
    ///
    /// Fitting the line through the neighbourhood rather than through the cell's own mean matters where a
    /// surface runs along a cell boundary: its hits then split between two rows of cells whose means lie on
    /// either side of it, and matching each end point to its own row's mean makes a dead band in which the
    /// pose is not observed.
    pub(super) fn line(&self, ox: i32, oy: i32, pw: i32, ph: i32, radius: i32) -> Option<(f64, f64, f64, bool)> {
        // the neighbourhood's means and weights, the cell itself first, and their occupied indices
        const MAX: usize = ((2 * NORMAL_RADIUS + 1) * (2 * NORMAL_RADIUS + 1)) as usize;
        let mut pts = [(0.0f64, 0.0f64, 0.0f64); MAX];
        let mut ids = [0u32; MAX];
        let mut n = 0;
        let words = self.geometry.words;
        // `occ` holds this build's indices only where `occ_bits` marks an occupied cell
        let occupied_at = |x: i32, y: i32| {
            let (x, y) = (x as usize, y as usize);
            (self.occ_bits[y * words + x / 64] >> (x % 64) & 1 != 0).then(|| self.occ[y * pw as usize + x])
        };
        let own = occupied_at(ox, oy).unwrap_or(0);
        for y in (oy - radius).max(0)..=(oy + radius).min(ph - 1) {
            for x in (ox - radius).max(0)..=(ox + radius).min(pw - 1) {
                let Some(k) = occupied_at(x, y).filter(|_| n < MAX) else {
                    continue;
                };
                let (_, _, mx, my, hits, _) = self.occupied[k as usize - 1];
                let p = (mx as f64, my as f64, hits.min(LINE_WEIGHT_CAP) as f64);
                if k == own {
                    pts[n] = pts[0];
                    ids[n] = ids[0];
                    pts[0] = p;
                    ids[0] = k;
                } else {
                    pts[n] = p;
                    ids[n] = k;
                }
                n += 1;
            }
        }
        // A clean fit (every mean within LINE_OUTLIER cells of the line) is the surface. Otherwise the
        // neighbourhood holds another surface too (the other face of a corner, clutter): of the lines through
        // the cell's own mean and each neighbour's, the one most means support is refitted to its supporters,
        // so a corner's cells get the line of their own face rather than a tilted average of both.
        let tol = LINE_OUTLIER * self.delta;
        let (x0, y0, _) = pts[0];
        if let Some((nx, ny, c)) = fit(&pts[..n], LINE_RATIO)
            && pts[..n].iter().all(|&(x, y, _)| (nx * x + ny * y - c).abs() <= tol)
        {
            return Some(self.orient(nx, ny, c, &ids[..n]));
        }
        let mut best: Option<(f64, f64, f64)> = None;
        for j in 1..n {
            let (dx, dy) = (pts[j].0 - x0, pts[j].1 - y0);
            let len = (dx * dx + dy * dy).sqrt();
            if len < 0.5 * self.delta {
                continue;
            }
            let (nx, ny) = (-dy / len, dx / len);
            let support: f64 =
                pts[..n].iter().filter(|&&(x, y, _)| (nx * (x - x0) + ny * (y - y0)).abs() <= tol).map(|p| p.2).sum();
            if best.is_none_or(|b| support > b.0) {
                best = Some((support, nx, ny));
            }
        }
        let (_, nx, ny) = best?;
        let mut kept = 0;
        for i in 0..n {
            let (x, y, _) = pts[i];
            if (nx * (x - x0) + ny * (y - y0)).abs() <= tol {
                pts[kept] = pts[i];
                ids[kept] = ids[i];
                kept += 1;
            }
        }
        let (nx, ny, c) = fit(&pts[..kept], LINE_RATIO)?;
        Some(self.orient(nx, ny, c, &ids[..kept]))
    }

    /// The line (n, c) with its normal turned towards the side the beams that hit occupied cells `ids`
    /// (1-based) came from, when they came from one side: (nx, ny, c, oriented).
    fn orient(&self, nx: f64, ny: f64, c: f64, ids: &[u32]) -> (f64, f64, f64, bool) {
        let (mut along, mut total) = (0.0, 0.0);
        for &k in ids {
            let (_, _, _, _, hits, dir) = self.occupied[k as usize - 1];
            along += nx * dir[0] as f64 + ny * dir[1] as f64;
            total += hits as f64 * DIR_SCALE;
        }
        if along.abs() > ORIENTED_FRACTION * total && total > 0.0 {
            // beams travel against the outward normal
            let sg = if along > 0.0 { -1.0 } else { 1.0 };
            (sg * nx, sg * ny, sg * c, true)
        } else {
            (nx, ny, c, false)
        }
    }
}

/// Weighted total-least-squares line through points (x, y, weight): unit normal, offset and total weight,
/// when there are at least [`NORMAL_MIN_CELLS`] points and the scatter across the line is at most `ratio`
/// times the scatter along it.
fn fit(pts: &[(f64, f64, f64)], ratio: f64) -> Option<(f64, f64, f64)> {
    if pts.len() < NORMAL_MIN_CELLS {
        return None;
    }
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for &(x, y, w) in pts {
        sw += w;
        sx += w * x;
        sy += w * y;
    }
    let (mx, my) = (sx / sw, sy / sw);
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for &(x, y, w) in pts {
        let (dx, dy) = (x - mx, y - my);
        a += w * dx * dx;
        b += w * dx * dy;
        c += w * dy * dy;
    }
    let mid = 0.5 * (a + c);
    let rad = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (big, small) = (mid + rad, mid - rad);
    if big.is_nan() || big <= 0.0 || small > ratio * big {
        return None;
    }
    // the normal: the eigenvector of the small eigenvalue, from whichever row of (S - small·I) is larger
    let (ex, ey) =
        if (a - small).abs() + b.abs() >= (c - small).abs() + b.abs() { (-b, a - small) } else { (c - small, -b) };
    let len = (ex * ex + ey * ey).sqrt();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    let (nx, ny) = (ex / len, ey / len);
    Some((nx, ny, nx * mx + ny * my))
}
