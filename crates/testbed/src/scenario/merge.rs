//! A scenario's merge settings: when, which algorithms with which settings, and the host robot.

use super::error::{Ctx, ScenarioError};
use super::file::MergeFile;
use super::robot::RobotSetup;
use mrslam_merge::{Algorithm, Encoding, Model};

/// When the maps are merged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MergeWhen {
    /// When every robot has finished its route (the paper's common point), or at the duration at the latest.
    Rendezvous,
    /// At the end of the run.
    End,
    /// At this simulated time, seconds; the run ends there.
    At(f64),
}

/// Merge settings.
#[derive(Debug, Clone)]
pub struct MergeSetup {
    /// When to merge.
    pub when: MergeWhen,
    /// Algorithms to run on the same maps, in order.
    pub algorithms: Vec<Algorithm>,
    /// Transform model of the SIFT merger.
    pub model: Model,
    /// Lowe's ratio.
    pub ratio: f32,
    /// Map-to-image encoding.
    pub encoding: Encoding,
    /// Descriptor candidates per feature (1: nearest neighbour with the ratio test, as the paper).
    pub candidates: usize,
    /// Transforms handed to verification (1: the paper's single answer).
    pub hypotheses: usize,
    /// Cells by which walls grow before SIFT.
    pub wall_dilation: usize,
    /// SIFT doubles each map image first (OpenCV's and Lowe's default).
    pub upscale: bool,
    /// Robot that hosts the merge (the paper: Experia); the other's map is merged into its frame.
    pub host: String,
}

pub(super) fn resolve_merge(
    cx: &Ctx,
    m: &MergeFile,
    robots: &[RobotSetup],
    duration: f64,
) -> Result<MergeSetup, ScenarioError> {
    let when = match &m.when {
        None => MergeWhen::Rendezvous,
        Some(toml::Value::String(s)) if s == "rendezvous" => MergeWhen::Rendezvous,
        Some(toml::Value::String(s)) if s == "end" => MergeWhen::End,
        Some(toml::Value::Float(t)) => MergeWhen::At(*t),
        Some(toml::Value::Integer(t)) => MergeWhen::At(*t as f64),
        Some(v) => {
            return Err(cx.err("merge.when", format!("expected \"rendezvous\", \"end\" or a time in seconds, got {v}")));
        }
    };
    if let MergeWhen::At(t) = when {
        if t.is_nan() || t <= 0.0 {
            return Err(cx.err("merge.when", format!("merge time must be positive, got {t}")));
        }
        if t > duration {
            return Err(cx.err("merge.when", format!("merge time {t} s is after the end of the run ({duration} s)")));
        }
    }
    let algorithms = match &m.algorithms {
        None => vec![Algorithm::Sift],
        Some(names) => names
            .iter()
            .map(|a| a.parse::<Algorithm>().map_err(|e| cx.err("merge.algorithms", e.to_string())))
            .collect::<Result<_, _>>()?,
    };
    let model = match &m.model {
        None => Model::Rigid,
        Some(s) => s.parse().map_err(|e: String| cx.err("merge.model", e))?,
    };
    let ratio = m.ratio.unwrap_or(0.75);
    if !(ratio > 0.0 && ratio <= 1.0) {
        return Err(cx.err("merge.ratio", format!("must lie in (0, 1], got {ratio}")));
    }
    let encoding = match &m.encoding {
        None => Encoding::default(),
        Some(s) => s.parse().map_err(|e: String| cx.err("merge.encoding", e))?,
    };
    let host = m.host.clone().unwrap_or_else(|| robots[0].name.clone());
    if !robots.iter().any(|r| r.name == host) {
        return Err(cx.err("merge.host", format!("no robot named `{host}`")));
    }
    let in_range = |field: &str, v: Option<usize>, lo: usize, hi: usize, default: usize| match v {
        Some(x) if !(lo..=hi).contains(&x) => Err(cx.err(field, format!("must lie in {lo}..={hi}, got {x}"))),
        v => Ok(v.unwrap_or(default)),
    };
    let candidates = in_range("merge.candidates", m.candidates, 1, 16, 1)?;
    let hypotheses = in_range("merge.hypotheses", m.hypotheses, 1, 16, 1)?;
    let wall_dilation = in_range("merge.wall_dilation", m.wall_dilation, 0, 4, 0)?;
    let upscale = m.upscale.unwrap_or(true);
    Ok(MergeSetup { when, algorithms, model, ratio, encoding, candidates, hypotheses, wall_dilation, upscale, host })
}
