//! Change detection for the online filters: a windowed score test (Rao's
//! test) that the velocity measurements of the last few seconds still agree
//! with the filter's parameter belief. When a new user boards ([Farina, Fig. 6b]) the
//! radii jump by millimetres; the process-noise rule of [Farina, eq. 11] (with
//! α = 1e-4) then grows only to micrometres per step and cannot follow. The
//! test turns the same disagreement into a decision: when it fires, the
//! particle filter re-inflates the spread and count of its particles, and
//! the Kalman filters re-open their parameter covariance by the same spread
//! ([`KalmanChange`]); each then re-converges. The same detector, the same
//! threshold and the same spread for every method, so that re-convergence
//! times compare like with like.
//!
//! With the linearised model `z_j = h_j(θ) + n_j`, `n_j ~ N(0, S_j)`, the
//! score over the window (exponential forgetting, factor `λ = e^{−dt/τ}` per
//! step) is `g = Σ λ^k J_jᵀ S_j⁻¹ ν_j` with innovations `ν_j = z_j − h_j(θ̂)`
//! at the filter's mean θ̂. If the parameters have not changed and
//! θ̂ − θ ~ N(0, P) (the particle covariance), `g ~ N(0, F₂ + F P F)` with
//! `F = Σ λ^k J_jᵀ S_j⁻¹ J_j` and `F₂` the same sum with `λ^{2k}`, so
//! `T = gᵀ (F₂ + F P F)⁺ g` is χ² with (at most) 3 degrees of freedom. The
//! test fires when `T` exceeds the χ²₃ quantile of `1 − false_alarm`. While
//! the filter is still uncertain (large P) the test is mute by construction;
//! directions without information (D on a straight run) drop out of the
//! pseudo-inverse.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::units::PAPER_RADIUS_M;
use crate::stats::chi2_quantile;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

/// Settings of the change detector (used by `adaptive-pf`, and by `dkf` and
/// `akf` when `kalman` is set; the fixed `pf` is the plain filter of \[Farina\] and
/// has none).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChangeParams {
    /// Whether the detector runs (false: the rules of \[Farina\] alone).
    pub enabled: bool,
    /// Whether the Kalman filters (`dkf`, `akf`) run it too (default: the
    /// same detector for every method). Their robust likelihood takes a
    /// change of the radii, seen over intervals of a second at many times
    /// the intervals' σ, for a run of outliers and follows it only slowly;
    /// the detector re-opens their covariance instead. `odocal experiment
    /// changing` compares every filter with it on and off.
    pub kalman: bool,
    /// Time constant τ of the window's exponential forgetting (s).
    pub window: f64,
    /// Probability that one evaluation fires without a change (sets the χ²₃
    /// threshold; evaluations within a window are strongly correlated, so the
    /// false-alarm rate per window is of this order).
    pub false_alarm: f64,
    /// Smallest spread (σ, in wheel radii) added to R_R, R_L, D when the
    /// test fires; the spread is widened to the window's estimate of the
    /// jump when larger.
    pub jump_sigma: [f64; 3],
    /// Naming of what changed at each firing, after the run
    /// (`diagnose::onset`).
    pub naming: crate::effects::change::OnsetParams,
}

impl Default for ChangeParams {
    fn default() -> Self {
        Self {
            enabled: true,
            kalman: true,
            window: 5.0,
            false_alarm: 1e-5,
            jump_sigma: [3e-3 / PAPER_RADIUS_M, 3e-3 / PAPER_RADIUS_M, 0.0],
            naming: Default::default(),
        }
    }
}

impl ChangeParams {
    /// Checks ranges; the message names the bad field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.window.is_finite() && self.window > 0.0) {
            return Err("change.window must be > 0 s".into());
        }
        if !(self.false_alarm > 0.0 && self.false_alarm < 1.0) {
            return Err("change.false_alarm must be in (0, 1)".into());
        }
        if !self.jump_sigma.iter().all(|s| s.is_finite() && *s >= 0.0) {
            return Err("change.jump_sigma entries must be finite and ≥ 0".into());
        }
        self.naming.validate()
    }

    /// The detector's own settings, its spread in metres for a robot whose
    /// lengths are `unit` (m) wheel radii (not the naming, which runs after).
    pub fn detector(&self, unit: f64) -> DetectorParams {
        DetectorParams {
            window: self.window,
            false_alarm: self.false_alarm,
            jump_sigma: self.jump_sigma.map(|s| s * unit),
        }
    }
}

/// What a running detector needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorParams {
    /// Time constant τ of the window's exponential forgetting (s).
    pub window: f64,
    /// Probability that one evaluation fires without a change.
    pub false_alarm: f64,
    /// Smallest spread (σ, m) added to R_R, R_L, D when the test fires.
    pub jump_sigma: [f64; 3],
}

impl DetectorParams {
    /// The χ²₃ quantile of `1 − false_alarm`.
    pub fn threshold(&self) -> f64 {
        chi2_quantile(1.0 - self.false_alarm, 3)
    }
}

