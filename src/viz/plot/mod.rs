//! PNG figures with plotters, drawn in memory and written atomically: time
//! series in stacked panels ([`line_chart`]), x–y trajectories at equal
//! aspect ([`trajectory_plot`]), and grouped bars ([`bar_chart`]). Every
//! figure has a title, axis labels with units and a legend column beside the
//! plot so text never covers data.

mod bars;
mod canvas;
mod frame;
mod line;
mod trajectory;

pub use bars::{bar_chart, render_bar_chart, BarChart, BarPanel};
pub use canvas::Rgb;
pub use line::{line_chart, render_line_chart, LineChart, LinePanel, Series};
pub use trajectory::{render_trajectory_plot, trajectory_plot, PathSeries, TrajectoryPlot};
