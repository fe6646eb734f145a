//! Real-data multi-robot studies: a CARMEN log split in time into N consecutive parts ("robots"), each part
//! mapped by the SLAM, every pair of parts that the benchmark relations connect merged with each algorithm,
//! and each merge scored against the relations whose two stamps fall in the two parts.
//!
//! Ground truth of a pair (i, j): a relation from a scan of part i (stamp t1) to a scan of part j (stamp
//! t2) gives `T_i_j = P_i(t1) · rel · P_j(t2)⁻¹`, part j's map frame in part i's (`P_k` is part k's SLAM
//! trajectory); the pair's truth is the robust centre of these (median x, y and heading). A merge's
//! estimate is scored by mapping every cross relation through it: the relation's error is
//! `rel⁻¹ · (P_i(t1)⁻¹ · T · P_j(t2))`, and the merge's error is the median over the pair's relations of
//! the errors' translation and rotation. The truth itself has a non-zero error (the parts' SLAM errors):
//! it is reported beside each merge as the floor.

use super::StudyError;
use super::results::TrialRow;
use mrslam_core::relations::{Relation, StampedPose, pose_at};
use mrslam_core::{CellState, OccupancyGrid, Pose2};
use mrslam_core::{Xyt, pose, pose::normalize_angle};
use mrslam_log::{ScanRecord, span};
use mrslam_merge::{Algorithm, Encoding, MergeParams, MergerConfig, merge};
use mrslam_slam::{LogRunError, Rbpf, SlamParams, map_log};
use mrslam_testbed::eval::transform_error;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

/// Default success threshold: median cross-relation translation error at most this, metres.
pub const MAX_ERROR_M: f64 = 0.3;
/// Default success threshold: median cross-relation rotation error at most this, degrees.
pub const MAX_ERROR_DEG: f64 = 2.0;

/// Splits scans stamped `stamps` (in time order) into `parts` consecutive ranges of equal duration.
///
/// Part k holds the scans stamped in `[t0 + k·D/N, t0 + (k+1)·D/N)` (the last part also its end stamp).
/// Fails when fewer than 2 parts are asked for, the stamps are not in order, or a part has no scan.
pub fn split_by_time(stamps: &[f64], parts: usize) -> Result<Vec<Range<usize>>, StudyError> {
    let bad = |m: String| Err(StudyError::Invalid(m));
    if parts < 2 {
        return bad(format!("--parts {parts}: a study needs at least 2 parts (robots)"));
    }
    if let Some(k) = stamps.windows(2).position(|w| w[1] < w[0] || !w[0].is_finite()) {
        return bad(format!("scan {} is stamped before scan {}: stamps are not in time order", k + 1, k));
    }
    let (Some(&t0), Some(&t1)) = (stamps.first(), stamps.last()) else {
        return bad("no scans to split".into());
    };
    let duration = t1 - t0;
    let mut ranges = Vec::with_capacity(parts);
    let mut start = 0;
    for k in 0..parts {
        let end = if k + 1 == parts {
            stamps.len()
        } else {
            let boundary = t0 + duration * (k + 1) as f64 / parts as f64;
            start + stamps[start..].partition_point(|&s| s < boundary)
        };
        if end <= start {
            return bad(format!(
                "part {k} of {parts} ({:.1} s to {:.1} s) has no scan: the log's {} scans over {duration:.1} s do \
                 not fill {parts} parts",
                t0 + duration * k as f64 / parts as f64,
                t0 + duration * (k + 1) as f64 / parts as f64,
                stamps.len()
            ));
        }
        ranges.push(start..end);
        start = end;
    }
    Ok(ranges)
}

/// One part mapped by the SLAM.
#[derive(Debug, Clone)]
pub struct PartMap {
    /// The best particle's map.
    pub map: OccupancyGrid,
    /// A pose for every scan of the part, in stamp order, in the part's map frame.
    pub trajectory: Vec<StampedPose>,
    /// Scans the filter processed (the others are placed by odometry).
    pub processed: usize,
    /// Wall time of the SLAM, seconds.
    pub seconds: f64,
}

