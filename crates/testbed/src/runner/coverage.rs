//! How much of the building the robots have mapped, from the truth: the free area a robot can reach, and the
//! share of it some robot's map marks free where the truth is free.

use mrslam_core::{CellState, OccupancyGrid, Pose2};
use std::collections::VecDeque;

/// The reachable free cells of the true map and what a robot's map says of them.
pub(super) struct Coverage {
    /// Indices (into the truth's cells) of the free cells a robot of the team can sweep with its body: free cells
    /// within a body radius of a place its centre can reach from a start.
    reachable: Vec<usize>,
    /// Area of one truth cell, m².
    cell_area: f64,
}

impl Coverage {
    /// The free area of `truth` reachable from `starts` by a robot of bounding radius `radius` (metres).
    ///
    /// The centre can stand where no occupied cell lies within `radius` (8-connected steps, so a little more
    /// than a disc); the area counted is the free cells within `radius` of such places: what the robot's body
    /// could sweep, hence what its lidar sees first.
    pub(super) fn new(truth: &OccupancyGrid, starts: &[Pose2], radius: f64) -> Self {
        let (w, h) = (truth.width(), truth.height());
        let r = (radius / truth.resolution()).ceil().max(1.0) as u32;
        let free: Vec<bool> = truth.cells().iter().map(|&l| CellState::from_log_odds(l) == CellState::Free).collect();
        let near_wall = within(w, h, r, (0..w * h).filter(|&i| truth.cells()[i] > 0.0 && !free[i]).collect(), |_| true);
        let seeds: Vec<usize> = starts
            .iter()
            .filter_map(|s| truth.world_to_cell(&nalgebra::Point2::from(s.translation.vector)))
            .map(|(x, y)| y * w + x)
            .collect();
        let centre = within(w, h, u32::MAX, seeds, |i| free[i] && near_wall[i] == u32::MAX);
        let swept = within(w, h, r, (0..w * h).filter(|&i| centre[i] != u32::MAX).collect(), |i| free[i]);
        let reachable = (0..w * h).filter(|&i| free[i] && swept[i] != u32::MAX).collect();
        Coverage { reachable, cell_area: truth.resolution() * truth.resolution() }
    }

    /// The reachable free area, m².
    pub(super) fn reachable_m2(&self) -> f64 {
        self.reachable.len() as f64 * self.cell_area
    }

    /// Share of the reachable free area that at least one of `maps` marks free; each map is in its own frame,
    /// placed in the world by its pose.
    pub(super) fn fraction(&self, truth: &OccupancyGrid, maps: &[(&OccupancyGrid, Pose2)]) -> f64 {
        if self.reachable.is_empty() {
            return 0.0;
        }
        let w = truth.width();
        let covered = self
            .reachable
            .iter()
            .filter(|&&i| {
                let p = truth.cell_center((i % w) as i64, (i / w) as i64);
                maps.iter().any(|(m, frame)| {
                    let q = frame.inverse_transform_point(&p);
                    let (x, y) = m.world_to_cell_i(&q);
                    m.get_checked(x, y).is_some_and(|l| CellState::from_log_odds(l) == CellState::Free)
                })
            })
            .count();
        covered as f64 / self.reachable.len() as f64
    }

    /// Of the reachable free cells some robot's beams crossed, the share more than one robot's crossed (each of
    /// `observed` is one robot's mark per truth cell); 0 when none was seen.
    pub(super) fn redundancy(&self, observed: &[&[bool]]) -> f64 {
        let (mut once, mut more) = (0usize, 0usize);
        for &i in &self.reachable {
            match observed.iter().filter(|o| o.get(i).copied().unwrap_or(false)).count() {
                0 => {}
                1 => once += 1,
                _ => more += 1,
            }
        }
        if once + more == 0 { 0.0 } else { more as f64 / (once + more) as f64 }
    }
}