/// A fired test: the statistic and the window's estimate of the jump.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jump {
    /// The statistic T (χ²₃ under no change).
    pub statistic: f64,
    /// Estimated change of (R_R, R_L, D) over the window (m): `F⁺ g`.
    pub delta: [f64; 3],
}

impl Jump {
    /// The spread (σ, m) to re-open the belief with: per radius the larger
    /// of the configured `floor` and the window's estimate of the jump,
    /// bounded by 10 % of the parameter's `mean`; the wheel base gets its
    /// configured σ.
    pub fn spread(&self, floor: &[f64; 3], mean: &[f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| {
            let est = if k < 2 { self.delta[k].abs() } else { 0.0 };
            let est = if est.is_finite() { est } else { 0.0 };
            floor[k].max(est).min(0.1 * mean[k].abs())
        })
    }
}

/// The running score test.
#[derive(Debug, Clone)]
pub struct ChangeDetector {
    g: Vector3<f64>,
    f: Matrix3<f64>,
    f2: Matrix3<f64>,
    tau: f64,
    threshold: f64,
    last: f64,
    /// Time accumulated since the start or the last firing (s).
    age: f64,
}

impl ChangeDetector {
    /// A detector with an empty window.
    pub fn new(p: &DetectorParams) -> Self {
        Self {
            g: Vector3::zeros(),
            f: Matrix3::zeros(),
            f2: Matrix3::zeros(),
            tau: p.window,
            threshold: p.threshold(),
            last: 0.0,
            age: 0.0,
        }
    }

    /// The statistic after the last [`ChangeDetector::end_step`].
    pub fn statistic(&self) -> f64 {
        self.last
    }

    /// Forgets the window by the step length `dt` (s); call before the step's
    /// measurements.
    pub fn begin_step(&mut self, dt: f64) {
        self.age += dt.max(0.0);
        let l = (-dt.max(0.0) / self.tau).exp();
        self.g *= l;
        self.f *= l;
        self.f2 *= l * l;
    }

    /// Forgets the window by `dt` (s) and adds the step's fused measurements
    /// (V, W) against the prediction at the mean, with the Jacobians `j` of
    /// V and W with respect to (R_R, R_L, D) and the precision `1/(fused
    /// variance + model variance)`.
    pub(crate) fn observe(
        &mut self,
        dt: f64,
        fused: &[Option<super::fuse::Fused>; 2],
        pred: &super::fuse::Prediction,
        j: [Vector3<f64>; 2],
    ) {
        self.begin_step(dt);
        for k in 0..2 {
            if let Some(f) = fused[k] {
                let prec = 1.0 / (f.var + pred.model_var[k]);
                self.add(f.value - pred.value[k], [j[k][0], j[k][1], j[k][2]], prec);
            }
        }
    }

    /// Adds one measurement: innovation `nu` at the mean, Jacobian `j` of the
    /// measured quantity with respect to (R_R, R_L, D), and its precision
    /// `1/S` (already scaled by any robust weight). The caller passes W's
    /// Jacobian with D's observability (`kalman::turn_jacobian`): on a
    /// straight run the linearised score for D is dominated by the model's
    /// curvature (any predicted W is "explained" by a larger D), not by
    /// evidence.
    pub fn add(&mut self, nu: f64, j: [f64; 3], precision: f64) {
        let j = Vector3::from(j);
        if !(nu.is_finite() && precision.is_finite() && j.iter().all(|x| x.is_finite())) {
            return;
        }
        self.g += j * (precision * nu);
        let jj = j * j.transpose() * precision;
        self.f += jj;
        self.f2 += jj;
    }

    /// Evaluates the test against the belief covariance `p` (m²); on firing
    /// returns the jump and empties the window. The test is armed only once
    /// a whole window (τ) has passed since the start or the last firing: a
    /// freshly spread particle cloud does not describe its own uncertainty
    /// well enough to be tested against.
    pub fn end_step(&mut self, p: &Matrix3<f64>) -> Option<Jump> {
        let m = self.f2 + self.f * p * self.f;
        let t = quad_pinv(&m, &self.g);
        self.last = t;
        if !(t > self.threshold) || self.age < self.tau {
            return None;
        }
        self.age = 0.0;
        let d = pinv(&self.f) * self.g;
        let jump = Jump {
            statistic: t,
            delta: [d[0], d[1], d[2]],
        };
        self.g = Vector3::zeros();
        self.f = Matrix3::zeros();
        self.f2 = Matrix3::zeros();
        Some(jump)
    }
}

/// Pseudo-inverse of a symmetric PSD 3×3 matrix (eigenvalues below 1e-6 of
/// the largest, i.e. directions with a millionth of the information, are
/// treated as zero).
fn pinv(m: &Matrix3<f64>) -> Matrix3<f64> {
    let e = SymmetricEigen::new(0.5 * (m + m.transpose()));
    let top = e.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    if !(top > 0.0) || !top.is_finite() {
        return Matrix3::zeros();
    }
    let inv = e
        .eigenvalues
        .map(|l| if l > 1e-6 * top { 1.0 / l } else { 0.0 });
    e.eigenvectors * Matrix3::from_diagonal(&inv) * e.eigenvectors.transpose()
}