/// Maps `scans` with the SLAM as `mrslam slam` does (filter seeded `seed`; a pose for every scan from the
/// filter's at the processed scans); `log` names the log in errors, `on_scan` is called after each scan.
pub fn map_part(
    scans: &[ScanRecord],
    params: &SlamParams,
    seed: u64,
    log: &Path,
    on_scan: &mut dyn FnMut(),
) -> Result<PartMap, StudyError> {
    let first = scans.first().ok_or_else(|| StudyError::file(log, "a part without scans"))?;
    let start = std::time::Instant::now();
    let mut filter = Rbpf::new(params.clone(), first.laser_offset, seed)
        .map_err(|e| StudyError::Invalid(format!("slam parameters: {e}")))?;
    let run =
        map_log(&mut filter, scans.iter().map(|r| (&r.odometry, &r.scan)), |_, _| on_scan()).map_err(|e| match e {
            LogRunError::Reading { index, error } => StudyError::file(log, format!("{}: {error}", scans[index].source)),
            LogRunError::NothingProcessed => StudyError::file(
                log,
                format!(
                    "{}: the filter processed no scan of this part",
                    span(&first.source, scans.last().map_or(&first.source, |r| &r.source))
                ),
            ),
        })?;
    let map = filter.map().map_err(|e| StudyError::file(log, format!("building a part's map: {e}")))?;
    let (poses, processed) = (run.poses, run.processed);
    let stamps: Vec<f64> = scans.iter().map(|r| r.scan.stamp).collect();
    let trajectory = stamps.iter().zip(poses).map(|(&stamp, pose)| StampedPose { stamp, pose }).collect();
    Ok(PartMap { map, trajectory, processed: processed.len(), seconds: start.elapsed().as_secs_f64() })
}

/// A relation whose two stamps fall in two different parts, oriented from the earlier part `i` to the
/// later part `j`, with the parts' SLAM poses at its stamps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrossRelation {
    /// Line of the relation in its file.
    pub line: usize,
    /// Stamp of its scan in part i.
    pub stamp_i: f64,
    /// Stamp of its scan in part j.
    pub stamp_j: f64,
    /// The robot's pose at `stamp_j` in its frame at `stamp_i` (the relation, inverted when it was written
    /// from part j to part i).
    pub delta: Pose2,
    /// Part i's pose at `stamp_i`, in part i's map frame.
    pub pose_i: Pose2,
    /// Part j's pose at `stamp_j`, in part j's map frame.
    pub pose_j: Pose2,
}

impl CrossRelation {
    /// The transform from part j's map frame into part i's that this relation implies.
    pub fn transform(&self) -> Pose2 {
        self.pose_i * self.delta * self.pose_j.inverse()
    }

    /// The relation's error under an estimated `t_i_j`: (translation m, rotation rad) of
    /// `delta⁻¹ · (pose_i⁻¹ · t_i_j · pose_j)`.
    pub fn error(&self, t_i_j: &Pose2) -> (f64, f64) {
        let e = self.delta.inverse() * self.pose_i.inverse() * t_i_j * self.pose_j;
        let Xyt { x, y, theta: t } = Xyt::from_pose(&e);
        (x.hypot(y), normalize_angle(t).abs())
    }
}

/// The part whose trajectory has a pose nearest `stamp` within `tolerance`, with that pose.
fn locate(trajectories: &[&[StampedPose]], stamp: f64, tolerance: f64) -> Option<(usize, Pose2)> {
    let mut best: Option<(f64, usize, Pose2)> = None;
    for (k, t) in trajectories.iter().enumerate() {
        if let Some(p) = pose_at(t, stamp, tolerance) {
            let i = t.partition_point(|q| q.stamp < stamp);
            let dt = t[i.saturating_sub(1)..].iter().take(2).map(|q| (q.stamp - stamp).abs()).fold(f64::MAX, f64::min);
            if best.is_none_or(|b| dt < b.0) {
                best = Some((dt, k, p));
            }
        }
    }
    best.map(|(_, k, p)| (k, p))
}

