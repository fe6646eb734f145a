//! Relations drawn from a true trajectory, so that a generated log can be scored with Kümmerle's metric as the
//! benchmark logs are ([`crate::relations`]).
//!
//! Kümmerle et al. 2009 chose pairs of scans a person verified to overlap: mostly scans close in time, some
//! across loops. With the truth known, both kinds are drawn exactly: a *local* relation from every scan to the
//! first later scan at least `local_travel` metres (or `local_turn` radians) away, and a *loop* relation each
//! `loop_spacing` metres of driving that brings the robot back within `loop_radius` of where it was at least
//! `loop_min_travel` metres of driving earlier. The loop relations score what the local ones cannot: whether
//! the map closed its loops.

use crate::pose::normalize_angle;
use crate::relations::{Relation, StampedPose};

/// How relations are drawn from a true trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthRelations {
    /// A local relation joins a scan to the first later scan this many metres of driving away...
    pub local_travel: f64,
    /// ... or this many radians of turning, whichever comes first.
    pub local_turn: f64,
    /// A loop relation joins poses at most this far apart, metres.
    pub loop_radius: f64,
    /// ... whose headings differ by at most this much, radians (the scans must see the same walls).
    pub loop_heading: f64,
    /// ... with at least this many metres of driving between them.
    pub loop_min_travel: f64,
    /// At most one loop relation per this many metres of driving.
    pub loop_spacing: f64,
}

impl Default for TruthRelations {
    fn default() -> Self {
        Self {
            local_travel: 1.0,
            local_turn: 0.5,
            loop_radius: 1.0,
            loop_heading: std::f64::consts::FRAC_PI_4,
            loop_min_travel: 20.0,
            loop_spacing: 2.0,
        }
    }
}

/// What [`relations_from_truth`] drew.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DrawnRelations {
    /// Relations between scans close in driving, in stamp order of their first scan.
    pub local: Vec<Relation>,
    /// Relations across loops, in stamp order of their second scan.
    pub loops: Vec<Relation>,
    /// The metres driven between the two scans of each loop relation, in the order of `loops`.
    pub loop_lengths: Vec<f64>,
}

impl DrawnRelations {
    /// Every relation, local ones first, numbered by their line in a file that lists them in that order.
    pub fn all(&self) -> Vec<Relation> {
        self.local.iter().chain(&self.loops).enumerate().map(|(i, r)| Relation { line: i + 1, ..*r }).collect()
    }
}

