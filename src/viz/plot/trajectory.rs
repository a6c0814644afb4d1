//! Trajectories in the x–y plane at equal aspect (1 m is as long on both
//! axes), e.g. raw and calibrated odometry against the reference (the
//! paper's Fig. 7). Each path's start is marked with a dot.

use super::canvas::{
    draw_legend, legend_width, own_or_palette, padded_range, plot_err, render, tick_formatter,
    LegendEntry, Rgb,
};
use super::frame::{axes, draw_curve, draw_mesh, frame, Chart};
use super::line::Series;
use crate::viz::VizError;
use plotters::prelude::*;
use std::path::Path;

/// One named path: a [`Series`] of `[x, y]` positions (m, world frame) in
/// time order; non-finite ones break the line. Each path has its own legend
/// entry.
pub type PathSeries = Series;

/// An x–y figure of several paths.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryPlot {
    /// Title above the plot.
    pub title: String,
    /// The paths, drawn in order (later on top).
    pub paths: Vec<PathSeries>,
    /// Image size (px).
    pub size: (u32, u32),
}

impl TrajectoryPlot {
    /// A plot of `paths` at a default 1100 × 900 px.
    pub fn new(title: impl Into<String>, paths: Vec<PathSeries>) -> Self {
        TrajectoryPlot {
            title: title.into(),
            paths,
            size: (1100, 900),
        }
    }
}

const MARGIN: u32 = 12;
const X_AREA: u32 = 55;
const Y_AREA: u32 = 85;

/// Widens the shorter of the two ranges so that data units per pixel are
/// equal on both axes for a plotting area of `w × h` px.
fn equal_aspect(x: (f64, f64), y: (f64, f64), w: u32, h: u32) -> ((f64, f64), (f64, f64)) {
    let (sx, sy) = (x.1 - x.0, y.1 - y.0);
    let (w, h) = (w.max(1) as f64, h.max(1) as f64);
    if sx / w > sy / h {
        let want = sx / w * h;
        let c = 0.5 * (y.0 + y.1);
        (x, (c - 0.5 * want, c + 0.5 * want))
    } else {
        let want = sy / h * w;
        let c = 0.5 * (x.0 + x.1);
        ((c - 0.5 * want, c + 0.5 * want), y)
    }
}

/// Draws the trajectories into an RGB image.
pub fn render_trajectory_plot(plot: &TrajectoryPlot) -> Result<Rgb, VizError> {
    let pts = || plot.paths.iter().flat_map(|p| p.points.iter());
    let x = padded_range(pts().filter(|p| p[1].is_finite()).map(|p| p[0]), 0.05);
    let y = padded_range(pts().filter(|p| p[0].is_finite()).map(|p| p[1]), 0.05);
    let (Some(x), Some(y)) = (x, y) else {
        return Err(VizError::Input(format!("{}: no finite points", plot.title)));
    };
    let colors: Vec<RGBColor> = plot
        .paths
        .iter()
        .enumerate()
        .map(|(i, p)| own_or_palette(p.color, i))
        .collect();
    let names: Vec<&str> = plot.paths.iter().map(|p| p.name.as_str()).collect();
    let legend_w = legend_width(&names);
    render(plot.size, |root| {
        let f = frame(root, &plot.title, legend_w)?;
        let (w, h) = f.size;
        let pw = w.saturating_sub(legend_w + 2 * MARGIN + Y_AREA);
        let ph = h.saturating_sub(2 * MARGIN + X_AREA);
        let ((xlo, xhi), (ylo, yhi)) = equal_aspect(x, y, pw, ph);
        let mut c = axes(&f.plots, MARGIN, (X_AREA, Y_AREA), xlo..xhi, ylo..yhi)?;
        let fx = tick_formatter(xlo, xhi);
        let fy = tick_formatter(ylo, yhi);
        let mut mesh = c.configure_mesh();
        mesh.x_desc("x (m)")
            .y_desc("y (m)")
            .x_label_formatter(&fx)
            .y_label_formatter(&fy);
        draw_mesh(mesh)?;
        for (p, &color) in plot.paths.iter().zip(&colors) {
            draw_path(&mut c, p, color)?;
        }
        draw_legend(&f.legend, &legend_entries(plot, &colors), 30)
    })
}

/// Draws path `p` in `color` and marks its first finite position with a dot.
fn draw_path<DB: DrawingBackend>(
    c: &mut Chart<'_, DB>,
    p: &PathSeries,
    color: RGBColor,
) -> Result<(), VizError> {
    draw_curve(c, &p.points, p.dashed, color.stroke_width(2))?;
    let first = p
        .points
        .iter()
        .find(|q| q[0].is_finite() && q[1].is_finite());
    if let Some(s) = first {
        c.draw_series([Circle::new((s[0], s[1]), 5, color.filled())])
            .map_err(plot_err)?;
    }
    Ok(())
}

/// One legend entry per path, then the start marker's.
fn legend_entries<'a>(plot: &'a TrajectoryPlot, colors: &[RGBColor]) -> Vec<LegendEntry<'a>> {
    let mut entries: Vec<LegendEntry> = plot
        .paths
        .iter()
        .zip(colors)
        .map(|(p, c)| LegendEntry {
            name: &p.name,
            color: *c,
            dashed: p.dashed,
            boxed: false,
        })
        .collect();
    entries.push(LegendEntry {
        name: "● start",
        color: WHITE,
        dashed: false,
        boxed: true,
    });
    entries
}

/// Draws the trajectories and writes the PNG to `path` (atomically).
pub fn trajectory_plot(path: &Path, plot: &TrajectoryPlot) -> Result<(), VizError> {
    render_trajectory_plot(plot)?.save_png(path)
}

#[cfg(test)]
mod tests {
    use super::equal_aspect;

    #[test]
    fn equal_aspect_gives_same_units_per_pixel() {
        let ((x0, x1), (y0, y1)) = equal_aspect((0.0, 10.0), (0.0, 2.0), 800, 400);
        assert!(((x1 - x0) / 800.0 - (y1 - y0) / 400.0).abs() < 1e-12);
        assert_eq!((x0, x1), (0.0, 10.0));
        assert!((0.5 * (y0 + y1) - 1.0).abs() < 1e-12);
    }
}