/// The relations connecting two parts, by pair (i, j) with i < j, each oriented from i to j.
///
/// A relation's stamp belongs to the part whose trajectory (sorted by stamp) has a pose within `tolerance`
/// seconds of it (the nearest); relations within one part, or with a stamp in no part, are left out.
pub fn cross_relations(
    relations: &[Relation],
    trajectories: &[&[StampedPose]],
    tolerance: f64,
) -> BTreeMap<(usize, usize), Vec<CrossRelation>> {
    let mut pairs: BTreeMap<(usize, usize), Vec<CrossRelation>> = BTreeMap::new();
    for r in relations {
        let (Some((a, pa)), Some((b, pb))) =
            (locate(trajectories, r.t1, tolerance), locate(trajectories, r.t2, tolerance))
        else {
            continue;
        };
        let c = if a < b {
            CrossRelation { line: r.line, stamp_i: r.t1, stamp_j: r.t2, delta: r.delta, pose_i: pa, pose_j: pb }
        } else if b < a {
            let delta = r.delta.inverse();
            CrossRelation { line: r.line, stamp_i: r.t2, stamp_j: r.t1, delta, pose_i: pb, pose_j: pa }
        } else {
            continue;
        };
        pairs.entry((a.min(b), a.max(b))).or_default().push(c);
    }
    pairs
}

/// The median of `v` (the mean of the two middle values for an even count); NaN when empty.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { (v[n / 2 - 1] + v[n / 2]) / 2.0 }
}

/// The robust centre of a set of transforms: median x, median y, and the median heading taken around the
/// headings' circular mean (so that headings either side of ±π are not split apart). `None` when empty.
pub fn robust_centre(transforms: &[Pose2]) -> Option<Pose2> {
    if transforms.is_empty() {
        return None;
    }
    let xyt: Vec<Xyt> = transforms.iter().map(Xyt::from_pose).collect();
    let (s, c) = xyt.iter().fold((0.0, 0.0), |(s, c), p| (s + p.theta.sin(), c + p.theta.cos()));
    let reference = s.atan2(c);
    let mut xs: Vec<f64> = xyt.iter().map(|p| p.x).collect();
    let mut ys: Vec<f64> = xyt.iter().map(|p| p.y).collect();
    let mut ts: Vec<f64> = xyt.iter().map(|p| normalize_angle(p.theta - reference)).collect();
    Some(pose(median(&mut xs), median(&mut ys), normalize_angle(reference + median(&mut ts))))
}

/// The ground-truth transform of a pair: the robust centre of its cross relations' transforms.
pub fn true_transform(cross: &[CrossRelation]) -> Option<Pose2> {
    robust_centre(&cross.iter().map(CrossRelation::transform).collect::<Vec<_>>())
}

/// An estimate's median error over a pair's cross relations: (translation m, rotation degrees); `None`
/// without relations.
pub fn median_error(t_i_j: &Pose2, cross: &[CrossRelation]) -> Option<(f64, f64)> {
    if cross.is_empty() {
        return None;
    }
    let (mut ts, mut rs): (Vec<f64>, Vec<f64>) = cross.iter().map(|c| c.error(t_i_j)).unzip();
    Some((median(&mut ts), median(&mut rs).to_degrees()))
}

/// Known cells of `b` that land on known cells of `a` under `t_a_b` (cell centres), and `b`'s known cells.
fn landing(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2) -> (usize, usize) {
    let (mut hit, mut known) = (0, 0);
    for iy in 0..b.height() {
        for ix in 0..b.width() {
            if b.state(ix, iy) == CellState::Unknown {
                continue;
            }
            known += 1;
            let p = t_a_b * b.cell_center(ix as i64, iy as i64);
            if a.world_to_cell(&p).is_some_and(|(x, y)| a.state(x, y) != CellState::Unknown) {
                hit += 1;
            }
        }
    }
    (hit, known)
}

/// The overlap of two maps under the true `t_a_b`: (Jaccard of their known areas, as the other studies
/// measure overlap; share of the smaller map's known cells that land on known cells of the other).
pub fn overlap(a: &OccupancyGrid, b: &OccupancyGrid, t_a_b: &Pose2) -> (f64, f64) {
    let (b_on_a, known_b) = landing(a, b, t_a_b);
    let (a_on_b, known_a) = landing(b, a, &t_a_b.inverse());
    // Areas in square metres, so that maps of different resolutions compare.
    let (ra, rb) = (a.resolution() * a.resolution(), b.resolution() * b.resolution());
    let both = b_on_a as f64 * rb;
    let union = known_a as f64 * ra + known_b as f64 * rb - both;
    let jaccard = if union > 0.0 { (both / union).clamp(0.0, 1.0) } else { 0.0 };
    let smaller = if known_b as f64 * rb <= known_a as f64 * ra {
        if known_b == 0 { 0.0 } else { b_on_a as f64 / known_b as f64 }
    } else {
        a_on_b as f64 / known_a as f64
    };
    (jaccard, smaller)
}

