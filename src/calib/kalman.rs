//! Pieces shared by the Kalman baselines: the motion model's Jacobian with
//! respect to the parameters and the initial parameter belief.

use super::params::CalibParams;
use nalgebra::{Matrix3, Vector3};

/// `f(θ) = [V, W]` for θ = [R_R, R_L, D] and wheel rates (rad/s), with its
/// Jacobian rows `∂V/∂θ`, `∂W/∂θ`.
pub(crate) fn model(theta: &Vector3<f64>, wr: f64, wl: f64) -> ([f64; 2], [Vector3<f64>; 2]) {
    let (rr, rl, d) = (theta[0], theta[1], theta[2].max(1e-6));
    let v = 0.5 * (wr * rr + wl * rl);
    let w = (wr * rr - wl * rl) / d;
    let jv = Vector3::new(0.5 * wr, 0.5 * wl, 0.0);
    let jw = Vector3::new(wr / d, -wl / d, -w / d);
    ([v, w], [jv, jw])
}

/// Initial belief: centre of the uniform ranges, variance of the uniform
/// distribution (width²/12).
pub(crate) fn prior(params: &CalibParams) -> (Vector3<f64>, Matrix3<f64>) {
    let r = params.ranges.all();
    let mean = Vector3::from_fn(|i, _| 0.5 * (r[i][0] + r[i][1]));
    let var = Vector3::from_fn(|i, _| (r[i][1] - r[i][0]).powi(2) / 12.0);
    (mean, Matrix3::from_diagonal(&var))
}
