//! Each method's figures over the repetitions: median and mean.

use super::LiteratureRun;
use crate::experiments::compare::{ClassicMethod, ClassicResult};
use crate::experiments::stats::{finite_stat, Stat};
use crate::robot::DiffDrive;
use serde::Serialize;

/// One method over all repetitions (median and mean).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LiteratureRow {
    /// The method.
    pub method: ClassicMethod,
    /// |final R_R − truth| (m).
    pub err_r_right: Stat,
    /// |final R_L − truth| (m).
    pub err_r_left: Stat,
    /// |final D − truth| (m).
    pub err_wheel_base: Stat,
    /// RMSE of position on the evaluation paths (m).
    pub rmse_xy: Stat,
    /// RMSE of heading (rad).
    pub rmse_theta: Stat,
    /// End-position error as % of the path length.
    pub path_error_percent: Stat,
    /// Compute time of calibration (and filtering, for heading-pf) (ms).
    pub compute_ms: Stat,
}

/// Median and mean of every metric per method over the repetitions.
pub(super) fn summarize(
    per_run: &[LiteratureRun],
    rows_of: fn(&LiteratureRun) -> &Vec<ClassicResult>,
) -> Vec<LiteratureRow> {
    let Some(first) = per_run.first() else {
        return Vec::new();
    };
    rows_of(first)
        .iter()
        .enumerate()
        .map(|(m, r0)| {
            let col = |f: &dyn Fn(&ClassicResult) -> f64| {
                finite_stat(per_run.iter().map(|r| f(&rows_of(r)[m])).collect())
            };
            let err = |f: fn(&DiffDrive) -> f64| {
                move |r: &ClassicResult| r.param_errors.as_ref().map_or(f64::NAN, f)
            };
            LiteratureRow {
                method: r0.method,
                err_r_right: col(&err(|e| e.r_right)),
                err_r_left: col(&err(|e| e.r_left)),
                err_wheel_base: col(&err(|e| e.wheel_base)),
                rmse_xy: col(&|r| r.rmse_xy),
                rmse_theta: col(&|r| r.rmse_theta),
                path_error_percent: col(&|r| r.path_error_percent),
                compute_ms: col(&|r| r.compute_ms),
            }
        })
        .collect()
}
