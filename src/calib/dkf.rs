//! Dual Kalman filter \[WanNelson1997\]: a state filter on [V, W] that predicts
//! with the parameter filter's latest estimate, and a parameter filter on
//! [R_R, R_L, D] that takes the state filter's latest estimate as its
//! measurement, with the state's variance plus the velocity model's own
//! noise (`NoiseParams::model_sigma_v`, `model_sigma_w`: encoder
//! quantisation, slip), without which the parameter filter would trust each
//! step's wheel-rate prediction as exact and chase its noise.

use super::change::KalmanChange;
use super::kalman::{
    kalman_estimate, model, model_var_at, observability, prior, turn_jacobian,
    turn_rate_for_observability,
};
use super::params::KalmanSettings;
use super::robust::student_t_weight;
use super::steps::{usable, CalibStep, Kind};
use super::{Calibrator, Estimate};
use nalgebra::{Matrix3, Vector3};

/// The dual Kalman filter baseline (`dkf`).
#[derive(Debug, Clone)]
pub struct DualKf {
    theta: Vector3<f64>,
    p_theta: Matrix3<f64>,
    q_theta: f64,
    q_x: [f64; 2],
    floor: f64,
    dof: f64,
    w_obs: f64,
    model_var: [f64; 2],
    per_step: bool,
    change: Option<KalmanChange>,
}

impl DualKf {
    /// Starts at the centre of `p.ranges` with the uniform variances.
    pub fn new(p: &KalmanSettings) -> Self {
        let (theta, p_theta) = prior(&p.ranges);
        let n = &p.noise;
        Self {
            theta,
            p_theta,
            q_theta: n.kalman_param_sigma.powi(2),
            q_x: [n.kalman_velocity_sigma.powi(2), n.kalman_turn_sigma.powi(2)],
            floor: n.sigma_floor,
            dof: n.robust_dof,
            w_obs: n.observability_turn_rate,
            model_var: [n.model_sigma_v.powi(2), n.model_sigma_w.powi(2)],
            per_step: p.per_step,
            change: KalmanChange::new(p.detector.as_ref()),
        }
    }
}

impl Calibrator for DualKf {
    fn step(&mut self, s: &CalibStep) -> Estimate {
        // State filter: predict with the latest parameters.
        let ([v0, w0], _) = model(&self.theta, s.omega_right, s.omega_left);
        // D's observability this step (see `NoiseParams::observability_turn_rate`).
        let obs = observability(turn_rate_for_observability(s, self.floor, w0), self.w_obs);
        // Parameter filter, time update: random walk (D's scaled by it).
        // (per √s: times dt; per step under the paper's preset).
        let dt = if self.per_step { 1.0 } else { s.dt().max(0.0) };
        self.p_theta += Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, obs * obs))
            * self.q_theta
            * dt;
        let model_var = model_var_at(self.model_var, s.dt());
        if let Some(c) = &mut self.change {
            let fd = (self.floor, self.dof);
            c.observe(s, &self.theta, &self.p_theta, obs, fd, model_var);
        }
        // State filter update with the measurements (scalar updates, V and W
        // independent given θ), each robustly weighted.
        let mut x = [v0, w0];
        let mut px = self.q_x;
        let mut seen = [false, false];
        for m in s.measurements().iter().filter(|m| usable(m)) {
            let k = match m.kind {
                Kind::V => 0,
                Kind::W => 1,
            };
            let r = m.sigma.max(self.floor).powi(2);
            let nu = m.value - x[k];
            // Read against the prior predictive (its spread as noise, no
            // prior): this state filter's prior is a random walk of the
            // velocity, not a belief the parameters give, and read against
            // its posterior every measurement would pass.
            let r = r / student_t_weight(nu, px[k] + r, 0.0, self.dof);
            let g = px[k] / (px[k] + r);
            x[k] += g * (m.value - x[k]);
            px[k] *= 1.0 - g;
            seen[k] = true;
        }
        // Parameter filter, measurement update: the state estimate observes
        // f(θ) with the state filter's posterior variance plus the model's.
        for k in 0..2 {
            if !seen[k] {
                continue;
            }
            let (f, j) = model(&self.theta, s.omega_right, s.omega_left);
            let h = match k {
                0 => j[0],
                _ => turn_jacobian(&self.theta, &j[1], f[1], obs),
            };
            let ph = self.p_theta * h;
            let meas_var = px[k].max(self.floor * self.floor) + model_var[k];
            let sv = h.dot(&ph) + meas_var;
            let gain = ph / sv;
            self.theta += gain * (x[k] - f[k]);
            let ikh = Matrix3::identity() - gain * h.transpose();
            self.p_theta =
                ikh * self.p_theta * ikh.transpose() + gain * gain.transpose() * meas_var;
        }
        self.p_theta = 0.5 * (self.p_theta + self.p_theta.transpose());
        self.theta = self.theta.map(|t| t.max(1e-6));
        let changed = self
            .change
            .as_mut()
            .is_some_and(|c| c.end_step(&self.theta, &mut self.p_theta));
        let mut est = kalman_estimate(
            s.t1,
            self.theta.into(),
            [
                self.p_theta[(0, 0)],
                self.p_theta[(1, 1)],
                self.p_theta[(2, 2)],
            ],
            [x[0], x[1]],
            self.q_theta,
        );
        est.changed = changed;
        est
    }

    fn name(&self) -> &'static str {
        "dkf"
    }
}
