//! `plot.png`: success rate against overlap per algorithm with Wilson 95 % bands (top panel) and median
//! merge time (bottom panel), [`WIDTH`] × [`HEIGHT`] pixels. Text uses a font compiled into the
//! binary (Ubuntu Light, from `epaint_default_fonts`), so no system fonts are needed.

use super::StudyError;
use super::summary::SummaryRow;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::Path;
use std::sync::Once;

/// Width of `plot.png`, pixels.
pub const WIDTH: u32 = 1200;
/// Height of `plot.png`, pixels.
pub const HEIGHT: u32 = 900;

/// The colours of the lines, in order (matplotlib's first six).
pub(crate) const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Registers the compiled-in font as plotters' "sans-serif", once per process (every plot of the tools uses it).
pub fn register_sans_serif() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is valid (it ships with egui); should it ever not be, text is dropped, not the plot.
        let _ = register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

/// Draws the legend of `chart`'s labelled series at `position`: the one legend style of the studies' plots.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 18))
        .draw()
        .map_err(|e| e.to_string())
}

/// Draws the summary into an RGB buffer of [`WIDTH`] × [`HEIGHT`].
pub fn render(summary: &[SummaryRow]) -> Result<Vec<u8>, String> {
    register_sans_serif();
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (top, bottom) = root.split_vertically(HEIGHT * 11 / 20);
        let mut algorithms: Vec<&str> = Vec::new();
        for r in summary {
            if !algorithms.contains(&r.algorithm.as_str()) {
                algorithms.push(&r.algorithm);
            }
        }
        let x_max = summary.iter().map(|r| r.overlap_bin).fold(0.0f64, f64::max);
        let x_min = summary.iter().map(|r| r.overlap_bin).fold(x_max, f64::min);
        let pad = ((x_max - x_min) * 0.05).max(0.02);
        let xs = (x_min - pad).max(0.0)..(x_max + pad).min(1.0);
        let total: usize = summary.iter().map(|r| r.trials).sum();

        let mut chart = ChartBuilder::on(&top)
            .caption(format!("Merge success against overlap ({total} algorithm trials)"), ("sans-serif", 28))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(xs.clone(), 0.0f64..1.0f64)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("overlap")
            .y_desc("success rate (95% Wilson interval)")
            .light_line_style(WHITE)
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, alg) in algorithms.iter().enumerate() {
            let c = COLOURS[i % COLOURS.len()];
            let rows: Vec<&SummaryRow> = summary.iter().filter(|r| r.algorithm == *alg).collect();
            let mut band: Vec<(f64, f64)> = rows.iter().map(|r| (r.overlap_bin, r.success_hi)).collect();
            band.extend(rows.iter().rev().map(|r| (r.overlap_bin, r.success_lo)));
            chart.draw_series(std::iter::once(Polygon::new(band, c.mix(0.18)))).map_err(|e| e.to_string())?;
            let line: Vec<(f64, f64)> = rows.iter().map(|r| (r.overlap_bin, r.success_rate)).collect();
            chart
                .draw_series(std::iter::once(PathElement::new(line.clone(), c.stroke_width(3))))
                .map_err(|e| e.to_string())?
                .label(format!("{alg} success"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 5, c.filled()))).map_err(|e| e.to_string())?;
            let fm: Vec<(f64, f64)> = rows.iter().map(|r| (r.overlap_bin, r.false_merge_rate)).collect();
            chart
                .draw_series(std::iter::once(PathElement::new(fm, c.stroke_width(1))))
                .map_err(|e| e.to_string())?
                .label(format!("{alg} false merges"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(1)));
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;

        let times: Vec<f64> = summary.iter().map(|r| r.median_time_ms).filter(|t| t.is_finite() && *t > 0.0).collect();
        let t_hi = times.iter().copied().fold(0.0f64, f64::max);
        let t_hi = if times.is_empty() { 1.0 } else { t_hi * 1.15 };
        let mut chart = ChartBuilder::on(&bottom)
            .caption("Median merge time", ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(xs, 0.0..t_hi)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("overlap")
            .y_desc("median merge time, ms")
            .light_line_style(WHITE)
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, alg) in algorithms.iter().enumerate() {
            let c = COLOURS[i % COLOURS.len()];
            let line: Vec<(f64, f64)> = summary
                .iter()
                .filter(|r| r.algorithm == *alg && r.median_time_ms > 0.0)
                .map(|r| (r.overlap_bin, r.median_time_ms))
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(line.clone(), c.stroke_width(3))))
                .map_err(|e| e.to_string())?
                .label(alg.to_string())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 5, c.filled()))).map_err(|e| e.to_string())?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(buf)
}

/// Draws the summary into `path` as a PNG of [`WIDTH`] × [`HEIGHT`].
pub fn draw(summary: &[SummaryRow], path: &Path) -> Result<(), StudyError> {
    let buf = render(summary).map_err(|e| StudyError::file(path, format!("drawing the plot: {e}")))?;
    write_rgb_png(buf, (WIDTH, HEIGHT), path)
}

/// Writes an RGB buffer of `size` pixels as a PNG at `path` (under a temporary name, then renamed).
pub fn write_rgb_png(buf: Vec<u8>, size: (u32, u32), path: &Path) -> Result<(), StudyError> {
    let img = image::RgbImage::from_raw(size.0, size.1, buf)
        .ok_or_else(|| StudyError::file(path, "plot buffer of the wrong size"))?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| StudyError::file(path, e))?;
    mrslam_core::output::write_file_atomic(path, &bytes).map_err(|e| StudyError::file(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png_of_the_documented_size() {
        let rows: Vec<SummaryRow> = [(0.1, "sift", 0.5), (0.3, "sift", 0.9), (0.1, "rmap", 0.0), (0.3, "rmap", 0.2)]
            .iter()
            .map(|&(o, a, p)| SummaryRow {
                overlap_bin: o,
                algorithm: a.into(),
                trials: 10,
                successes: (p * 10.0) as usize,
                success_rate: p,
                success_lo: (p - 0.2f64).max(0.0),
                success_hi: (p + 0.2f64).min(1.0),
                false_merges: 1,
                false_merge_rate: 0.1,
                median_time_ms: 100.0 * (1.0 + p),
                mean_overlap: o,
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.png");
        draw(&rows, &path).unwrap();
        let img = image::open(&path).unwrap();
        assert_eq!((img.width(), img.height()), (WIDTH, HEIGHT));
        // Something was drawn besides the background.
        assert!(img.to_rgb8().pixels().any(|p| p.0 != [255, 255, 255]));
    }
}
