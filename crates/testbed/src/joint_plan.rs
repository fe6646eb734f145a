//! Frontier exploration by a team sharing one map: frontier clusters found once, every member's reach
//! searched once, the targets split between members by [`crate::assignment::assign`].

use crate::assignment::{AssignParams, assign};
use crate::frontier::{self, Clearance, MIN_CLUSTER_CELLS, Reach, Skip, WallDistance};
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// One robot of a team, as the team planner sees it.
#[derive(Debug, Clone, Copy)]
pub struct Member<'a> {
    /// Pose in the team map's frame.
    pub pose: Pose2,
    /// Distance kept from walls, metres (also the radius of the robot's own disc).
    pub clearance: Clearance,
    /// Goals it gave up on (the team map's frame): frontier cells near them are no targets for it.
    pub avoid: &'a [Point2<f64>],
}

/// Parameters of [`plan_team`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeamParams {
    /// The assignment's weights.
    pub assign: AssignParams,
    /// Frontier cells this close to a member's given-up goal are no targets for it, metres; by default the
    /// lone explorer's 0.5 m.
    pub avoid_radius: f64,
    /// Frontier clusters of fewer cells are dropped; [`MIN_CLUSTER_CELLS`] by default.
    pub min_cluster: usize,
}

impl Default for TeamParams {
    fn default() -> Self {
        TeamParams { assign: AssignParams::default(), avoid_radius: 0.5, min_cluster: MIN_CLUSTER_CELLS }
    }
}

/// Where a member is sent.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The target point (the team map's frame): a frontier cluster's cell nearest its centroid.
    pub target: Point2<f64>,
    /// The path to it (the team map's frame), from the member's cell, one point every ~0.4 m, ending at the
    /// target.
    pub path: Vec<Point2<f64>>,
}

