//! The SLAM benchmark metric of Kümmerle et al. 2009 ("On measuring the accuracy of SLAM algorithms"):
//! relations files, trajectory files, and the error of a trajectory against the relations.
//!
//! A relation `t1 t2 x y z roll pitch yaw` is the pose of the robot at the scan stamped `t2` expressed in
//! the frame of the robot at the scan stamped `t1` (x, y in metres and yaw in radians are used). For an
//! estimated trajectory `est`, the relation's error is `e = true⁻¹ ⊕ (est(t1)⁻¹ ⊕ est(t2))`; the metric
//! is the mean, standard deviation and maximum of `|translation(e)|` and `|rotation(e)|` over the
//! relations, and the means of their squares (the paper's ε split into its two terms).
//!
//! A trajectory file holds one pose a line, `stamp x y theta`, `#` starting a comment.

use crate::{
    pose::normalize_angle,
    se2::{Pose2, Xyt, pose},
};
use std::path::{Path, PathBuf};

/// One relation of a relations file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// Stamp of the scan whose frame the relation is expressed in, seconds.
    pub t1: f64,
    /// Stamp of the other scan, seconds.
    pub t2: f64,
    /// The pose at `t2` in the frame of the pose at `t1`.
    pub delta: Pose2,
    /// 1-based line number in its file.
    pub line: usize,
}

/// A stamped pose of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Seconds.
    pub stamp: f64,
    /// The robot's pose in the map frame.
    pub pose: Pose2,
}

/// Errors reading relations or trajectory files.
#[derive(Debug, thiserror::Error)]
pub enum RelationsError {
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A line is malformed.
    #[error("{path}:{line}: {message}")]
    Line {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong, naming the field.
        message: String,
    },
    /// The file holds no entries.
    #[error("{path}: no {what} in the file")]
    Empty {
        /// File at fault.
        path: PathBuf,
        /// What was expected.
        what: &'static str,
    },
}

/// Splits `text` into (line number, fields) of its non-empty, non-comment lines, each parsed as finite
/// numbers; `names` names the fields for errors, and a line has exactly `names.len()` of them (a file of the
/// other kind, a relations file given as a trajectory, is refused at its first line).
fn numeric_lines(text: &str, path: &Path, names: &[&str]) -> Result<Vec<(usize, Vec<f64>)>, RelationsError> {
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let body = line.split('#').next().unwrap_or("").trim();
        if body.is_empty() {
            continue;
        }
        let bad = |message: String| RelationsError::Line { path: path.to_path_buf(), line: i + 1, message };
        let fields: Vec<&str> = body.split_whitespace().collect();
        if fields.len() != names.len() {
            let hint = match fields.len() {
                8 => ": a relations file (t1 t2 x y z roll pitch yaw)?",
                4 => ": a trajectory (stamp x y theta)?",
                _ => "",
            };
            return Err(bad(format!(
                "expected {} fields ({}), found {}{hint}",
                names.len(),
                names.join(" "),
                fields.len()
            )));
        }
        let mut v = Vec::with_capacity(names.len());
        for (name, f) in names.iter().zip(&fields) {
            match f.parse::<f64>() {
                Ok(x) if x.is_finite() => v.push(x),
                _ => return Err(bad(format!("field {name}: `{f}` is not a finite number"))),
            }
        }
        rows.push((i + 1, v));
    }
    Ok(rows)
}

fn read_text(path: &Path) -> Result<String, RelationsError> {
    crate::input::read_text_limited(path, crate::input::DATA_LIMIT)
        .map_err(|cause| RelationsError::Io { path: path.to_path_buf(), cause })
}

/// Parses a relations file's text; `path` only names the source in errors.
pub fn parse_relations(text: &str, path: &Path) -> Result<Vec<Relation>, RelationsError> {
    let names = ["t1", "t2", "x", "y", "z", "roll", "pitch", "yaw"];
    let rows = numeric_lines(text, path, &names)?;
    if rows.is_empty() {
        return Err(RelationsError::Empty { path: path.to_path_buf(), what: "relations" });
    }
    Ok(rows.into_iter().map(|(line, v)| Relation { t1: v[0], t2: v[1], delta: pose(v[2], v[3], v[7]), line }).collect())
}

