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
//!
//! A firing is a change of the robot only when the window contradicts a
//! belief that was about as sure over it as it is at the test: read again
//! with each innovation against the covariance `P_j` of its own step, `F P
//! F` becomes `G Gᵀ` with `G = Σ λ^k J_jᵀ S_j⁻¹ J_j P_j^{1/2}` (the errors
//! of the window's means taken as one, as they are for a filter that moves
//! slowly, so `G Gᵀ ≥ F P F` while the belief narrows), and that statistic
//! must exceed the χ²₃ quantile of `1 − confirm_false_alarm`
//! ([`Jump::settled`]). A cloud converging from a wide start (the wheel
//! base the first time the robot turns) keeps in the window innovations of
//! a mean it was far less sure of: against its narrowed P they fire, and
//! the filter re-spreads (which is how a particle cloud narrowed on the
//! wrong values recovers), but that is its own convergence, not a change.
//! After a change the belief has been narrow all window long and both
//! readings agree.

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
    /// Level of the second reading of a firing, each measurement against
    /// the belief of its own step ([`Jump::settled`]): the firing is a
    /// change when that statistic exceeds the χ²₃ quantile of `1 −
    /// confirm_false_alarm` (≥ `false_alarm`). On simulated null runs the
    /// firings of a converging filter read 0.4–8.7 so (16.3 at 10⁻³), and
    /// radius steps of 4–5 mm 20–31.
    pub confirm_false_alarm: f64,
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
            confirm_false_alarm: 1e-3,
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
        if !(self.confirm_false_alarm >= self.false_alarm && self.confirm_false_alarm < 1.0) {
            return Err("change.confirm_false_alarm must be in [false_alarm, 1)".into());
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
            confirm_false_alarm: self.confirm_false_alarm,
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
    /// Level of a firing's second reading ([`ChangeParams::confirm_false_alarm`]).
    pub confirm_false_alarm: f64,
    /// Smallest spread (σ, m) added to R_R, R_L, D when the test fires.
    pub jump_sigma: [f64; 3],
}

impl DetectorParams {
    /// The χ²₃ quantile of `1 − false_alarm`.
    pub fn threshold(&self) -> f64 {
        chi2_quantile(1.0 - self.false_alarm, 3)
    }

    /// The χ²₃ quantile of `1 − confirm_false_alarm`.
    pub fn confirm_threshold(&self) -> f64 {
        chi2_quantile(1.0 - self.confirm_false_alarm, 3)
    }
}

