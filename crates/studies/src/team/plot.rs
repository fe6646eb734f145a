//! A team study's pictures, in the style of `plot.png` of the merge studies (same size, compiled-in font):
//! `plot.png`, coverage over time (each configuration's mean curve in its 95 % band), and `time90.png`, the mean
//! time to 90 % coverage against the number of robots (one line per coordination and whatever else varies,
//! 95 % error bars, each point labelled with how many of its trials reached 90 %).

use super::coverage::CoverageCurve;
use super::summary::{ConfigKey, TeamSummaryRow};
use crate::StudyError;
use crate::plot::{COLOURS, HEIGHT, WIDTH, draw_legend, register_sans_serif, write_rgb_png};
use plotters::prelude::*;
use std::path::Path;

/// What varies among `configs` (robots, range, coordination, merger), so labels name only that.
struct Varies {
    n: bool,
    range: bool,
    coordination: bool,
    merger: bool,
}

impl Varies {
    fn of(configs: &[ConfigKey]) -> Varies {
        let differ = |f: &dyn Fn(&ConfigKey, &ConfigKey) -> bool| configs.iter().any(|c| f(c, &configs[0]));
        Varies {
            n: differ(&|a, b| a.n != b.n),
            range: differ(&|a, b| a.range_m != b.range_m),
            coordination: differ(&|a, b| a.coordination != b.coordination),
            merger: differ(&|a, b| a.merger != b.merger),
        }
    }

    /// `c` named by what varies (with `with_n`, its robot count too); the whole of it when nothing varies.
    fn label(&self, c: &ConfigKey, with_n: bool) -> String {
        let mut parts = Vec::new();
        if with_n && self.n {
            parts.push(format!("N={}", c.n));
        }
        if self.range {
            parts.push(format!("{} m", c.range_m));
        }
        if self.coordination {
            parts.push(c.coordination.to_string());
        }
        if self.merger {
            parts.push(c.merger.to_string());
        }
        if parts.is_empty() { if with_n { c.label() } else { c.coordination.to_string() } } else { parts.join(", ") }
    }
}

/// The caption's note of what is fixed: `range 6 m, cascade` for what does not vary.
fn fixed(v: &Varies, c: &ConfigKey) -> String {
    let mut parts = Vec::new();
    if !v.n {
        parts.push(format!("N={}", c.n));
    }
    if !v.range {
        parts.push(format!("range {} m", c.range_m));
    }
    if !v.coordination {
        parts.push(c.coordination.to_string());
    }
    if !v.merger {
        parts.push(c.merger.to_string());
    }
    parts.join(", ")
}