/// Plans every member of a team on the team's map: per member, the path to its target, or `None` when no
/// frontier is left that it can reach.
///
/// Frontier clusters are found per member (its clearance, its given-up goals; no cluster under any member's
/// disc, where the lidars do not see), the targets of all members pooled (one target per cell), and each
/// member's travel distances measured by one breadth-first search from its pose. A target is a candidate for
/// a member when it is one of the member's own clusters' and the member reaches it. With one member, the
/// result is the nearest reachable cluster target: the lone explorer's rule, up to the clustering.
pub fn plan_team(map: &OccupancyGrid, members: &[Member<'_>], params: &TeamParams) -> Vec<Option<Plan>> {
    let walls = WallDistance::new(map);
    let footprints: Vec<(Point2<f64>, f64)> = members
        .iter()
        .map(|m| (Point2::new(m.pose.translation.x, m.pose.translation.y), m.clearance.preferred))
        .collect();
    // Members of the same clearance and given-up goals see the same clusters: found once for them.
    let first_alike: Vec<usize> = (0..members.len())
        .map(|i| {
            let alike =
                |j: &usize| members[*j].clearance == members[i].clearance && members[*j].avoid == members[i].avoid;
            (0..i).find(alike).unwrap_or(i)
        })
        .collect();
    let work: Vec<(Option<Reach>, Option<Vec<frontier::Frontier>>)> = members
        .par_iter()
        .enumerate()
        .map(|(i, m)| {
            let reach = Reach::new(map, &walls, &m.pose, m.clearance);
            let skip = Skip { avoid: m.avoid, avoid_radius: params.avoid_radius, footprints: &footprints };
            let clusters =
                (first_alike[i] == i).then(|| frontier::frontiers(map, &walls, m.clearance, &skip, params.min_cluster));
            (reach, clusters)
        })
        .collect();
    let searched: Vec<(&Option<Reach>, &[frontier::Frontier])> =
        (0..members.len()).map(|i| (&work[i].0, work[first_alike[i]].1.as_deref().unwrap_or_default())).collect();
    // The pooled targets, by cell in row-major order, each with the members whose clusters hold it.
    let mut pool: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
    for (i, (_, clusters)) in searched.iter().enumerate() {
        for f in clusters.iter() {
            pool.entry((f.cell.1, f.cell.0)).or_default().push(i);
        }
    }
    let cells: Vec<(usize, usize)> = pool.keys().map(|&(iy, ix)| (ix, iy)).collect();
    let targets: Vec<Point2<f64>> = cells.iter().map(|&(ix, iy)| map.cell_center(ix as i64, iy as i64)).collect();
    let costs: Vec<Vec<Option<f64>>> = searched
        .iter()
        .enumerate()
        .map(|(i, &(reach, _))| {
            pool.values()
                .zip(&cells)
                .map(
                    |(owners, &(ix, iy))| {
                        if owners.contains(&i) { reach.as_ref().and_then(|r| r.distance(ix, iy)) } else { None }
                    },
                )
                .collect()
        })
        .collect();
    assign(&targets, &costs, &params.assign)
        .into_iter()
        .zip(&searched)
        .map(|(t, &(reach, _))| {
            let t = t?;
            let (ix, iy) = cells[t];
            let path = reach.as_ref()?.path(map, ix, iy)?;
            Some(Plan { target: targets[t], path })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontier::frontier_path;
    use mrslam_core::pose;

    /// A corridor 2 m wide, walled north and south, known from x = 1 m to x = 9 m, unknown beyond both ends.
    fn corridor() -> OccupancyGrid {
        let mut g = OccupancyGrid::new(200, 40, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..40 {
            for ix in 20..180 {
                g.set(ix, iy, if iy == 0 || iy == 39 { 2.0 } else { -2.0 });
            }
        }
        g
    }

    fn member(x: f64, y: f64) -> Member<'static> {
        Member { pose: pose(x, y, 0.0), clearance: Clearance::uniform(0.2), avoid: &[] }
    }

    #[test]
    fn two_robots_side_by_side_split_the_corridor_s_two_ends() {
        let g = corridor();
        let team = [member(3.0, 0.6), member(3.0, 1.4)];
        // The nearest-frontier rule sends both west, 2 m away rather than 6 m.
        for m in &team {
            let end = *frontier_path(&g, &m.pose, m.clearance, &[], 0.0).unwrap().last().unwrap();
            assert!(end.x < 1.1, "{end:?}");
        }
        let plans = plan_team(&g, &team, &TeamParams::default());
        let targets: Vec<Point2<f64>> = plans.iter().map(|p| p.as_ref().unwrap().target).collect();
        assert!(targets[0].x < 1.1 && targets[1].x > 8.9, "robot 0 west, robot 1 east: {targets:?}");
        for p in plans.iter().flatten() {
            assert_eq!(p.path.last(), Some(&p.target));
            assert!(p.path.windows(2).all(|w| (w[1] - w[0]).norm() <= 0.4 + 1e-9));
        }
        assert_eq!(plans, plan_team(&g, &team, &TeamParams::default()), "same input, same output");
    }

    #[test]
    fn a_frontier_behind_a_wall_is_never_assigned() {
        // The corridor's west end walled off at x = 1.5 m: the west frontier is unreachable for both.
        let mut g = corridor();
        for iy in 0..40 {
            g.set(30, iy, 2.0);
        }
        let team = [member(3.0, 0.6), member(3.0, 1.4)];
        let plans = plan_team(&g, &team, &TeamParams::default());
        for p in &plans {
            let t = p.as_ref().expect("the east end is reachable").target;
            assert!(t.x > 8.9, "{t:?}");
        }
        // Walled off at both ends: nothing to explore.
        for iy in 0..40 {
            g.set(170, iy, 2.0);
        }
        assert_eq!(plan_team(&g, &team, &TeamParams::default()), [None, None]);
    }

    #[test]
    fn one_robot_goes_to_its_nearest_target_as_the_lone_explorer_does() {
        let g = corridor();
        for x in [2.0, 4.0, 6.5, 8.0] {
            let lone = member(x, 1.0);
            let plan = plan_team(&g, &[lone], &TeamParams::default()).remove(0).unwrap();
            let end = *frontier_path(&g, &lone.pose, lone.clearance, &[], 0.0).unwrap().last().unwrap();
            assert!((plan.target - end).norm() < 0.1, "at x = {x}: {plan:?} vs {end:?}");
        }
        // A goal given up on is skipped, as by the lone explorer.
        let avoid = [Point2::new(1.0, 1.0)];
        let lone = Member { avoid: &avoid, ..member(2.0, 1.0) };
        let plan = plan_team(&g, &[lone], &TeamParams { avoid_radius: 1.0, ..TeamParams::default() });
        assert!(plan[0].as_ref().unwrap().target.x > 8.9, "{plan:?}");
    }

    /// A 50 m x 20 m floor (1000 x 400 cells) of 5 m rooms off a corridor, each with a door, half of it seen.
    fn floor() -> OccupancyGrid {
        let mut g = OccupancyGrid::new(1000, 400, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 0..400 {
            for ix in 0..600 {
                let border = ix == 0 || iy == 0 || iy == 399;
                let corridor = (180..220).contains(&iy);
                let room_wall = !corridor && ix % 100 == 0;
                let door = (ix % 100 > 40 && ix % 100 < 60) || (ix % 100 == 0 && (iy % 200 > 80 && iy % 200 < 110));
                let corridor_wall = (iy == 180 || iy == 219) && !door;
                let wall = border || room_wall || corridor_wall;
                g.set(ix, iy, if wall { 2.0 } else { -2.0 });
            }
        }
        g
    }

    #[test]
    fn a_team_of_four_plans_on_a_large_floor() {
        let g = floor();
        let team = [member(5.0, 10.0), member(6.0, 10.0), member(2.5, 5.0), member(12.5, 15.0)];
        let plans = plan_team(&g, &team, &TeamParams::default());
        assert!(plans.iter().all(Option::is_some), "{plans:?}");
        let east = plans.iter().flatten().filter(|p| p.target.x > 29.0).count();
        assert!(east >= 1, "someone takes the unseen east half: {plans:?}");
    }
}
