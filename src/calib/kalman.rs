//! Pieces shared by the Kalman baselines: the motion model's Jacobian with
//! respect to the parameters and the initial parameter belief.

use super::params::Ranges;
use super::Estimate;
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

/// `∂W/∂θ` with D's observability `obs` (see
/// `NoiseParams::observability_turn_rate`): the wheel base that W sees is
/// `obs·D + (1 − obs)·(D/(R_R + R_L))·(R_R + R_L)` with the ratio frozen at
/// θ, so a straight run does not move D (its entry is scaled by `obs`) while
/// the direction θ itself, a common scale of radii and D, stays invisible
/// to W at every `obs`, as it physically is.
pub(crate) fn turn_jacobian(
    theta: &Vector3<f64>,
    jw: &Vector3<f64>,
    w: f64,
    obs: f64,
) -> Vector3<f64> {
    let d = theta[2].max(1e-6);
    let ratio = d / (theta[0] + theta[1]).max(1e-6);
    let shift = (1.0 - obs) * ratio * w / d;
    Vector3::new(jw[0] - shift, jw[1] - shift, jw[2] * obs)
}

/// The velocity model's variance `[V, W]` over a step of `dt` (s), for the
/// model σ's configured per [`super::PAPER_STEP_S`]: the model's error is an
/// error of the wheels' angles over the step (encoder quantisation, a
/// sample's timing, a slip's jerk), so its rate error falls as 1/dt; an
/// interval of a second carries 1/50 of a 0.02 s step's.
pub(crate) fn model_var_at(base: [f64; 2], dt: f64) -> [f64; 2] {
    let k = if dt > 0.0 {
        (super::PAPER_STEP_S / dt).min(1.0).powi(2)
    } else {
        1.0
    };
    base.map(|v| v * k)
}

/// Initial belief: centre of the uniform ranges, variance of the uniform
/// distribution (width²/12).
pub(crate) fn prior(ranges: &Ranges) -> (Vector3<f64>, Matrix3<f64>) {
    let r = ranges.all();
    let mean = Vector3::from_fn(|i, _| 0.5 * (r[i][0] + r[i][1]));
    let var = Vector3::from_fn(|i, _| (r[i][1] - r[i][0]).powi(2) / 12.0);
    (mean, Matrix3::from_diagonal(&var))
}

/// How observable the wheel base is at turn rate `w` (rad/s): `|w| / w_ref`
/// capped at 1 (W carries information about D only through `−W/D`); 1 when
/// `w_ref` is 0 (feature off).
pub(crate) fn observability(w: f64, w_ref: f64) -> f64 {
    if w_ref > 0.0 && w.is_finite() {
        (w.abs() / w_ref).min(1.0)
    } else {
        1.0
    }
}

/// The turn rate that decides D's observability for a step: the
/// inverse-variance mean of its usable W measurements (the motion, not the
/// estimate, decides), else `predicted` (rad/s).
pub(crate) fn turn_rate_for_observability(
    step: &super::steps::CalibStep,
    floor: f64,
    predicted: f64,
) -> f64 {
    let (mut s, mut sw) = (0.0, 0.0);
    for m in step
        .measurements()
        .iter()
        .filter(|m| m.kind == super::steps::Kind::W && super::steps::usable(m))
    {
        let iv = 1.0 / m.sigma.max(floor).powi(2);
        s += m.value * iv;
        sw += iv;
    }
    if sw > 0.0 {
        s / sw
    } else {
        predicted
    }
}

/// The estimate of a Kalman filter at time `t`: parameters `theta` =
/// (R_R, R_L, D) with variances `var` (a negative one read as 0), velocities
/// `vw` = (V, W) and the parameters' process noise variance `q`.
pub(super) fn kalman_estimate(
    t: f64,
    theta: [f64; 3],
    var: [f64; 3],
    vw: [f64; 2],
    q: f64,
) -> Estimate {
    let sd = |v: f64| v.max(0.0).sqrt();
    Estimate {
        t,
        r_right: theta[0],
        r_left: theta[1],
        wheel_base: theta[2],
        std_r_right: sd(var[0]),
        std_r_left: sd(var[1]),
        std_wheel_base: sd(var[2]),
        v: vw[0],
        w: vw[1],
        particles: 0,
        process_sigma: q.sqrt(),
        resampled: false,
        weights_reset: false,
        changed: false,
        respread: false,
    }
}

/// What the Kalman filters' tests compute their one-step updates by hand
/// from.
#[cfg(test)]
pub(crate) mod hand {
    use super::super::params::{KalmanSettings, NoiseParams, Ranges};

    /// Radii 0.30 ± 0.01 m and wheel base 0.60 ± 0.10 m (uniform: variances
    /// 1/30 000 and 1/300 m²); the dual filter's state prior σ 0.01 m/s and
    /// 0.05 rad/s; no model σ, gate or Student-t; `walk` the parameters' σ
    /// per √s, `w_obs` the turn rate (rad/s) at which D counts as observed
    /// (0: always).
    pub(crate) fn settings(walk: f64, w_obs: f64) -> KalmanSettings {
        KalmanSettings {
            noise: NoiseParams {
                kalman_velocity_sigma: 0.01,
                kalman_turn_sigma: 0.05,
                kalman_param_sigma: walk,
                kalman_gate: 0.0,
                model_sigma_v: 0.0,
                model_sigma_w: 0.0,
                robust_dof: 0.0,
                observability_turn_rate: w_obs,
                sigma_floor: 1e-9,
                ..NoiseParams::default()
            },
            detector: None,
            per_step: false,
            ranges: Ranges {
                r_right: [0.29, 0.31],
                r_left: [0.29, 0.31],
                wheel_base: [0.5, 0.7],
            },
        }
    }

    /// A Student-t weight of 4 degrees of freedom spares a filter an
    /// outlier and not a fit: `moved(dof, z)` is how far one V measurement
    /// `z` (σ 0.01 m/s, 0.45 m/s predicted) moves R_R. Half a σ off it moves
    /// it as the Gaussian update does, within 2 %; 20 σ off, less than a
    /// fifth as far, and the same way.
    pub(crate) fn student_t_spares_an_outlier(moved: impl Fn(f64, f64) -> f64) {
        let near = 0.45 + 0.005;
        assert!((moved(4.0, near) / moved(0.0, near) - 1.0).abs() < 0.02);
        let far = 0.45 + 0.2;
        assert!(moved(4.0, far) < 0.2 * moved(0.0, far));
        assert!(moved(4.0, far) > 0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_turn_jacobian_never_sees_a_common_scale_and_scales_d_by_observability() {
        let theta = Vector3::new(0.321, 0.317, 0.652);
        let ([_, w], [_, jw]) = model(&theta, 2.9, 2.4);
        for obs in [0.0, 0.25, 1.0] {
            let j = turn_jacobian(&theta, &jw, w, obs);
            // Moving along θ itself (all three scaled together) leaves W alone.
            assert!(j.dot(&theta).abs() < 1e-12, "obs {obs}: {}", j.dot(&theta));
            assert!((j[2] - obs * jw[2]).abs() < 1e-15);
        }
        // Fully observable: the model's own Jacobian.
        assert!((turn_jacobian(&theta, &jw, w, 1.0) - jw).norm() < 1e-15);
    }
}
