//! Augmented extended Kalman filter: state [V, W, R_R, R_L, D], the
//! parameters as random walks, V and W re-predicted from the wheel rates
//! with the velocity model's noise (`NoiseParams::model_sigma_v`,
//! `model_sigma_w`, the same the particle filters use) as process noise.

use super::change::KalmanChange;
use super::kalman::kalman_estimate;
use super::kalman::{model, observability, prior, turn_jacobian, turn_rate_for_observability};
use super::params::KalmanSettings;
use super::robust::student_t_weight;
use super::steps::{usable, CalibStep, Kind};
use super::{Calibrator, Estimate};
use nalgebra::{SMatrix, SVector, Vector3};

type M5 = SMatrix<f64, 5, 5>;
type V5 = SVector<f64, 5>;

/// The augmented EKF baseline (`akf`).
#[derive(Debug, Clone)]
pub struct AugmentedKf {
    x: V5,
    p: M5,
    q: V5,
    floor: f64,
    dof: f64,
    w_obs: f64,
    per_step: bool,
    change: Option<KalmanChange>,
}

impl AugmentedKf {
    /// Starts at the centre of `params.ranges` with the uniform variances.
    pub fn new(params: &KalmanSettings) -> Self {
        let (m, pm) = prior(&params.ranges);
        let mut x = V5::zeros();
        let mut p = M5::zeros();
        for i in 0..3 {
            x[2 + i] = m[i];
            p[(2 + i, 2 + i)] = pm[(i, i)];
        }
        let n = &params.noise;
        let (qv, qw, qp) = (
            n.model_sigma_v.powi(2),
            n.model_sigma_w.powi(2),
            n.kalman_param_sigma.powi(2),
        );
        p[(0, 0)] = qv;
        p[(1, 1)] = qw;
        Self {
            x,
            p,
            q: V5::new(qv, qw, qp, qp, qp),
            floor: params.noise.sigma_floor,
            dof: params.noise.robust_dof,
            w_obs: params.noise.observability_turn_rate,
            per_step: params.per_step,
            change: KalmanChange::new(params.detector.as_ref()),
        }
    }
}

impl Calibrator for AugmentedKf {
    fn step(&mut self, s: &CalibStep) -> Estimate {
        // Predict: V, W = f(θ); θ unchanged; F = [[0, J], [0, I]], W's row
        // with D's observability this step (see `kalman::turn_jacobian`).
        let theta = Vector3::new(self.x[2], self.x[3], self.x[4]);
        let ([v, w], [jv, jw]) = model(&theta, s.omega_right, s.omega_left);
        let obs = observability(turn_rate_for_observability(s, self.floor, w), self.w_obs);
        let jw = turn_jacobian(&theta, &jw, w, obs);
        let mut f = M5::zeros();
        for j in 0..3 {
            f[(0, 2 + j)] = jv[j];
            f[(1, 2 + j)] = jw[j];
            f[(2 + j, 2 + j)] = 1.0;
        }
        self.x[0] = v;
        self.x[1] = w;
        let mut q = self.q;
        // The parameters' random walk per √s (per step under the paper's
        // preset); the velocity model's error over this step's length.
        let dt = if self.per_step { 1.0 } else { s.dt().max(0.0) };
        (2..5).for_each(|i| q[i] *= dt);
        let model_var = super::kalman::model_var_at([self.q[0], self.q[1]], s.dt());
        (q[0], q[1]) = (model_var[0], model_var[1]);
        q[4] *= obs * obs;
        self.p = f * self.p * f.transpose() + M5::from_diagonal(&q);
        if let Some(c) = &mut self.change {
            let pt = self.p.fixed_view::<3, 3>(2, 2).into_owned();
            c.observe(s, &theta, &pt, obs, (self.floor, self.dof), model_var);
        }
        // Update: one scalar update per usable measurement (Joseph form [BucyJoseph1968]).
        for m in s.measurements().iter().filter(|m| usable(m)) {
            let k = match m.kind {
                Kind::V => 0,
                Kind::W => 1,
            };
            let r = m.sigma.max(self.floor).powi(2);
            let nu = m.value - self.x[k];
            let r = r / student_t_weight(nu, r, self.p[(k, k)], self.dof);
            let sv = self.p[(k, k)] + r;
            let gain: V5 = self.p.column(k) / sv;
            self.x += gain * (m.value - self.x[k]);
            let mut ikh = M5::identity();
            for i in 0..5 {
                ikh[(i, k)] -= gain[i];
            }
            self.p = ikh * self.p * ikh.transpose() + gain * gain.transpose() * r;
        }
        self.p = 0.5 * (self.p + self.p.transpose());
        for i in 2..5 {
            self.x[i] = self.x[i].max(1e-6);
        }
        let mut fired = None;
        if let Some(c) = &mut self.change {
            let theta = Vector3::new(self.x[2], self.x[3], self.x[4]);
            let mut pt = self.p.fixed_view::<3, 3>(2, 2).into_owned();
            fired = c.end_step(&theta, &mut pt);
            if fired.is_some() {
                self.p.fixed_view_mut::<3, 3>(2, 2).copy_from(&pt);
            }
        }
        let mut est = kalman_estimate(
            s.t1,
            [self.x[2], self.x[3], self.x[4]],
            [self.p[(2, 2)], self.p[(3, 3)], self.p[(4, 4)]],
            [self.x[0], self.x[1]],
            self.q[2],
        );
        super::change::Firing::mark(fired, &mut est);
        est
    }

