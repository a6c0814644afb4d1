//! Trajectories in the x–y plane at equal aspect (1 m is as long on both
//! axes), e.g. raw and calibrated odometry against the reference (the
//! paper's Fig. 7). Each path's start is marked with a dot.

use super::canvas::{
    draw_legend, legend_width, padded_range, palette, plot_err, render, tick_formatter,
    LegendEntry, Rgb, FAMILY,
};
use crate::viz::VizError;
use plotters::prelude::*;
use std::path::Path;

/// One named path of `[x, y]` positions (m, world frame).
#[derive(Clone, Debug, PartialEq)]
pub struct PathSeries {
    /// Legend name.
    pub name: String,
    /// Positions (m) in time order; non-finite ones break the line.
    pub xy: Vec<[f64; 2]>,
    /// sRGB colour; `None` takes the palette.
    pub color: Option<[u8; 3]>,
    /// Dashed instead of solid.
    pub dashed: bool,
}

impl PathSeries {
    /// A solid path with a palette colour.
    pub fn new(name: impl Into<String>, xy: Vec<[f64; 2]>) -> Self {
        PathSeries {
            name: name.into(),
            xy,
            color: None,
            dashed: false,
        }
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
    let pts = || plot.paths.iter().flat_map(|p| p.xy.iter());
    let x = padded_range(pts().filter(|p| p[1].is_finite()).map(|p| p[0]), 0.05);
    let y = padded_range(pts().filter(|p| p[0].is_finite()).map(|p| p[1]), 0.05);
    let (Some(x), Some(y)) = (x, y) else {
        return Err(VizError::Input(format!("{}: no finite points", plot.title)));
    };
    let colors: Vec<RGBColor> = plot
        .paths
        .iter()
        .enumerate()
        .map(|(i, p)| match p.color {
            Some([r, g, b]) => RGBColor(r, g, b),
            None => palette(i),
        })
        .collect();
    let names: Vec<&str> = plot.paths.iter().map(|p| p.name.as_str()).collect();
    let legend_w = legend_width(&names);
    render(plot.size, |root| {
        let body = root
            .titled(&plot.title, (FAMILY, 24).into_font())
            .map_err(plot_err)?;
        let (w, h) = body.dim_in_pixel();
        let (area, legend) = body.split_horizontally(w.saturating_sub(legend_w));
        let pw = w.saturating_sub(legend_w + 2 * MARGIN + Y_AREA);
        let ph = h.saturating_sub(2 * MARGIN + X_AREA);
        let ((xlo, xhi), (ylo, yhi)) = equal_aspect(x, y, pw, ph);
        let mut c = ChartBuilder::on(&area)
            .margin(MARGIN)
            .x_label_area_size(X_AREA)
            .y_label_area_size(Y_AREA)
            .build_cartesian_2d(xlo..xhi, ylo..yhi)
            .map_err(plot_err)?;
        let fx = tick_formatter(xlo, xhi);
        let fy = tick_formatter(ylo, yhi);
        c.configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 17))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(plot_err)?;
        for (p, &color) in plot.paths.iter().zip(&colors) {
            let style = color.stroke_width(2);
            let mut first = None;
            let mut run = Vec::new();
            for q in p.xy.iter().chain(std::iter::once(&[f64::NAN, f64::NAN])) {
                if q[0].is_finite() && q[1].is_finite() {
                    first.get_or_insert((q[0], q[1]));
                    run.push((q[0], q[1]));
                    continue;
                }
                let r = std::mem::take(&mut run);
                if r.is_empty() {
                    continue;
                }
                if p.dashed {
                    c.draw_series(DashedLineSeries::new(r, 10, 6, style))
                        .map_err(plot_err)?;
                } else {
                    c.draw_series(LineSeries::new(r, style)).map_err(plot_err)?;
                }
            }
            if let Some(s) = first {
                c.draw_series([Circle::new(s, 5, color.filled())])
                    .map_err(plot_err)?;
            }
        }
        let mut entries: Vec<LegendEntry> = plot
            .paths
            .iter()
            .zip(&colors)
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
        draw_legend(&legend, &entries, 30)
    })
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