/// A fired test: the statistic and the window's estimate of the jump.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jump {
    /// The statistic T (χ²₃ under no change).
    pub statistic: f64,
    /// Estimated change of (R_R, R_L, D) over the window (m): `F⁺ g`.
    pub delta: [f64; 3],
    /// Whether the window, each measurement read against the belief's spread
    /// at its own step (`F₂ + G Gᵀ`), still contradicts the belief at the
    /// confirmation's level: the data contradict a belief that was about as
    /// sure over the whole window as it is now (a change). When not, they
    /// contradict a belief still narrowing (the filter's own convergence):
    /// the filter re-spreads all the same, but no change of the robot is
    /// reported.
    pub settled: bool,
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
    /// `Σ λ^k J_jᵀ S_j⁻¹ J_j P_j^{1/2}`: the window's information, each
    /// measurement's times the square root of the belief it was read against.
    g_root: Matrix3<f64>,
    /// `P^{1/2}` of the belief this step's measurements are read against.
    root: Matrix3<f64>,
    tau: f64,
    threshold: f64,
    confirm: f64,
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
            g_root: Matrix3::zeros(),
            root: Matrix3::zeros(),
            tau: p.window,
            threshold: p.threshold(),
            confirm: p.confirm_threshold(),
            last: 0.0,
            age: 0.0,
        }
    }

    /// The statistic after the last [`ChangeDetector::end_step`].
    pub fn statistic(&self) -> f64 {
        self.last
    }

    /// Forgets the window by the step length `dt` (s) and takes the belief
    /// covariance `p` (m²) the step's measurements are read against; call
    /// before the step's measurements.
    pub fn begin_step(&mut self, dt: f64, p: &Matrix3<f64>) {
        self.age += dt.max(0.0);
        let l = (-dt.max(0.0) / self.tau).exp();
        self.g *= l;
        self.f *= l;
        self.g_root *= l;
        self.f2 *= l * l;
        self.root = sqrt_psd(p);
    }

    /// Forgets the window by `dt` (s) and adds the step's fused measurements
    /// (V, W) against the prediction at the mean of the belief of
    /// covariance `p`, with the Jacobians `j` of V and W with respect to
    /// (R_R, R_L, D) and the precision `1/(fused variance + model variance)`.
    pub(crate) fn observe(
        &mut self,
        dt: f64,
        p: &Matrix3<f64>,
        fused: &[Option<super::fuse::Fused>; 2],
        pred: &super::fuse::Prediction,
        j: [Vector3<f64>; 2],
    ) {
        self.begin_step(dt, p);
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
        self.g_root += jj * self.root;
    }

    /// Evaluates the test against the belief covariance `p` (m²) after the
    /// step; on firing returns the jump and empties the window. The test is
    /// armed only once a whole window (τ) has passed since the start or the
    /// last firing: a freshly spread particle cloud does not describe its
    /// own uncertainty well enough to be tested against.
    pub fn end_step(&mut self, p: &Matrix3<f64>) -> Option<Jump> {
        let t = quad_pinv(&(self.f2 + self.f * p * self.f), &self.g);
        self.last = t;
        if !(t > self.threshold) || self.age < self.tau {
            return None;
        }
        self.age = 0.0;
        let settled = quad_pinv(&(self.f2 + self.g_root * self.g_root.transpose()), &self.g);
        let d = pinv(&self.f) * self.g;
        let jump = Jump {
            statistic: t,
            delta: [d[0], d[1], d[2]],
            settled: settled > self.confirm,
        };
        self.g = Vector3::zeros();
        self.f = Matrix3::zeros();
        self.f2 = Matrix3::zeros();
        self.g_root = Matrix3::zeros();
        Some(jump)
    }
}

