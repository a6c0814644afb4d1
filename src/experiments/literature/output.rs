//! `odocal experiment literature`: the comparison, a chart of its medians.

use super::LiteratureParams;
use super::{literature, LiteratureRow};
use crate::experiments::inputs::{bad, ExperimentInputs};
use crate::experiments::output::{draw_bars, median_bars, ExperimentOutput, MedianPanel};
use crate::pipeline::PipelineError;
use std::path::Path;

/// The panels of the chart: parameter errors, RMSE and path error.
const PANELS: [MedianPanel<LiteratureRow>; 6] = [
    ("|error| R_R (mm)", |r| 1e3 * r.err_r_right.median),
    ("|error| R_L (mm)", |r| 1e3 * r.err_r_left.median),
    ("|error| D (mm)", |r| 1e3 * r.err_wheel_base.median),
    ("RMSE x,y (m)", |r| r.rmse_xy.median),
    ("RMSE θ (rad)", |r| r.rmse_theta.median),
    ("path error (%)", |r| r.path_error_percent.median),
];

/// Runs the comparison with `--runs` repetitions and draws its medians into `png`.
pub(in crate::experiments) fn literature_output(
    inp: &ExperimentInputs<'_>,
    params: &LiteratureParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let nominal = inp.robot.diff_drive();
    let t = literature(&nominal, inp.calib, params, inp.runs, inp.seed).map_err(bad)?;
    let labels = t.rows.iter().map(|r| r.method.name().to_string()).collect();
    let title = format!(
        "Literature methods on the same runs ({} repetitions, medians)",
        t.runs
    );
    draw_bars(png, &median_bars(title, labels, &t.rows, &PANELS))?;
    let heading = "Literature methods side by side";
    Ok(ExperimentOutput::titled(heading, t.markdown(), &t))
}