/// Thresholds and seeds of the merges of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoreParams {
    /// Success: median cross-relation translation error at most this, metres.
    pub max_error_m: f64,
    /// Success: median cross-relation rotation error at most this, degrees.
    pub max_error_deg: f64,
    /// Seed of the mergers' random draws.
    pub seed: u64,
    /// The SIFT merger's map-to-image encoding.
    pub encoding: Encoding,
    /// The verification gate's wall tolerance, cells ([`mrslam_merge::VerifyParams::wall_tolerance_cells`]).
    pub wall_tolerance_cells: usize,
}

impl Default for ScoreParams {
    fn default() -> Self {
        ScoreParams {
            max_error_m: MAX_ERROR_M,
            max_error_deg: MAX_ERROR_DEG,
            seed: 0,
            encoding: Encoding::default(),
            wall_tolerance_cells: mrslam_merge::VerifyParams::default().wall_tolerance_cells,
        }
    }
}

/// One pair of parts merged by one algorithm.
#[derive(Debug, Clone, PartialEq)]
pub struct PairRow {
    /// The earlier part (map a of the merge).
    pub part_i: usize,
    /// The later part (map b of the merge).
    pub part_j: usize,
    /// Algorithm.
    pub algorithm: String,
    /// Cross relations of the pair.
    pub relations: usize,
    /// Jaccard overlap of the two maps' known areas under the true transform.
    pub overlap: f64,
    /// Share of the smaller map's known cells on known cells of the other, under the true transform.
    pub overlap_smaller: f64,
    /// The true transform (x m, y m, heading degrees).
    pub truth: (f64, f64, f64),
    /// The true transform's own median relation error (translation m, rotation degrees): the floor.
    pub truth_error: (f64, f64),
    /// Passed the verification gate.
    pub accepted: bool,
    /// Accepted and within the thresholds.
    pub success: bool,
    /// Accepted but not a success.
    pub false_merge: bool,
    /// The estimated transform (x m, y m, heading degrees), accepted or not.
    pub estimate: Option<(f64, f64, f64)>,
    /// The estimate's median relation error (translation m, rotation degrees).
    pub error: Option<(f64, f64)>,
    /// The estimate's distance from the true transform (translation m, rotation degrees).
    pub error_to_truth: Option<(f64, f64)>,
    /// Merge wall time, milliseconds.
    pub time_ms: f64,
    /// Tentative correspondences.
    pub matches: usize,
    /// Correspondences supporting the transform.
    pub inliers: usize,
    /// The gate's confidence.
    pub confidence: f64,
    /// Carpin's acceptance index.
    pub acceptance_index: Option<f64>,
    /// Cells known in both maps under the estimate.
    pub common_cells: usize,
    /// Share of b's walls meeting a's walls.
    pub wall_agreement: Option<f64>,
    /// The stage of a cascade that decided (empty for one algorithm).
    pub stage: String,
    /// Why the merge was refused (empty when accepted).
    pub reason: String,
}

/// The header line of a logs study's `results.csv`.
pub const RESULTS_HEADER: &str = "part_i,part_j,algorithm,relations,overlap,overlap_smaller,truth_x,truth_y,\
truth_theta_deg,truth_error_m,truth_error_deg,accepted,success,false_merge,estimate_x,estimate_y,\
estimate_theta_deg,error_m,error_deg,error_to_truth_m,error_to_truth_deg,time_ms,matches,inliers,confidence,\
acceptance_index,common_cells,wall_agreement,stage,reason";

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| format!("{x:.6}"))
}

/// A CSV field: quoted (inner quotes doubled) when it holds a comma, a quote or a line break.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

