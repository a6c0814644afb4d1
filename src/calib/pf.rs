//! The particle-filter calibrator [Farina, Sec. III], optionally with the
//! Adaptive-PF rules of section V and a change detector. Particles are stored
//! as a structure of arrays; one step is a fused predict-and-reweight pass,
//! two normalise-and-summarise passes (register-sized, so they stay
//! vectorised) and, when triggered, one pass that resamples and moves into a
//! spare set swapped in afterwards. A step allocates nothing once the buffers
//! have grown.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

use super::adaptive::{occupied_bins, AdaptiveParams, CountRule};
use super::change::ChangeDetector;
use super::kernels::{self, MIN_LENGTH};
use super::params::{PfSettings, Ranges};
use super::pool::NormalPool;
use super::resample::{Resampler, Scheme};
use super::steps::CalibStep;
use super::trigger::Trigger;
use super::weights::Weights;
use super::{Calibrator, Estimate};
use nalgebra::Matrix3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// The particle set: χ = [V, W, R_R, R_L, D] per particle (eq. 1).
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Forward velocities V (m/s) of the last prediction (not carried
    /// through a resampling: the next prediction recomputes them).
    pub v: Vec<f64>,
    /// Turn rates W (rad/s) of the last prediction (same caveat as `v`).
    pub w: Vec<f64>,
    /// Right wheel radii R_R (m).
    pub rr: Vec<f64>,
    /// Left wheel radii R_L (m).
    pub rl: Vec<f64>,
    /// Wheel bases D (m).
    pub d: Vec<f64>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.rr.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.rr.is_empty()
    }

    fn resize(&mut self, n: usize) {
        for c in [
            &mut self.v,
            &mut self.w,
            &mut self.rr,
            &mut self.rl,
            &mut self.d,
        ] {
            c.resize(n, 0.0);
        }
    }
}

/// Weighted mean and covariance of the parameters (R_R, R_L, D) (m, m²).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Belief {
    mean: [f64; 3],
    cov: Matrix3<f64>,
}

/// The step's measurements reduced to one Gaussian term per velocity:
/// `−k_v (V − z_v)² − k_w (W − z_w)²` (constants dropped).
#[derive(Debug, Clone, Copy, Default)]
struct Update {
    kv: f64,
    zv: f64,
    kw: f64,
    zw: f64,
}

/// Particle-filter calibrator: `pf` (fixed count and noise) or `adaptive-pf`.
#[derive(Debug, Clone)]
pub struct ParticleFilter {
    p: Particles,
    spare: Particles,
    weights: Weights,
    resampler: Resampler,
    ancestors: Vec<usize>,
    keys: Vec<u64>,
    rng: Xoshiro256PlusPlus,
    pool: NormalPool,
    sigma: f64,
    scheme: Scheme,
    trigger: Trigger,
    neff_ratio: f64,
    max_weight_factor: f64,
    jitter: f64,
    floor: f64,
    model_var: [f64; 2],
    shrink: f64,
    robust_dof: f64,
    observability_turn_rate: f64,
    ema: Option<[f64; 2]>,
    belief: Belief,
    adaptive: Option<AdaptiveParams>,
    change: Option<ChangeDetector>,
    jump_sigma: [f64; 3],
    initial: usize,
    jumps: usize,
    per_step: bool,
    name: &'static str,
}

impl ParticleFilter {
    /// A filter with particles drawn uniformly in `p.ranges`, V = W = 0:
    /// the Adaptive-PF's rules and change detector when `p` holds them,
    /// else a fixed count and σ.
    pub fn new(p: &PfSettings) -> Self {
        let n = p.particles;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(p.seed);
        let Ranges {
            r_right,
            r_left,
            wheel_base,
        } = p.ranges.clone();
        let mut draw = |[lo, hi]: [f64; 2]| -> Vec<f64> {
            (0..n)
                .map(|_| lo + (hi - lo) * rng.random::<f64>())
                .collect()
        };
        let rr = draw(r_right);
        let rl = draw(r_left);
        let d = draw(wheel_base);
        let var = |[lo, hi]: [f64; 2]| (hi - lo) * (hi - lo) / 12.0;
        let mid = |[lo, hi]: [f64; 2]| 0.5 * (lo + hi);
        let belief = Belief {
            mean: [mid(r_right), mid(r_left), mid(wheel_base)],
            cov: Matrix3::from_diagonal(&nalgebra::Vector3::new(
                var(r_right),
                var(r_left),
                var(wheel_base),
            )),
        };
        let noise = &p.noise;
        Self {
            p: Particles {
                v: vec![0.0; n],
                w: vec![0.0; n],
                rr,
                rl,
                d,
            },
            spare: Particles::default(),
            weights: Weights::uniform(n),
            resampler: Resampler::new(),
            ancestors: Vec::with_capacity(n),
            keys: Vec::new(),
            rng,
            pool: NormalPool::new(),
            sigma: noise.param_sigma,
            scheme: p.resampler,
            trigger: p.trigger,
            neff_ratio: p.neff_ratio,
            max_weight_factor: p.max_weight_factor,
            jitter: noise.velocity_jitter,
            floor: noise.sigma_floor,
            model_var: [noise.model_sigma_v.powi(2), noise.model_sigma_w.powi(2)],
            shrink: noise.kernel_shrink,
            robust_dof: noise.robust_dof,
            observability_turn_rate: noise.observability_turn_rate,
            ema: None,
            belief,
            adaptive: p.adaptive.clone(),
            change: p.detector.as_ref().map(ChangeDetector::new),
            jump_sigma: p.detector.map_or([0.0; 3], |d| d.jump_sigma),
            initial: n,
            jumps: 0,
            per_step: p.per_step,
            name: if p.adaptive_pf { "adaptive-pf" } else { "pf" },
        }
    }

