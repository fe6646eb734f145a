//! `mrslam merge A.yaml B.yaml C.yaml ...`: three or more maps merged along a spanning tree of the most
//! confident accepted pairs, each placed in the first map's frame.

use anyhow::{Context, Result};
use mrslam_core::OccupancyGrid;
use mrslam_core::Xyt;
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_merge::{MergeParams, Merger, MultiReport, merge_many};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where the N-map merge's results go.
pub struct Outputs<'a> {
    /// The JSON report (`--report`).
    pub report: Option<&'a Path>,
    /// The merged map (`--output`).
    pub map: Option<&'a Path>,
}

/// The largest ratio between two maps' resolutions `merge` takes: a merge resamples both maps to one resolution,
/// and maps further apart than this are a wrong file (or a typo'd resolution), not two robots' maps.
pub const MAX_RESOLUTION_RATIO: f64 = 20.0;

/// Refuses a pair among `files` (their maps `maps`, in order) that cannot be two maps to merge: one map given
/// twice, by name, by another path to the same file, as two YAMLs naming one image, or as a copy holding the same
/// cells (wherever its origin puts them), since merging a map with itself measures nothing; or two maps whose
/// resolutions are further apart than [`MAX_RESOLUTION_RATIO`].
pub fn refuse_unmergeable_pairs(files: &[&Path], maps: &[&OccupancyGrid]) -> Result<()> {
    // Each YAML's image, resolved once.
    let images: Vec<Option<PathBuf>> =
        files.iter().map(|f| super::paths::read_files(f).get(1).and_then(|i| i.canonicalize().ok())).collect();
    for (i, ((fa, a), ia)) in files.iter().zip(maps).zip(&images).enumerate() {
        for ((fb, b), ib) in files.iter().zip(maps).zip(&images).skip(i + 1) {
            refuse_same_pair((fa, a, ia), (fb, b, ib))?;
            refuse_far_resolutions(fa, a, fb, b)?;
        }
    }
    Ok(())
}

/// Refuses `a` (read from `fa`, naming the image `ia`) and `b` when they are one map: one file, one image, or the
/// same cells.
fn refuse_same_pair(
    (fa, a, ia): (&Path, &OccupancyGrid, &Option<PathBuf>),
    (fb, b, ib): (&Path, &OccupancyGrid, &Option<PathBuf>),
) -> Result<()> {
    let same_file = fa.canonicalize().ok().is_some_and(|p| fb.canonicalize().ok() == Some(p));
    if same_file {
        anyhow::bail!("{} and {}: the same map file given twice", fa.display(), fb.display());
    }
    if let Some(shared) = ia.as_ref().filter(|i| ib.as_ref() == Some(*i)) {
        anyhow::bail!(
            "{} and {} both name the image {}: merging a map with itself measures nothing",
            fa.display(),
            fb.display(),
            shared.display()
        );
    }
    if a.width() == b.width() && a.height() == b.height() && a.cells() == b.cells() {
        anyhow::bail!(
            "{} holds the same cells as {} (a copy?): merging a map with itself measures nothing",
            fb.display(),
            fa.display()
        );
    }
    Ok(())
}

/// Refuses two maps whose resolutions differ by more than [`MAX_RESOLUTION_RATIO`].
fn refuse_far_resolutions(fa: &Path, a: &OccupancyGrid, fb: &Path, b: &OccupancyGrid) -> Result<()> {
    let (ra, rb) = (a.resolution(), b.resolution());
    if ra.max(rb) > MAX_RESOLUTION_RATIO * ra.min(rb) {
        anyhow::bail!(
            "{} ({ra} m per pixel) and {} ({rb} m per pixel): resolutions more than {MAX_RESOLUTION_RATIO}x apart \
             are not two robots' maps of one place; check the files' `resolution`",
            fa.display(),
            fb.display()
        );
    }
    Ok(())
}

