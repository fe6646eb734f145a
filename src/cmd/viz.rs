//! The rerun flags shared by `mrslam run` and `mrslam merge`: --rrd, --spawn, --connect.

use anyhow::Result;
use clap::Args;
use mrslam_viz::{Recorder, Target};
use std::path::PathBuf;

/// Where to send a rerun recording (none of them: nothing is recorded).
#[derive(Args, Debug, Default)]
pub struct VizArgs {
    /// Save a rerun recording here (.rrd; open it with `rerun FILE`). Reproducible: same input, same recorded content.
    #[arg(long, value_name = "FILE")]
    pub rrd: Option<PathBuf>,
    /// Start the rerun viewer (`rerun` on PATH; `pip install rerun-sdk==0.36.3`) and stream to it.
    #[arg(long)]
    pub spawn: bool,
    /// Stream to a running rerun viewer at ADDR (HOST:PORT or rerun+http://HOST:PORT/proxy;
    /// default 127.0.0.1:9876).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = mrslam_viz::DEFAULT_CONNECT)]
    pub connect: Option<String>,
}

impl VizArgs {
    /// The destinations asked for.
    pub fn targets(&self) -> Result<Vec<Target>> {
        let mut t = Vec::new();
        if let Some(p) = &self.rrd {
            t.push(Target::File(p.clone()));
        }
        if self.spawn {
            t.push(Target::Spawn);
        }
        if let Some(addr) = &self.connect {
            t.push(Target::connect(Some(addr))?);
        }
        Ok(t)
    }

    /// Opens the recording `id` (named `name` in the viewer) on every destination asked for, or `None` when none
    /// was: call before any long work, so that a bad destination fails at once.
    pub fn open(&self, id: &str, name: &str) -> Result<Option<Recorder>> {
        let targets = self.targets()?;
        if targets.is_empty() {
            return Ok(None);
        }
        Ok(Some(Recorder::open(&targets, id, name)?))
    }

    /// A line for the summary: where the recording went.
    pub fn describe(&self) -> String {
        self.targets().map(|t| t.iter().map(Target::describe).collect::<Vec<_>>().join(", ")).unwrap_or_default()
    }
}
