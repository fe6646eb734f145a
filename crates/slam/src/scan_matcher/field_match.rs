//! The likelihood-field matcher's parts of [`ScanMatcher`]: the field around a scan, scoring on it, and the
//! Gauss-Newton refinement to the score's optimum.

use super::{Beam, Evaluation, NULL_LIKELIHOOD, PosePrior, PreparedScan, ScanMatcher, Xyt, exp_neg};
use crate::field::{Field, Lookup, Surfel};
use crate::tile_map::TileMap;
use mrslam_matching::Information;

/// Metres around the scan's end points (at the starting pose) that the likelihood field covers beyond them:
/// how far the optimiser may move an end point and still find the field.
const FIELD_MARGIN: f64 = 0.5;
/// Gauss-Newton stops when a step moves less than this (metres, and radians).
const REFINE_TOLERANCE: f64 = 1e-4;

impl ScanMatcher {
    /// Builds `field` for `map` around the end points of `scan` at robot pose `p`.
    pub fn build_field(&self, map: &TileMap, p: &Xyt, scan: &PreparedScan, field: &mut Field) {
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        let (mut x0, mut y0, mut x1, mut y1) = (lp.x, lp.y, lp.x, lp.y);
        for b in scan.hits.iter().chain(&scan.matched) {
            let (px, py) = (lp.x + c * b.x - s * b.y, lp.y + s * b.x + c * b.y);
            x0 = x0.min(px);
            y0 = y0.min(py);
            x1 = x1.max(px);
            y1 = y1.max(py);
        }
        // Where the matcher may move each end point: the arc it sweeps as the heading search and the climb's
        // first angular steps turn the robot, widened by the margin. Sampled every margin along the arc, so
        // the discs cover a band about the arc rather than the disc around the end point a long beam's arc
        // spans (at 30 m, a band a metre wide instead of a disc 9 m across).
        let turn = self.params.heading_search + 2.0 * self.params.astep;
        let near = scan.hits.iter().flat_map(move |b| {
            let (ex, ey) = (lp.x + c * b.x - s * b.y - p.x, lp.y + s * b.x + c * b.y - p.y);
            let arm = ex.hypot(ey);
            let k = (arm * turn / FIELD_MARGIN).ceil() as i32;
            let step = if k > 0 { turn / k as f64 } else { 0.0 };
            (-k..=k).map(move |i| {
                let (si, ci) = (i as f64 * step).sin_cos();
                (p.x + ci * ex - si * ey, p.y + si * ex + ci * ey, FIELD_MARGIN)
            })
        });
        let (a, b) = map.cell_of(x0 - FIELD_MARGIN, y0 - FIELD_MARGIN);
        let (c, d) = map.cell_of(x1 + FIELD_MARGIN, y1 + FIELD_MARGIN);
        field.build_near(map, [a, b, c, d], self.params.field_reach, self.params.field_lines, near);
    }

    /// Score, log-likelihood and matched beams of robot pose `p` on a likelihood field.
    #[inline]
    pub fn field_eval(&self, f: &Field, p: &Xyt, beams: &[Beam]) -> Evaluation {
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        let (ox, oy) = f.origin();
        let (lx, ly) = (lp.x - ox, lp.y - oy);
        let inv_sigma = 1.0 / self.params.sigma;
        let inv_lsigma = 1.0 / self.params.lsigma;
        let unknown = self.unknown_score;
        let mut e = Evaluation::default();
        for b in beams {
            let u = lx + c * b.x - s * b.y;
            let v = ly + s * b.x + c * b.y;
            match f.lookup(u, v, c * b.c - s * b.s, s * b.c + c * b.s) {
                Lookup::Hit(d2) => {
                    e.score += exp_neg(d2 * inv_sigma);
                    e.likelihood -= d2 * inv_lsigma;
                    e.matched += 1;
                }
                Lookup::Unseen if unknown.is_some() => e.score += unknown.unwrap_or(0.0),
                _ => e.likelihood += NULL_LIKELIHOOD * inv_lsigma,
            }
        }
        e
    }