/// `gᵀ M⁺ g`, 0 for an empty or non-finite window.
fn quad_pinv(m: &Matrix3<f64>, g: &Vector3<f64>) -> f64 {
    let t = g.dot(&(pinv(m) * g));
    if t.is_finite() {
        t.max(0.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Feeds V and W measurements of a robot with parameters `truth` to a
    /// detector that believes `belief` with covariance `p`; returns the step
    /// at which it fired.
    fn feed(truth: [f64; 3], belief: [f64; 3], p: Matrix3<f64>, steps: usize) -> Option<usize> {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(4);
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(PAPER_RADIUS_M));
        let (sv, sw) = (0.05f64, 0.01f64);
        for k in 0..steps {
            let t = k as f64 * 0.02;
            let (wr, wl) = (2.5 + 0.8 * (0.3 * t).sin(), 2.5 - 0.8 * (0.3 * t).sin());
            let h = |q: [f64; 3]| {
                (
                    0.5 * (wr * q[0] + wl * q[1]),
                    (wr * q[0] - wl * q[1]) / q[2],
                )
            };
            let (vt, wt) = h(truth);
            let (vb, wb) = h(belief);
            let n: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            det.begin_step(0.02);
            det.add(
                vt + sv * n[0] - vb,
                [0.5 * wr, 0.5 * wl, 0.0],
                1.0 / (sv * sv),
            );
            let jw = [wr / belief[2], -wl / belief[2], -wb / belief[2]];
            det.add(wt + sw * n[1] - wb, jw, 1.0 / (sw * sw));
            if det.end_step(&p).is_some() {
                return Some(k);
            }
        }
        None
    }

    #[test]
    fn threshold_is_the_chi2_quantile() {
        // χ²₃ quantiles: 0.99 → 11.345, 0.999 → 16.266.
        for (fa, q) in [(0.01, 11.345), (0.001, 16.266)] {
            let p = ChangeParams {
                false_alarm: fa,
                ..Default::default()
            }
            .detector(1.0);
            assert!((p.threshold() - q).abs() < 1e-3, "{}", p.threshold());
        }
    }

    #[test]
    fn fires_on_a_jump_and_stays_quiet_without_one() {
        let k = [0.32, 0.3185, 0.65];
        let p = Matrix3::from_diagonal(&Vector3::new(1e-8, 1e-8, 1e-6));
        assert_eq!(feed(k, k, p, 5000), None, "no change: no alarm in 100 s");
        let after = [0.324, 0.3205, 0.65];
        let fired = feed(after, k, p, 5000).expect("a 4 mm jump is detected");
        // Armed after one window (5 s = 250 steps), then at once.
        assert!((250..300).contains(&fired), "detected after {fired} steps");
        // The same disagreement inside a wide belief is not a change.
        let wide = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-3));
        assert_eq!(feed(after, k, wide, 2000), None);
    }
}

/// The change handling of a Kalman filter: the detector fed with the step's
/// fused measurements against the prior belief, and on a firing the
/// parameter covariance re-opened by the jump's spread (σ², added to its
/// diagonal), so the filter's gain rises and it follows the new parameters.
#[derive(Debug, Clone)]
pub(crate) struct KalmanChange {
    det: ChangeDetector,
    floor: [f64; 3],
}

impl KalmanChange {
    /// The detector of a Kalman filter (`None`: it runs none).
    pub(crate) fn new(p: Option<&DetectorParams>) -> Option<Self> {
        p.map(|p| Self {
            det: ChangeDetector::new(p),
            floor: p.jump_sigma,
        })
    }

    /// Feeds the step before the update: prior mean `theta` and covariance
    /// `p` of (R_R, R_L, D), D's observability `obs`, the measurement floor,
    /// the Student-t ν and the model variances of (V, W).
    pub(crate) fn observe(
        &mut self,
        s: &super::steps::CalibStep,
        theta: &Vector3<f64>,
        p: &Matrix3<f64>,
        obs: f64,
        floor_dof: (f64, f64),
        model_var: [f64; 2],
    ) {
        let ([v, w], [jv, jw]) = super::kalman::model(theta, s.omega_right, s.omega_left);
        let jw = super::kalman::turn_jacobian(theta, &jw, w, obs);
        let pred = super::fuse::Prediction {
            value: [v, w],
            var: [jv.dot(&(p * jv)).max(0.0), jw.dot(&(p * jw)).max(0.0)],
            model_var,
        };
        let fused = super::fuse::fuse(s, &pred, floor_dof.0, floor_dof.1);
        self.det.observe(s.dt(), &fused, &pred, [jv, jw]);
    }

    /// After the update: tests against the posterior covariance `p` and, on
    /// a firing, adds the jump's spread² to its diagonal. Returns whether it
    /// fired.
    pub(crate) fn end_step(&mut self, theta: &Vector3<f64>, p: &mut Matrix3<f64>) -> bool {
        let Some(jump) = self.det.end_step(p) else {
            return false;
        };
        let s = jump.spread(&self.floor, &[theta[0], theta[1], theta[2]]);
        for k in 0..3 {
            p[(k, k)] += s[k] * s[k];
        }
        true
    }
}