    /// The particle set (for plots of the (R_R, R_L) cloud).
    pub fn particles(&self) -> &Particles {
        &self.p
    }

    /// The current weights.
    pub fn weights(&self) -> &Weights {
        &self.weights
    }

    /// The change detector's statistic after the last step (χ²₃ when nothing
    /// changed); 0 without a detector.
    pub fn change_statistic(&self) -> f64 {
        self.change.as_ref().map_or(0.0, |c| c.statistic())
    }

    /// How often the change detector has fired so far.
    pub fn jumps(&self) -> usize {
        self.jumps
    }

    /// Reduces the step's usable measurements to one term per velocity.
    /// The measurements of one velocity (ICP's W and the gyro's W) are fused
    /// first, each with its own σ (floored) scaled by its Student-t weight
    /// against the prior prediction (whose variance includes the parameter
    /// spread and the model's); the velocity model's variance is then added
    /// once to the fused measurement: the model's error (encoder
    /// quantisation, slip) is one error shared by every measurement of that
    /// velocity, not one per measurement, which would count it as
    /// independent evidence twice. The fused innovations also feed the
    /// change detector. Returns the update and the turn rate that decides
    /// D's observability.
    fn measurements(&mut self, s: &CalibStep) -> (Update, f64) {
        let (wr, wl) = (s.omega_right, s.omega_left);
        let Belief { mean: m, cov } = self.belief;
        let theta = nalgebra::Vector3::new(m[0], m[1], m[2]);
        let ([v_hat, w_hat], [jv, jw]) = super::kalman::model(&theta, wr, wl);
        let w_seen = super::kalman::turn_rate_for_observability(s, self.floor, w_hat);
        let obs = super::kalman::observability(w_seen, self.observability_turn_rate);
        // W as the predict pass models it (D's entry scaled by `obs`).
        let jw = super::kalman::turn_jacobian(&theta, &jw, w_hat, obs);
        let pred = super::fuse::Prediction {
            value: [v_hat, w_hat],
            var: [jv.dot(&(cov * jv)).max(0.0), jw.dot(&(cov * jw)).max(0.0)],
            model_var: super::kalman::model_var_at(self.model_var, s.dt()),
        };
        let fused = super::fuse::fuse(s, &pred, self.floor, self.robust_dof);
        let mut u = Update::default();
        for (k, f) in fused.iter().enumerate() {
            let Some(f) = f else { continue };
            let prec = 1.0 / (f.var + pred.model_var[k]);
            if k == 0 {
                (u.kv, u.zv) = (0.5 * prec, f.value);
            } else {
                (u.kw, u.zw) = (0.5 * prec, f.value);
            }
        }
        if let Some(det) = &mut self.change {
            det.observe(s.dt(), &cov, &fused, &pred, [jv, jw]);
        }
        (u, w_seen)
    }