impl PairRow {
    /// The row as a CSV line of [`RESULTS_HEADER`]'s columns (no newline).
    pub fn to_csv(&self) -> String {
        let (tx, ty, tt) = self.truth;
        format!(
            "{},{},{},{},{:.6},{:.6},{tx:.6},{ty:.6},{tt:.6},{:.6},{:.6},{},{},{},{},{},{},{},{},{},{},{:.3},{},{},{:.6},{},{},{},{},{}",
            self.part_i,
            self.part_j,
            self.algorithm,
            self.relations,
            self.overlap,
            self.overlap_smaller,
            self.truth_error.0,
            self.truth_error.1,
            self.accepted,
            self.success,
            self.false_merge,
            opt(self.estimate.map(|e| e.0)),
            opt(self.estimate.map(|e| e.1)),
            opt(self.estimate.map(|e| e.2)),
            opt(self.error.map(|e| e.0)),
            opt(self.error.map(|e| e.1)),
            opt(self.error_to_truth.map(|e| e.0)),
            opt(self.error_to_truth.map(|e| e.1)),
            self.time_ms,
            self.matches,
            self.inliers,
            self.confidence,
            opt(self.acceptance_index),
            self.common_cells,
            opt(self.wall_agreement),
            self.stage,
            csv_field(&self.reason),
        )
    }

    /// The row as a map-study row (for the summary bins and the plot): trial = `trial`, overlap observed.
    pub fn to_trial_row(&self, trial: usize) -> TrialRow {
        TrialRow {
            trial,
            overlap_target: None,
            overlap: self.overlap,
            seed: 0,
            algorithm: self.algorithm.clone(),
            accepted: self.accepted,
            success: self.success,
            false_merge: self.false_merge,
            rotation_error_deg: self.error.map(|e| e.1),
            translation_error_m: self.error.map(|e| e.0),
            time_ms: self.time_ms,
            rotation_error_at_end_deg: None,
            translation_error_at_end_m: None,
            stage: self.stage.clone(),
        }
    }
}

/// Merges part j's map into part i's with `algorithm` and scores the merge against the pair's relations.
pub fn merge_pair(
    algorithm: Algorithm,
    (i, a): (usize, &OccupancyGrid),
    (j, b): (usize, &OccupancyGrid),
    cross: &[CrossRelation],
    p: &ScoreParams,
) -> Result<PairRow, StudyError> {
    let truth = true_transform(cross)
        .ok_or_else(|| StudyError::Invalid(format!("parts {i} and {j}: no relation connects them")))?;
    let truth_error = median_error(&truth, cross).unwrap_or((f64::NAN, f64::NAN));
    let (overlap, overlap_smaller) = overlap(a, b, &truth);
    let merger = MergerConfig { encoding: p.encoding, ..MergerConfig::new(algorithm, p.seed) }.build();
    let mut mp = MergeParams::default();
    mp.verify.wall_tolerance_cells = p.wall_tolerance_cells;
    let out = merge(merger.as_ref(), a, b, &mp);
    let r = out.report;
    let estimate = r.transform.map(|x| x.to_pose());
    let error = estimate.and_then(|e| median_error(&e, cross));
    let success = r.accepted && error.is_some_and(|(m, deg)| m <= p.max_error_m && deg <= p.max_error_deg);
    let deg = |p: Xyt| (p.x, p.y, p.theta.to_degrees());
    Ok(PairRow {
        part_i: i,
        part_j: j,
        algorithm: algorithm.to_string(),
        relations: cross.len(),
        overlap,
        overlap_smaller,
        truth: deg(Xyt::from_pose(&truth)),
        truth_error,
        accepted: r.accepted,
        success,
        false_merge: r.accepted && !success,
        estimate: estimate.map(|e| deg(Xyt::from_pose(&e))),
        error,
        error_to_truth: estimate.map(|e| {
            let (rot, d) = transform_error(&e, &truth);
            (d, rot.to_degrees())
        }),
        time_ms: r.time_ms,
        matches: r.matches,
        inliers: r.inliers,
        confidence: r.confidence,
        acceptance_index: r.acceptance_index,
        common_cells: r.common_cells,
        wall_agreement: r.wall_agreement,
        stage: r.stage.unwrap_or_default(),
        reason: r.reason.unwrap_or_default(),
    })
}