/// The symmetric square root of a symmetric PSD 3×3 matrix (negative
/// eigenvalues, from rounding, as 0; zeros when not finite).
fn sqrt_psd(m: &Matrix3<f64>) -> Matrix3<f64> {
    if !m.iter().all(|x| x.is_finite()) {
        return Matrix3::zeros();
    }
    let e = SymmetricEigen::new(0.5 * (m + m.transpose()));
    let root = e.eigenvalues.map(|l| l.max(0.0).sqrt());
    e.eigenvectors * Matrix3::from_diagonal(&root) * e.eigenvectors.transpose()
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
            det.begin_step(0.02, &p);
            det.add(
                vt + sv * n[0] - vb,
                [0.5 * wr, 0.5 * wl, 0.0],
                1.0 / (sv * sv),
            );
            let jw = [wr / belief[2], -wl / belief[2], -wb / belief[2]];
            det.add(wt + sw * n[1] - wb, jw, 1.0 / (sw * sw));
            if let Some(jump) = det.end_step(&p) {
                // Each firing here is a change: the belief is as sure all
                // window long as at the test.
                assert!(jump.settled, "{jump:?}");
                return Some(k);
            }
        }
        None
    }

    #[test]
    fn each_setting_out_of_range_is_refused_and_the_edges_accepted() {
        let with = |f: &dyn Fn(&mut ChangeParams)| {
            let mut p = ChangeParams::default();
            f(&mut p);
            p.validate()
        };
        assert_eq!(with(&|_| ()), Ok(()));
        for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = with(&|p| p.window = w).unwrap_err();
            assert!(e.contains("change.window"), "{w}: {e}");
        }
        assert_eq!(with(&|p| p.window = 1e-9), Ok(()));
        for a in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
            let e = with(&|p| p.false_alarm = a).unwrap_err();
            assert!(e.contains("change.false_alarm"), "{a}: {e}");
        }
        for a in [1e-12, 1e-3] {
            assert_eq!(with(&|p| p.false_alarm = a), Ok(()), "{a}");
        }
        // The confirmation is at least as loose as the firing.
        let both = |fa: f64, c: f64| {
            with(&|p| {
                p.false_alarm = fa;
                p.confirm_false_alarm = c;
            })
        };
        assert_eq!(both(0.5, 0.999), Ok(()));
        assert_eq!(both(0.01, 0.01), Ok(()));
        for (fa, c) in [(0.01, 0.009), (1e-5, 1.0), (1e-5, f64::NAN), (0.5, 0.4)] {
            let e = both(fa, c).unwrap_err();
            assert!(e.contains("change.confirm_false_alarm"), "{fa} {c}: {e}");
        }
        for k in 0..3 {
            for bad in [-1e-9, f64::NAN, f64::INFINITY] {
                let e = with(&|p| p.jump_sigma[k] = bad).unwrap_err();
                assert!(e.contains("change.jump_sigma"), "{k} {bad}: {e}");
            }
            assert_eq!(with(&|p| p.jump_sigma[k] = 0.0), Ok(()));
        }
    }

    #[test]
    fn the_detector_takes_its_spread_in_metres_of_the_robot() {
        let p = ChangeParams {
            window: 3.0,
            false_alarm: 1e-3,
            jump_sigma: [0.01, 0.02, 0.5],
            ..Default::default()
        }
        .detector(0.3);
        assert_eq!((p.window, p.false_alarm), (3.0, 1e-3));
        let want = [0.003, 0.006, 0.15];
        assert!(
            (0..3).all(|k| (p.jump_sigma[k] - want[k]).abs() < 1e-15),
            "{p:?}"
        );
    }

    #[test]
    fn a_jump_spreads_the_radii_by_its_size_within_bounds_and_d_by_its_floor() {
        let floor = [1e-3, 1e-3, 2e-3];
        let jump = |delta| Jump {
            statistic: 30.0,
            delta,
            settled: true,
        };
        // R_R: the jump's 4 mm over the 1 mm floor; R_L: the floor over its
        // 0.5 mm, then bounded by a tenth of its 5 mm mean; D: the floor,
        // whatever the window says of it.
        let s = jump([4e-3, -5e-4, 9.0]).spread(&floor, &[0.3, 0.005, 0.65]);
        assert_eq!(s, [4e-3, 5e-4, 2e-3]);
        // A jump past a tenth of the mean is bounded there; one not finite
        // leaves the floor.
        let s = jump([-0.05, f64::NAN, 0.0]).spread(&floor, &[0.3, 0.3, 0.65]);
        assert!(
            (s[0] - 0.03).abs() < 1e-15 && s[1] == 1e-3 && s[2] == 2e-3,
            "{s:?}"
        );
    }

    #[test]
    fn the_window_forgets_by_its_time_constant_and_the_test_reads_it_by_hand() {
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        assert_eq!(det.statistic(), 0.0);
        let p2 = Matrix3::from_diagonal(&Vector3::new(2.0, 0.0, 0.0));
        det.begin_step(0.0, &p2);
        det.add(3.0, [1.0, 0.0, 0.0], 1.0);
        // One second of a 5 s window: g, F and G by e^(−0.2), F₂ by
        // e^(−0.4).
        det.begin_step(1.0, &Matrix3::zeros());
        let l = (-0.2f64).exp();
        let r2 = 2f64.sqrt();
        assert!((det.g[0] - 3.0 * l).abs() < 1e-12 && (det.f[(0, 0)] - l).abs() < 1e-12);
        assert!((det.f2[(0, 0)] - l * l).abs() < 1e-12 && det.age == 1.0);
        assert!((det.g_root[(0, 0)] - r2 * l).abs() < 1e-12);
        // A step back in time forgets nothing and ages nothing.
        det.begin_step(-2.0, &Matrix3::zeros());
        assert!((det.g[0] - 3.0 * l).abs() < 1e-12 && det.age == 1.0);
        // T = g² / (F₂ + F P F): with P = 0, 9 l² / l² = 9; with P = 2,
        // 9 l² / (l² + 2 l²) = 3. Not armed before a whole window.
        assert_eq!(det.end_step(&Matrix3::zeros()), None);
        assert!((det.statistic() - 9.0).abs() < 1e-9, "{}", det.statistic());
        assert_eq!(det.end_step(&p2), None);
        assert!((det.statistic() - 3.0).abs() < 1e-9, "{}", det.statistic());
        // Armed after τ, over the threshold (27.3 at 10⁻⁵) with g = 6 and
        // a belief of no spread: T = 36 / 1, the jump F⁺ g = 6 on R_R.
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        det.begin_step(5.0, &Matrix3::zeros());
        det.add(6.0, [1.0, 0.0, 0.0], 1.0);
        let jump = det.end_step(&Matrix3::zeros()).expect("fires");
        assert!((jump.statistic - 36.0).abs() < 1e-9 && (jump.delta[0] - 6.0).abs() < 1e-9);
        assert!(jump.settled);
        assert_eq!((jump.delta[1], jump.delta[2], det.age), (0.0, 0.0, 0.0));
    }

    #[test]
    fn observe_adds_each_fused_velocity_at_its_model_widened_precision() {
        // V fused 1.2 (var 1) against 1.0 predicted, model var 3: precision
        // 1/4; W absent. g = J_V · 0.2 / 4, F = J_V J_Vᵀ / 4, after a step
        // of 0 s (nothing forgotten).
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        let fused = [
            Some(crate::calib::fuse::Fused {
                value: 1.2,
                var: 1.0,
            }),
            None,
        ];
        let pred = crate::calib::fuse::Prediction {
            value: [1.0, 9.0],
            var: [0.0, 0.0],
            model_var: [3.0, 5.0],
        };
        let jv = Vector3::new(0.5, 0.25, 0.0);
        det.observe(
            0.0,
            &Matrix3::identity(),
            &fused,
            &pred,
            [jv, Vector3::new(1.0, 1.0, 1.0)],
        );
        assert!((det.g - jv * 0.05).norm() < 1e-15, "{}", det.g);
        assert!((det.f - jv * jv.transpose() / 4.0).norm() < 1e-15);
        // (With P = I the root is I: G = F.)
        assert!((det.g_root - det.f).norm() < 1e-15);
    }

    #[test]
    fn a_measurement_not_finite_adds_nothing() {
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        for (nu, j, prec) in [
            (f64::NAN, [1.0, 0.0, 0.0], 1.0),
            (1.0, [f64::INFINITY, 0.0, 0.0], 1.0),
            (1.0, [1.0, 0.0, f64::NAN], 1.0),
            (1.0, [1.0, 0.0, 0.0], f64::INFINITY),
        ] {
            det.add(nu, j, prec);
        }
        assert_eq!(
            (det.g, det.f, det.f2),
            (Vector3::zeros(), Matrix3::zeros(), Matrix3::zeros())
        );
        det.add(-2.0, [1.0, 0.0, 0.0], 0.5);
        assert_eq!((det.g[0], det.f[(0, 0)], det.f2[(0, 0)]), (-1.0, 0.5, 0.5));
    }

    #[test]
    fn the_test_fires_strictly_above_its_threshold_from_one_whole_window_on() {
        // g = 6 on R_R with no spread: T = 36.
        let fed = |age: f64, threshold: f64| {
            let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
            det.begin_step(age, &Matrix3::zeros());
            det.add(6.0, [1.0, 0.0, 0.0], 1.0);
            det.threshold = threshold;
            det.end_step(&Matrix3::zeros()).is_some()
        };
        assert!(fed(5.0, 35.9), "armed at exactly one window (5 s)");
        assert!(!fed(4.99, 35.9), "not before");
        assert!(!fed(5.0, 36.0), "T equal to the threshold does not fire");
    }

    #[test]
    fn the_pseudo_inverse_drops_directions_below_a_millionth_of_the_largest() {
        // diag(4, 1e-6, 2): 1e-6 is under 4e-6, dropped; the others inverted.
        let m = Matrix3::from_diagonal(&Vector3::new(4.0, 1e-6, 2.0));
        let want = Matrix3::from_diagonal(&Vector3::new(0.25, 0.0, 0.5));
        assert!((pinv(&m) - want).norm() < 1e-12, "{}", pinv(&m));
        // Kept just over the bound (2e-6 of 1.0 is over 1e-6 of it).
        let m = Matrix3::from_diagonal(&Vector3::new(1.0, 2e-6, 1.0));
        assert!((pinv(&m)[(1, 1)] - 5e5).abs() < 1e-3, "{}", pinv(&m));
        // Nothing to invert: zero, or not finite.
        assert_eq!(pinv(&Matrix3::zeros()), Matrix3::zeros());
        assert_eq!(pinv(&-Matrix3::identity()), Matrix3::zeros());
        let inf = Matrix3::from_diagonal(&Vector3::new(f64::INFINITY, 1.0, 1.0));
        assert_eq!(pinv(&inf), Matrix3::zeros());
        // gᵀ M⁺ g, and 0 when it is not finite.
        let g = Vector3::new(2.0, 3.0, 0.0);
        let m = Matrix3::from_diagonal(&Vector3::new(4.0, 1.0, 1.0));
        assert!((quad_pinv(&m, &g) - 10.0).abs() < 1e-12);
        assert_eq!(quad_pinv(&m, &Vector3::new(f64::NAN, 0.0, 0.0)), 0.0);
    }

    #[test]
    fn a_kalman_filter_s_firing_re_opens_its_covariance_by_the_spread() {
        let p = ChangeParams::default().detector(0.3);
        let mut k = KalmanChange::new(Some(&p)).expect("a detector");
        assert!(KalmanChange::new(None).is_none());
        // Nothing fed: no firing, the covariance untouched.
        let theta = Vector3::new(0.3, 0.3, 0.6);
        let mut cov = Matrix3::identity() * 1e-8;
        assert_eq!(k.end_step(&theta, &mut cov), None);
        assert_eq!(cov, Matrix3::identity() * 1e-8);
        // A measured V 0.1 m/s over the prediction (wheels 1 rad/s: V = R),
        // precision 1e4, after one window: T ≈ (100·1)²/… far over; the jump
        // is on the radii, each spread by its estimate (bounded by a tenth
        // of 0.3 m), D by its floor.
        let s = super::super::CalibStep::new(0.0, 5.0, 1.0, 1.0).with(
            super::super::steps::Kind::V,
            0.4,
            0.01,
        );
        k.observe(
            &s,
            &theta,
            &(Matrix3::identity() * 1e-8),
            1.0,
            (1e-4, f64::INFINITY),
            [0.0, 0.0],
        );
        let fired = k.end_step(&theta, &mut cov).expect("fires");
        assert_eq!(fired, Firing::Change);
        let grown = (0..3).map(|i| cov[(i, i)] - 1e-8).collect::<Vec<_>>();
        assert!(grown[0] > 1e-6 && grown[1] > 1e-6, "{grown:?}");
        assert!(
            (grown[2] - p.jump_sigma[2].powi(2)).abs() < 1e-15,
            "{grown:?}"
        );
        assert!(grown[0] <= 0.03f64.powi(2) + 1e-15);
    }

    #[test]
    fn a_firing_marks_the_estimate_as_a_change_or_a_re_spread() {
        let mut e =
            super::super::kalman::kalman_estimate(0.0, [0.3, 0.3, 0.6], [0.0; 3], [0.0; 2], 0.0);
        for (f, changed, respread) in [
            (Some(Firing::Change), true, false),
            (Some(Firing::Respread), false, true),
            (None, false, false),
        ] {
            Firing::mark(f, &mut e);
            assert_eq!((e.changed, e.respread), (changed, respread), "{f:?}");
        }
        let jump = |settled| Jump {
            statistic: 40.0,
            delta: [0.0; 3],
            settled,
        };
        assert_eq!(
            (Firing::of(&jump(true)), Firing::of(&jump(false))),
            (Firing::Change, Firing::Respread)
        );
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

    /// A belief converging on the truth as a filter's does from a wide
    /// start: the wheel base's mean 40 mm off, the error and its σ halving
    /// every half second, on a run that turns from the start. Each step's
    /// innovations are taken at that step's mean; `own` passes each step's
    /// covariance with them (as the filters do), otherwise the final, narrow
    /// one throughout. Returns the first firing: its step and whether it was
    /// a change.
    fn converging(own: bool) -> Option<(usize, bool)> {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(PAPER_RADIUS_M));
        let truth = Vector3::new(0.32, 0.32, 0.65);
        let (sv, sw) = (0.05f64, 0.01f64);
        let belief = |t: f64| {
            let e = 0.04 * 0.5f64.powf(t / 0.5);
            let sd = e.max(1e-4);
            let p = Matrix3::from_diagonal(&Vector3::new(1e-8, 1e-8, sd * sd));
            (truth + Vector3::new(0.0, 0.0, e), p)
        };
        let narrow = belief(20.0).1;
        for k in 0..1000 {
            let t = k as f64 * 0.02;
            let (wr, wl) = (2.5 + 0.8 * (0.3 * t).cos(), 2.5 - 0.8 * (0.3 * t).cos());
            let (m, p) = belief(t);
            let h = |q: &Vector3<f64>| {
                (
                    0.5 * (wr * q[0] + wl * q[1]),
                    (wr * q[0] - wl * q[1]) / q[2],
                )
            };
            let ((vt, wt), (vb, wb)) = (h(&truth), h(&m));
            let n: [f64; 2] = [
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ];
            det.begin_step(0.02, if own { &p } else { &narrow });
            det.add(
                vt + sv * n[0] - vb,
                [0.5 * wr, 0.5 * wl, 0.0],
                1.0 / (sv * sv),
            );
            det.add(
                wt + sw * n[1] - wb,
                [wr / m[2], -wl / m[2], -wb / m[2]],
                1.0 / (sw * sw),
            );
            if let Some(jump) = det.end_step(&belief(t + 0.02).1) {
                return Some((k, jump.settled));
            }
        }
        None
    }

    #[test]
    fn a_converging_belief_fires_as_a_respread_not_a_change() {
        // The window keeps innovations of means far off, which the narrowed
        // belief does not cover: the test fires as soon as it is armed
        // (5 s). Each read against the belief of its own step, the data
        // show no change: a re-spread.
        let (at, settled) = converging(true).expect("fires");
        assert!(
            (250..260).contains(&at) && !settled,
            "step {at}, settled {settled}"
        );
        // The negative control: the same innovations with the narrow belief
        // stated throughout are a change.
        let (at, settled) = converging(false).expect("fires");
        assert!(
            (250..260).contains(&at) && settled,
            "step {at}, settled {settled}"
        );
    }

    #[test]
    fn each_measurement_carries_the_spread_of_its_step() {
        // G = Σ λ^k J Jᵀ/S P^{1/2}: one measurement of J = (1, 0, 0) and
        // precision 4 against a belief of σ_R_R = 0.5, then one of J = (0,
        // 2, 0) and precision 1 against σ_R_L = 3 (no forgetting between).
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        det.begin_step(0.0, &Matrix3::from_diagonal(&Vector3::new(0.25, 9.0, 1.0)));
        det.add(0.2, [1.0, 0.0, 0.0], 4.0);
        det.begin_step(0.0, &Matrix3::from_diagonal(&Vector3::new(0.25, 9.0, 1.0)));
        det.add(-1.0, [0.0, 2.0, 0.0], 1.0);
        // g = (4·0.2, 2·(−1), 0); G = diag(4·0.5, 4·3, 0); F₂ = diag(4, 4, 0):
        // against each step's belief T = 0.64 / (4 + 4) + 4 / (4 + 144),
        // against a belief of no spread 0.64 / 4 + 4 / 4 = 1.16. With the
        // threshold between, a firing that is no change; below both, a
        // change.
        let t = 0.64 / 8.0 + 4.0 / 148.0;
        (det.age, det.threshold) = (10.0, 1.0);
        let mut again = det.clone();
        det.confirm = 1.01 * t;
        let jump = det.end_step(&Matrix3::zeros()).expect("fires");
        assert!(
            !jump.settled && (jump.statistic - 1.16).abs() < 1e-12,
            "{jump:?}"
        );
        let mut tie = again.clone();
        again.confirm = 0.99 * t;
        assert!(again.end_step(&Matrix3::zeros()).expect("fires").settled);
        // A second reading exactly at the confirmation is no change.
        tie.confirm = quad_pinv(&(tie.f2 + tie.g_root * tie.g_root.transpose()), &tie.g);
        assert!((tie.confirm - t).abs() < 1e-12);
        assert!(!tie.end_step(&Matrix3::zeros()).expect("fires").settled);
        // The default confirmation: the χ²₃ quantile of 1 − 10⁻³, 16.266.
        let d = ChangeParams::default().detector(1.0);
        assert!((d.confirm_threshold() - 16.266).abs() < 1e-3);
        assert_eq!(ChangeDetector::new(&d).confirm, d.confirm_threshold());
        // The square root of a rotated covariance: P = R diag(4, 1, 0) Rᵀ.
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.9).into_inner();
        let p = r * Matrix3::from_diagonal(&Vector3::new(4.0, 1.0, 0.0)) * r.transpose();
        let root = sqrt_psd(&p);
        assert!((root * root - p).norm() < 1e-12 && (root - root.transpose()).norm() < 1e-12);
        // (The zero eigenvalue comes out of the product as ±1e-16, whose
        // root is 1e-8.)
        let want = r * Matrix3::from_diagonal(&Vector3::new(2.0, 1.0, 0.0)) * r.transpose();
        assert!((root - want).norm() < 1e-7, "{root}");
        // Rounding below zero is zero; a covariance not finite reads as none.
        let tiny = Matrix3::from_diagonal(&Vector3::new(-1e-20, 1.0, 1.0));
        assert!(
            (sqrt_psd(&tiny) - Matrix3::from_diagonal(&Vector3::new(0.0, 1.0, 1.0))).norm() < 1e-12
        );
        let mut bad = Matrix3::identity();
        bad[(0, 1)] = f64::NAN;
        assert_eq!(sqrt_psd(&bad), Matrix3::zeros());
        // A firing empties the window, the spreads with it.
        let mut det = ChangeDetector::new(&ChangeParams::default().detector(1.0));
        det.begin_step(10.0, &Matrix3::identity());
        det.add(100.0, [1.0, 0.0, 0.0], 1.0);
        assert!(det.end_step(&Matrix3::zeros()).is_some());
        assert_eq!(
            (det.g, det.f, det.f2, det.g_root),
            (
                Vector3::zeros(),
                Matrix3::zeros(),
                Matrix3::zeros(),
                Matrix3::zeros()
            )
        );
    }
}

