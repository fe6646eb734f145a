//! The run report (`report.json`) and its human summary.

use mrslam_core::Xyt;
use std::collections::BTreeMap;

/// Per-robot results.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobotReport {
    /// RMS position error of the SLAM trajectory (final best particle) against truth, metres.
    pub slam_rmse_m: f64,
    /// RMS position error of raw odometry against truth over the same stamps, metres.
    pub odom_rmse_m: f64,
    /// Acceptance index of the robot's map against the true map.
    pub map_acceptance: f64,
    /// Final position error of SLAM, metres.
    pub slam_final_error_m: f64,
    /// Final position error of odometry, metres.
    pub odom_final_error_m: f64,
    /// Scans delivered by the lidar.
    pub scans: usize,
    /// Scans the filter processed (it skips scans until the robot has moved enough).
    pub processed: usize,
    /// Resampling steps.
    pub resamples: usize,
    /// Effective sample size after the last update.
    pub final_neff: f64,
    /// Distance driven (truth), metres.
    pub distance_m: f64,
    /// Steps during which the robot touched an obstacle.
    pub contact_steps: usize,
    /// Whether the robot finished its route or exploration.
    pub finished: bool,
    /// Wall time spent in this robot's SLAM, seconds.
    pub slam_s: f64,
}

/// One merge, evaluated.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MergeResult {
    /// Algorithm.
    pub algorithm: String,
    /// Passed the verification gate.
    pub accepted: bool,
    /// Accepted and within the scenario's thresholds of the truth.
    pub success: bool,
    /// Rotation error against the true relative transform, degrees (null when no transform was found).
    pub rotation_error_deg: Option<f64>,
    /// Translation error against the true relative transform, metres.
    pub translation_error_m: Option<f64>,
    /// Rotation error, degrees, against the relative transform of the two maps as the robots' last poses place
    /// them (each map frame put in the world so that its robot's final SLAM pose is the true one).
    ///
    /// Where the robots end at a common point, in the overlap of their maps (the paper's scenarios), this
    /// separates what the merger got wrong from what the two SLAM maps' own drift since their start frames
    /// adds to `rotation_error_deg`; where they end apart, each map's error at its robot's end counts.
    #[serde(default)]
    pub rotation_error_at_end_deg: Option<f64>,
    /// Translation error against that same transform, metres.
    #[serde(default)]
    pub translation_error_at_end_m: Option<f64>,
    /// Acceptance index of the two aligned maps (the algorithm's own verification).
    pub acceptance_index: Option<f64>,
    /// Acceptance index of the merged map against the true map.
    pub merged_map_acceptance: Option<f64>,
    /// Merge wall time, milliseconds.
    pub time_ms: f64,
    /// Why it was rejected.
    pub reason: Option<String>,
    /// The stage of a cascade that decided (its last stage for a refusal); none for one algorithm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    /// Estimated transform (host ← other).
    pub transform: Option<Xyt>,
    /// True transform (host ← other).
    pub true_transform: Xyt,
    /// The maps' relative transform as the robots' last poses place them (host ← other).
    pub true_transform_at_end: Xyt,
    /// Inliers and matches of the algorithm.
    pub inliers: usize,
    /// Tentative matches.
    pub matches: usize,
}

/// Everything a run produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunReport {
    /// Scenario name.
    pub scenario: String,
    /// Seed.
    pub seed: u64,
    /// Simulated time, seconds.
    pub sim_s: f64,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// Physics steps.
    pub steps: u64,
    /// Simulated time at which the maps were merged.
    pub merge_at_s: f64,
    /// The robots whose maps were merged: the host (the merge's frame), and the robot whose map was merged into
    /// it. With more than two robots, the others' maps are evaluated but not merged.
    pub merge_pair: [String; 2],
    /// Per-robot results, by name.
    pub robots: BTreeMap<String, RobotReport>,
    /// One entry per algorithm.
    pub merges: Vec<MergeResult>,
    /// Jaccard overlap of the true cells the two robots of the merge pair observed.
    pub observed_overlap: f64,
}

impl RunReport {
    /// The short human summary printed after a run.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "scenario {} (seed {}): {:.1} s simulated in {:.1} s wall ({:.0}x real time), merge at {:.1} s, observed overlap {:.3}\n",
            self.scenario,
            self.seed,
            self.sim_s,
            self.wall_s,
            self.sim_s / self.wall_s.max(1e-9),
            self.merge_at_s,
            self.observed_overlap
        );
        for (name, r) in &self.robots {
            s += &format!(
                "  {name:8} SLAM RMSE {:.3} m (odometry {:.3} m), final error {:.3} m (odometry {:.3} m), map acceptance {:.3}, {}/{} scans processed, {:.1} m driven{}\n",
                r.slam_rmse_m,
                r.odom_rmse_m,
                r.slam_final_error_m,
                r.odom_final_error_m,
                r.map_acceptance,
                r.processed,
                r.scans,
                r.distance_m,
                if r.finished { "" } else { ", route NOT finished" }
            );
        }
        if self.robots.len() > 2 {
            let [host, other] = &self.merge_pair;
            s += &format!("  merges of {host}'s and {other}'s maps (the other robots' maps are not merged)\n");
        }
        for m in &self.merges {
            let at_end = match (m.rotation_error_at_end_deg, m.translation_error_at_end_m) {
                (Some(r), Some(t)) => format!(" (at the robots' last poses {r:.2} deg, {t:.3} m)"),
                _ => String::new(),
            };
            let err = match (m.rotation_error_deg, m.translation_error_m) {
                (Some(r), Some(t)) => format!("error {r:.2} deg, {t:.3} m{at_end}"),
                _ => "no transform".to_string(),
            };
            s += &format!(
                "  merge {:5} {} ({}), {err}, {} inliers of {} matches, {:.0} ms{}\n",
                m.algorithm,
                if m.accepted { "accepted" } else { "rejected" },
                if m.success { "SUCCESS" } else { "failure" },
                m.inliers,
                m.matches,
                m.time_ms,
                m.reason.as_ref().map_or(String::new(), |r| format!(": {r}"))
            );
        }
        s
    }
}
