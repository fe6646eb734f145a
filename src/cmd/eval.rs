//! `mrslam eval relations TRAJ RELATIONS`: a trajectory scored with the benchmark metric of Kümmerle et
//! al. 2009 (mean ± std and max of the relations' translational and rotational errors).

use anyhow::{Result, bail};
use clap::Subcommand;
use mrslam_core::output::write_file_atomic;
use mrslam_core::relations::{self, RelationsScore};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Stamps of a relation and of a trajectory pose match when this close, seconds (both are the scans'
/// ipc timestamps, written with 6 decimals).
pub const DEFAULT_TOLERANCE: f64 = 0.001;

/// Evaluation subcommands.
#[derive(Subcommand)]
pub enum EvalCommand {
    /// Score a trajectory (`stamp x y theta` lines) against a relations file (`t1 t2 x y z roll pitch yaw`).
    Relations {
        /// Trajectory file: one pose a line, `stamp x y theta`; `#` starts a comment.
        trajectory: PathBuf,
        /// Relations file of the benchmark (Kümmerle et al. 2009).
        relations: PathBuf,
        /// A relation's stamp takes the trajectory's nearest pose within this many seconds.
        #[arg(long, default_value_t = DEFAULT_TOLERANCE)]
        tolerance: f64,
        /// Also write the metric as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
        /// How many of the worst relations to list.
        #[arg(long, default_value_t = 5)]
        worst: usize,
    },
}

/// Runs an eval subcommand.
pub fn run(cmd: EvalCommand) -> Result<ExitCode> {
    match cmd {
        EvalCommand::Relations { trajectory, relations, tolerance, json, worst } => {
            if !(tolerance.is_finite() && tolerance >= 0.0) {
                bail!("--tolerance {tolerance}: must be a non-negative number of seconds");
            }
            if let Some(out) = &json {
                super::Outputs::reading([trajectory.as_path(), relations.as_path()])
                    .file("--json", out, super::kind::JSON)
                    .check()?;
            }
            let traj = relations::read_trajectory(&trajectory)?;
            let rels = relations::read_relations(&relations)?;
            let score = relations::score(&traj, &rels, tolerance);
            if score.used() == 0 {
                bail!(
                    "{}: none of the {} relations of {} has poses at both stamps (within {tolerance} s); the \
                     trajectory spans {:.3} s to {:.3} s",
                    trajectory.display(),
                    rels.len(),
                    relations.display(),
                    traj[0].stamp,
                    traj[traj.len() - 1].stamp
                );
            }
            print!("{}", describe(&score, tolerance, worst));
            if let Some(out) = &json {
                write_json(out, &to_json(&score, tolerance, worst))?;
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// The metric as text: relations used and missing, translation and rotation, the worst relations.
pub fn describe(score: &RelationsScore, tolerance: f64, worst: usize) -> String {
    use std::fmt::Write as _;
    let (t, r) = (&score.translation, &score.rotation);
    let mut s = String::new();
    let _ =
        writeln!(s, "relations: {} used, {} missing (no pose within {tolerance} s)", score.used(), score.missing.len());
    let _ =
        writeln!(s, "translation: {:.4} ± {:.4} m, max {:.3} m, mean square {:.5} m²", t.mean, t.std, t.max, t.mean_sq);
    let _ = writeln!(
        s,
        "rotation:    {:.3} ± {:.3} deg, max {:.2} deg, mean square {:.4} deg²",
        r.mean.to_degrees(),
        r.std.to_degrees(),
        r.max.to_degrees(),
        r.mean_sq * (180.0 / std::f64::consts::PI).powi(2)
    );
    let w = score.worst(worst);
    if !w.is_empty() {
        let _ = writeln!(s, "worst relations (translation):");
        for e in w {
            let _ = writeln!(
                s,
                "  line {:>5}: t1 {:.6} t2 {:.6}: {:.3} m, {:.2} deg",
                e.line,
                e.t1,
                e.t2,
                e.translation,
                e.rotation.to_degrees()
            );
        }
    }
    if let Some(m) = score.missing.first() {
        let _ = writeln!(s, "first missing relation: line {}: t1 {:.6} t2 {:.6}", m.line, m.t1, m.t2);
    }
    s
}

/// The metric as JSON (keys name their units).
pub fn to_json(score: &RelationsScore, tolerance: f64, worst: usize) -> Value {
    let (t, r) = (&score.translation, &score.rotation);
    let deg = 180.0 / std::f64::consts::PI;
    json!({
        "translation_mean_m": t.mean,
        "translation_std_m": t.std,
        "translation_max_m": t.max,
        "translation_mean_sq_m2": t.mean_sq,
        "rotation_mean_deg": r.mean * deg,
        "rotation_std_deg": r.std * deg,
        "rotation_max_deg": r.max * deg,
        "rotation_mean_sq_deg2": r.mean_sq * deg * deg,
        "used": score.used(),
        "missing": score.missing.len(),
        "tolerance_s": tolerance,
        "worst": score.worst(worst).iter().map(|e| json!({
            "line": e.line,
            "t1": e.t1,
            "t2": e.t2,
            "translation_m": e.translation,
            "rotation_deg": e.rotation * deg,
        })).collect::<Vec<_>>(),
    })
}

/// Writes pretty JSON atomically.
pub fn write_json(path: &Path, value: &Value) -> Result<()> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    write_file_atomic(path, text.as_bytes())?;
    Ok(())
}
