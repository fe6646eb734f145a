//! `mrslam merge A.yaml B.yaml [C.yaml ...] -o MERGED.yaml`: merge two maps (or more) of unknown relative pose.

use anyhow::{Context, Result, bail};
use clap::Args;
use mrslam_core::OccupancyGrid;
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_merge::MapImage;
use mrslam_merge::{Evidence, MapEncoding, MergeReport, merge};
use mrslam_testbed::runner::merge_view;
use mrslam_viz::pair::record_pair;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `mrslam merge`.
#[derive(Args)]
pub struct MergeArgs {
    /// First map (map_server YAML); the merged map is in its frame.
    pub a: PathBuf,
    /// Second map (map_server YAML).
    pub b: PathBuf,
    /// More maps: with three or more, every pair is merged and a spanning tree of the most confident accepted
    /// pairs places each map in the first map's frame; exit 2 when some map joins nothing.
    pub more: Vec<PathBuf>,
    /// Merged map to write (YAML, with the PGM and a PNG preview beside it); not written when the merge is
    /// rejected (with three or more maps: when no map joins the first).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the merge report (JSON) here, accepted or not.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// The merger and the pipeline around it.
    #[command(flatten)]
    pub merger: super::merger_args::MergerArgs,
    /// Draw both maps side by side with the inlier matches (PNG).
    #[arg(long)]
    pub matches_png: Option<PathBuf>,
    /// Rerun recording of the merge.
    #[command(flatten)]
    pub viz: super::viz::VizArgs,
}

/// Fails on the flags that only make sense for two maps (the match drawing, the rerun recording).
fn refuse_pair_only_flags(args: &MergeArgs) -> Result<()> {
    let n = 2 + args.more.len();
    if args.matches_png.is_some() {
        bail!("--matches-png draws the matches of two maps, and {n} maps were given; merge a pair to draw it");
    }
    if args.merger.contact.is_some() {
        bail!("--contact places two robots, one in each of two maps, and {n} maps were given; merge a pair with it");
    }
    if !args.viz.targets()?.is_empty() {
        bail!(
            "--rrd, --spawn and --connect record the merge of two maps, and {n} maps were given; merge a pair to record it"
        );
    }
    Ok(())
}

/// Runs `mrslam merge`.
pub fn run(args: MergeArgs) -> Result<ExitCode> {
    super::Outputs::reading([&args.a, &args.b].into_iter().chain(&args.more).map(PathBuf::as_path))
        .maybe("--output", args.output.as_deref(), super::kind::MAP)
        .maybe("--report", args.report.as_deref(), super::kind::JSON)
        .maybe("--matches-png", args.matches_png.as_deref(), super::kind::PNG)
        .maybe("--rrd", args.viz.rrd.as_deref(), super::kind::RRD)
        .check()?;
    if !args.more.is_empty() {
        refuse_pair_only_flags(&args)?;
    }
    let a = super::map::read_yaml_map(&args.a)?;
    let b = super::map::read_yaml_map(&args.b)?;
    super::merge_many::refuse_unmergeable_pairs(&[args.a.as_path(), args.b.as_path()], &[&a, &b])?;
    let (name_a, name_b) = pair_names(&args.a, &args.b);
    let (algorithm, seed) = (args.merger.algorithm, args.merger.seed);
    let recording_id = format!("merge-{name_a}-{name_b}-{algorithm}-seed{seed}");
    let mut viz = args.viz.open(&recording_id, &format!("merge {name_a} + {name_b} ({algorithm})"))?;
    let merger = args.merger.config().build();
    let mp = args.merger.params();
    if !args.more.is_empty() {
        let files: Vec<&Path> = [&args.a, &args.b].into_iter().chain(&args.more).map(PathBuf::as_path).collect();
        let outputs = super::merge_many::Outputs { report: args.report.as_deref(), map: args.output.as_deref() };
        return super::merge_many::run(&files, vec![a, b], merger.as_ref(), &mp, outputs);
    }
    let out = merge(merger.as_ref(), &a, &b, &mp);
    if let Some(p) = &args.report {
        let json = serde_json::to_vec_pretty(&out.report).context("serialising the report")?;
        write_file_atomic(p, &json)?;
    }
    if let Some(p) = &args.matches_png {
        draw_matches(&a, &b, &out.evidence, p)?;
    }
    print!("{}", summary(&out.report));
    if let Some(mut rec) = viz.take() {
        let view = merge_view(&out, &name_a, &name_b, None);
        record_pair(&mut rec, &a, &b, &view);
        let stats = rec.finish()?;
        println!("rerun:       {} ({} rows)", args.viz.describe(), stats.rows);
    }
    match (&out.merged, &args.output) {
        (Some(g), Some(path)) => {
            map_io::write_ros_map_with_preview(g, path)?;
            println!("merged map: {} ({}x{} cells)", path.display(), g.width(), g.height());
        }
        (None, Some(path)) => println!("merged map: not written to {} (merge rejected)", path.display()),
        _ => {}
    }
    Ok(if out.report.accepted { ExitCode::SUCCESS } else { ExitCode::from(2) })
}