/// Writes a logs study's `results.csv` (through a temporary file).
pub fn write_pair_rows(rows: &[PairRow], path: &Path) -> Result<(), StudyError> {
    let mut s = format!("{RESULTS_HEADER}\n");
    for r in rows {
        let _ = writeln!(s, "{}", r.to_csv());
    }
    mrslam_core::output::write_file_atomic(path, s.as_bytes()).map_err(|e| StudyError::file(path, e))
}

/// One algorithm over all pairs of a logs study.
#[derive(Debug, Clone, PartialEq)]
pub struct AlgorithmSummary {
    /// Algorithm.
    pub algorithm: String,
    /// Pairs merged.
    pub pairs: usize,
    /// Merges accepted by the gate.
    pub accepted: usize,
    /// Accepted and within the thresholds.
    pub successes: usize,
    /// Accepted but wrong.
    pub false_merges: usize,
    /// Median merge wall time, milliseconds.
    pub median_time_ms: f64,
    /// Median over accepted merges of their median relation error, metres (NaN when none).
    pub median_error_m: f64,
    /// Same, degrees.
    pub median_error_deg: f64,
}

/// The header line of a logs study's `summary.csv`.
pub const SUMMARY_HEADER: &str =
    "algorithm,pairs,accepted,successes,false_merges,median_time_ms,median_error_m,median_error_deg";

/// Summarises rows per algorithm, in order of first appearance.
pub fn summarise_pairs(rows: &[PairRow]) -> Vec<AlgorithmSummary> {
    let mut order: Vec<&str> = Vec::new();
    for r in rows {
        if !order.contains(&r.algorithm.as_str()) {
            order.push(&r.algorithm);
        }
    }
    order
        .iter()
        .map(|&alg| {
            let sel: Vec<&PairRow> = rows.iter().filter(|r| r.algorithm == alg).collect();
            let accepted: Vec<&&PairRow> = sel.iter().filter(|r| r.accepted).collect();
            let (mut em, mut ed): (Vec<f64>, Vec<f64>) = accepted.iter().filter_map(|r| r.error).unzip();
            AlgorithmSummary {
                algorithm: alg.to_string(),
                pairs: sel.len(),
                accepted: accepted.len(),
                successes: sel.iter().filter(|r| r.success).count(),
                false_merges: sel.iter().filter(|r| r.false_merge).count(),
                median_time_ms: median(&mut sel.iter().map(|r| r.time_ms).collect::<Vec<_>>()),
                median_error_m: median(&mut em),
                median_error_deg: median(&mut ed),
            }
        })
        .collect()
}

fn num(v: f64, digits: usize) -> String {
    if v.is_finite() { format!("{v:.digits$}") } else { String::new() }
}

/// Writes a logs study's `summary.csv` (through a temporary file).
pub fn write_algorithm_summary(rows: &[AlgorithmSummary], path: &Path) -> Result<(), StudyError> {
    let mut s = format!("{SUMMARY_HEADER}\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            r.algorithm,
            r.pairs,
            r.accepted,
            r.successes,
            r.false_merges,
            num(r.median_time_ms, 3),
            num(r.median_error_m, 4),
            num(r.median_error_deg, 3)
        );
    }
    mrslam_core::output::write_file_atomic(path, s.as_bytes()).map_err(|e| StudyError::file(path, e))
}