/// Draws relations from `truth` (one pose per scan, in stamp order) as `params` says.
pub fn relations_from_truth(truth: &[StampedPose], params: &TruthRelations) -> DrawnRelations {
    let relation = |i: usize, j: usize| Relation {
        t1: truth[i].stamp,
        t2: truth[j].stamp,
        delta: truth[i].pose.inv_mul(&truth[j].pose),
        line: 0,
    };
    // Metres driven up to each scan.
    let mut travel = Vec::with_capacity(truth.len());
    let mut driven = 0.0;
    for (k, p) in truth.iter().enumerate() {
        if k > 0 {
            driven += (p.pose.translation.vector - truth[k - 1].pose.translation.vector).norm();
        }
        travel.push(driven);
    }
    let heading = |k: usize| truth[k].pose.rotation.angle();
    let mut local = Vec::new();
    let mut j = 0;
    for i in 0..truth.len() {
        j = j.max(i + 1);
        // The turn from i is not monotonic in j; the travel is, so j only moves forward.
        while j < truth.len()
            && travel[j] - travel[i] < params.local_travel
            && normalize_angle(heading(j) - heading(i)).abs() < params.local_turn
        {
            j += 1;
        }
        if j < truth.len() {
            local.push(relation(i, j));
        }
    }
    let mut loops = Vec::new();
    let mut loop_lengths = Vec::new();
    let mut next_at = 0.0;
    for j in 0..truth.len() {
        if travel[j] < next_at {
            continue;
        }
        let here = truth[j].pose.translation.vector;
        let earlier = (0..j).take_while(|&i| travel[j] - travel[i] >= params.loop_min_travel);
        let nearest = earlier
            .filter(|&i| normalize_angle(heading(j) - heading(i)).abs() <= params.loop_heading)
            .map(|i| (i, (truth[i].pose.translation.vector - here).norm()))
            .filter(|&(_, d)| d <= params.loop_radius)
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        if let Some((i, _)) = nearest {
            loops.push(relation(i, j));
            loop_lengths.push(travel[j] - travel[i]);
            next_at = travel[j] + params.loop_spacing;
        }
    }
    DrawnRelations { local, loops, loop_lengths }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relations::score;
    use crate::se2::pose;
    use std::f64::consts::PI;

    /// A robot driving a square of side 10 m twice, a pose every 0.1 m, stamped 0.1 s apart.
    fn square_twice() -> Vec<StampedPose> {
        let mut poses = Vec::new();
        for lap in 0..2 {
            for side in 0..4 {
                let theta = side as f64 * PI / 2.0;
                let (c, s) = (theta.cos(), theta.sin());
                let corner = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)][side];
                for k in 0..100 {
                    let d = k as f64 * 0.1;
                    let stamp = (lap * 400 + side * 100 + k) as f64 * 0.1;
                    poses.push(StampedPose { stamp, pose: pose(corner.0 + c * d, corner.1 + s * d, theta) });
                }
            }
        }
        poses
    }

    #[test]
    fn the_truth_scores_zero_and_loop_relations_join_the_laps() {
        let truth = square_twice();
        let drawn = relations_from_truth(&truth, &TruthRelations::default());
        // Every scan but those of the last metre has a local relation, about 1 m (10 or 11 scans, as the sums
        // of 0.1 m round) ahead, or sooner across a corner's quarter turn.
        assert!((truth.len() - 11..=truth.len() - 10).contains(&drawn.local.len()), "{}", drawn.local.len());
        assert!(drawn.local.iter().all(|r| r.t2 > r.t1 && r.t2 - r.t1 < 1.15), "{:?}", drawn.local);
        assert!(drawn.local.iter().filter(|r| r.t2 - r.t1 < 0.95).count() >= 8, "the corners' turns count");
        // The second lap revisits the first: loop relations from 40 m of driving on, one per 2 m, each between
        // the same place on both laps (exactly 40 m of driving apart, the nearest earlier pose).
        assert_eq!(drawn.loops.len(), 20, "{:?}", drawn.loops.len());
        for (r, length) in drawn.loops.iter().zip(&drawn.loop_lengths) {
            assert!((r.t2 - r.t1 - 40.0).abs() < 1e-9, "{r:?}");
            assert!((length - 40.0).abs() < 1e-6, "{length}");
            assert!(r.delta.translation.vector.norm() < 1e-9);
        }
        let all = drawn.all();
        assert_eq!(all.last().map(|r| r.line), Some(all.len()));
        let s = score(&truth, &all, 1e-6);
        assert_eq!(s.used(), all.len());
        assert!(s.translation.max < 1e-9 && s.rotation.max < 1e-9);
    }

    #[test]
    fn a_trajectory_that_does_not_close_its_loop_shows_in_the_loop_relations_only() {
        let truth = square_twice();
        // The second lap drifted 0.5 m sideways: consecutive poses keep their relations, the loops do not.
        let est: Vec<StampedPose> = truth
            .iter()
            .enumerate()
            .map(|(k, p)| StampedPose { pose: if k >= 400 { pose(0.0, 0.5, 0.0) * p.pose } else { p.pose }, ..*p })
            .collect();
        let drawn = relations_from_truth(&truth, &TruthRelations::default());
        let loops = score(&est, &drawn.loops, 1e-6);
        assert!((loops.translation.mean - 0.5).abs() < 1e-9, "{:?}", loops.translation);
        let local = score(&est, &drawn.local, 1e-6);
        assert!(local.translation.max < 0.51 && local.translation.mean < 0.01, "{:?}", local.translation);
    }

    #[test]
    fn format_and_parse_round_trip() {
        let drawn = relations_from_truth(&square_twice(), &TruthRelations::default());
        let text = crate::relations::format_relations("generated", &drawn.all());
        let back = crate::relations::parse_relations(&text, std::path::Path::new("r")).unwrap();
        assert_eq!(back.len(), drawn.all().len());
        for (a, b) in back.iter().zip(drawn.all()) {
            assert_eq!(a.line, b.line + 1, "the header line shifts the numbers");
            assert!(
                (a.t1 - b.t1).abs() < 1e-6 && (a.delta.translation.vector - b.delta.translation.vector).norm() < 1e-5
            );
        }
    }
}
