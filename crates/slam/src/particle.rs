//! A particle: pose, weights, its own map, and its trajectory as a tree of shared nodes (GMapping's `TNode`).

use crate::tile_map::TileMap;
use mrslam_core::LaserScan;
use mrslam_core::Xyt;
use std::sync::Arc;

/// One processed scan of a particle's trajectory. Nodes are shared between particles descending from a
/// common ancestor, so N trajectories cost one tree.
#[derive(Debug, Clone)]
pub struct TrajectoryNode {
    /// Stamp of the scan, seconds.
    pub stamp: f64,
    /// Robot pose in the map frame when the scan was taken.
    pub pose: Xyt,
    /// The scan (shared by every particle's node for the same update).
    pub scan: Arc<LaserScan>,
    /// The previous processed scan's node.
    pub parent: Option<Arc<TrajectoryNode>>,
}

impl Drop for TrajectoryNode {
    /// Drops long chains iteratively: the default recursive drop could overflow the stack.
    fn drop(&mut self) {
        let mut next = self.parent.take();
        while let Some(node) = next {
            match Arc::try_unwrap(node) {
                Ok(mut n) => next = n.parent.take(),
                Err(_) => break,
            }
        }
    }
}

/// Iterates a trajectory from the newest node to the root.
pub fn ancestry(node: &Option<Arc<TrajectoryNode>>) -> impl Iterator<Item = &TrajectoryNode> {
    let mut cur = node.as_deref();
    std::iter::from_fn(move || {
        let n = cur?;
        cur = n.parent.as_deref();
        Some(n)
    })
}

/// A hypothesis of the robot's path and map.
#[derive(Debug, Clone)]
pub struct Particle {
    /// Current robot pose in the map frame.
    pub pose: Xyt,
    /// Log weight accumulated since the last resampling (GMapping's `weight`).
    pub weight: f64,
    /// Log weight accumulated over the particle's whole lineage (GMapping's `weightSum`): picks the best.
    pub weight_sum: f64,
    /// The particle's map.
    pub map: TileMap,
    /// Newest node of the particle's trajectory.
    pub node: Option<Arc<TrajectoryNode>>,
}

impl Particle {
    /// A particle at the origin with an empty map.
    pub fn new(delta: f64) -> Self {
        Particle {
            pose: Xyt { x: 0.0, y: 0.0, theta: 0.0 },
            weight: 0.0,
            weight_sum: 0.0,
            map: TileMap::new(delta),
            node: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_chains_drop_without_overflow() {
        let scan = Arc::new(LaserScan {
            stamp: 0.0,
            angle_min: 0.0,
            angle_increment: 0.1,
            range_min: 0.0,
            range_max: 1.0,
            ranges: vec![],
        });
        let mut node: Option<Arc<TrajectoryNode>> = None;
        for i in 0..1_000_000 {
            node = Some(Arc::new(TrajectoryNode {
                stamp: i as f64,
                pose: Xyt { x: 0.0, y: 0.0, theta: 0.0 },
                scan: scan.clone(),
                parent: node,
            }));
        }
        assert_eq!(ancestry(&node).count(), 1_000_000);
        let branch = node.clone();
        drop(node);
        assert_eq!(ancestry(&branch).count(), 1_000_000);
        drop(branch);
    }
}
