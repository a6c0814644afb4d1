//! Grouped bars with optional error bars, one panel per metric: e.g. the
//! resampling comparison (the paper's Fig. 3/4), methods as categories and
//! resampling triggers as groups, error and time per iteration as panels.

use super::canvas::{
    draw_legend, legend_width, padded_range, palette, plot_err, render, tick_formatter,
    LegendEntry, Rgb, FAMILY,
};
use super::frame::{axes, draw_mesh, frame, Chart};
use crate::viz::VizError;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One metric: bars `values[group][category]`, optional `errors` (same shape,
/// drawn as ± whiskers).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct BarPanel {
    /// Y-axis label with unit, e.g. `"time per iteration (ms)"`.
    pub y_label: String,
    /// Bar heights, one row per group, one column per category.
    pub values: Vec<Vec<f64>>,
    /// Whisker half-lengths of the same shape, or `None`.
    pub errors: Option<Vec<Vec<f64>>>,
}

/// A figure of grouped bars in stacked panels sharing the categories.
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    /// Title above the panels.
    pub title: String,
    /// Category names along the x axis.
    pub categories: Vec<String>,
    /// Group names (one colour each, in the legend).
    pub groups: Vec<String>,
    /// Panels top to bottom.
    pub panels: Vec<BarPanel>,
    /// Image size (px).
    pub size: (u32, u32),
}

impl BarChart {
    /// An empty chart; the height grows with each [`BarChart::panel`].
    pub fn new(title: impl Into<String>, categories: Vec<String>, groups: Vec<String>) -> Self {
        BarChart {
            title: title.into(),
            categories,
            groups,
            panels: Vec::new(),
            size: (1100, 80),
        }
    }

    /// Adds a panel below the others.
    pub fn panel(
        mut self,
        y_label: impl Into<String>,
        values: Vec<Vec<f64>>,
        errors: Option<Vec<Vec<f64>>>,
    ) -> Self {
        self.panels.push(BarPanel {
            y_label: y_label.into(),
            values,
            errors,
        });
        self.size.1 += 360;
        self
    }

    fn validate(&self) -> Result<(), VizError> {
        let (g, c) = (self.groups.len(), self.categories.len());
        if g == 0 || c == 0 || self.panels.is_empty() {
            return Err(VizError::Input(format!("{}: nothing to draw", self.title)));
        }
        let shaped = |m: &Vec<Vec<f64>>| m.len() == g && m.iter().all(|r| r.len() == c);
        for p in &self.panels {
            if !shaped(&p.values) || p.errors.as_ref().is_some_and(|e| !shaped(e)) {
                return Err(VizError::Input(format!(
                    "{}: panel '{}' is not {g} groups × {c} categories",
                    self.title, p.y_label
                )));
            }
        }
        Ok(())
    }
}

/// Draws the chart into an RGB image.
pub fn render_bar_chart(chart: &BarChart) -> Result<Rgb, VizError> {
    chart.validate()?;
    let names: Vec<&str> = chart.groups.iter().map(String::as_str).collect();
    let legend_w = legend_width(&names);
    render(chart.size, |root| {
        let f = frame(root, &chart.title, legend_w)?;
        let areas = f.plots.split_evenly((chart.panels.len(), 1));
        for (panel, area) in chart.panels.iter().zip(&areas) {
            draw_panel(root, area, chart, panel)?;
        }
        let entries: Vec<LegendEntry> = chart
            .groups
            .iter()
            .enumerate()
            .map(|(g, n)| LegendEntry {
                name: n,
                color: palette(g),
                dashed: false,
                boxed: true,
            })
            .collect();
        draw_legend(&f.legend, &entries, 30)
    })
}

/// Whisker half-length of bar (`g`, `c`) of `panel`: 0 without one.
fn whisker(panel: &BarPanel, g: usize, c: usize) -> f64 {
    panel
        .errors
        .as_ref()
        .map(|e| e[g][c])
        .filter(|e| e.is_finite())
        .unwrap_or(0.0)
        .abs()
}