/// What a firing of the detector was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Firing {
    /// The data contradict a belief settled over the window: a change.
    Change,
    /// The data contradict a belief still narrowing: the filter re-spreads,
    /// no change is reported.
    Respread,
}

impl Firing {
    /// The firing `jump` is.
    pub(crate) fn of(jump: &Jump) -> Self {
        if jump.settled {
            Self::Change
        } else {
            Self::Respread
        }
    }

    /// Marks the step's estimate `e` with the firing `f`, if any.
    pub(crate) fn mark(f: Option<Self>, e: &mut super::Estimate) {
        e.changed = f == Some(Self::Change);
        e.respread = f == Some(Self::Respread);
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
        self.det.observe(s.dt(), p, &fused, &pred, [jv, jw]);
    }

    /// After the update: tests against the posterior covariance `p` and, on
    /// a firing, adds the jump's spread² to its diagonal. Returns the
    /// firing, if any: whether it is a change ([`Jump::settled`]).
    pub(crate) fn end_step(
        &mut self,
        theta: &Vector3<f64>,
        p: &mut Matrix3<f64>,
    ) -> Option<Firing> {
        let jump = self.det.end_step(p)?;
        let s = jump.spread(&self.floor, &[theta[0], theta[1], theta[2]]);
        for k in 0..3 {
            p[(k, k)] += s[k] * s[k];
        }
        Some(Firing::of(&jump))
    }
}
