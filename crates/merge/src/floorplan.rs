//! Procedural floor plans: rooms by recursive partition, doors, furniture, all from a seed.
//!
//! Gives tests and studies as many realistic, fully known ground-truth maps as they need without shipping
//! data. Walls are occupied, the building's inside free, the outside unknown.

use mrslam_core::{OccupancyGrid, pose};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Shape of the generated floor plans.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FloorplanParams {
    /// Building width, metres.
    pub width_m: f64,
    /// Building height, metres.
    pub height_m: f64,
    /// Cell size, metres.
    pub resolution: f64,
    /// Rooms are not split below this size, metres.
    pub min_room_m: f64,
    /// Wall thickness, metres.
    pub wall_m: f64,
    /// Door width, metres.
    pub door_m: f64,
    /// Most pieces of furniture per room.
    pub max_furniture: usize,
    /// Unknown margin around the building, metres.
    pub margin_m: f64,
}

impl Default for FloorplanParams {
    fn default() -> Self {
        FloorplanParams {
            width_m: 24.0,
            height_m: 18.0,
            resolution: 0.05,
            min_room_m: 3.0,
            wall_m: 0.1,
            door_m: 0.9,
            max_furniture: 3,
            margin_m: 0.5,
        }
    }
}

struct Canvas {
    w: usize,
    h: usize,
    cells: Vec<f32>,
}

impl Canvas {
    fn fill(&mut self, x0: usize, y0: usize, x1: usize, y1: usize, l: f32) {
        for y in y0.min(self.h)..y1.min(self.h) {
            for x in x0.min(self.w)..x1.min(self.w) {
                self.cells[y * self.w + x] = l;
            }
        }
    }
}

const OCC: f32 = 2.0;
const FREE: f32 = -2.0;

/// Generates the floor plan of a seed.
pub fn generate(seed: u64, p: &FloorplanParams) -> OccupancyGrid {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let c = |m: f64| (m / p.resolution).round().max(1.0) as usize;
    let (margin, wall) = (c(p.margin_m), c(p.wall_m));
    let (bw, bh) = (c(p.width_m), c(p.height_m));
    let (w, h) = (bw + 2 * margin, bh + 2 * margin);
    let mut cv = Canvas { w, h, cells: vec![0.0; w * h] };
    let (x0, y0, x1, y1) = (margin, margin, margin + bw, margin + bh);
    cv.fill(x0, y0, x1, y1, OCC);
    cv.fill(x0 + wall, y0 + wall, x1 - wall, y1 - wall, FREE);
    let mut leaves = Vec::new();
    split(&mut cv, &mut rng, p, (x0 + wall, y0 + wall, x1 - wall, y1 - wall), &mut leaves);
    for (rx0, ry0, rx1, ry1) in leaves {
        furnish(&mut cv, &mut rng, p, (rx0, ry0, rx1, ry1));
    }
    OccupancyGrid::from_cells(w, h, p.resolution, pose(0.0, 0.0, 0.0), cv.cells)
        .expect("floor plan size is bounded by its parameters")
}

type Rect = (usize, usize, usize, usize);

fn split(cv: &mut Canvas, rng: &mut ChaCha8Rng, p: &FloorplanParams, r: Rect, leaves: &mut Vec<Rect>) {
    let c = |m: f64| (m / p.resolution).round().max(1.0) as usize;
    let (min, wall, door) = (c(p.min_room_m), c(p.wall_m), c(p.door_m));
    let (x0, y0, x1, y1) = r;
    let (rw, rh) = (x1 - x0, y1 - y0);
    let can_x = rw >= 2 * min + wall;
    let can_y = rh >= 2 * min + wall;
    // Stop at random once a room is modest, so room sizes vary.
    let modest = rw < 3 * min && rh < 3 * min;
    if (!can_x && !can_y) || (modest && rng.random_bool(0.3)) {
        leaves.push(r);
        return;
    }
    let vertical = if can_x && can_y { rw as f64 * rng.random_range(0.7..1.3) > rh as f64 } else { can_x };
    if vertical {
        let sx = rng.random_range(x0 + min..=x1 - min - wall);
        cv.fill(sx, y0, sx + wall, y1, OCC);
        if rh > door + 2 * wall {
            let d = rng.random_range(y0 + wall..=y1 - wall - door);
            cv.fill(sx, d, sx + wall, d + door, FREE);
        }
        split(cv, rng, p, (x0, y0, sx, y1), leaves);
        split(cv, rng, p, (sx + wall, y0, x1, y1), leaves);
    } else {
        let sy = rng.random_range(y0 + min..=y1 - min - wall);
        cv.fill(x0, sy, x1, sy + wall, OCC);
        if rw > door + 2 * wall {
            let d = rng.random_range(x0 + wall..=x1 - wall - door);
            cv.fill(d, sy, d + door, sy + wall, FREE);
        }
        split(cv, rng, p, (x0, y0, x1, sy), leaves);
        split(cv, rng, p, (x0, sy + wall, x1, y1), leaves);
    }
}

/// Puts up to `max_furniture` boxes and round pillars in a room, clear of its walls.
fn furnish(cv: &mut Canvas, rng: &mut ChaCha8Rng, p: &FloorplanParams, r: Rect) {
    let c = |m: f64| (m / p.resolution).round().max(1.0) as usize;
    let (x0, y0, x1, y1) = (r.0 + c(0.3), r.1 + c(0.3), r.2.saturating_sub(c(0.3)), r.3.saturating_sub(c(0.3)));
    if x1 <= x0 + c(1.3) || y1 <= y0 + c(1.3) {
        return;
    }
    let n = rng.random_range(0..=p.max_furniture);
    for _ in 0..n {
        if rng.random_bool(0.75) {
            let (fw, fh) = (rng.random_range(c(0.3)..=c(1.2)), rng.random_range(c(0.3)..=c(1.2)));
            let fx = rng.random_range(x0..=x1 - fw);
            let fy = rng.random_range(y0..=y1 - fh);
            cv.fill(fx, fy, fx + fw, fy + fh, OCC);
        } else {
            let rad = rng.random_range(c(0.1)..=c(0.3)) as i64;
            let cx = rng.random_range(x0 as i64 + rad..=x1 as i64 - rad);
            let cy = rng.random_range(y0 as i64 + rad..=y1 as i64 - rad);
            for y in cy - rad..=cy + rad {
                for x in cx - rad..=cx + rad {
                    if (x - cx).pow(2) + (y - cy).pow(2) <= rad * rad {
                        cv.cells[y as usize * cv.w + x as usize] = OCC;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::CellState;

    #[test]
    fn plans_are_seeded_walled_and_varied() {
        let p = FloorplanParams::default();
        let a = generate(1, &p);
        assert_eq!(a, generate(1, &p));
        assert_ne!(a.cells(), generate(2, &p).cells());
        assert_eq!((a.width(), a.height()), (500, 380));
        let (free, occ, unknown) = a.state_counts();
        assert!(occ > 5_000 && free > 100_000, "{free} free, {occ} occupied");
        assert_eq!(unknown, 500 * 380 - 480 * 360);
        // the outer wall is closed except where the building ends
        assert_eq!(a.state(10, 10), CellState::Occupied);
        assert_eq!(a.state(0, 0), CellState::Unknown);
    }
}