/// The per-pair results and the summary as aligned text tables (what the CLI prints).
pub fn pairs_table(rows: &[PairRow], summary: &[AlgorithmSummary]) -> String {
    let mut s = format!(
        "{:<6} {:<11} {:>5} {:>7}  {:>17}  {:<8} {:>9} {:>9} {:>10}  {}\n",
        "pair",
        "algo",
        "rels",
        "overlap",
        "truth floor m/deg",
        "result",
        "error m",
        "error deg",
        "time ms",
        "reason or stage"
    );
    for r in rows {
        let result = if r.success {
            "success"
        } else if r.false_merge {
            "FALSE"
        } else {
            "refused"
        };
        let _ = writeln!(
            s,
            "{:<6} {:<11} {:>5} {:>7.3}  {:>8.3}/{:<8.2}  {:<8} {:>9} {:>9} {:>10.1}  {}",
            format!("{}-{}", r.part_i, r.part_j),
            r.algorithm,
            r.relations,
            r.overlap,
            r.truth_error.0,
            r.truth_error.1,
            result,
            r.error.map_or("-".into(), |e| format!("{:.3}", e.0)),
            r.error.map_or("-".into(), |e| format!("{:.2}", e.1)),
            r.time_ms,
            if r.accepted && !r.stage.is_empty() { format!("by {}", r.stage) } else { r.reason.clone() }
        );
    }
    let _ = writeln!(
        s,
        "\n{:<11} {:>5} {:>8} {:>9} {:>6} {:>11} {:>14}",
        "algo", "pairs", "accepted", "successes", "false", "median ms", "median err m"
    );
    for r in summary {
        let _ = writeln!(
            s,
            "{:<11} {:>5} {:>8} {:>9} {:>6} {:>11.1} {:>14}",
            r.algorithm,
            r.pairs,
            r.accepted,
            r.successes,
            r.false_merges,
            r.median_time_ms,
            if r.median_error_m.is_finite() { format!("{:.3}", r.median_error_m) } else { "-".into() }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;
    use std::path::PathBuf;

    #[test]
    fn splits_in_time_into_equal_durations() {
        // 0..=10 s, one scan a second, but a gap from 3 s to 7 s.
        let stamps = [0.0, 1.0, 2.0, 3.0, 7.0, 8.0, 9.0, 10.0];
        assert_eq!(split_by_time(&stamps, 2).unwrap(), vec![0..4, 4..8]);
        // Thirds: [0, 3.33), [3.33, 6.67) is empty.
        let e = split_by_time(&stamps, 3).unwrap_err().to_string();
        assert!(e.contains("part 1 of 3") && e.contains("has no scan"), "{e}");
        let even: Vec<f64> = (0..=9).map(f64::from).collect();
        assert_eq!(split_by_time(&even, 3).unwrap(), vec![0..3, 3..6, 6..10]);
        for n in [0, 1] {
            assert!(split_by_time(&even, n).unwrap_err().to_string().contains("at least 2 parts"));
        }
        assert!(split_by_time(&[0.0, 2.0, 1.0], 2).unwrap_err().to_string().contains("not in time order"));
        assert!(split_by_time(&[], 2).is_err());
    }

    /// A robot driving a circle; part 0 is mapped in the true frame, part 1 in a frame `t_0_1` away, and
    /// relations between scans of both parts (and within each) from the true poses.
    fn two_robots(t_0_1: Pose2) -> (Vec<StampedPose>, Vec<StampedPose>, Vec<Relation>) {
        let truth = |k: usize| {
            let a = k as f64 * 0.1;
            pose(3.0 * a.cos(), 3.0 * a.sin(), a + std::f64::consts::FRAC_PI_2)
        };
        let p0: Vec<StampedPose> = (0..60).map(|k| StampedPose { stamp: k as f64, pose: truth(k) }).collect();
        let p1: Vec<StampedPose> =
            (60..120).map(|k| StampedPose { stamp: k as f64, pose: t_0_1.inverse() * truth(k) }).collect();
        let rel = |a: usize, b: usize, line: usize| Relation {
            t1: a as f64,
            t2: b as f64,
            delta: truth(a).inverse() * truth(b),
            line,
        };
        // Cross relations both ways round, and one within part 0.
        let relations = vec![rel(5, 70, 1), rel(100, 20, 2), rel(59, 60, 3), rel(3, 4, 4), rel(10, 118, 5)];
        (p0, p1, relations)
    }

    #[test]
    fn the_true_transform_comes_back_from_the_relations() {
        let t = pose(4.0, -2.5, 3.0); // near ±π: the heading median must not split
        let (p0, p1, rels) = two_robots(t);
        let cross = cross_relations(&rels, &[&p0, &p1], 0.001);
        assert_eq!(cross.keys().copied().collect::<Vec<_>>(), vec![(0, 1)]);
        let c = &cross[&(0, 1)];
        assert_eq!(c.iter().map(|c| c.line).collect::<Vec<_>>(), vec![1, 2, 3, 5]);
        // Line 2 was written from part 1 to part 0: turned round.
        assert_eq!((c[1].stamp_i, c[1].stamp_j), (20.0, 100.0));
        let est = true_transform(c).unwrap();
        let (rot, d) = transform_error(&est, &t);
        assert!(rot < 1e-9 && d < 1e-9, "{:?}", Xyt::from_pose(&est));
        let (m, deg) = median_error(&est, c).unwrap();
        assert!(m < 1e-9 && deg < 1e-7);
        // A stamp in no part (beyond the tolerance) drops its relation.
        let far = Relation { t1: 5.5, t2: 70.0, delta: Pose2::identity(), line: 9 };
        assert!(cross_relations(&[far], &[&p0, &p1], 0.001).is_empty());
    }

    #[test]
    fn the_centre_is_robust_and_headings_wrap() {
        let near_pi = [pose(1.0, 2.0, 3.1), pose(1.1, 2.1, -3.1), pose(0.9, 1.9, 3.13), pose(50.0, -40.0, 0.0)];
        let c = robust_centre(&near_pi).unwrap();
        let Xyt { x, y, theta: t } = Xyt::from_pose(&c);
        assert!((x - 1.05).abs() < 1e-9 && (y - 1.95).abs() < 1e-9, "{x} {y}");
        assert!(normalize_angle(t - 3.13).abs() < 0.03, "heading {t}: the outlier must not drag it to 0");
        assert!(robust_centre(&[]).is_none());
    }

    #[test]
    fn merges_are_scored_by_their_median_relation_error() {
        let t = pose(4.0, -2.5, 0.4);
        let (p0, p1, rels) = two_robots(t);
        let cross = cross_relations(&rels, &[&p0, &p1], 0.001).remove(&(0, 1)).unwrap();
        // An estimate 0.2 m off along x of part 0's frame, then one 3 degrees off.
        let off = pose(0.2, 0.0, 0.0) * t;
        let (m, deg) = median_error(&off, &cross).unwrap();
        assert!((m - 0.2).abs() < 1e-9 && deg < 1e-7, "{m} {deg}");
        let turned = pose(0.0, 0.0, 3f64.to_radians()) * t;
        let (_, deg) = median_error(&turned, &cross).unwrap();
        assert!((deg - 3.0).abs() < 1e-6, "{deg}");
        assert!(median_error(&t, &[]).is_none());
    }

    #[test]
    fn a_merge_of_two_cuts_is_scored_and_the_rows_summarised() {
        // Two maps of one floor plan, b's frame `t` away from a's; relations from the truth.
        let plan = mrslam_merge::floorplan::generate(
            5,
            &mrslam_merge::floorplan::FloorplanParams { width_m: 12.0, height_m: 10.0, ..Default::default() },
        );
        let t = pose(1.5, -0.5, 0.3);
        let mut b = plan.clone();
        b.set_origin(t.inverse() * plan.origin());
        let (o, small) = overlap(&plan, &b, &t);
        assert!(o > 0.95 && small > 0.95, "{o} {small}");
        let p0 = vec![StampedPose { stamp: 1.0, pose: pose(5.0, 4.0, 0.0) }];
        let p1 = vec![StampedPose { stamp: 2.0, pose: t.inverse() * pose(6.0, 4.0, 0.0) }];
        let rel = Relation { t1: 1.0, t2: 2.0, delta: pose(1.0, 0.0, 0.0), line: 1 };
        let cross = cross_relations(&[rel], &[&p0, &p1], 0.001).remove(&(0, 1)).unwrap();
        let row = merge_pair(Algorithm::Sift, (0, &plan), (1, &b), &cross, &ScoreParams::default()).unwrap();
        assert!(row.truth_error.0 < 1e-9);
        assert_eq!(row.false_merge, row.accepted && !row.success);
        assert_eq!(
            row.to_csv().split(',').count(),
            RESULTS_HEADER.split(',').count() + row.reason.matches(',').count()
        );
        let summary = summarise_pairs(&[row.clone(), row.clone()]);
        assert_eq!(summary.len(), 1);
        assert_eq!(summary[0].pairs, 2);
        assert_eq!(summary[0].successes, 2 * usize::from(row.success));
        let dir = tempfile::tempdir().unwrap();
        let path: PathBuf = dir.path().join("summary.csv");
        write_algorithm_summary(&summary, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with(SUMMARY_HEADER), "{text}");
        assert_eq!(csv_field("a, \"b\""), "\"a, \"\"b\"\"\"");
    }
}