    fn name(&self) -> &'static str {
        "akf"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::kalman::hand;

    /// [`hand::settings`] with the velocity model's σ_V `model_v` per
    /// 0.02 s step.
    fn filter(model_v: f64, walk: f64, w_obs: f64) -> AugmentedKf {
        let mut s = hand::settings(walk, w_obs);
        s.noise.model_sigma_v = model_v;
        AugmentedKf::new(&s)
    }

    #[test]
    fn one_measured_speed_moves_each_radius_by_its_share_of_the_prediction_s_variance() {
        // Wheels at 2 and 1 rad/s: V = (2 R_R + R_L)/2 = 0.45 m/s, whose
        // variance is (1² + 0.5²)/30 000 = 4.1667e-5 m²/s², plus the model's
        // 0.005² = 2.5e-5; with the measurement's 0.01² the innovation's is
        // 1.6667e-4. V measured 0.02 m/s over: R_R gains 1/30 000 / 1.6667e-4
        // = 0.2 of it, R_L 0.1; D, which V does not see, stays; V itself
        // moves by (4.1667e-5 + 2.5e-5) / 1.6667e-4 = 0.4; R_R's variance
        // keeps 1 − 0.2 of itself.
        let mut f = filter(0.005, 0.0, 0.0);
        let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, 0.47, 0.01));
        assert!((e.r_right - 0.304).abs() < 1e-12, "{}", e.r_right);
        assert!((e.r_left - 0.302).abs() < 1e-12, "{}", e.r_left);
        assert!((e.wheel_base - 0.6).abs() < 1e-12);
        assert!((e.v - 0.458).abs() < 1e-12, "{}", e.v);
        assert!((e.std_r_right - (0.8f64 / 30_000.0).sqrt()).abs() < 1e-12);
        assert!((e.std_wheel_base - (1.0f64 / 300.0).sqrt()).abs() < 1e-12);
        assert_eq!(f.name(), "akf");
    }

    #[test]
    fn a_measured_turn_rate_moves_the_wheel_base_by_its_share() {
        // W = (2 R_R − R_L)/D = 0.5 rad/s; its Jacobian (2, −1, −0.5)/0.6,
        // so its variance is (4 + 1)/0.36/30 000 + 0.25/0.36/300 =
        // 2.7778e-3, 5.2778e-3 with the measurement's 0.05². W measured
        // 0.05 over: D moves by −(0.5/0.6/300) / 5.2778e-3 · 0.05.
        let mut f = filter(0.0, 0.0, 0.0);
        let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::W, 0.55, 0.05));
        let s = 5.0 / 0.36 / 30_000.0 + 0.25 / 0.36 / 300.0 + 0.0025;
        let d = 0.6 - (0.5 / 0.6 / 300.0) / s * 0.05;
        assert!(
            (e.wheel_base - d).abs() < 1e-12,
            "{} against {d}",
            e.wheel_base
        );
        assert!((e.r_right - (0.3 + (2.0 / 0.6 / 30_000.0) / s * 0.05)).abs() < 1e-12);
        assert!((e.r_left - (0.3 - (1.0 / 0.6 / 30_000.0) / s * 0.05)).abs() < 1e-12);
    }

    #[test]
    fn the_parameters_walk_per_root_second_and_the_wheel_base_by_its_observability() {
        // σ 1e-3 per √s over 0.25 s adds 2.5e-7 m² to each radius; the
        // wheels turn the robot at 0.5 rad/s, half the 1 rad/s at which D is
        // observed, so D's walk is a quarter of that.
        let mut f = filter(0.0, 1e-3, 1.0);
        let e = f.step(&CalibStep::new(0.0, 0.25, 2.0, 1.0));
        let grew = |std: f64, prior: f64| std * std - prior;
        assert!((grew(e.std_r_right, 1.0 / 30_000.0) - 2.5e-7).abs() < 1e-15);
        assert!((grew(e.std_r_left, 1.0 / 30_000.0) - 2.5e-7).abs() < 1e-15);
        assert!((grew(e.std_wheel_base, 1.0 / 300.0) - 0.25 * 2.5e-7).abs() < 1e-15);
        // Per step (the paper's), the whole σ² each step.
        let mut g = filter(0.0, 1e-3, 0.0);
        g.per_step = true;
        let e = g.step(&CalibStep::new(0.0, 0.25, 2.0, 1.0));
        assert!((grew(e.std_r_right, 1.0 / 30_000.0) - 1e-6).abs() < 1e-15);
    }

    #[test]
    fn a_student_t_weight_spares_the_filter_an_outlier_and_not_a_fit() {
        hand::student_t_spares_an_outlier(|dof, z| {
            let mut f = filter(0.0, 0.0, 0.0);
            f.dof = dof;
            let e = f.step(&CalibStep::new(0.0, 0.02, 2.0, 1.0).with(Kind::V, z, 0.01));
            e.r_right - 0.3
        });
    }
}