/// Reads a relations file.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>, RelationsError> {
    parse_relations(&read_text(path)?, path)
}

/// Parses a trajectory file's text (`stamp x y theta` a line); `path` only names the source in errors.
/// The poses are returned sorted by stamp.
pub fn parse_trajectory(text: &str, path: &Path) -> Result<Vec<StampedPose>, RelationsError> {
    let rows = numeric_lines(text, path, &["stamp", "x", "y", "theta"])?;
    if rows.is_empty() {
        return Err(RelationsError::Empty { path: path.to_path_buf(), what: "poses" });
    }
    let mut poses: Vec<StampedPose> =
        rows.into_iter().map(|(_, v)| StampedPose { stamp: v[0], pose: pose(v[1], v[2], v[3]) }).collect();
    poses.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    Ok(poses)
}

/// Reads a trajectory file.
pub fn read_trajectory(path: &Path) -> Result<Vec<StampedPose>, RelationsError> {
    parse_trajectory(&read_text(path)?, path)
}

/// Formats a trajectory as `stamp x y theta` lines after `header` (each header line gets a `# `).
pub fn format_trajectory(header: &str, poses: &[StampedPose]) -> String {
    use std::fmt::Write as _;
    let mut text = String::with_capacity(header.len() + 48 * poses.len());
    for l in header.lines() {
        let _ = writeln!(text, "# {l}");
    }
    for p in poses {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&p.pose);
        let _ = writeln!(text, "{:.6} {x:.6} {y:.6} {t:.6}", p.stamp);
    }
    text
}

/// Formats relations as `t1 t2 x y z roll pitch yaw` lines (z, roll and pitch 0) after `header` (each header
/// line gets a `# `): the layout [`parse_relations`] reads.
pub fn format_relations(header: &str, relations: &[Relation]) -> String {
    use std::fmt::Write as _;
    let mut text = String::with_capacity(header.len() + 80 * relations.len());
    for l in header.lines() {
        let _ = writeln!(text, "# {l}");
    }
    for r in relations {
        let Xyt { x, y, theta: t } = Xyt::from_pose(&r.delta);
        let _ = writeln!(text, "{:.6} {:.6} {x:.6} {y:.6} 0 0 0 {t:.6}", r.t1, r.t2);
    }
    text
}

/// The error of one relation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelationError {
    /// The relation's first stamp.
    pub t1: f64,
    /// The relation's second stamp.
    pub t2: f64,
    /// The relation's line in its file.
    pub line: usize,
    /// |translation(e)|, metres.
    pub translation: f64,
    /// |rotation(e)|, radians.
    pub rotation: f64,
}

/// Mean, standard deviation (population), maximum and mean square of a set of errors.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorStats {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (divided by n).
    pub std: f64,
    /// Largest.
    pub max: f64,
    /// Mean of the squares.
    pub mean_sq: f64,
}

impl ErrorStats {
    fn of(values: impl Iterator<Item = f64> + Clone) -> ErrorStats {
        let n = values.clone().count();
        if n == 0 {
            return ErrorStats::default();
        }
        let mean = values.clone().sum::<f64>() / n as f64;
        let mean_sq = values.clone().map(|v| v * v).sum::<f64>() / n as f64;
        let var = values.clone().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
        ErrorStats { mean, std: var.sqrt(), max: values.fold(0.0, f64::max), mean_sq }
    }
}

/// The metric of a trajectory against a set of relations.
#[derive(Debug, Clone, PartialEq)]
pub struct RelationsScore {
    /// Translational errors, metres.
    pub translation: ErrorStats,
    /// Rotational errors, radians.
    pub rotation: ErrorStats,
    /// Each relation scored, in the file's order.
    pub errors: Vec<RelationError>,
    /// Relations of which a stamp has no pose within the tolerance, in the file's order.
    pub missing: Vec<Relation>,
}

impl RelationsScore {
    /// Number of relations scored.
    pub fn used(&self) -> usize {
        self.errors.len()
    }

    /// The `k` relations with the largest translational error, largest first.
    pub fn worst(&self, k: usize) -> Vec<RelationError> {
        let mut v = self.errors.clone();
        v.sort_by(|a, b| b.translation.total_cmp(&a.translation).then(a.line.cmp(&b.line)));
        v.truncate(k);
        v
    }
}

