//! Grouped bars with optional error bars, one panel per metric: e.g. the
//! resampling comparison (the paper's Fig. 3/4), methods as categories and
//! resampling triggers as groups, error and time per iteration as panels.

use super::canvas::{
    draw_legend, legend_width, padded_range, palette, plot_err, render, tick_formatter,
    LegendEntry, Rgb, FAMILY,
};
use crate::viz::VizError;
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
    let nc = chart.categories.len();
    let ng = chart.groups.len();
    render(chart.size, |root| {
        let body = root
            .titled(&chart.title, (FAMILY, 24).into_font())
            .map_err(plot_err)?;
        let (w, _) = body.dim_in_pixel();
        let (plots, legend) = body.split_horizontally(w.saturating_sub(legend_w));
        let areas = plots.split_evenly((chart.panels.len(), 1));
        for (panel, area) in chart.panels.iter().zip(&areas) {
            let err = |g: usize, c: usize| {
                panel
                    .errors
                    .as_ref()
                    .map(|e| e[g][c])
                    .filter(|e| e.is_finite())
                    .unwrap_or(0.0)
                    .abs()
            };
            let tops = (0..ng).flat_map(|g| {
                (0..nc).flat_map(move |c| {
                    let v = panel.values[g][c];
                    [v + err(g, c), v - err(g, c), 0.0]
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
            let mut c = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(95)
                .build_cartesian_2d(-0.5..(nc as f64 - 0.5), ylo..yhi)
                .map_err(plot_err)?;
            let fy = tick_formatter(ylo, yhi);
            c.configure_mesh()
                .disable_x_mesh()
                .x_labels(0)
                .y_desc(panel.y_label.as_str())
                .y_label_formatter(&fy)
                .y_labels(6)
                .label_style((FAMILY, 15))
                .axis_desc_style((FAMILY, 17))
                .light_line_style(RGBColor(238, 238, 238))
                .bold_line_style(RGBColor(215, 215, 215))
                .draw()
                .map_err(plot_err)?;
            let bw = 0.8 / ng as f64;
            for g in 0..ng {
                let color = palette(g);
                for k in 0..nc {
                    let v = panel.values[g][k];
                    if !v.is_finite() {
                        continue;
                    }
                    let x0 = k as f64 - 0.4 + g as f64 * bw;
                    let base = 0.0f64.clamp(ylo, yhi);
                    c.draw_series([Rectangle::new(
                        [(x0 + 0.08 * bw, base), (x0 + 0.92 * bw, v)],
                        color.filled(),
                    )])
                    .map_err(plot_err)?;
                    let e = err(g, k);
                    if e > 0.0 {
                        let xm = x0 + 0.5 * bw;
                        let black = BLACK.stroke_width(1);
                        c.draw_series([
                            PathElement::new(vec![(xm, v - e), (xm, v + e)], black),
                            PathElement::new(
                                vec![(xm - 0.2 * bw, v + e), (xm + 0.2 * bw, v + e)],
                                black,
                            ),
                            PathElement::new(
                                vec![(xm - 0.2 * bw, v - e), (xm + 0.2 * bw, v - e)],
                                black,
                            ),
                        ])
                        .map_err(plot_err)?;
                    }
                }
            }
            // Category names centred under their groups (pixel positions,
            // drawn on the root so they may sit in the label area).
            let font = (FAMILY, 16)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Top));
            for (k, name) in chart.categories.iter().enumerate() {
                let (px, py) = c.backend_coord(&(k as f64, ylo));
                root.draw(&Text::new(name.clone(), (px, py + 10), font.clone()))
                    .map_err(plot_err)?;
            }
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
        draw_legend(&legend, &entries, 30)
    })
}

/// Draws the chart and writes the PNG to `path` (atomically).
pub fn bar_chart(path: &Path, chart: &BarChart) -> Result<(), VizError> {
    render_bar_chart(chart)?.save_png(path)
}