    /// Predict (eq. 2–3) and update (eq. 4) in one pass: random walk on the
    /// parameters (D's scaled by its observability), V and W from the wheel
    /// rates, the measurements' log-likelihood. Returns the prior
    /// weighted-mean velocities (V_O, W_O) and the largest log-weight.
    fn predict_and_weigh(&mut self, s: &CalibStep, u: Update, w_turn: f64) -> (f64, f64, f64) {
        let (wr, wl) = (s.omega_right, s.omega_left);
        let n = self.p.len();
        let obs = super::kalman::observability(w_turn, self.observability_turn_rate);
        // The random walk per √s (per step under the paper's preset).
        let k = if self.per_step {
            1.0
        } else {
            s.dt().max(0.0).sqrt()
        };
        let (sr, sd) = (self.sigma * k, self.sigma * k * obs);
        let [o1, o2, o3] = self.pool.offsets::<3, _>(n, &mut self.rng);
        let pool = self.pool.data();
        let e = [&pool[o1..o1 + n], &pool[o2..o2 + n], &pool[o3..o3 + n]];
        let (lw, rho) = self.weights.parts_mut();
        let Particles { v, w, rr, rl, d } = &mut self.p;
        // With velocity jitter the likelihood is added after it (below).
        let (kv, kw) = if self.jitter > 0.0 {
            (0.0, 0.0)
        } else {
            (u.kv, u.kw)
        };
        let out = kernels::predict(kernels::Predict {
            rr,
            rl,
            d,
            v,
            w,
            lw,
            rho,
            e,
            wr,
            wl,
            sr,
            sd,
            obs,
            ratio: self.belief.mean[2]
                / (self.belief.mean[0] + self.belief.mean[1]).max(MIN_LENGTH),
            kv,
            zv: u.zv,
            kw,
            zw: u.zw,
        });
        let mut mx = out.max;
        if self.jitter > 0.0 {
            // The uniform jitter on V and W of [Farina] (off by default), applied
            // before the likelihood, which the loop above then left out.
            let j = self.jitter;
            let (lw, _) = self.weights.parts_mut();
            let Particles { v, w, .. } = &mut self.p;
            let (zv, zw) = (u.zv, u.zw);
            mx = f64::NEG_INFINITY;
            for i in 0..n {
                v[i] += j * (2.0 * self.rng.random::<f64>() - 1.0);
                w[i] += j * (2.0 * self.rng.random::<f64>() - 1.0);
                let (ev, ew) = (v[i] - zv, w[i] - zw);
                lw[i] -= u.kv * ev * ev + u.kw * ew * ew;
                mx = mx.max(lw[i]);
            }
        }
        (out.vo, out.wo, mx)
    }

    /// Normalises the weights (log-sum-exp with the maximum `mx`) and, in the
    /// same two passes, accumulates the weighted means of every column and the
    /// covariance of the parameters. Returns the estimate at time `t`.
    fn normalize_and_summarize(&mut self, mx: f64, t: f64) -> Estimate {
        let n = self.p.len();
        let reset = !(mx > f64::NEG_INFINITY) || !mx.is_finite();
        if reset {
            self.weights.reset_after_underflow();
        }
        let r = self.belief.mean;
        let (lw, buf) = self.weights.parts_mut();
        buf.resize(n, 0.0);
        let Particles { v, w, rr, rl, d } = &self.p;
        let kernels::Sums {
            sum,
            sq,
            max: emax,
            s1,
            s2,
        } = kernels::summarize(kernels::Summarize {
            rr,
            rl,
            d,
            v,
            w,
            lw,
            buf,
            shift: if reset { 0.0 } else { mx },
            uniform: reset,
            r,
        });
        self.weights.finish(sum, sq, emax, reset);
        let m = s1;
        let c = |k: usize, x: usize, y: usize| s2[k] - m[x] * m[y];
        let cov = Matrix3::new(
            c(0, 0, 0),
            c(1, 0, 1),
            c(2, 0, 2),
            c(1, 0, 1),
            c(3, 1, 1),
            c(4, 1, 2),
            c(2, 0, 2),
            c(4, 1, 2),
            c(5, 2, 2),
        );
        self.belief = Belief {
            mean: [r[0] + m[0], r[1] + m[1], r[2] + m[2]],
            cov,
        };
        let sd = |k: usize| cov[(k, k)].max(0.0).sqrt();
        Estimate {
            t,
            r_right: self.belief.mean[0],
            r_left: self.belief.mean[1],
            wheel_base: self.belief.mean[2],
            std_r_right: sd(0),
            std_r_left: sd(1),
            std_wheel_base: sd(2),
            v: m[3],
            w: m[4],
            particles: n,
            process_sigma: self.sigma,
            resampled: false,
            weights_reset: reset,
            changed: false,
            respread: false,
        }
    }

    /// The particle count the next resampling draws.
    fn target_count(&mut self, est: &Estimate) -> usize {
        let n = self.p.len();
        let Some(a) = &self.adaptive else {
            return n;
        };
        match a.rule {
            CountRule::Fixed => n,
            CountRule::Dispersion => a.dispersion_count(est.std_r_right, est.std_r_left),
            CountRule::Kld => {
                self.resampler.resample(
                    Scheme::Systematic,
                    self.weights.normalized(),
                    n,
                    &mut self.rng,
                    &mut self.ancestors,
                );
                let k = occupied_bins(
                    &self.ancestors,
                    &self.p.rr,
                    &self.p.rl,
                    &self.p.d,
                    a.kld_bin,
                    &mut self.keys,
                );
                a.kld_count(k)
            }
        }
    }

