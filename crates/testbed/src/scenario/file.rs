//! The scenario file as written: TOML tables before they are checked and resolved.

use serde::Deserialize;
use std::collections::BTreeMap;

/// The whole file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ScenarioFile {
    pub(super) name: Option<String>,
    pub(super) description: Option<String>,
    pub(super) world: String,
    pub(super) seed: u64,
    pub(super) duration: f64,
    pub(super) dt: Option<f64>,
    pub(super) truth_resolution: Option<f64>,
    pub(super) robots: Vec<RobotFile>,
    #[serde(default)]
    pub(super) merge: MergeFile,
    #[serde(default)]
    pub(super) success: SuccessFile,
    pub(super) team: Option<TeamFile>,
}

/// A pose: a named point of the world, `[x, y, theta]` or a table `{ x, y, theta }` as world files write
/// their named points (theta in radians, default 0).
#[derive(Deserialize)]
#[serde(untagged, expecting = "a pose: a named point of the world, [x, y, theta] or { x = .., y = .., theta = .. }")]
pub(super) enum PoseRef {
    Named(String),
    Xyt([f64; 3]),
    Table(mrslam_sim::NamedPoint),
}

/// A point: a named point of the world, `[x, y]` or a table `{ x, y }` (a `theta` is allowed and ignored).
#[derive(Deserialize)]
#[serde(untagged, expecting = "a point: a named point of the world, [x, y] or { x = .., y = .. }")]
pub(super) enum PointRef {
    Named(String),
    Xy([f64; 2]),
    Table(mrslam_sim::NamedPoint),
}

/// A lidar: a preset's name or a table.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum LidarRef {
    Preset(String),
    Table(LidarFile),
}

/// A lidar table: a preset and the values that change it.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct LidarFile {
    pub(super) preset: Option<String>,
    pub(super) fov_deg: Option<f64>,
    pub(super) resolution_deg: Option<f64>,
    pub(super) range_min: Option<f64>,
    pub(super) range_max: Option<f64>,
    pub(super) scan_period: Option<f64>,
    pub(super) range_noise_const: Option<f64>,
    pub(super) range_noise_prop: Option<f64>,
    pub(super) angular_jitter_deg: Option<f64>,
    pub(super) dropout_prob: Option<f64>,
    pub(super) mount: Option<[f64; 3]>,
    pub(super) skew: Option<bool>,
}

/// A robot's `slip` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct SlipFile {
    pub(super) none: Option<bool>,
    pub(super) speed_noise: Option<f64>,
    pub(super) turn_noise: Option<f64>,
    pub(super) noise_correlation_time: Option<f64>,
    pub(super) event_rate: Option<f64>,
    pub(super) event_turn_gain: Option<f64>,
    pub(super) event_duration: Option<f64>,
    pub(super) event_magnitude: Option<f64>,
}

/// A robot's `encoder` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct EncoderFile {
    pub(super) ticks_per_rev: Option<u32>,
    pub(super) left_radius_error: Option<f64>,
    pub(super) right_radius_error: Option<f64>,
    pub(super) wheel_base_error: Option<f64>,
}

/// A robot's `slam` table: an optional `preset`, then any parameter of [`mrslam_slam::SlamParams::set`] by name.
#[derive(Deserialize, Default)]
pub(super) struct SlamFile {
    pub(super) preset: Option<String>,
    #[serde(flatten)]
    pub(super) params: BTreeMap<String, toml::Value>,
}

/// One `[[robots]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RobotFile {
    pub(super) name: String,
    pub(super) model: String,
    pub(super) lidar: LidarRef,
    pub(super) start: PoseRef,
    #[serde(default)]
    pub(super) route: Vec<PointRef>,
    pub(super) controller: Option<String>,
    pub(super) speed: Option<f64>,
    pub(super) lookahead: Option<f64>,
    pub(super) odometry: Option<String>,
    #[serde(default)]
    pub(super) slip: SlipFile,
    #[serde(default)]
    pub(super) encoder: EncoderFile,
    #[serde(default)]
    pub(super) slam: SlamFile,
}

/// The `[merge]` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct MergeFile {
    pub(super) when: Option<toml::Value>,
    pub(super) algorithms: Option<Vec<String>>,
    pub(super) model: Option<String>,
    pub(super) ratio: Option<f32>,
    pub(super) encoding: Option<String>,
    pub(super) candidates: Option<usize>,
    pub(super) hypotheses: Option<usize>,
    pub(super) wall_dilation: Option<usize>,
    pub(super) upscale: Option<bool>,
    pub(super) host: Option<String>,
}

/// The `[success]` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct SuccessFile {
    pub(super) rotation_deg: Option<f64>,
    pub(super) translation_m: Option<f64>,
}

/// The `[team]` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct TeamFile {
    pub(super) range: Option<f64>,
    pub(super) line_of_sight: Option<bool>,
    pub(super) exchange_period: Option<f64>,
    pub(super) coordination: Option<String>,
    pub(super) merger: Option<String>,
    pub(super) coverage_period: Option<f64>,
    pub(super) beta: Option<f64>,
    pub(super) min_known_m2: Option<f64>,
    pub(super) search_near_contact: Option<bool>,
}