/// The y range of `panel`: bar tops with their whiskers and 0, padded; from
/// 0 when no value is negative.
fn y_range(panel: &BarPanel, ng: usize, nc: usize) -> (f64, f64) {
    let tops = (0..ng).flat_map(|g| {
        (0..nc).flat_map(move |c| {
            let v = panel.values[g][c];
            [v + whisker(panel, g, c), v - whisker(panel, g, c), 0.0]
        })
    });
    let (mut ylo, yhi) = padded_range(tops, 0.08).unwrap_or((0.0, 1.0));
    if panel
        .values
        .iter()
        .flatten()
        .all(|v| !v.is_finite() || *v >= 0.0)
    {
        ylo = 0.0;
    }
    (ylo, yhi)
}

/// Draws one panel in `area`: axes, bars, whiskers, and the category names
/// under the groups (on `root`, so they may sit in the label area).
fn draw_panel<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    area: &DrawingArea<DB, Shift>,
    chart: &BarChart,
    panel: &BarPanel,
) -> Result<(), VizError> {
    let nc = chart.categories.len();
    let ng = chart.groups.len();
    let (ylo, yhi) = y_range(panel, ng, nc);
    let mut c = axes(area, 12, (40, 95), -0.5..(nc as f64 - 0.5), ylo..yhi)?;
    let fy = tick_formatter(ylo, yhi);
    let mut mesh = c.configure_mesh();
    mesh.disable_x_mesh()
        .x_labels(0)
        .y_desc(panel.y_label.as_str())
        .y_label_formatter(&fy)
        .y_labels(6);
    draw_mesh(mesh)?;
    let bw = 0.8 / ng as f64;
    for g in 0..ng {
        for k in 0..nc {
            let v = panel.values[g][k];
            if v.is_finite() {
                let x0 = k as f64 - 0.4 + g as f64 * bw;
                let e = whisker(panel, g, k);
                draw_bar(&mut c, (x0, bw), (v, e), (ylo, yhi), palette(g))?;
            }
        }
    }
    // Category names centred under their groups (pixel positions).
    let font = (FAMILY, 16)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Top));
    for (k, name) in chart.categories.iter().enumerate() {
        let (px, py) = c.backend_coord(&(k as f64, ylo));
        root.draw(&Text::new(name.clone(), (px, py + 10), font.clone()))
            .map_err(plot_err)?;
    }
    Ok(())
}

/// A bar of height `v` from 0 (clamped into the y range) in the slot from
/// `x0`, `bw` wide, with a ± `e` whisker on its top unless `e` is 0.
fn draw_bar<DB: DrawingBackend>(
    c: &mut Chart<'_, DB>,
    (x0, bw): (f64, f64),
    (v, e): (f64, f64),
    (ylo, yhi): (f64, f64),
    color: RGBColor,
) -> Result<(), VizError> {
    let base = 0.0f64.clamp(ylo, yhi);
    c.draw_series([Rectangle::new(
        [(x0 + 0.08 * bw, base), (x0 + 0.92 * bw, v)],
        color.filled(),
    )])
    .map_err(plot_err)?;
    if e > 0.0 {
        let xm = x0 + 0.5 * bw;
        let black = BLACK.stroke_width(1);
        c.draw_series([
            PathElement::new(vec![(xm, v - e), (xm, v + e)], black),
            PathElement::new(vec![(xm - 0.2 * bw, v + e), (xm + 0.2 * bw, v + e)], black),
            PathElement::new(vec![(xm - 0.2 * bw, v - e), (xm + 0.2 * bw, v - e)], black),
        ])
        .map_err(plot_err)?;
    }
    Ok(())
}

/// Draws the chart and writes the PNG to `path` (atomically).
pub fn bar_chart(path: &Path, chart: &BarChart) -> Result<(), VizError> {
    render_bar_chart(chart)?.save_png(path)
}