fn chart_err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Draws the coverage curves into an RGB buffer of [`WIDTH`] × [`HEIGHT`].
pub fn render_coverage(curves: &[CoverageCurve]) -> Result<Vec<u8>, String> {
    register_sans_serif();
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(chart_err)?;
        let configs: Vec<ConfigKey> = curves.iter().map(|c| c.config).collect();
        let varies = Varies::of(&configs);
        let t_max = curves.iter().filter_map(|c| c.times.last()).copied().fold(1.0f64, f64::max);
        let trials: Vec<usize> = curves.iter().filter_map(|c| c.mean.first().map(|m| m.n)).collect();
        let n_text = if trials.windows(2).all(|w| w[0] == w[1]) {
            format!("{} trials each", trials.first().copied().unwrap_or(0))
        } else {
            "trials per configuration in the legend".to_string()
        };
        let caption = match configs.first() {
            Some(c) if !fixed(&varies, c).is_empty() => format!("Coverage over time ({}; {n_text})", fixed(&varies, c)),
            _ => format!("Coverage over time ({n_text})"),
        };
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 28))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..t_max, 0.0f64..1.0f64)
            .map_err(chart_err)?;
        chart
            .configure_mesh()
            .x_desc("simulated time, s")
            .y_desc("share of the reachable free area mapped (mean, 95% t interval)")
            .light_line_style(WHITE)
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .draw()
            .map_err(chart_err)?;
        for (i, c) in curves.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            // Earlier curves wider, so that one drawn over an equal one (a lone robot's runs under two
            // coordinations are one run) still shows at its edges.
            let width = 2 + 2 * (curves.len() - 1 - i).min(3) as u32;
            let pts: Vec<(f64, &crate::student_t::MeanCi)> = c.times.iter().copied().zip(&c.mean).collect();
            // The band where there is an interval (two trials or more); the mean line everywhere.
            let mut band: Vec<(f64, f64)> =
                pts.iter().filter(|(_, m)| m.hi.is_finite()).map(|(t, m)| (*t, m.hi)).collect();
            band.extend(pts.iter().rev().filter(|(_, m)| m.lo.is_finite()).map(|(t, m)| (*t, m.lo)));
            if band.len() > 2 {
                chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.15)))).map_err(chart_err)?;
            }
            let line: Vec<(f64, f64)> = pts.iter().map(|(t, m)| (*t, m.mean)).collect();
            let n = c.mean.first().map_or(0, |m| m.n);
            chart
                .draw_series(std::iter::once(PathElement::new(line, colour.stroke_width(width))))
                .map_err(chart_err)?
                .label(format!("{} (n={n})", varies.label(&c.config, true)))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(width)));
        }
        let ninety = vec![(0.0, 0.9), (t_max, 0.9)];
        chart.draw_series(std::iter::once(PathElement::new(ninety, BLACK.mix(0.4)))).map_err(chart_err)?;
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        root.present().map_err(chart_err)?;
    }
    Ok(buf)
}

/// Draws the mean time to 90 % against the number of robots into an RGB buffer of [`WIDTH`] × [`HEIGHT`].
pub fn render_time90(summary: &[TeamSummaryRow]) -> Result<Vec<u8>, String> {
    register_sans_serif();
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(chart_err)?;
        let configs: Vec<ConfigKey> = summary.iter().map(|r| r.config).collect();
        let varies = Varies::of(&configs);
        // One line per configuration without its robot count, in order of first appearance.
        let mut lines: Vec<ConfigKey> = Vec::new();
        for c in &configs {
            if !lines.iter().any(|l| ConfigKey { n: c.n, ..*l } == *c) {
                lines.push(*c);
            }
        }
        let n_max = configs.iter().map(|c| c.n).max().unwrap_or(1);
        let n_min = configs.iter().map(|c| c.n).min().unwrap_or(1);
        let top = summary
            .iter()
            .flat_map(|r| [r.time_to_90.mean, r.time_to_90.hi])
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let y_max = if top > 0.0 { top * 1.2 } else { 1.0 };
        let caption = match configs.first() {
            Some(c) => {
                let f = fixed(&Varies { n: true, ..Varies::of(&configs) }, c);
                if f.is_empty() { "Time to 90 % coverage".to_string() } else { format!("Time to 90 % coverage ({f})") }
            }
            None => "Time to 90 % coverage".to_string(),
        };
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 28))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((n_min as f64 - 0.5)..(n_max as f64 + 0.5), 0.0..y_max)
            .map_err(chart_err)?;
        chart
            .configure_mesh()
            .x_desc("robots (N)")
            .y_desc("time to 90 %, s (mean of trials that reached it, 95% t interval)")
            .x_labels(2 * (n_max - n_min) + 3)
            .x_label_formatter(&|x| if (x - x.round()).abs() < 1e-6 { format!("{x:.0}") } else { String::new() })
            .light_line_style(WHITE)
            .label_style(("sans-serif", 18))
            .axis_desc_style(("sans-serif", 20))
            .draw()
            .map_err(chart_err)?;
        let k = lines.len().max(1) as f64;
        // Half the width of an error bar's caps, in robots.
        let cap = 0.025;
        for (i, line) in lines.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            // Lines side by side around each N so that their error bars do not hide each other.
            let dx = (i as f64 - (k - 1.0) / 2.0) * 0.12;
            let rows: Vec<&TeamSummaryRow> =
                summary.iter().filter(|r| ConfigKey { n: r.config.n, ..*line } == r.config).collect();
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.time_to_90.mean.is_finite())
                .map(|r| (r.config.n as f64 + dx, r.time_to_90.mean))
                .collect();
            chart
                .draw_series(std::iter::once(PathElement::new(pts.clone(), colour.stroke_width(3))))
                .map_err(chart_err)?
                .label(varies.label(line, false))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 6, colour.filled()))).map_err(chart_err)?;
            for r in &rows {
                let x = r.config.n as f64 + dx;
                let t = &r.time_to_90;
                if t.lo.is_finite() && t.hi.is_finite() {
                    // The interval as a vertical bar with caps (plotters' ErrorBar needs a feature not built).
                    let bar = [
                        vec![(x, t.lo), (x, t.hi)],
                        vec![(x - cap, t.lo), (x + cap, t.lo)],
                        vec![(x - cap, t.hi), (x + cap, t.hi)],
                    ];
                    chart
                        .draw_series(bar.into_iter().map(|p| PathElement::new(p, colour.stroke_width(2))))
                        .map_err(chart_err)?;
                }
                // How many trials the point stands on; at the bottom when none reached 90 %.
                let y = if t.mean.is_finite() { t.mean } else { y_max * 0.03 };
                let text = format!("{}/{}", r.reached_90, r.trials);
                let style = ("sans-serif", 18).into_font().color(&colour);
                chart.draw_series(std::iter::once(Text::new(text, (x + cap + 0.01, y), style))).map_err(chart_err)?;
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        root.present().map_err(chart_err)?;
    }
    Ok(buf)
}

