//! mrslam-viz: the testbed's runs in the rerun viewer — the only crate of the workspace that knows rerun.
//!
//! A [`Recorder`] writes one reproducible recording to any of its [`Target`]s: an `.rrd` file, a viewer it
//! starts (`rerun` on PATH), or a viewer already running (gRPC). On top of it, [`RunRecorder`] records a
//! testbed run (world, robots, particles, scans, growing maps, merges, metrics, events, explorers' goals, the
//! teams' maps, merge attempts and coverage, and a layout) from plain data handed over by the simulation loop,
//! [`SlamLogRecorder`] the SLAM on a recorded log (`mrslam slam`), and [`pair::record_pair`] a stand-alone merge of
//! two maps.
//! [`inspect::summarize`] reads a recording back with rerun's own decoder.
//!
//! Entity paths (ARCHITECTURE.md, "Recordings"): `world/{walls,truth_map}`,
//! `robots/<name>/{truth,truth/path,odom,odom/path,slam/pose,slam/path,slam/particles,slam/goal,slam/goal/path,scan}`,
//! `maps/<name>`, `merge/<algorithm>/{keypoints/<name>,matches,merged}`, `metrics/{error,neff,slip}/...`, `events`;
//! a run with teams adds `team/{maps/<root>,attempts,events}` and `metrics/{coverage,merges}/...`; a SLAM run
//! on a log adds `robots/<name>/{odom/pose,relations}` and `metrics/{realtime,relations}/...`; timelines
//! `sim_time` (seconds) and `step`. Nothing here runs unless a recording was asked for.
//!
//! ```
//! use mrslam_viz::{Recorder, Target};
//!
//! // A recording written to a file: under a temporary name until it is finished.
//! let path = std::env::temp_dir().join(format!("mrslam-viz-doc-{}.rrd", std::process::id()));
//! let recorder = Recorder::open(&[Target::File(path.clone())], "doc", "doc").unwrap();
//! recorder.finish().unwrap();
//! assert!(path.exists());
//! std::fs::remove_file(&path).unwrap();
//! ```

#![deny(missing_docs)]

// Private modules, their items re-exported below; `inspect`, `pair` and `paths` are public namespaces
// (`inspect::summarize`, `pair::record_pair`, the entity paths), their items not re-exported.
mod blueprint;
mod convert;
mod error;
pub mod inspect;
mod maps;
mod metrics;
pub mod pair;
pub mod paths;
mod recorder;
mod robot;
mod run;
mod slam_log;
mod target;
mod team;
mod world;

pub use error::VizError;
pub use metrics::Level;
pub use recorder::{Recorder, RecordingStats};
pub use run::{MergeView, Rates, RobotInfo, RunRecorder, SlamState};
pub use slam_log::{ProcessedScan, RelationMark, SlamLogRecorder};
pub use target::{DEFAULT_CONNECT, Target, partial_path};
pub use team::{ATTEMPT_REFUSED, ATTEMPT_SHOW_S, AttemptOutcome, AttemptView};
