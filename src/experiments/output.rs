//! What an experiment hands back to be written: its markdown, summary and
//! JSON, and the figures drawn beside them.

use crate::pipeline::PipelineError;
use crate::viz::plot::{self, BarChart, LineChart, TrajectoryPlot};
use serde::Serialize;
use std::path::Path;

/// An experiment's outputs: the markdown written to `NAME.md`, the text the
/// command prints, and the JSON written to `NAME.json` (and printed with `--json`).
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentOutput {
    /// Content of `NAME.md`.
    pub markdown: String,
    /// Human-readable summary for stdout.
    pub summary: String,
    /// Content of `NAME.json` (pretty-printed, fields in declaration order).
    pub json: String,
}

impl ExperimentOutput {
    /// `md` under the heading `title` for `NAME.md`, `md` alone as the
    /// summary, and `result` as pretty-printed JSON.
    pub(super) fn titled<T: Serialize>(title: &str, md: String, result: &T) -> Self {
        Self {
            markdown: format!("# {title}\n\n{md}"),
            summary: md,
            json: serde_json::to_string_pretty(result).expect("experiment results serialise"),
        }
    }
}

/// A panel of a chart of medians: its axis label and the row's value.
pub(super) type MedianPanel<R> = (&'static str, fn(&R) -> f64);

/// One bar per row (named by `labels`) in a single "median" group, one
/// panel per metric.
pub(super) fn median_bars<R>(
    title: String,
    labels: Vec<String>,
    rows: &[R],
    panels: &[MedianPanel<R>],
) -> BarChart {
    panels.iter().fold(
        BarChart::new(title, labels, vec!["median".into()]),
        |chart, (label, value)| chart.panel(*label, vec![rows.iter().map(value).collect()], None),
    )
}

/// Draws a bar chart into `png`.
pub(super) fn draw_bars(png: &Path, chart: &BarChart) -> Result<(), PipelineError> {
    plot::bar_chart(png, chart).map_err(|e| PipelineError::write(png, e))
}

/// Draws a line chart into `png`.
pub(super) fn draw_lines(png: &Path, chart: &LineChart) -> Result<(), PipelineError> {
    plot::line_chart(png, chart).map_err(|e| PipelineError::write(png, e))
}

/// Draws a trajectory plot into `png`.
pub(super) fn draw_paths(png: &Path, fig: &TrajectoryPlot) -> Result<(), PipelineError> {
    plot::trajectory_plot(png, fig).map_err(|e| PipelineError::write(png, e))
}

/// `items` formatted by `f`, separated by ", ".
pub(super) fn comma_list<T>(items: impl IntoIterator<Item = T>, f: impl Fn(T) -> String) -> String {
    items.into_iter().map(f).collect::<Vec<_>>().join(", ")
}
