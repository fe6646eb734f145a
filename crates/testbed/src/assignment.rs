//! Coordinated target assignment for a team of robots (Burgard, Moors, Stachniss and Schneider, "Coordinated
//! multi-robot exploration", IEEE Transactions on Robotics 21(3), 2005).
//!
//! What the library search turned up of the paper (its abstract, IEEE T-RO 21(3) p. 376): each robot's target
//! is chosen by weighing the cost of reaching it against its utility, and once a target is given to a robot
//! the utility of the unexplored area seen from there is lowered for the others, so that the robots end up
//! with different targets. The details below are the paper's Algorithm 1 as we recall it (the search did not
//! return those passages): every target starts with utility 1; repeatedly, among the robots that have no
//! target yet, the pair (robot i, target t) with the largest `U_t - beta * V_t^i` is chosen (`V_t^i`: robot
//! i's cost of reaching t, `beta`: how much cost counts against utility, 1 in their experiments, which found
//! exploration times hardly changing over a wide range of it); then every target t' loses `P(|t - t'|)` of
//! its utility, the chance that t' shows nothing t does not, which the paper approximates as falling
//! linearly with distance: `P(d) = 1 - d / range` below the sensor's range, 0 beyond. The chosen target
//! itself falls to utility 0, so a second robot goes elsewhere unless every other target costs it more than
//! the utility it would bring.
//!
//! Costs: the paper's cost is the length of the cheapest path to the target (computed there by value
//! iteration on the grid; here by a breadth-first search, [`crate::frontier::Reach`]). To make costs
//! commensurable with utilities in [0, 1], we divide every cost by the largest cost of any robot to any
//! target it can reach in this assignment, so that costs also lie in [0, 1]. We could not check the paper's
//! own scaling: this one is our choice.

use nalgebra::Point2;

/// Parameters of [`assign`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssignParams {
    /// Weight of the (normalised) travel cost against the utility; the paper's 1 by default.
    pub beta: f64,
    /// Range of the utility reduction, metres: a target this far or farther from a chosen one keeps its
    /// utility. By default 4 m, the reach of the Hokuyo URG-04LX the testbed's robots carry.
    pub range: f64,
}

impl Default for AssignParams {
    fn default() -> Self {
        AssignParams { beta: 1.0, range: 4.0 }
    }
}

/// The paper's utility reduction `P(d)`: `1 - d / range` for `d < range`, else 0.
pub fn utility_reduction(d: f64, range: f64) -> f64 {
    if d < range { 1.0 - d / range } else { 0.0 }
}

/// Assigns targets to robots: `costs[i][t]` is robot i's travel distance to `targets[t]` in metres, `None`
/// when it cannot reach it. Returns, per robot, the index of its target, or `None` when it reaches none.
///
/// Deterministic: ties go to the lower robot index, then to the lower target index. A robot is given a target
/// another already has only when it reaches no other; every robot that reaches a target gets one.
pub fn assign(targets: &[Point2<f64>], costs: &[Vec<Option<f64>>], params: &AssignParams) -> Vec<Option<usize>> {
    let n = costs.len();
    let mut out = vec![None; n];
    let largest = costs.iter().flatten().flatten().copied().filter(|c| c.is_finite()).fold(0.0f64, f64::max);
    let scale = if largest > 0.0 { 1.0 / largest } else { 0.0 };
    let mut utility = vec![1.0f64; targets.len()];
    let mut open = vec![true; n];
    loop {
        let mut best: Option<(f64, usize, usize)> = None;
        for (i, row) in costs.iter().enumerate().filter(|&(i, _)| open[i]) {
            for (t, cost) in row.iter().enumerate().take(targets.len()) {
                let Some(cost) = cost.filter(|c| c.is_finite()) else { continue };
                let score = utility[t] - params.beta * cost * scale;
                if best.is_none_or(|(b, _, _)| score > b) {
                    best = Some((score, i, t));
                }
            }
        }
        let Some((_, i, t)) = best else { break };
        out[i] = Some(t);
        open[i] = false;
        let chosen = targets[t];
        for (u, p) in utility.iter_mut().zip(targets) {
            *u -= utility_reduction((p - chosen).norm(), params.range);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reduction_falls_linearly_to_zero_at_the_range() {
        assert_eq!(utility_reduction(0.0, 4.0), 1.0);
        assert!((utility_reduction(1.0, 4.0) - 0.75).abs() < 1e-12);
        assert_eq!(utility_reduction(4.0, 4.0), 0.0);
        assert_eq!(utility_reduction(9.0, 4.0), 0.0);
    }

    #[test]
    fn a_second_robot_skips_a_target_half_a_metre_from_the_first_ones() {
        // Targets 0 and 1 lie 0.5 m apart, target 2 far from both; robot 1 is nearest target 1.
        let targets = [Point2::new(5.0, 0.0), Point2::new(5.0, 0.5), Point2::new(0.0, 5.0)];
        let costs = vec![vec![Some(1.0), Some(1.5), Some(6.0)], vec![Some(1.2), Some(1.1), Some(4.0)]];
        // Robot 0 takes target 0 (1 - 1/6 beats robot 1's 1 - 1.1/6); target 1 is left 0.5 / 4 of its utility,
        // so robot 1 prefers target 2 (1 - 4/6) to target 1 (0.125 - 1.1/6).
        assert_eq!(assign(&targets, &costs, &AssignParams::default()), [Some(0), Some(2)]);
        // Without the reduction reaching 0.5 m, robot 1 takes its nearest, next to robot 0's.
        let short = AssignParams { range: 0.4, ..AssignParams::default() };
        assert_eq!(assign(&targets, &costs, &short), [Some(0), Some(1)]);
    }

    #[test]
    fn unreachable_targets_are_never_assigned() {
        let targets = [Point2::new(1.0, 0.0), Point2::new(9.0, 0.0)];
        let costs = vec![vec![None, Some(8.0)], vec![None, Some(7.0)], vec![None, None]];
        assert_eq!(assign(&targets, &costs, &AssignParams::default()), [Some(1), Some(1), None]);
        assert_eq!(assign(&[], &[vec![], vec![]], &AssignParams::default()), [None, None]);
    }

    #[test]
    fn one_robot_takes_the_nearest_target_and_ties_go_to_the_lower_index() {
        let targets = [Point2::new(3.0, 0.0), Point2::new(-1.0, 0.0), Point2::new(0.0, 1.0)];
        let costs = vec![vec![Some(3.0), Some(1.0), Some(1.0)]];
        assert_eq!(assign(&targets, &costs, &AssignParams::default()), [Some(1)]);
        // Two robots with the same costs: robot 0 chooses first.
        let two = vec![costs[0].clone(), costs[0].clone()];
        let out = assign(&targets, &two, &AssignParams::default());
        assert_eq!(out[0], Some(1));
        assert_eq!(out, assign(&targets, &two, &AssignParams::default()), "same input, same output");
    }
}
