//! Dual Kalman filter \[WanNelson1997\]: a state filter on [V, W] that predicts
//! with the parameter filter's latest estimate, and a parameter filter on
//! [R_R, R_L, D] that takes the state filter's latest estimate as its
//! measurement, with the state's variance plus the velocity model's own
//! noise (`NoiseParams::model_sigma_v`, `model_sigma_w`: encoder
//! quantisation, slip), without which the parameter filter would trust each
//! step's wheel-rate prediction as exact and chase its noise. The state
//! filter's prior is loose (it must follow the measurements), so its
//! Student-t weight passes what a small robot's scan matching gets wrong;
//! the parameter filter's residual is therefore gated against its own
//! prior predictive (`NoiseParams::kalman_gate`).

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
    gate: f64,
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
            gate: n.kalman_gate,
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
            let hph = h.dot(&ph);
            let meas_var = gated(x[k] - f[k], hph, meas_var, self.gate);
            let sv = hph + meas_var;
            let gain = ph / sv;
            self.theta += gain * (x[k] - f[k]);
            let ikh = Matrix3::identity() - gain * h.transpose();
            self.p_theta =
                ikh * self.p_theta * ikh.transpose() + gain * gain.transpose() * meas_var;
        }
        self.p_theta = 0.5 * (self.p_theta + self.p_theta.transpose());
        self.theta = self.theta.map(|t| t.max(1e-6));
        let fired = self
            .change
            .as_mut()
            .and_then(|c| c.end_step(&self.theta, &mut self.p_theta));
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
        super::change::Firing::mark(fired, &mut est);
        est
    }

    fn name(&self) -> &'static str {
        "dkf"
    }
}