/// Runs the N-map merge of the maps in `files`: `maps` holds the first ones, read already; the rest are read here.
pub fn run(
    files: &[&Path],
    mut maps: Vec<OccupancyGrid>,
    merger: &dyn Merger,
    mp: &MergeParams,
    to: Outputs,
) -> Result<ExitCode> {
    for p in &files[maps.len()..] {
        maps.push(super::map::read_yaml_map(p)?);
    }
    refuse_unmergeable_pairs(files, &maps.iter().collect::<Vec<_>>())?;
    let out = merge_many(merger, &maps, mp);
    if let Some(p) = to.report {
        let files = files.iter().map(|f| f.display().to_string()).collect();
        let bytes =
            serde_json::to_vec_pretty(&Report { files, report: &out.report }).context("serialising the report")?;
        write_file_atomic(p, &bytes)?;
    }
    print!("{}", summary(&out.report, files));
    match (&out.merged, to.map) {
        (Some(g), Some(path)) => {
            map_io::write_ros_map_with_preview(g, path)?;
            let joined = out.report.maps - out.report.not_connected.len();
            println!(
                "merged map: {} ({}x{} cells, {joined} of {} maps)",
                path.display(),
                g.width(),
                g.height(),
                out.report.maps
            );
        }
        (None, Some(path)) => {
            println!("merged map: not written to {} (no map joins {})", path.display(), files[0].display())
        }
        _ => {}
    }
    Ok(if out.report.all_connected() { ExitCode::SUCCESS } else { ExitCode::from(2) })
}

/// The JSON `--report` writes: the map files in order, then the library's report.
#[derive(serde::Serialize)]
struct Report<'a> {
    /// The maps as given, in order (indices in the report refer to them).
    files: Vec<String>,
    /// The N-map merge's report.
    #[serde(flatten)]
    report: &'a MultiReport,
}

/// A transform as the summary prints it.
fn xyt(t: &Xyt) -> String {
    format!("x {:.3} m, y {:.3} m, theta {:.4} rad ({:.2} deg)", t.x, t.y, t.theta, t.theta.to_degrees())
}

/// The human summary of an N-map merge: a line per pair, the tree, each map's transform, the maps left out, the
/// accepted pairs the tree contradicts.
pub fn summary(r: &MultiReport, files: &[&Path]) -> String {
    let name = |i: usize| files.get(i).map_or_else(|| format!("map {i}"), |f| short(f));
    let joined = r.maps - r.not_connected.len();
    let mut s =
        format!("merge of {} maps ({}): {joined} of {} in the frame of {}\n", r.maps, r.algorithm, r.maps, name(0));
    s += "pairs (transform takes the second map into the first's frame):\n";
    for q in &r.pairs {
        let m = &q.report;
        s += &format!("  {} + {}: ", name(q.a), name(q.b));
        if m.accepted {
            let t = m.transform.as_ref().map_or_else(|| "-".to_string(), xyt);
            s += &format!("ACCEPTED  confidence {:.2}, {} inliers; {t}\n", m.confidence, m.inliers);
        } else {
            s += &format!("REJECTED  {}\n", m.reason.as_deref().unwrap_or("no reason given"));
        }
    }
    s += "tree (most confident accepted pairs, Kruskal):\n";
    if r.tree.is_empty() {
        s += "  no accepted pair\n";
    }
    for e in &r.tree {
        s += &format!("  {} -> {} (confidence {:.2})\n", name(e.parent), name(e.child), e.confidence);
    }
    s += &format!("transforms into the frame of {}:\n", name(0));
    for (i, t) in r.transforms.iter().enumerate() {
        s += &format!("  {}: {}\n", name(i), t.as_ref().map_or_else(|| "not connected".to_string(), xyt));
    }
    for c in r.components.iter().skip(1) {
        let names: Vec<String> = c.iter().map(|&i| name(i)).collect();
        if c.len() == 1 {
            s += &format!("left out:   {} joins no other map\n", names.join(""));
        } else {
            s += &format!("left out:   {} join each other but not {}\n", names.join(", "), name(0));
        }
    }
    // An accepted pair the tree's chain contradicts: a pair on that cycle is wrong, so a placement may be too.
    for d in &r.disagreements {
        let q = &r.pairs[d.pair];
        s += &format!(
            "WARNING:    {} + {} was accepted {:.1} deg and {:.2} m away from the tree's chain between them: one of \
             the pairs on that cycle is wrong, check the placements\n",
            name(q.a),
            name(q.b),
            d.rotation_deg,
            d.translation_m
        );
    }
    s += &format!("time:       {:.1} ms\n", r.time_ms);
    s
}

/// A map's file name for the summary (the whole path when it has none).
fn short(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}