/// Names of the two maps in a recording: their file stems, or `a` and `b` when the stems are alike.
fn pair_names(a: &Path, b: &Path) -> (String, String) {
    let stem = |p: &Path| p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let (sa, sb) = (stem(a), stem(b));
    if sa.is_empty() || sb.is_empty() || sa == sb { ("a".into(), "b".into()) } else { (sa, sb) }
}

/// The human summary of a merge.
pub fn summary(r: &MergeReport) -> String {
    // A cascade names the stage that merged; a refusal's reason names every stage's.
    let name = match (&r.stage, r.accepted) {
        (Some(stage), true) => format!("{}: {stage}", r.algorithm),
        _ => r.algorithm.clone(),
    };
    let mut s = format!("merge ({name}): {}\n", if r.accepted { "ACCEPTED" } else { "REJECTED" });
    if let Some(reason) = &r.reason {
        s += &format!("  reason:      {reason}\n");
    }
    if let Some(t) = &r.transform {
        s += &format!(
            "  transform:   x {:.3} m, y {:.3} m, theta {:.4} rad ({:.2} deg), scale {:.4}\n",
            t.x,
            t.y,
            t.theta,
            t.theta.to_degrees(),
            r.scale.unwrap_or(1.0)
        );
    }
    s += &format!(
        "  evidence:    {} inliers of {} matches, confidence {:.2}, acceptance index {}, {} common cells\n",
        r.inliers,
        r.matches,
        r.confidence,
        r.acceptance_index.map_or("-".to_string(), |v| format!("{v:.3}")),
        r.common_cells
    );
    // A cascade's stages in total (each stage's own breakdown is in the JSON report).
    let stages: Vec<String> = r
        .timings_ms
        .iter()
        .filter(|(k, _)| r.stage.is_none() || !k.contains('/'))
        .map(|(k, v)| format!("{k} {v:.1}"))
        .collect();
    s += &format!("  time:        {:.1} ms ({})\n", r.time_ms, stages.join(", "));
    s
}

/// Draws both maps side by side (a left, b right), every feature as a dot and the inliers as lines.
fn draw_matches(a: &OccupancyGrid, b: &OccupancyGrid, ev: &Evidence, path: &Path) -> Result<()> {
    let enc = MapEncoding::PAPER;
    let (ia, ib) = (MapImage::render(a, &enc, 8), MapImage::render(b, &enc, 8));
    let (w, h) = (ia.width + ib.width, ia.height.max(ib.height));
    if w == 0 || h == 0 {
        bail!("{}: nothing to draw, both maps are empty", path.display());
    }
    let mut img = image::RgbImage::from_pixel(w as u32, h as u32, image::Rgb([205, 205, 205]));
    for (im, dx) in [(&ia, 0usize), (&ib, ia.width)] {
        for v in 0..im.height {
            for u in 0..im.width {
                let g = im.pixels[v * im.width + u] as u8;
                img.put_pixel((u + dx) as u32, v as u32, image::Rgb([g, g, g]));
            }
        }
    }
    let to_px = |im: &MapImage, g: &OccupancyGrid, p: &nalgebra::Point2<f64>, dx: usize| {
        let (u, v) = im.map_to_pixel(g, p);
        (u + dx as f64, v)
    };
    let mut dot = |x: f64, y: f64, c: [u8; 3]| {
        for oy in -1..=1 {
            for ox in -1..=1 {
                let (px, py) = (x.round() as i64 + ox, y.round() as i64 + oy);
                if px >= 0 && py >= 0 && (px as usize) < w && (py as usize) < h {
                    img.put_pixel(px as u32, py as u32, image::Rgb(c));
                }
            }
        }
    };
    for p in &ev.points_a {
        let (x, y) = to_px(&ia, a, p, 0);
        dot(x, y, [40, 90, 220]);
    }
    for p in &ev.points_b {
        let (x, y) = to_px(&ib, b, p, ia.width);
        dot(x, y, [40, 90, 220]);
    }
    for &(i, j) in &ev.inlier_pairs {
        let (x0, y0) = to_px(&ia, a, &ev.points_a[i], 0);
        let (x1, y1) = to_px(&ib, b, &ev.points_b[j], ia.width);
        let n = (x1 - x0).abs().max((y1 - y0).abs()).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (x, y) = (x0 + t * (x1 - x0), y0 + t * (y1 - y0));
            if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
                img.put_pixel(x as u32, y as u32, image::Rgb([20, 170, 60]));
            }
        }
    }
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .with_context(|| format!("{}: encoding PNG", path.display()))?;
    write_file_atomic(path, &bytes)?;
    Ok(())
}