/// The measurement variance `r` of a residual `nu` whose prior predictive
/// variance is `hph + r`, raised when `|nu|` lies beyond `gate` σ of it so
/// that the residual stands at `gate` σ of the raised predictive. The
/// prediction then moves by `hph·gate²/ν`: at most `gate` of its own σ at
/// the gate, less the further out the residual lies, as a robust filter
/// treats a measurement its model cannot explain (Huber's bound on one
/// observation's influence, here by its variance). `gate` ≤ 0 leaves `r`.
fn gated(nu: f64, hph: f64, r: f64, gate: f64) -> f64 {
    let s = hph + r;
    if !(gate > 0.0) || !(s > 0.0) || !nu.is_finite() || nu * nu <= gate * gate * s {
        return r;
    }
    // (hph + r') = ν²/gate² → r' = ν²/gate² − hph, which exceeds r here.
    nu * nu / (gate * gate) - hph
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::steps::Measurement;
    use crate::calib::{CalibParams, Method, Ranges};

    #[test]
    fn the_gate_raises_the_variance_of_a_residual_beyond_it_and_only_then() {
        // ν = 20 against hph 3 + r 1 (σ 2): 10 σ, beyond 5 → r' with
        // (3 + r')·25 = 400, r' = 13; the residual then stands at 20/4 = 5 σ.
        assert_eq!(gated(20.0, 3.0, 1.0, 5.0), 13.0);
        assert_eq!(gated(-20.0, 3.0, 1.0, 5.0), 13.0);
        // ν = 9: 4.5 σ, inside.
        assert_eq!(gated(9.0, 3.0, 1.0, 5.0), 1.0);
        // Exactly at the gate (ν = 10 = 5·2): left as it is.
        assert_eq!(gated(10.0, 3.0, 1.0, 5.0), 1.0);
        // Off, or nothing to read against.
        assert_eq!(gated(20.0, 3.0, 1.0, 0.0), 1.0);
        assert_eq!(gated(f64::NAN, 3.0, 1.0, 5.0), 1.0);
        assert_eq!(gated(20.0, 0.0, 0.0, 5.0), 0.0);
    }

    /// A filter of a small robot (R 20 mm, D 90 mm, 1 cm/s), five intervals
    /// into its stream (R known to ±0.7 mm, as after a change detector has
    /// re-spread it), sees one interval whose V is four times what its
    /// wheels give: a residual of 3 cm/s, 28 σ of its prediction, that the
    /// state filter's loose prior (σ 5 cm/s) passes. Gated at 3 σ, R moves
    /// by a tenth of its σ (hph·9/ν on V = R̄/2); without the gate, by 8 σ.
    #[test]
    fn one_wild_interval_moves_a_converged_filter_by_at_most_the_gate() {
        let settings = |gate: Option<f64>| {
            let mut p = CalibParams {
                method: Method::Dkf,
                ranges: Some(Ranges::around(0.02, 0.02, 0.09, 0.1)),
                ..Default::default()
            };
            p.change.enabled = false;
            if let Some(g) = gate {
                p.noise.kalman_gate = g;
            }
            p.kalman_settings()
        };
        let step = |t: f64, v: f64| {
            let mut s = CalibStep::new(t, t + 1.0, 0.5, 0.5);
            s.push(Measurement {
                kind: Kind::V,
                value: v,
                sigma: 0.001,
            });
            s.push(Measurement {
                kind: Kind::W,
                value: 0.0,
                sigma: 0.001,
            });
            s
        };
        let mut moved = [0.0; 2];
        // The default gate (3 σ), then none.
        for (i, gate) in [None, Some(0.0)].into_iter().enumerate() {
            let mut f = DualKf::new(&settings(gate));
            // Five intervals of 1 cm/s on wheels at 0.5 rad/s: R = 20 mm.
            let mut last = f.step(&step(0.0, 0.01));
            for k in 1..5 {
                last = f.step(&step(k as f64, 0.01));
            }
            let before = 0.5 * (last.r_right + last.r_left);
            assert!((before - 0.02).abs() < 2e-4, "gate {gate:?}: R {before}");

            let sd = 0.5 * (last.std_r_right + last.std_r_left);
            // One interval at 4 cm/s.
            let after = f.step(&step(5.0, 0.04));
            moved[i] = (0.5 * (after.r_right + after.r_left) - before).abs() / sd;
        }
        // V = 0.5 rad/s · R̄: 3 σ of V's prediction is at most 3 σ of R.
        assert!(moved[0] <= 3.0, "gated: R moved {} σ", moved[0]);
        // The negative control: ungated, the same bound fails.
        assert!(moved[1] > 3.0, "ungated: R moved only {} σ", moved[1]);
    }

    fn hand(walk: f64, w_obs: f64) -> DualKf {
        DualKf::new(&crate::calib::kalman::hand::settings(walk, w_obs))
    }

    #[test]
    fn the_state_filter_s_speed_observes_the_parameters_by_hand() {
        // Wheels at 2 and 1 rad/s predict V 0.45 m/s. The state filter
        // (prior 1e-4, measurement 0.01² = 1e-4) takes half of the 0.02
        // innovation: V 0.46, variance 5e-5 = 1.5/30 000. The parameter
        // filter reads that V against (2 R_R + R_L)/2, whose variance is
        // 1.25/30 000: R_R gains 1/2.75 = 4/11 of the 0.01, R_L 2/11, D
        // nothing; R_R keeps 7/11 of its variance.
        let mut f = hand(0.0, 0.0);
        let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, 0.47, 0.01));
        assert!((e.v - 0.46).abs() < 1e-12, "{}", e.v);
        assert!(
            (e.r_right - (0.3 + 0.04 / 11.0)).abs() < 1e-12,
            "{}",
            e.r_right
        );
        assert!(
            (e.r_left - (0.3 + 0.02 / 11.0)).abs() < 1e-12,
            "{}",
            e.r_left
        );
        assert!((e.wheel_base - 0.6).abs() < 1e-12);
        assert!((e.std_r_right - (7.0 / 11.0 / 30_000.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(f.name(), "dkf");
        // The residual, 0.01 against σ √(2.75/30 000) = 0.0096, lies inside
        // a 3 σ gate: the same update.
        let mut g = hand(0.0, 0.0);
        g.gate = 3.0;
        let e = g.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, 0.47, 0.01));
        assert!(
            (e.r_right - (0.3 + 0.04 / 11.0)).abs() < 1e-12,
            "{}",
            e.r_right
        );
        // The velocity model's σ_V 0.005 per 0.02 s adds 0.75/30 000 to
        // the parameter filter's measurement: R_R gains 1/3.5 of the 0.01.
        let mut m = hand(0.0, 0.0);
        m.model_var = [2.5e-5, 0.0];
        let e = m.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, 0.47, 0.01));
        assert!(
            (e.r_right - (0.3 + 0.01 / 3.5)).abs() < 1e-12,
            "{}",
            e.r_right
        );
    }

    #[test]
    fn the_state_filter_s_turn_rate_observes_the_wheel_base_by_hand() {
        // W predicted 0.5 rad/s; the state filter (prior and measurement
        // 0.05²) takes half of the 0.05: W 0.525, variance 1.25e-3. Its
        // Jacobian (2, −1, −0.5)/0.6: predicted variance
        // 5/0.36/30 000 + 0.25/0.36/300; D moves by −(0.5/0.6/300) over that
        // plus 1.25e-3, times 0.025.
        let mut f = hand(0.0, 0.0);
        let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::W, 0.55, 0.05));
        let s = 5.0 / 0.36 / 30_000.0 + 0.25 / 0.36 / 300.0 + 1.25e-3;
        let d = 0.6 - (0.5 / 0.6 / 300.0) / s * 0.025;
        assert!((e.w - 0.525).abs() < 1e-12, "{}", e.w);
        assert!(
            (e.wheel_base - d).abs() < 1e-12,
            "{} against {d}",
            e.wheel_base
        );
        assert!((e.r_left - (0.3 - (1.0 / 0.6 / 30_000.0) / s * 0.025)).abs() < 1e-12);
    }

    #[test]
    fn the_parameters_walk_per_root_second_and_the_wheel_base_by_its_observability() {
        // σ 1e-3 per √s over 0.25 s adds 2.5e-7 m²; the robot turns at half
        // the turn rate that observes D, so D's walk is a quarter of it;
        // per step, the whole 1e-6.
        let grew = |std: f64, prior: f64| std * std - prior;
        let mut f = hand(1e-3, 1.0);
        let e = f.step(&CalibStep::new(0.0, 0.25, 2.0, 1.0));
        assert!((grew(e.std_r_left, 1.0 / 30_000.0) - 2.5e-7).abs() < 1e-15);
        assert!((grew(e.std_wheel_base, 1.0 / 300.0) - 0.25 * 2.5e-7).abs() < 1e-15);
        let mut g = hand(1e-3, 0.0);
        g.per_step = true;
        let e = g.step(&CalibStep::new(0.0, 0.25, 2.0, 1.0));
        assert!((grew(e.std_r_right, 1.0 / 30_000.0) - 1e-6).abs() < 1e-15);
    }

    #[test]
    fn a_student_t_weight_spares_the_filter_an_outlier_and_not_a_fit() {
        crate::calib::kalman::hand::student_t_spares_an_outlier(|dof, z| {
            let mut f = hand(0.0, 0.0);
            f.dof = dof;
            let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, z, 0.01));
            e.r_right - 0.3
        });
    }
}
