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
    ///
    /// `None` for a team of one robot.
    pub merge_pair: Option<[String; 2]>,
    /// Per-robot results, by name.
    pub robots: BTreeMap<String, RobotReport>,
    /// One entry per algorithm.
    pub merges: Vec<MergeResult>,
    /// Jaccard overlap of the true cells the two robots of the merge pair observed.
    pub observed_overlap: f64,
    /// A scenario with a `[team]` table: the merges while driving, coverage and communication.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<TeamReport>,
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
        if let Some(team) = &self.team {
            s += &team.summary();
        }
        if let (true, Some([host, other])) = (self.robots.len() > 2, &self.merge_pair) {
            s += &format!(
                "  merges of {host}'s and {other}'s maps after driving (the other robots' maps are not merged)\n"
            );
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

/// One try at joining two teams' maps while the robots drive.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MergeAttempt {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// The two robots in contact (host team's first).
    pub robots: [String; 2],
    /// The robots of the host's team and of the other's before the try.
    pub teams: [Vec<String>; 2],
    /// The area each team's map knew (free or occupied), m², host's first.
    #[serde(default)]
    pub known_m2: [f64; 2],
    /// Passed the merger's gate: the teams joined.
    pub accepted: bool,
    /// Accepted and within the scenario's success thresholds of the true transform where the two robots meet
    /// (`*_at_contact`); `false` when accepted outside them (a false merge: the teams joined on a wrong
    /// transform) or refused.
    pub correct: bool,
    /// Rotation error of the merger's transform against the truth of the two teams' frames (their roots'
    /// start poses), degrees (null without a transform): the merger's error plus both maps' drift since then.
    pub rotation_error_deg: Option<f64>,
    /// Translation error against the same, metres.
    pub translation_error_m: Option<f64>,
    /// Rotation error against the two maps' relative transform as the two robots' current poses place them
    /// (each map put in the world so that its robot's SLAM pose is the true one), degrees: the merger's own
    /// error where the maps meet, without the drift the maps carry from their starts.
    #[serde(default)]
    pub rotation_error_at_contact_deg: Option<f64>,
    /// Translation error against that same transform at the other robot's position, metres.
    #[serde(default)]
    pub translation_error_at_contact_m: Option<f64>,
    /// The cascade's deciding stage.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    /// Why the gate refused.
    pub reason: Option<String>,
    /// Merge wall time, milliseconds.
    pub time_ms: f64,
    /// The wall time of each stage the merge ran (the cascade's `sift`, `sift+boundary`, `correlative`; a lone
    /// merger's steps), milliseconds.
    #[serde(default)]
    pub stage_ms: BTreeMap<String, f64>,
}

/// A joined team's frontier assignment at one moment.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TeamPlan {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// The team's root robot: the targets are in its SLAM frame.
    pub root: String,
    /// Each exploring robot of the team and its target (x, y in the root's frame; null: none reachable).
    pub targets: BTreeMap<String, Option<[f64; 2]>>,
}

/// A team run's results: coverage of the true free area over time, the online merges, communication.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TeamReport {
    /// Coordination of joined teams (`none` or `frontiers`).
    pub coordination: String,
    /// Communication range, metres.
    pub range_m: f64,
    /// The merger of the online merges.
    pub merger: String,
    /// Free area of the truth the robots can reach, m².
    pub reachable_free_m2: f64,
    /// (simulated time s, share of the reachable free area some robot's map marks free), oldest first.
    pub coverage: Vec<[f64; 2]>,
    /// The last sample's share.
    pub final_coverage: f64,
    /// First time the coverage reached 50 %, seconds (null: never).
    pub time_to_50_s: Option<f64>,
    /// First time it reached 90 %.
    pub time_to_90_s: Option<f64>,
    /// First time it reached 95 %.
    pub time_to_95_s: Option<f64>,
    /// Distance driven by all robots, metres (each robot's is in `robots`).
    pub distance_m: f64,
    /// Of the reachable free area the robots' beams crossed, the share more than one robot's crossed.
    pub redundancy: f64,
    /// Time of the first accepted and correct merge, seconds.
    pub first_correct_merge_s: Option<f64>,
    /// Online merges accepted.
    pub merges_accepted: usize,
    /// Online merges refused by the gate.
    pub merges_refused: usize,
    /// Online merges accepted on a wrong transform (also counted in `merges_accepted`).
    pub merges_false: usize,
    /// Bytes of map messages sent (each a ROS `nav_msgs/OccupancyGrid`: one byte a cell and its header).
    pub bytes_exchanged: u64,
    /// Every merge attempt, in time order.
    pub attempts: Vec<MergeAttempt>,
    /// Every joint plan of a joined team (coordination `frontiers`), in time order.
    pub plans: Vec<TeamPlan>,
    /// The teams at the end: each a list of robot names, its root (the frame of its map) first.
    pub teams: Vec<Vec<String>>,
    /// Carpin's acceptance index of the largest team's merged map against the truth.
    pub team_map_acceptance: Option<f64>,
}

impl TeamReport {
    /// The lines the run's summary prints for the team.
    pub fn summary(&self) -> String {
        let t = |v: Option<f64>| v.map_or("never".to_string(), |s| format!("{s:.0} s"));
        let teams: Vec<String> = self.teams.iter().map(|m| format!("[{}]", m.join(", "))).collect();
        let mut s = format!(
            "  team ({} coordination, range {:.1} m, {}): coverage {:.1} % of {:.0} m² reachable (50 % at {}, 90 % at {}, \
             95 % at {}), {:.0} m driven, redundancy {:.2}\n",
            self.coordination,
            self.range_m,
            self.merger,
            100.0 * self.final_coverage,
            self.reachable_free_m2,
            t(self.time_to_50_s),
            t(self.time_to_90_s),
            t(self.time_to_95_s),
            self.distance_m,
            self.redundancy
        );
        s += &format!(
            "  online merges: {} accepted ({} FALSE), {} refused, first correct at {}; {:.1} MB of maps exchanged; \
             teams {}{}\n",
            self.merges_accepted,
            self.merges_false,
            self.merges_refused,
            t(self.first_correct_merge_s),
            self.bytes_exchanged as f64 / 1e6,
            teams.join(" "),
            self.team_map_acceptance.map_or(String::new(), |a| format!(", team map acceptance {a:.3}"))
        );
        s
    }
}