    /// Resamples `n_new` particles and moves their parameters in the same
    /// pass: with `spread` (a detected change) by independent Gaussian
    /// jitter of those σ (m); otherwise by the Liu–West kernel \[LiuWest2001\] (see
    /// `NoiseParams::kernel_shrink`) around the pre-resampling belief, whose
    /// mean and covariance it preserves.
    fn resample(&mut self, n_new: usize, spread: Option<[f64; 3]>) {
        self.resampler.resample(
            self.scheme,
            self.weights.normalized(),
            n_new,
            &mut self.rng,
            &mut self.ancestors,
        );
        let n = self.ancestors.len();
        self.spare.resize(n);
        let (a, m) = match spread {
            Some(_) => (1.0, [0.0; 3]),
            None => (self.shrink, self.belief.mean),
        };
        let l = match spread {
            Some(s) => [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]],
            None => cholesky(&self.belief.cov),
        };
        let h = if spread.is_some() {
            1.0
        } else {
            (1.0 - a * a).sqrt()
        };
        let moving = a < 1.0 || spread.is_some();
        let [o1, o2, o3] = self.pool.offsets::<3, _>(n, &mut self.rng);
        let pool = self.pool.data();
        let (e1, e2, e3) = (&pool[o1..o1 + n], &pool[o2..o2 + n], &pool[o3..o3 + n]);
        // Gather and move in one pass (ancestors ascend: sequential reads).
        // V and W are not carried over: the next prediction overwrites them.
        let anc = &self.ancestors[..n];
        let (src, dst) = (&self.p, &mut self.spare);
        let (srr, srl, sd) = (&src.rr[..], &src.rl[..], &src.d[..]);
        let (rr, rl, d) = (&mut dst.rr[..n], &mut dst.rl[..n], &mut dst.d[..n]);
        let (e1, e2, e3) = (&e1[..n], &e2[..n], &e3[..n]);
        if moving {
            let c = [(1.0 - a) * m[0], (1.0 - a) * m[1], (1.0 - a) * m[2]];
            let l = [
                h * l[0][0],
                h * l[1][0],
                h * l[1][1],
                h * l[2][0],
                h * l[2][1],
                h * l[2][2],
            ];
            kernels::gather_move(kernels::GatherMove {
                anc,
                src: [srr, srl, sd],
                dst: [rr, rl, d],
                e: [e1, e2, e3],
                a,
                c,
                l,
            });
        } else {
            for k in 0..n {
                let i = anc[k];
                rr[k] = srr[i];
                rl[k] = srl[i];
                d[k] = sd[i];
            }
        }
        std::mem::swap(&mut self.p, &mut self.spare);
        self.weights.reset_uniform(n);
    }
}

/// Lower Cholesky factor of a 3×3 covariance (nalgebra's); a covariance that
/// is not positive definite falls back to the square roots of its diagonal.
fn cholesky(c: &Matrix3<f64>) -> [[f64; 3]; 3] {
    match c.cholesky() {
        Some(ch) => {
            let l = ch.l();
            [
                [l[(0, 0)], 0.0, 0.0],
                [l[(1, 0)], l[(1, 1)], 0.0],
                [l[(2, 0)], l[(2, 1)], l[(2, 2)]],
            ]
        }
        None => {
            let mut d = [[0.0; 3]; 3];
            for i in 0..3 {
                d[i][i] = c[(i, i)].max(0.0).sqrt();
            }
            d
        }
    }
}