/// Breadth-first steps (8-connected) from `seeds` through the cells `open` lets in, at most `limit` steps:
/// each cell's step count, `u32::MAX` where not reached. Seeds count as reached whatever `open` says.
fn within(w: usize, h: usize, limit: u32, seeds: Vec<usize>, open: impl Fn(usize) -> bool) -> Vec<u32> {
    let mut steps = vec![u32::MAX; w * h];
    let mut queue = VecDeque::with_capacity(seeds.len());
    for s in seeds {
        if s < w * h && steps[s] == u32::MAX {
            steps[s] = 0;
            queue.push_back(s);
        }
    }
    while let Some(c) = queue.pop_front() {
        let d = steps[c];
        if d >= limit {
            continue;
        }
        let (x, y) = ((c % w) as i64, (c / w) as i64);
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)] {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                continue;
            }
            let n = ny as usize * w + nx as usize;
            if steps[n] == u32::MAX && open(n) {
                steps[n] = d + 1;
                queue.push_back(n);
            }
        }
    }
    steps
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;

    /// Two 2 m x 2 m rooms (0.05 m cells) joined by a door `door` cells wide, walled all round.
    fn two_rooms(door: usize) -> OccupancyGrid {
        let mut g = OccupancyGrid::new(82, 42, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..42 {
            for ix in 0..82 {
                let outer = ix == 0 || iy == 0 || ix == 81 || iy == 41;
                let middle = ix == 41 && !(21 - door / 2..21 - door / 2 + door).contains(&iy);
                g.set(ix, iy, if outer || middle { 3.0 } else { -3.0 });
            }
        }
        g
    }

    #[test]
    fn a_door_narrower_than_the_robot_keeps_the_other_room_out_of_reach() {
        let start = [pose(1.0, 1.0, 0.0)];
        let wide = Coverage::new(&two_rooms(16), &start, 0.2);
        let narrow = Coverage::new(&two_rooms(4), &start, 0.2);
        // One room is 40 x 40 cells = 4 m²; with a 0.8 m door the robot reaches both.
        assert!((narrow.reachable_m2() - 4.0).abs() < 0.05, "{}", narrow.reachable_m2());
        assert!(wide.reachable_m2() > 7.9, "{}", wide.reachable_m2());
    }

    #[test]
    fn coverage_counts_free_cells_of_any_map_placed_by_its_frame() {
        let truth = two_rooms(16);
        let cov = Coverage::new(&truth, &[pose(1.0, 1.0, 0.0)], 0.2);
        // A map of the west room only, in a frame whose origin is the robot's start (1, 1) in the world.
        let mut west = OccupancyGrid::new(40, 40, 0.05, pose(-0.95, -0.95, 0.0)).unwrap();
        west.cells_mut().fill(-3.0);
        let at_start = pose(1.0, 1.0, 0.0);
        let half = cov.fraction(&truth, &[(&west, at_start)]);
        assert!((half - 0.5).abs() < 0.03, "{half}");
        // The same map placed 2 m east covers the east room: together, everything.
        let east = pose(3.05, 1.0, 0.0);
        let all = cov.fraction(&truth, &[(&west, at_start), (&west, east)]);
        assert!(all > 0.97, "{all}");
        // Occupied or unknown cells cover nothing.
        let mut wrong = west.clone();
        wrong.cells_mut().fill(3.0);
        assert_eq!(cov.fraction(&truth, &[(&wrong, at_start)]), 0.0);
        assert_eq!(cov.fraction(&truth, &[]), 0.0);
    }

    #[test]
    fn redundancy_is_the_share_seen_twice() {
        let truth = two_rooms(16);
        let cov = Coverage::new(&truth, &[pose(1.0, 1.0, 0.0)], 0.2);
        let n = truth.width() * truth.height();
        let all = vec![true; n];
        let none = vec![false; n];
        assert_eq!(cov.redundancy(&[&all, &none]), 0.0);
        assert_eq!(cov.redundancy(&[&all, &all]), 1.0);
        assert_eq!(cov.redundancy(&[&none, &none]), 0.0);
        let west: Vec<bool> = (0..n).map(|i| i % truth.width() < 41).collect();
        let r = cov.redundancy(&[&all, &west]);
        assert!((r - 0.5).abs() < 0.03, "{r}");
    }
}
