//! Named series over a shared x axis (usually time, s), in one or more
//! stacked panels: radius evolution against truth (the paper's Fig. 6/8),
//! particle count (Fig. 5), error over time.

use super::canvas::{
    draw_legend, legend_width, padded_range, palette, plot_err, render, tick_formatter,
    LegendEntry, Rgb, FAMILY,
};
use crate::viz::VizError;
use plotters::prelude::*;
use std::path::Path;

/// One named curve. Non-finite points break the line instead of being drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend name (series with the same name in several panels share one
    /// legend entry).
    pub name: String,
    /// `[x, y]` points in drawing order.
    pub points: Vec<[f64; 2]>,
    /// sRGB colour; `None` takes the next palette colour.
    pub color: Option<[u8; 3]>,
    /// Dashed (e.g. the true value) instead of solid.
    pub dashed: bool,
}

impl Series {
    /// A solid series with a palette colour.
    pub fn new(name: impl Into<String>, points: Vec<[f64; 2]>) -> Self {
        Series {
            name: name.into(),
            points,
            color: None,
            dashed: false,
        }
    }

    /// The series from parallel `xs` and `ys` (extra values of the longer
    /// slice are ignored).
    pub fn from_xy(name: impl Into<String>, xs: &[f64], ys: &[f64]) -> Self {
        Self::new(name, xs.iter().zip(ys).map(|(&x, &y)| [x, y]).collect())
    }

    /// With a fixed colour.
    pub fn color(mut self, rgb: [u8; 3]) -> Self {
        self.color = Some(rgb);
        self
    }

    /// Drawn dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// One panel: its y-axis label (with unit) and its series.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LinePanel {
    /// Y-axis label, with unit, e.g. `"R_R (m)"`.
    pub y_label: String,
    /// Curves drawn in this panel.
    pub series: Vec<Series>,
}

/// A figure of stacked panels sharing the x axis.
#[derive(Clone, Debug, PartialEq)]
pub struct LineChart {
    /// Title above the panels.
    pub title: String,
    /// X-axis label with unit, e.g. `"time (s)"`.
    pub x_label: String,
    /// Panels top to bottom.
    pub panels: Vec<LinePanel>,
    /// Image size (px).
    pub size: (u32, u32),
}

impl LineChart {
    /// An empty chart of a readable default size (1100 × 420 px per panel,
    /// set when panels are added via [`LineChart::panel`]).
    pub fn new(title: impl Into<String>, x_label: impl Into<String>) -> Self {
        LineChart {
            title: title.into(),
            x_label: x_label.into(),
            panels: Vec::new(),
            size: (1100, 80),
        }
    }

    /// Adds a panel below the others and grows the default height.
    pub fn panel(mut self, y_label: impl Into<String>, series: Vec<Series>) -> Self {
        self.panels.push(LinePanel {
            y_label: y_label.into(),
            series,
        });
        self.size.1 += 340;
        self
    }
}

/// Colour of each series: its own, else the palette by first appearance of
/// its name, so one name keeps one colour across panels.
fn series_colors(chart: &LineChart) -> Vec<(String, RGBColor, bool)> {
    let mut named: Vec<(String, RGBColor, bool)> = Vec::new();
    for s in chart.panels.iter().flat_map(|p| &p.series) {
        if named.iter().any(|(n, _, _)| *n == s.name) {
            continue;
        }
        let c = match s.color {
            Some([r, g, b]) => RGBColor(r, g, b),
            None => palette(named.len()),
        };
        named.push((s.name.clone(), c, s.dashed));
    }
    named
}

/// Runs of consecutive finite points.
fn finite_runs(points: &[[f64; 2]]) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for p in points {
        if p[0].is_finite() && p[1].is_finite() {
            cur.push((p[0], p[1]));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// Draws the chart into an RGB image.
pub fn render_line_chart(chart: &LineChart) -> Result<Rgb, VizError> {
    let all = || chart.panels.iter().flat_map(|p| &p.series);
    let (xlo, xhi) = padded_range(all().flat_map(|s| s.points.iter().map(|p| p[0])), 0.0)
        .ok_or_else(|| VizError::Input(format!("{}: no finite points", chart.title)))?;
    let colors = series_colors(chart);
    let color_of = |name: &str| {
        colors
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, c, _)| *c)
            .unwrap_or(BLACK)
    };
    let names: Vec<&str> = colors.iter().map(|(n, _, _)| n.as_str()).collect();
    let legend_w = legend_width(&names);
    render(chart.size, |root| {
        let body = root
            .titled(&chart.title, (FAMILY, 24).into_font())
            .map_err(plot_err)?;
        let (w, _) = body.dim_in_pixel();
        let (plots, legend) = body.split_horizontally(w.saturating_sub(legend_w));
        let areas = plots.split_evenly((chart.panels.len(), 1));
        let n = chart.panels.len();
        for (k, (panel, area)) in chart.panels.iter().zip(&areas).enumerate() {
            let last = k + 1 == n;
            let ys = panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().filter(|p| p[0].is_finite()).map(|p| p[1]));
            let (ylo, yhi) = padded_range(ys, 0.06).unwrap_or((0.0, 1.0));
            let mut c = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(if last { 55 } else { 30 })
                .y_label_area_size(95)
                .build_cartesian_2d(xlo..xhi, ylo..yhi)
                .map_err(plot_err)?;
            let fx = tick_formatter(xlo, xhi);
            let fy = tick_formatter(ylo, yhi);
            c.configure_mesh()
                .x_desc(if last { chart.x_label.as_str() } else { "" })
                .y_desc(panel.y_label.as_str())
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .x_labels(10)
                .y_labels(6)
                .label_style((FAMILY, 15))
                .axis_desc_style((FAMILY, 17))
                .light_line_style(RGBColor(238, 238, 238))
                .bold_line_style(RGBColor(215, 215, 215))
                .draw()
                .map_err(plot_err)?;
            for s in &panel.series {
                let style = color_of(&s.name).stroke_width(2);
                for run in finite_runs(&s.points) {
                    if s.dashed {
                        c.draw_series(DashedLineSeries::new(run, 10, 6, style))
                            .map_err(plot_err)?;
                    } else {
                        c.draw_series(LineSeries::new(run, style))
                            .map_err(plot_err)?;
                    }
                }
            }
        }
        let entries: Vec<LegendEntry> = colors
            .iter()
            .map(|(n, c, d)| LegendEntry {
                name: n,
                color: *c,
                dashed: *d,
                boxed: false,
            })
            .collect();
        draw_legend(&legend, &entries, 30)
    })
}

/// Draws the chart and writes it as PNG to `path` (atomically).
pub fn line_chart(path: &Path, chart: &LineChart) -> Result<(), VizError> {
    render_line_chart(chart)?.save_png(path)
}