    /// Gauss-Newton refinement of robot pose `p` on a likelihood field: iteratively reweighted least squares
    /// of the beams' distances to their surfels with the score's own weights exp(-d²/sigma), i.e. Newton
    /// steps towards the nearest maximum of the score.
    pub fn refine(&self, f: &Field, p: &Xyt, beams: &[Beam], prior: Option<&PosePrior>) -> Xyt {
        let mut p = *p;
        for _ in 0..self.params.refine_iterations {
            let (mut h, mut g) = self.normal_equations(f, &p, beams);
            if let Some(pr) = prior {
                let d = pr.delta(&p);
                let i = &pr.info;
                for k in 0..6 {
                    h[k] += i[k];
                }
                g[0] += i[0] * d[0] + i[1] * d[1] + i[2] * d[2];
                g[1] += i[1] * d[0] + i[3] * d[1] + i[4] * d[2];
                g[2] += i[2] * d[0] + i[4] * d[1] + i[5] * d[2];
            }
            let Some(d) = solve3(&h, &g) else { break };
            p.x -= d[0];
            p.y -= d[1];
            p.theta -= d[2];
            if d[0].abs() + d[1].abs() < REFINE_TOLERANCE && d[2].abs() < REFINE_TOLERANCE {
                break;
            }
        }
        p
    }

    /// The scan's information about robot pose `p` on a likelihood field: the Gauss-Newton normal matrix of
    /// [`ScanMatcher::refine`] without the prior (upper triangle 00 01 02 11 12 22, map frame), i.e. the
    /// curvature of the negated score in the units of `PosePrior::info`. Near zero in a direction the scan
    /// does not observe.
    pub fn scan_information(&self, f: &Field, p: &Xyt, beams: &[Beam]) -> Information {
        self.normal_equations(f, p, beams).0
    }

    /// The normal matrix (upper triangle) and gradient of the beams' weighted squared distances at `p`.
    fn normal_equations(&self, f: &Field, p: &Xyt, beams: &[Beam]) -> (Information, [f64; 3]) {
        let (ox, oy) = f.origin();
        let inv_sigma = 1.0 / self.params.sigma;
        // residuals in metres with the kernel's variance sigma/2: weights w·2/sigma in chi-square units
        let scale = 2.0 * inv_sigma;
        let lp = self.laser_pose(p);
        let (s, c) = lp.theta.sin_cos();
        let (lx, ly) = (lp.x - ox, lp.y - oy);
        let (rx, ry) = (p.x - ox, p.y - oy);
        let mut h = Information::ZERO; // the 3x3 normal matrix
        let mut g = [0.0f64; 3];
        let mut add = |j: [f64; 3], r: f64, w: f64| {
            let w = w * scale;
            h[0] += w * j[0] * j[0];
            h[1] += w * j[0] * j[1];
            h[2] += w * j[0] * j[2];
            h[3] += w * j[1] * j[1];
            h[4] += w * j[1] * j[2];
            h[5] += w * j[2] * j[2];
            g[0] += w * j[0] * r;
            g[1] += w * j[1] * r;
            g[2] += w * j[2] * r;
        };
        for b in beams {
            let u = lx + c * b.x - s * b.y;
            let v = ly + s * b.x + c * b.y;
            let Some((sf, d2)) = f.nearest(u, v, c * b.c - s * b.s, s * b.c + c * b.s) else { continue };
            let w = exp_neg(d2 * inv_sigma);
            let (ex, ey) = (u - sf.mx as f64, v - sf.my as f64);
            // d(end point)/d(theta)
            let (tx, ty) = (-(v - ry), u - rx);
            if sf.kind & Surfel::LINE == 0 {
                add([1.0, 0.0, tx], ex, w);
                add([0.0, 1.0, ty], ey, w);
                continue;
            }
            let (nx, ny) = sf.normal();
            let half = f.half(&sf);
            add([nx, ny, nx * tx + ny * ty], nx * ex + ny * ey, w);
            let along = -ny * ex + nx * ey;
            let over = along.abs() - half;
            if over > 0.0 {
                let sg = along.signum();
                add([-ny * sg, nx * sg, sg * (-ny * tx + nx * ty)], over, w);
            }
        }
        (h, g)
    }
}

/// Solves the symmetric 3x3 system H·x = g; None when
/// H is (nearly) singular.
fn solve3(h: &Information, g: &[f64; 3]) -> Option<[f64; 3]> {
    let (a, b, c, d, e, f) = (h[0], h[1], h[2], h[3], h[4], h[5]);
    // cofactors
    let c00 = d * f - e * e;
    let c01 = c * e - b * f;
    let c02 = b * e - c * d;
    let det = a * c00 + b * c01 + c * c02;
    let scale = a.abs().max(d.abs()).max(f.abs());
    if det.is_nan() || det.abs() <= 1e-12 * scale * scale * scale || !det.is_finite() {
        return None;
    }
    let c11 = a * f - c * c;
    let c12 = b * c - a * e;
    let c22 = a * d - b * b;
    let inv = 1.0 / det;
    Some([
        (c00 * g[0] + c01 * g[1] + c02 * g[2]) * inv,
        (c01 * g[0] + c11 * g[1] + c12 * g[2]) * inv,
        (c02 * g[0] + c12 * g[1] + c22 * g[2]) * inv,
    ])
}