/// Draws `plot.png` (coverage over time) at `path`.
pub fn draw_coverage(curves: &[CoverageCurve], path: &Path) -> Result<(), StudyError> {
    let buf = render_coverage(curves).map_err(|e| StudyError::file(path, format!("drawing the plot: {e}")))?;
    write_rgb_png(buf, (WIDTH, HEIGHT), path)
}

/// Draws `time90.png` (time to 90 % against robots) at `path`.
pub fn draw_time90(summary: &[TeamSummaryRow], path: &Path) -> Result<(), StudyError> {
    let buf = render_time90(summary).map_err(|e| StudyError::file(path, format!("drawing the plot: {e}")))?;
    write_rgb_png(buf, (WIDTH, HEIGHT), path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::coverage::coverage_curves;
    use crate::team::row::TeamRow;
    use crate::team::row::tests::row;
    use crate::team::summary::summarise_team;
    use mrslam_testbed::scenario::Coordination;

    #[test]
    fn both_pictures_are_drawn_at_the_documented_size() {
        let mut rows = Vec::new();
        for (i, (n, c)) in
            [(1, Coordination::None), (2, Coordination::None), (2, Coordination::Frontiers)].into_iter().enumerate()
        {
            for s in 0..3 {
                let t90 = (s + i != 4).then_some(100.0 - 10.0 * (i + s) as f64);
                let mut r = row(3 * i + s, n, c, t90);
                r.coverage = vec![0.0, 0.3 + 0.05 * s as f64, 0.8, 0.92];
                rows.push(r);
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let (plot, time90) = (dir.path().join("plot.png"), dir.path().join("time90.png"));
        draw_coverage(&coverage_curves(&rows), &plot).unwrap();
        draw_time90(&summarise_team(&rows), &time90).unwrap();
        for p in [plot, time90] {
            let img = image::open(&p).unwrap();
            assert_eq!((img.width(), img.height()), (WIDTH, HEIGHT));
            assert!(img.to_rgb8().pixels().any(|p| p.0 != [255, 255, 255]));
        }
        // Nothing reached 90 %, one configuration: still a picture, no panic.
        let none: Vec<TeamRow> = (0..2).map(|t| row(t, 1, Coordination::None, None)).collect();
        draw_time90(&summarise_team(&none), &dir.path().join("none.png")).unwrap();
    }
}