impl Calibrator for ParticleFilter {
    fn cloud(&self) -> Option<super::CloudView<'_>> {
        let p = self.particles();
        let w = self.weights().normalized();
        (p.rr.len() == w.len() && p.rl.len() == w.len()).then_some(super::CloudView {
            r_right: &p.rr,
            r_left: &p.rl,
            weights: w,
        })
    }

    fn step(&mut self, s: &CalibStep) -> Estimate {
        let (u, w_hat) = self.measurements(s);
        let (vo, wo, mx) = self.predict_and_weigh(s, u, w_hat);
        let mut est = self.normalize_and_summarize(mx, s.t1);
        if let Some(a) = &self.adaptive {
            if let Some(e) = a.residuals(s, vo, wo, self.floor) {
                a.average(&mut self.ema, e, s.dt());
                self.sigma = a.sigma_of(self.ema.unwrap_or(e));
            }
        }
        let cov = self.belief.cov;
        if let Some(jump) = self.change.as_mut().and_then(|c| c.end_step(&cov)) {
            // A change: keep what the weights say, then re-inflate the spread
            // and the count so the cloud can find the new parameters.
            let spread = jump.spread(&self.jump_sigma, &self.belief.mean);
            let n_new = self.initial.max(self.p.len());
            self.resample(n_new, Some(spread));
            self.jumps += 1;
            est.resampled = true;
            super::change::Firing::mark(Some(super::change::Firing::of(&jump)), &mut est);
        } else if self
            .trigger
            .fires(&self.weights, self.neff_ratio, self.max_weight_factor)
        {
            let n_new = self.target_count(&est);
            self.resample(n_new, None);
            est.resampled = true;
        }
        est.process_sigma = self.sigma;
        est
    }

    fn name(&self) -> &'static str {
        self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::change::DetectorParams;
    use crate::calib::params::NoiseParams;
    use crate::calib::steps::Kind;
    use rand_distr::{Distribution, StandardNormal};

    /// The settings of a plain filter of `n` particles drawn in the
    /// default ranges: no process noise, no model σ, Gaussian likelihood,
    /// no observability scaling, no Liu–West move, no resampling.
    fn plain(n: usize) -> PfSettings {
        PfSettings {
            adaptive_pf: false,
            particles: n,
            seed: 1,
            resampler: Scheme::Systematic,
            trigger: Trigger::Neff,
            neff_ratio: 1e-9,
            max_weight_factor: 2.0,
            noise: NoiseParams {
                param_sigma: 0.0,
                model_sigma_v: 0.0,
                model_sigma_w: 0.0,
                robust_dof: 0.0,
                observability_turn_rate: 0.0,
                kernel_shrink: 1.0,
                sigma_floor: 1e-9,
                ..NoiseParams::default()
            },
            adaptive: None,
            detector: None,
            per_step: false,
            ranges: Ranges::default(),
        }
    }

    /// A plain filter of three particles placed by hand.
    fn three(rr: [f64; 3], rl: [f64; 3], d: [f64; 3]) -> ParticleFilter {
        let mut f = ParticleFilter::new(&plain(3));
        f.p.rr = rr.to_vec();
        f.p.rl = rl.to_vec();
        f.p.d = d.to_vec();
        f
    }

    #[test]
    fn one_step_weighs_each_particle_by_its_predicted_velocities() {
        // Wheels at 2.0 (right) and 1.0 (left) rad/s. Particle k predicts
        // V = (2 R_R + R_L)/2 and W = (2 R_R − R_L)/D:
        //   0: R 0.30/0.30, D 0.60 → V 0.450, W 0.500
        //   1: R 0.32/0.30, D 0.60 → V 0.470, W 0.5666…
        //   2: R 0.30/0.30, D 0.50 → V 0.450, W 0.600
        let mut f = three([0.30, 0.32, 0.30], [0.30, 0.30, 0.30], [0.60, 0.60, 0.50]);
        let step = CalibStep::new(0.0, 0.1, 2.0, 1.0)
            .with(Kind::V, 0.47, 0.01)
            .with(Kind::W, 0.55, 0.05);
        let e = f.step(&step);
        // Log-likelihoods −(V − 0.47)²/(2·0.01²) − (W − 0.55)²/(2·0.05²):
        let ll = |v: f64, w: f64| -(v - 0.47f64).powi(2) / 2e-4 - (w - 0.55f64).powi(2) / 5e-3;
        let l = [ll(0.45, 0.5), ll(0.47, 0.34 / 0.6), ll(0.45, 0.6)];
        let m = l.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = l.iter().map(|x| (x - m).exp()).sum();
        let w: Vec<f64> = l.iter().map(|x| (x - m).exp() / z).collect();
        let got = f.weights().normalized();
        for k in 0..3 {
            assert!((got[k] - w[k]).abs() < 1e-12, "{k}: {} vs {}", got[k], w[k]);
        }
        // The estimate is the weighted mean and its spread, not the best
        // particle (particle 1 carries most of the weight, not all).
        let mean = |x: [f64; 3]| (0..3).map(|k| w[k] * x[k]).sum::<f64>();
        let rr = mean([0.30, 0.32, 0.30]);
        let d = mean([0.60, 0.60, 0.50]);
        assert!((e.r_right - rr).abs() < 1e-12 && (e.wheel_base - d).abs() < 1e-12);
        let var = (0..3)
            .map(|k| w[k] * ([0.30, 0.32, 0.30][k] - rr).powi(2))
            .sum::<f64>();
        assert!((e.std_r_right - var.sqrt()).abs() < 1e-12);
        // exp(−0.056) / (exp(−0.056) + 2 exp(−2.5)) = 0.852.
        assert!((w[1] - 0.852).abs() < 1e-3, "{w:?}");
        // V and W of the estimate: the weighted means of the predictions.
        let v = mean([0.45, 0.47, 0.45]);
        assert!((e.v - v).abs() < 1e-12);
    }

    #[test]
    fn a_step_without_measurements_keeps_the_weights() {
        let mut f = three([0.30, 0.32, 0.31], [0.30, 0.30, 0.30], [0.60, 0.60, 0.60]);
        f.step(&CalibStep::new(0.0, 0.1, 2.0, 1.0));
        let w = f.weights().normalized();
        assert!(w.iter().all(|x| (x - 1.0 / 3.0).abs() < 1e-15), "{w:?}");
    }

    #[test]
    fn a_measurement_with_infinite_sigma_is_ignored() {
        let mut f = three([0.30, 0.32, 0.31], [0.30, 0.30, 0.30], [0.60, 0.60, 0.60]);
        f.step(&CalibStep::new(0.0, 0.1, 2.0, 1.0).with(Kind::V, 0.9, f64::INFINITY));
        let w = f.weights().normalized();
        assert!(w.iter().all(|x| (x - 1.0 / 3.0).abs() < 1e-15), "{w:?}");
    }

    #[test]
    fn the_cholesky_factor_rebuilds_the_covariance_and_falls_back_to_the_diagonal() {
        let c = Matrix3::new(4e-6, 1e-6, 0.0, 1e-6, 9e-6, 2e-6, 0.0, 2e-6, 16e-6);
        let l = cholesky(&c);
        for r in 0..3 {
            for k in 0..3 {
                let s: f64 = (0..3).map(|j| l[r][j] * l[k][j]).sum();
                assert!((s - c[(r, k)]).abs() < 1e-18, "{r}{k}");
            }
        }
        // Not positive definite: the square roots of the diagonal.
        let bad = Matrix3::new(1e-6, 2e-6, 0.0, 2e-6, 1e-6, 0.0, 0.0, 0.0, 4e-6);
        let d = cholesky(&bad);
        assert_eq!(d, [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 2e-3]]);
    }

    /// `n` particles drawn in the default ranges, resampled at every step
    /// with the Liu–West shrink `a`.
    fn resampling(n: usize, a: f64) -> ParticleFilter {
        let mut s = plain(n);
        s.trigger = Trigger::Every;
        s.noise.kernel_shrink = a;
        ParticleFilter::new(&s)
    }

    /// Mean and (population) standard deviation.
    fn mean_std(x: &[f64]) -> (f64, f64) {
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        let v = x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / n;
        (m, v.sqrt())
    }

    #[test]
    fn the_velocity_model_s_variance_adds_to_the_measurement_s_once() {
        // V measured at 0.47 ± 0.01 m/s, the model's σ_V 0.02 m/s per 0.02 s
        // step: over a step of 0.02 s the likelihood's variance is
        // 1e-4 + 4e-4; over 0.1 s the model's is (0.02/0.1)² of that,
        // 1.6e-5, and the variance 1.16e-4.
        for (dt, var) in [(0.02, 5e-4), (0.1, 1.16e-4)] {
            let mut f = three([0.30, 0.32, 0.30], [0.30, 0.30, 0.30], [0.60, 0.60, 0.50]);
            f.model_var = [4e-4, 0.0];
            f.step(&CalibStep::new(0.0, dt, 2.0, 1.0).with(Kind::V, 0.47, 0.01));
            let ll = |v: f64| -(v - 0.47f64).powi(2) / (2.0 * var);
            let l = [ll(0.45), ll(0.47), ll(0.45)];
            let z: f64 = l.iter().map(|x| x.exp()).sum();
            let got = f.weights().normalized();
            for k in 0..3 {
                let w = l[k].exp() / z;
                assert!(
                    (got[k] - w).abs() < 1e-12,
                    "dt {dt}, {k}: {} vs {w}",
                    got[k]
                );
            }
        }
    }

    #[test]
    fn the_random_walk_grows_per_root_second_and_the_wheel_base_s_by_its_observability() {
        // Every particle at R 0.30 / 0.30, D 0.60; σ 1e-3 per √s; wheels at
        // 2 and 1 rad/s turn the robot at (0.6 − 0.3)/0.6 = 0.5 rad/s, half
        // the 1 rad/s at which D counts as observed. Over 0.25 s the radii
        // spread by 1e-3 · 0.5 and D by half that; per step (the paper's),
        // by 1e-3 and 0.5e-3.
        for (per_step, sr) in [(false, 5e-4), (true, 1e-3)] {
            let n = 20_000;
            let mut f = ParticleFilter::new(&plain(n));
            f.per_step = per_step;
            f.sigma = 1e-3;
            f.observability_turn_rate = 1.0;
            f.p.rr = vec![0.3; n];
            f.p.rl = vec![0.3; n];
            f.p.d = vec![0.6; n];
            f.belief.mean = [0.3, 0.3, 0.6];
            let e = f.step(&CalibStep::new(0.0, 0.25, 2.0, 1.0));
            assert!(!e.resampled);
            let (_, s_rr) = mean_std(&f.particles().rr);
            let (_, s_rl) = mean_std(&f.particles().rl);
            let (_, s_d) = mean_std(&f.particles().d);
            for (got, want) in [(s_rr, sr), (s_rl, sr), (s_d, 0.5 * sr)] {
                assert!(
                    (got / want - 1.0).abs() < 0.03,
                    "per step {per_step}: {got} against {want}"
                );
            }
            assert!((e.std_r_right / sr - 1.0).abs() < 0.03);
        }
        // D half observed also in the predicted W: with the belief at R
        // 0.30 / 0.30, D 0.50 the wheels turn it at (0.6 − 0.3)/0.5 =
        // 0.6 rad/s, observability 0.6, and each particle's W uses the
        // wheel base 0.6 D + 0.4 · (0.5/0.6) (R_R + R_L).
        let mut f = three([0.30, 0.32, 0.30], [0.30, 0.30, 0.30], [0.60, 0.60, 0.50]);
        f.observability_turn_rate = 1.0;
        f.belief.mean = [0.3, 0.3, 0.5];
        f.step(&CalibStep::new(0.0, 0.1, 2.0, 1.0));
        let want = [0.3 / 0.56, 0.34 / (0.36 + 0.4 / 1.2 * 0.62), 0.3 / 0.5];
        for k in 0..3 {
            let got = f.particles().w[k];
            assert!(
                (got - want[k]).abs() < 1e-12,
                "{k}: W {got} against {}",
                want[k]
            );
        }
    }

    #[test]
    fn liu_west_resampling_keeps_the_belief_s_mean_and_spread() {
        // A measured step weighs the cloud; the resampled and moved cloud
        // (shrink 0.9: each particle drawn to 0.9 of its ancestor's offset
        // from the mean, plus a Gaussian of √(1 − 0.81) of the belief's
        // covariance) has the weighted belief's mean and std again, now
        // with equal weights. Without the move (shrink 1) every particle
        // is a copy of an ancestor.
        let step = CalibStep::new(0.0, 0.1, 2.0, 1.0)
            .with(Kind::V, 0.47, 0.005)
            .with(Kind::W, 0.52, 0.05);
        let n = 20_000;
        let mut f = resampling(n, 0.9);
        let e = f.step(&step);
        assert!(e.resampled && f.particles().len() == n && !f.particles().is_empty());
        let w = f.weights().normalized();
        assert!(w.iter().all(|x| (x - 1.0 / n as f64).abs() < 1e-15));
        for (x, m, sd) in [
            (&f.particles().rr, e.r_right, e.std_r_right),
            (&f.particles().rl, e.r_left, e.std_r_left),
            (&f.particles().d, e.wheel_base, e.std_wheel_base),
        ] {
            let (gm, gs) = mean_std(x);
            assert!(
                (gm - m).abs() < 0.05 * sd,
                "mean {gm} against {m} (std {sd})"
            );
            assert!((gs / sd - 1.0).abs() < 0.04, "std {gs} against {sd}");
        }
        // Moved, no two particles share a value (resampling alone repeats
        // about a third of them and more).
        let mut rr = f.particles().rr.clone();
        rr.sort_by(f64::total_cmp);
        rr.dedup();
        assert_eq!(rr.len(), n);
        // The prior's spread of R_R is (0.335 − 0.305)/√12 = 8.7 mm; the
        // measurement narrowed it.
        assert!(e.std_r_right < 0.8 * 0.03 / 12f64.sqrt());
        let mut g = resampling(n, 1.0);
        let before = g.particles().rr.clone();
        g.step(&step);
        assert!(g.particles().rr.iter().all(|x| before.contains(x)));
        let mut copies = g.particles().rr.clone();
        copies.sort_by(f64::total_cmp);
        copies.dedup();
        assert!(copies.len() < n * 2 / 3, "{} distinct", copies.len());
        assert_eq!(g.particles().len(), n);
    }

    #[test]
    fn the_change_detector_fires_after_a_step_of_the_radii_and_not_before() {
        // A cloud within 0.3 % of R 0.30 / 0.30, D 0.60, 400 steps of 0.1 s
        // measured there, then the right radius 3 % larger: the detector
        // (the default settings) stays quiet on the first, fires on the
        // second; with none configured, nothing fires.
        let detector = crate::calib::change::ChangeParams::default().detector(0.3);
        let run = |det: Option<DetectorParams>| {
            let mut s = plain(2000);
            s.neff_ratio = 0.5;
            s.noise.kernel_shrink = 0.95;
            s.noise.param_sigma = 1e-5;
            s.detector = det;
            s.ranges = Ranges {
                r_right: [0.299, 0.301],
                r_left: [0.299, 0.301],
                wheel_base: [0.598, 0.602],
            };
            let mut f = ParticleFilter::new(&s);
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
            let mut fired_at = Vec::new();
            let mut quiet = 0.0f64;
            for k in 0..800 {
                let t = 0.1 * k as f64;
                let rr = if k < 400 { 0.30 } else { 0.309 };
                let (wr, wl) = (2.0 + (0.3 * t).sin(), 2.0 + (0.5 * t).cos());
                let v = 0.5 * (rr * wr + 0.3 * wl);
                let w = (rr * wr - 0.3 * wl) / 0.6;
                let e1: f64 = StandardNormal.sample(&mut rng);
                let e2: f64 = StandardNormal.sample(&mut rng);
                let e = f.step(
                    &CalibStep::new(t, t + 0.1, wr, wl)
                        .with(Kind::V, v + 0.002 * e1, 0.002)
                        .with(Kind::W, w + 0.005 * e2, 0.005),
                );
                if e.changed {
                    fired_at.push(k);
                }
                if k == 399 {
                    quiet = f.change_statistic();
                }
            }
            (fired_at, f.jumps(), quiet)
        };
        let (fired, jumps, quiet) = run(Some(detector));
        assert!(fired.iter().all(|&k| k >= 400), "fired at {fired:?}");
        assert!(!fired.is_empty() && fired[0] < 450, "fired at {fired:?}");
        assert_eq!(jumps, fired.len());
        assert!(quiet > 0.0 && quiet < detector.threshold(), "{quiet}");
        let (none, jumps, statistic) = run(None);
        assert!(none.is_empty() && jumps == 0 && statistic == 0.0);
    }

    #[test]
    fn farina_s_velocity_jitter_moves_v_and_w_before_they_are_weighed() {
        // Every particle predicts V 0.45 m/s and W 0.5 rad/s (R 0.30 / 0.30,
        // D 0.60, wheels at 2 and 1 rad/s); a jitter of 0.1 spreads them
        // uniformly over ±0.1 (std 0.1/√3), and each weight is then the
        // likelihood of its own jittered V and W.
        // Every other particle has R_R 0.31 m and predicts V 0.46 m/s and
        // W 0.5333 rad/s: its weight too is the likelihood of its own
        // jittered V and W, not of its prediction.
        let n = 20_000;
        let mut f = ParticleFilter::new(&plain(n));
        f.jitter = 0.1;
        f.p.rr = (0..n)
            .map(|k| if k % 2 == 0 { 0.30 } else { 0.31 })
            .collect();
        f.p.rl = vec![0.3; n];
        f.p.d = vec![0.6; n];
        f.step(
            &CalibStep::new(0.0, 0.1, 2.0, 1.0)
                .with(Kind::V, 0.46, 0.05)
                .with(Kind::W, 0.52, 0.1),
        );
        let (v, w) = (&f.particles().v, &f.particles().w);
        let pv = |k: usize| if k % 2 == 0 { 0.45 } else { 0.46 };
        let pw = |k: usize| if k % 2 == 0 { 0.5 } else { 0.32 / 0.6 };
        let dv: Vec<f64> = (0..n).map(|k| v[k] - pv(k)).collect();
        let dw: Vec<f64> = (0..n).map(|k| w[k] - pw(k)).collect();
        assert!(dv.iter().chain(&dw).all(|x| x.abs() <= 0.1 + 1e-12));
        let (mv, sv) = mean_std(&dv);
        let (_, sw) = mean_std(&dw);
        let uniform = 0.1 / 3f64.sqrt();
        assert!(mv.abs() < 0.002 && (sv / uniform - 1.0).abs() < 0.02);
        assert!((sw / uniform - 1.0).abs() < 0.02);
        let ll = |k: usize| -(v[k] - 0.46).powi(2) / 5e-3 - (w[k] - 0.52).powi(2) / 2e-2;
        let wn = f.weights().normalized();
        for k in [1, 100, 5000] {
            let ratio = wn[k] / wn[0];
            let want = (ll(k) - ll(0)).exp();
            assert!(
                (ratio / want - 1.0).abs() < 1e-9,
                "{k}: {ratio} against {want}"
            );
        }
    }

    #[test]
    fn the_adaptive_count_follows_the_radii_s_dispersion_and_the_cloud_is_shown_whole() {
        // Fariña's rule: ceil(6 (σ_R + σ_L) / 1e-5 m) particles at each
        // resampling, here within [10, 100 000]; the fixed rule keeps the
        // count.
        let step = CalibStep::new(0.0, 0.1, 2.0, 1.0)
            .with(Kind::V, 0.47, 0.005)
            .with(Kind::W, 0.52, 0.05);
        let rules = |rule: CountRule| {
            let mut s = plain(5000);
            s.adaptive_pf = true;
            s.trigger = Trigger::Every;
            s.adaptive = Some(AdaptiveParams {
                rule,
                per_particle: 1e-5,
                dispersion_sigmas: 6.0,
                n_min: 10,
                n_max: 100_000,
                ..AdaptiveParams::default()
            });
            let mut f = ParticleFilter::new(&s);
            let e = f.step(&step);
            (e, f)
        };
        let (e, f) = rules(CountRule::Dispersion);
        let want = (6.0 * (e.std_r_right + e.std_r_left) / 1e-5).ceil() as usize;
        assert!(want > 1000 && want != 5000, "{want}");
        assert_eq!(f.particles().len(), want);
        assert_eq!(f.name(), "adaptive-pf");
        let (_, fixed) = rules(CountRule::Fixed);
        assert_eq!(fixed.particles().len(), 5000);
        // The cloud of the radii with its weights, one per particle.
        let c = f.cloud().unwrap();
        assert_eq!(
            (c.r_right.len(), c.r_left.len(), c.weights.len()),
            (want, want, want)
        );
        assert_eq!(c.r_right, &f.particles().rr[..]);
        assert_eq!(c.r_left, &f.particles().rl[..]);
        assert!((c.weights.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        assert_eq!(ParticleFilter::new(&plain(3)).name(), "pf");
        assert!(Particles::default().is_empty());
    }
}
