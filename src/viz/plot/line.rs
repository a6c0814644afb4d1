//! Named series over a shared x axis (usually time, s), in one or more
//! stacked panels: radius evolution against truth (the paper's Fig. 6/8),
//! particle count (Fig. 5), error over time.

use super::canvas::{
    draw_legend, legend_width, own_or_palette, padded_range, render, tick_formatter, LegendEntry,
    Rgb,
};
use super::frame::{axes, draw_curve, draw_mesh, frame};
use crate::viz::VizError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One named curve. Non-finite points break the line instead of being drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend name (in a line chart, series with the same name in several
    /// panels share one legend entry).
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
    /// This panel's own x-axis label (with unit), when its x is another
    /// quantity than the chart's: it then gets its own x range and label.
    pub x_label: Option<String>,
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
            x_label: None,
        });
        self.size.1 += 340;
        self
    }

    /// Adds a panel with its own x quantity (label with unit, own range).
    pub fn panel_x(
        mut self,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        series: Vec<Series>,
    ) -> Self {
        self = self.panel(y_label, series);
        if let Some(p) = self.panels.last_mut() {
            p.x_label = Some(x_label.into());
        }
        self.size.1 += 20;
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
        named.push((
            s.name.clone(),
            own_or_palette(s.color, named.len()),
            s.dashed,
        ));
    }
    named
}

/// Draws the chart into an RGB image.
pub fn render_line_chart(chart: &LineChart) -> Result<Rgb, VizError> {
    let all = || chart.panels.iter().flat_map(|p| &p.series);
    let shared = || {
        chart
            .panels
            .iter()
            .filter(|p| p.x_label.is_none())
            .flat_map(|p| &p.series)
    };
    let xs = |s: &Series| s.points.iter().map(|p| p[0]).collect::<Vec<_>>();
    let x = padded_range(shared().flat_map(xs), 0.0)
        .or_else(|| padded_range(all().flat_map(xs), 0.0))
        .ok_or_else(|| VizError::Input(format!("{}: no finite points", chart.title)))?;
    let colors = series_colors(chart);
    let names: Vec<&str> = colors.iter().map(|(n, _, _)| n.as_str()).collect();
    let legend_w = legend_width(&names);
    render(chart.size, |root| {
        let f = frame(root, &chart.title, legend_w)?;
        let areas = f.plots.split_evenly((chart.panels.len(), 1));
        let n = chart.panels.len();
        for (k, (panel, area)) in chart.panels.iter().zip(&areas).enumerate() {
            let (range, x_label) = match &panel.x_label {
                Some(l) => (
                    padded_range(
                        panel
                            .series
                            .iter()
                            .flat_map(|s| s.points.iter().map(|p| p[0])),
                        0.0,
                    )
                    .unwrap_or(x),
                    Some(l.as_str()),
                ),
                None => (x, (k + 1 == n).then_some(chart.x_label.as_str())),
            };
            draw_panel(area, panel, range, x_label, &colors)?;
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
        draw_legend(&f.legend, &entries, 30)
    })
}

/// Draws one panel over the x range `(xlo, xhi)`; the bottom one has the
/// x-axis label `x_label` (and room for it).
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &LinePanel,
    (xlo, xhi): (f64, f64),
    x_label: Option<&str>,
    colors: &[(String, RGBColor, bool)],
) -> Result<(), VizError> {
    let ys = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().filter(|p| p[0].is_finite()).map(|p| p[1]));
    let (ylo, yhi) = padded_range(ys, 0.06).unwrap_or((0.0, 1.0));
    let x_area = if x_label.is_some() { 55 } else { 30 };
    let mut c = axes(area, 12, (x_area, 95), xlo..xhi, ylo..yhi)?;
    let fx = tick_formatter(xlo, xhi);
    let fy = tick_formatter(ylo, yhi);
    let mut mesh = c.configure_mesh();
    mesh.x_desc(x_label.unwrap_or(""))
        .y_desc(panel.y_label.as_str())
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_labels(10)
        .y_labels(6);
    draw_mesh(mesh)?;
    for s in &panel.series {
        let color = colors
            .iter()
            .find(|(n, _, _)| *n == s.name)
            .map(|(_, c, _)| *c)
            .unwrap_or(BLACK);
        draw_curve(&mut c, &s.points, s.dashed, color.stroke_width(2))?;
    }
    Ok(())
}

/// Draws the chart and writes it as PNG to `path` (atomically).
pub fn line_chart(path: &Path, chart: &LineChart) -> Result<(), VizError> {
    render_line_chart(chart)?.save_png(path)
}
