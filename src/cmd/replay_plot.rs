//! The pictures of `mrslam sim replay --report R.json`: `R.residuals.png` (per range band, the real residuals'
//! histogram against the fitted model's and the lidar model's) and, with a trajectory, `R.odometry.png` (the
//! reference path, the log's odometry and each simulated robot's, all placed at the first pose). Drawn with
//! plotters into a buffer, written under a temporary name and renamed.

use anyhow::{Result, anyhow};
use mrslam_core::Pose2;
use mrslam_sim::replay::{BandStats, HISTOGRAM_BIN_M, OUTLIER_M, ReplayReport};
use mrslam_studies::plot::{register_sans_serif, write_rgb_png};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Size of `R.residuals.png`, pixels.
pub const RESIDUALS_SIZE: (u32, u32) = (1500, 900);
/// Size of `R.odometry.png`, pixels.
pub const ODOMETRY_SIZE: (u32, u32) = (1100, 1000);

const COLOURS: [RGBColor; 5] = [
    RGBColor(40, 40, 40),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
];

/// `R.json` → `R.<what>.png` beside it.
pub fn plot_path(report: &Path, what: &str) -> PathBuf {
    let stem = report.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    report.with_file_name(format!("{stem}.{what}.png"))
}

/// A histogram's counts as densities (per metre) at the bins' centres.
fn density(counts: &[usize]) -> Vec<(f64, f64)> {
    let n = counts.iter().sum::<usize>().max(1) as f64;
    counts
        .iter()
        .enumerate()
        .map(|(k, &c)| (-OUTLIER_M + (k as f64 + 0.5) * HISTOGRAM_BIN_M, c as f64 / (n * HISTOGRAM_BIN_M)))
        .collect()
}

fn band_name(b: &BandStats) -> String {
    if b.to.is_finite() { format!("{}-{} m", b.from, b.to) } else { format!(">= {} m", b.from) }
}

/// Draws the residual histograms of every range band of `r` into `path`; `lidar` names the model compared.
pub fn residuals(r: &ReplayReport, lidar: &str, path: &Path) -> Result<()> {
    register_sans_serif();
    let (w, h) = RESIDUALS_SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let root = root
            .titled(
                &format!("Replay residuals (real − simulated range) by range band: real, fitted + bias, {lidar}"),
                ("sans-serif", 26),
            )
            .map_err(|e| anyhow!("{e}"))?;
        let panels = root.split_evenly((2, 3));
        for (panel, band) in panels.iter().zip(&r.by_range) {
            let series = [
                ("real", density(&band.histogram.real)),
                ("fitted + bias", density(&band.histogram.fitted)),
                (lidar, density(&band.histogram.model)),
            ];
            let top = series.iter().flat_map(|(_, s)| s.iter().map(|p| p.1)).fold(1.0f64, f64::max) * 1.1;
            let ks = |v: Option<f64>| v.map_or("-".into(), |d| format!("{d:.3}"));
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    format!(
                        "{}: {} beams, KS D fitted {} / model {}",
                        band_name(band),
                        band.beams - band.outliers,
                        ks(band.ks_fitted),
                        ks(band.ks_model)
                    ),
                    ("sans-serif", 18),
                )
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(50)
                .build_cartesian_2d(-OUTLIER_M..OUTLIER_M, 0.0..top)
                .map_err(|e| anyhow!("{e}"))?;
            chart
                .configure_mesh()
                .x_desc("residual, m")
                .y_desc("density, 1/m")
                .light_line_style(WHITE)
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
            let half = 0.5 * HISTOGRAM_BIN_M;
            chart
                .draw_series(
                    series[0].1.iter().map(|&(x, y)| {
                        Rectangle::new([(x - half, 0.0), (x + half, y)], RGBColor(170, 170, 170).filled())
                    }),
                )
                .map_err(|e| anyhow!("{e}"))?
                .label("real")
                .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], RGBColor(170, 170, 170).filled()));
            for (k, (name, s)) in series.iter().enumerate().skip(1) {
                let c = COLOURS[k];
                chart
                    .draw_series(std::iter::once(PathElement::new(s.clone(), c.stroke_width(2))))
                    .map_err(|e| anyhow!("{e}"))?
                    .label(name.to_string())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(write_rgb_png(buf, (w, h), path)?)
}

/// Draws named paths (the first is the reference) into `path`, axes in metres with equal scales.
pub fn odometry(paths: &[(String, Vec<Pose2>)], path: &Path) -> Result<()> {
    register_sans_serif();
    let (w, h) = ODOMETRY_SIZE;
    let pts = |p: &[Pose2]| -> Vec<(f64, f64)> { p.iter().map(|q| (q.translation.x, q.translation.y)).collect() };
    let all: Vec<(f64, f64)> = paths.iter().flat_map(|(_, p)| pts(p)).filter(|p| p.0.is_finite()).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in &all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if all.is_empty() {
        (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
    }
    // Equal scales: the shorter side widened to the longer one's extent per pixel.
    let span = ((x1 - x0) / w as f64).max((y1 - y0) / h as f64).max(1e-3) * 1.08;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (hx, hy) = (0.5 * span * w as f64, 0.5 * span * h as f64);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Odometry against the reference path (all placed at its first pose)", ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(cx - hx..cx + hx, cy - hy..cy + hy)
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("x, m")
            .y_desc("y, m")
            .light_line_style(WHITE)
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for (k, (name, p)) in paths.iter().enumerate() {
            let c = COLOURS[k % COLOURS.len()];
            let width = if k == 0 { 3 } else { 2 };
            chart
                .draw_series(std::iter::once(PathElement::new(pts(p), c.stroke_width(width))))
                .map_err(|e| anyhow!("{e}"))?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(width)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(write_rgb_png(buf, (w, h), path)?)
}

/// `odom` (poses in its own frame) placed so that its first pose lies on `start`.
pub fn placed_at(start: &Pose2, odom: &[Pose2]) -> Vec<Pose2> {
    let Some(first) = odom.first() else { return Vec::new() };
    let to = start * first.inverse();
    odom.iter().map(|o| to * o).collect()
}

/// A simulated robot's odometry error against its own true poses `truth` (which slip takes off the reference),
/// carried onto `reference` step by step: each step of the reference followed by that step's odometry error
/// (`(truth step)⁻¹ · odometry step`), from the reference's first pose: the odometry the robot would have read
/// driving the reference itself.
pub fn error_on_reference(reference: &[Pose2], truth: &[Pose2], odom: &[Pose2]) -> Vec<Pose2> {
    let Some(&first) = reference.first() else { return Vec::new() };
    let mut out = vec![first];
    let n = reference.len().min(truth.len()).min(odom.len());
    for k in 1..n {
        let error = truth[k - 1].inv_mul(&truth[k]).inv_mul(&odom[k - 1].inv_mul(&odom[k]));
        let last = out[k - 1];
        out.push(last * reference[k - 1].inv_mul(&reference[k]) * error);
    }
    out
}
