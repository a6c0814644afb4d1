//! What every figure is built from: the title above, the legend column on
//! the right, Cartesian axes with their grid in one style, and curves drawn
//! as runs of finite points.

use super::canvas::{plot_err, FAMILY};
use crate::viz::VizError;
use plotters::chart::MeshStyle;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;

/// A chart with `f64` axes.
pub(crate) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The parts of a figure below its title: the plotting part, the legend
/// column `legend_w` px wide on its right, and their joint size (px).
pub(crate) struct Frame<DB: DrawingBackend> {
    pub plots: DrawingArea<DB, Shift>,
    pub legend: DrawingArea<DB, Shift>,
    pub size: (u32, u32),
}

/// Puts `title` above and splits what is below into the plotting part and
/// a legend column `legend_w` px wide.
pub(crate) fn frame<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    legend_w: u32,
) -> Result<Frame<DB>, VizError> {
    let body = root
        .titled(title, (FAMILY, 24).into_font())
        .map_err(plot_err)?;
    let size = body.dim_in_pixel();
    let (plots, legend) = body.split_horizontally(size.0.saturating_sub(legend_w));
    Ok(Frame {
        plots,
        legend,
        size,
    })
}

/// Axes over `x × y` on `area`, `margin` px inside it, with label areas of
/// `label_areas` = (below, left) px for the ticks and axis names.
pub(crate) fn axes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    margin: u32,
    label_areas: (u32, u32),
    x: Range<f64>,
    y: Range<f64>,
) -> Result<Chart<'_, DB>, VizError> {
    ChartBuilder::on(area)
        .margin(margin)
        .x_label_area_size(label_areas.0)
        .y_label_area_size(label_areas.1)
        .build_cartesian_2d(x, y)
        .map_err(plot_err)
}

/// Draws the grid, ticks and axis names `mesh` was set up with, in the
/// figures' fonts and grid colours.
pub(crate) fn draw_mesh<DB: DrawingBackend>(
    mut mesh: MeshStyle<'_, '_, RangedCoordf64, RangedCoordf64, DB>,
) -> Result<(), VizError> {
    mesh.label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(plot_err)
}

/// Runs of consecutive finite points.
pub(crate) fn finite_runs(points: &[[f64; 2]]) -> Vec<Vec<(f64, f64)>> {
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

/// Draws `points` as a curve, `dashed` or solid, broken where a point is
/// not finite.
pub(crate) fn draw_curve<DB: DrawingBackend>(
    c: &mut Chart<'_, DB>,
    points: &[[f64; 2]],
    dashed: bool,
    style: ShapeStyle,
) -> Result<(), VizError> {
    for run in finite_runs(points) {
        if dashed {
            c.draw_series(DashedLineSeries::new(run, 10, 6, style))
                .map_err(plot_err)?;
        } else {
            c.draw_series(LineSeries::new(run, style))
                .map_err(plot_err)?;
        }
    }
    Ok(())
}
