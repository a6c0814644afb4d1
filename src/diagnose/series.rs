//! Residual series and the regressors that expose effects (speed, turn
//! rate, accelerations, lagged correlations), for the report's plots.

use super::data::{GyroRow, IcpRow};
use super::model::Replay;
use super::stats::{cross_correlation, median};
use crate::effects::Departures;
use serde::Serialize;

/// Residual series and regressors for the report's plots (one entry per ICP
/// row or gyro window, in time order).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ResidualSeries {
    /// Start of the held-out part (s).
    pub split: f64,
    /// ICP interval midpoints (s).
    pub t: Vec<f64>,
    /// Predicted forward speed V (m/s, nominal model).
    pub speed: Vec<f64>,
    /// Predicted turn rate W (rad/s, nominal model).
    pub turn_rate: Vec<f64>,
    /// |V|·|W| (m/s · rad/s).
    pub speed_turn: Vec<f64>,
    /// dV/dt (m/s²).
    pub accel: Vec<f64>,
    /// dW/dt (rad/s²).
    pub turn_accel: Vec<f64>,
    /// ICP V residual before/after (m/s).
    pub v_before: Vec<f64>,
    /// After the extension.
    pub v_after: Vec<f64>,
    /// ICP lateral residual before/after (m/s).
    pub lateral_before: Vec<f64>,
    /// After the extension.
    pub lateral_after: Vec<f64>,
    /// ICP W residual before/after (rad/s).
    pub w_before: Vec<f64>,
    /// After the extension.
    pub w_after: Vec<f64>,
    /// Gyro window midpoints (s).
    pub gyro_t: Vec<f64>,
    /// Gyro residual before/after (rad/s).
    pub gyro_before: Vec<f64>,
    /// After the extension.
    pub gyro_after: Vec<f64>,
    /// Cross-correlation of the V residual (before) with dV/dt at lags (s):
    /// a peak away from zero lag or a strong zero-lag value hints at latency.
    pub lag_v_accel: Vec<(f64, f64)>,
    /// Same for the W residual with dW/dt.
    pub lag_w_accel: Vec<(f64, f64)>,
}

/// The series of the ICP and gyro rows from their residuals before (`b`) and
/// after (`a`) the extension, with the nominal model's predictions as
/// regressors.
pub fn series(
    replay: &Replay,
    icp: &[IcpRow],
    gyro: &[GyroRow],
    b: &[Vec<f64>; 4],
    a: &[Vec<f64>; 4],
    split: f64,
) -> ResidualSeries {
    let x0 = Departures::default();
    let t: Vec<f64> = icp.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let pred: Vec<(f64, f64)> = icp.iter().map(|r| replay.body(&x0, r.t0, r.t1)).collect();
    let n = t.len();
    let deriv = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..n)
            .map(|i| {
                let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
                let dt = t[i1] - t[i0];
                if dt > 0.0 {
                    (f(i1) - f(i0)) / dt
                } else {
                    0.0
                }
            })
            .collect()
    };
    let accel = deriv(&|i| pred[i].0);
    let turn_accel = deriv(&|i| pred[i].1);
    let dt_med = {
        let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        median(&mut d)
    };
    let lagged = |res: &[f64], reg: &[f64]| {
        cross_correlation(res, reg, 10)
            .into_iter()
            .map(|(l, c)| (l as f64 * dt_med, c))
            .collect()
    };
    ResidualSeries {
        split,
        speed: pred.iter().map(|p| p.0).collect(),
        turn_rate: pred.iter().map(|p| p.1).collect(),
        speed_turn: pred.iter().map(|p| p.0.abs() * p.1.abs()).collect(),
        lag_v_accel: lagged(&b[0], &accel),
        lag_w_accel: lagged(&b[2], &turn_accel),
        accel,
        turn_accel,
        t,
        v_before: b[0].clone(),
        v_after: a[0].clone(),
        lateral_before: b[1].clone(),
        lateral_after: a[1].clone(),
        w_before: b[2].clone(),
        w_after: a[2].clone(),
        gyro_t: gyro.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect(),
        gyro_before: b[3].clone(),
        gyro_after: a[3].clone(),
    }
}
