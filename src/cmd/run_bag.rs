//! `--mcap OUT.mcap` of `mrslam run` and `mrslam sim log`: the simulated run as a ROS 2 bag, written as the run
//! goes (through the run's per-step tap) under a temporary name, renamed when the run's maps are in it.

use anyhow::{Context, Result};
use mrslam_core::Odometry;
use mrslam_core::output::AtomicFile;
use mrslam_log::{RunBagWriter, WORLD_FRAME, robot_frame};
use mrslam_testbed::runner::{RobotStep, RunOutput};
use mrslam_testbed::scenario::Scenario;
use std::path::{Path, PathBuf};

/// A run's bag as it is written.
pub struct RunBag {
    path: PathBuf,
    /// The hidden name it is written under until the rename.
    partial: PathBuf,
    writer: RunBagWriter<AtomicFile>,
    /// The first write error: the run goes on, the bag is refused at the end.
    error: Option<anyhow::Error>,
}

/// A bag ready to be renamed into place.
pub struct FinishedBag {
    path: PathBuf,
    file: AtomicFile,
}

impl RunBag {
    /// Starts the bag of `scenario` at `path` (checked by the output rule before): `/tf_static` with every
    /// robot's laser mount.
    pub fn create(path: &Path, scenario: &Scenario) -> Result<Self> {
        let context = || format!("--mcap {}", path.display());
        let file = AtomicFile::create(path).with_context(context)?;
        let partial = file.temporary_path().to_path_buf();
        let mut writer = RunBagWriter::new(file).with_context(context)?;
        let mounts: Vec<(&str, _)> = scenario.robots.iter().map(|r| (r.name.as_str(), r.lidar.mount)).collect();
        writer.mounts(0.0, &mounts).with_context(context)?;
        Ok(Self { path: path.to_path_buf(), partial, writer, error: None })
    }

    /// The hidden name the bag is written under until it is complete: removed on an interruption.
    pub fn temporary(&self) -> &Path {
        &self.partial
    }

    /// Writes what robot `s.robot` did in a step: its SLAM's `map -> odom` (as it stood before the step's
    /// scans), the scans that came in (received at the step's end), its odometry with its `/tf`, its true pose.
    pub fn step(&mut self, s: &RobotStep<'_>) {
        if self.error.is_some() {
            return;
        }
        let w = &mut self.writer;
        let written = (|| {
            if let Some(t) = &s.map_to_odom {
                w.map_to_odom(s.name, s.time, t)?;
            }
            for scan in s.scans {
                w.scan(s.name, s.time, scan)?;
            }
            w.odometry(s.name, &Odometry { stamp: s.time, pose: s.odometry.pose })?;
            w.ground_truth(s.name, s.time, s.true_pose)
        })();
        if let Err(e) = written {
            self.error = Some(anyhow::Error::new(e).context(format!("--mcap {}", self.path.display())));
        }
    }

    /// Writes the run's maps (each robot's as `/NAME/map`, the truth as `/truth_map` in the world frame, each
    /// accepted merge in the host's map frame: `/merged_map`, or `/merged_map/ALGORITHM` when several
    /// algorithms ran), stamped at the end of the drive, and the bag's summary.
    pub fn finish(self, out: &RunOutput) -> Result<FinishedBag> {
        let context = || format!("--mcap {}", self.path.display());
        if let Some(e) = self.error {
            return Err(e);
        }
        let mut w = self.writer;
        let t = out.report.sim_s;
        for (name, map) in &out.maps {
            w.map(&format!("/{name}/map"), &robot_frame(name, "map"), t, map).with_context(context)?;
        }
        w.map("/truth_map", WORLD_FRAME, t, &out.truth).with_context(context)?;
        let host = out.report.merge_pair.as_ref().map_or("", |[host, _]| host.as_str());
        let host_frame = robot_frame(host, "map");
        for m in &out.merges {
            if let Some(g) = &m.merged {
                let topic = match out.merges.len() {
                    1 => "/merged_map".to_string(),
                    _ => format!("/merged_map/{}", m.report.algorithm),
                };
                w.map(&topic, &host_frame, t, g).with_context(context)?;
            }
        }
        let file = w.finish().with_context(context)?;
        Ok(FinishedBag { path: self.path, file })
    }
}

impl FinishedBag {
    /// Renames the bag into place; returns its path.
    pub fn commit(self) -> Result<PathBuf> {
        self.file.commit()?;
        Ok(self.path)
    }
}