/// The pose of `trajectory` (sorted by stamp) nearest in time to `stamp`, when within `tolerance` seconds.
pub fn pose_at(trajectory: &[StampedPose], stamp: f64, tolerance: f64) -> Option<Pose2> {
    let i = trajectory.partition_point(|p| p.stamp < stamp);
    let mut best: Option<&StampedPose> = None;
    for p in trajectory[i.saturating_sub(1)..].iter().take(2) {
        if best.is_none_or(|b| (p.stamp - stamp).abs() < (b.stamp - stamp).abs()) {
            best = Some(p);
        }
    }
    best.filter(|p| (p.stamp - stamp).abs() <= tolerance).map(|p| p.pose)
}

/// Scores `trajectory` (sorted by stamp) against `relations`: each relation's stamps take the nearest pose
/// within `tolerance` seconds; relations lacking one are listed as missing.
pub fn score(trajectory: &[StampedPose], relations: &[Relation], tolerance: f64) -> RelationsScore {
    let mut errors = Vec::with_capacity(relations.len());
    let mut missing = Vec::new();
    for r in relations {
        match (pose_at(trajectory, r.t1, tolerance), pose_at(trajectory, r.t2, tolerance)) {
            (Some(a), Some(b)) => {
                let e = r.delta.inv_mul(&a.inv_mul(&b));
                let Xyt { x, y, theta: t } = Xyt::from_pose(&e);
                errors.push(RelationError {
                    t1: r.t1,
                    t2: r.t2,
                    line: r.line,
                    translation: x.hypot(y),
                    rotation: normalize_angle(t).abs(),
                });
            }
            _ => missing.push(*r),
        }
    }
    RelationsScore {
        translation: ErrorStats::of(errors.iter().map(|e| e.translation)),
        rotation: ErrorStats::of(errors.iter().map(|e| e.rotation)),
        errors,
        missing,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn traj(poses: &[(f64, f64, f64, f64)]) -> Vec<StampedPose> {
        poses.iter().map(|&(s, x, y, t)| StampedPose { stamp: s, pose: pose(x, y, t) }).collect()
    }

    #[test]
    fn a_perfect_trajectory_scores_zero_and_a_known_error_scores_exactly_that() {
        // The robot drives along x, turning: relations taken from the truth.
        let truth = traj(&[(0.0, 0.0, 0.0, 0.0), (1.0, 1.0, 0.0, 0.5), (2.0, 1.5, 0.8, 1.2), (3.0, 1.0, 2.0, 3.0)]);
        let rel = |i: usize, j: usize| Relation {
            t1: truth[i].stamp,
            t2: truth[j].stamp,
            delta: truth[i].pose.inv_mul(&truth[j].pose),
            line: i + 1,
        };
        let relations = [rel(0, 1), rel(1, 2), rel(2, 3)];
        let s = score(&truth, &relations, 1e-6);
        assert_eq!((s.used(), s.missing.len()), (3, 0));
        assert!(s.translation.max < 1e-12 && s.rotation.max < 1e-12, "{s:?}");
        // Move the last pose 0.3 m sideways in its own frame and turn it by 0.2 rad: only the last relation
        // sees it, with exactly that error.
        let mut est = truth.clone();
        est[3].pose *= pose(0.0, 0.3, 0.2);
        let s = score(&est, &relations, 1e-6);
        assert!((s.errors[2].translation - 0.3).abs() < 1e-12, "{:?}", s.errors[2]);
        assert!((s.errors[2].rotation - 0.2).abs() < 1e-12);
        assert!(s.errors[0].translation < 1e-12 && s.errors[1].translation < 1e-12);
        assert!((s.translation.mean - 0.1).abs() < 1e-12);
        assert!((s.translation.std - (0.02f64).sqrt()).abs() < 1e-12);
        assert!((s.translation.mean_sq - 0.03).abs() < 1e-12);
        assert_eq!(s.worst(1)[0].line, 3);
    }

    #[test]
    fn a_relations_file_is_no_trajectory_and_a_trajectory_no_relations_file() {
        let rels = "# t1 t2 x y z roll pitch yaw\n1.0 2.0 0.5 0 0 0 0 0.1\n";
        let e = parse_trajectory(rels, Path::new("r.relations")).unwrap_err().to_string();
        assert!(e.starts_with("r.relations:2: expected 4 fields (stamp x y theta), found 8: a relations file"), "{e}");
        let e = parse_relations("1.0 0 0 0\n", Path::new("t.txt")).unwrap_err().to_string();
        assert!(e.starts_with("t.txt:1: expected 8 fields") && e.contains("a trajectory (stamp x y theta)?"), "{e}");
        assert!(parse_trajectory("1.0 0 0 0 # a comment\n", Path::new("t.txt")).is_ok());
    }

    #[test]
    fn rotation_errors_wrap_around_pi() {
        let est = traj(&[(0.0, 0.0, 0.0, 3.1), (1.0, 0.0, 0.0, -3.1)]);
        // True relation: turned by +0.1 rad (through +-pi); estimate: 2pi - 6.2 = 0.0832 rad.
        let r = [Relation { t1: 0.0, t2: 1.0, delta: pose(0.0, 0.0, 0.1), line: 1 }];
        let s = score(&est, &r, 0.0);
        assert!((s.rotation.mean - (0.1 - (2.0 * PI - 6.2)).abs()).abs() < 1e-9, "{s:?}");
        let r = [Relation { t1: 0.0, t2: 1.0, delta: pose(0.0, 0.0, -3.0), line: 1 }];
        let s = score(&est, &r, 0.0);
        // estimate 0.0832 vs true -3.0: the difference 3.0832 rad, under pi.
        assert!((s.rotation.mean - (3.0 + 2.0 * PI - 6.2)).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn stamps_match_within_the_tolerance_only() {
        let est = traj(&[(10.0, 0.0, 0.0, 0.0), (10.5, 1.0, 0.0, 0.0)]);
        assert!(pose_at(&est, 10.0004, 0.001).is_some());
        assert!(pose_at(&est, 10.2, 0.001).is_none());
        assert_eq!(pose_at(&est, 10.3, 0.3).map(|p| p.translation.x), Some(1.0));
        let r = [Relation { t1: 10.0, t2: 10.2, delta: pose(1.0, 0.0, 0.0), line: 7 }];
        let s = score(&est, &r, 0.001);
        assert_eq!((s.used(), s.missing.len(), s.missing[0].line), (0, 1, 7));
    }

    #[test]
    fn files_parse_and_errors_name_line_and_field() {
        let p = Path::new("r.relations");
        let r = parse_relations("# c\n1.5 2.5 0.4 0.1 0 0 0 0.05\n", p).unwrap();
        assert_eq!((r[0].t1, r[0].t2, r[0].line), (1.5, 2.5, 2));
        assert!((r[0].delta.rotation.angle() - 0.05).abs() < 1e-12);
        let e = parse_relations("1 2 0 0 0 0 0 0\n1 2 0 x 0 0 0 0\n", p).unwrap_err().to_string();
        assert_eq!(e, "r.relations:2: field y: `x` is not a finite number");
        let e = parse_relations("1 2 0\n", p).unwrap_err().to_string();
        assert!(e.starts_with("r.relations:1: expected 8 fields"), "{e}");
        assert!(parse_relations("# only a comment\n", p).unwrap_err().to_string().contains("no relations"));
        let t = parse_trajectory("# header\n2 1 1 0\n1 0 0 0.5\n", Path::new("t.txt")).unwrap();
        assert_eq!(t.iter().map(|p| p.stamp).collect::<Vec<_>>(), [1.0, 2.0]);
        let text = format_trajectory("made by a test\nsecond line", &t);
        assert!(text.starts_with("# made by a test\n# second line\n1.000000 0.000000 0.000000 0.500000\n"), "{text}");
        assert_eq!(parse_trajectory(&text, Path::new("t.txt")).unwrap(), t);
        let e = parse_trajectory("1 2 nan 0\n", Path::new("t.txt")).unwrap_err().to_string();
        assert_eq!(e, "t.txt:1: field y: `nan` is not a finite number");
    }
}
