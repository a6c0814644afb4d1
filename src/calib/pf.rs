//! The particle-filter calibrator (seed 000, section III), optionally with the
//! Adaptive-PF rules of section V. Particles are stored as a structure of
//! arrays; a step allocates nothing once the buffers have grown.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

use super::adaptive::{occupied_bins, AdaptiveParams, CountRule};
use super::params::{CalibParams, Method, Ranges};
use super::resample::{Resampler, Scheme};
use super::steps::{usable, CalibStep, Kind};
use super::trigger::Trigger;
use super::weights::Weights;
use super::{Calibrator, Estimate};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

/// Smallest value a radius or wheel base may take (m): noise never makes a
/// particle's geometry zero or negative.
const MIN_LENGTH: f64 = 1e-6;

/// The particle set: χ = [V, W, R_R, R_L, D] per particle (eq. 1).
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Forward velocities V (m/s).
    pub v: Vec<f64>,
    /// Turn rates W (rad/s).
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

    fn gather(&mut self, from: &Particles, idx: &[usize]) {
        let g = |dst: &mut Vec<f64>, src: &[f64]| {
            dst.clear();
            dst.extend(idx.iter().map(|&i| src[i]));
        };
        g(&mut self.v, &from.v);
        g(&mut self.w, &from.w);
        g(&mut self.rr, &from.rr);
        g(&mut self.rl, &from.rl);
        g(&mut self.d, &from.d);
    }
}

/// Weighted mean and standard deviation of one particle column.
fn mean_std(x: &[f64], w: &[f64]) -> (f64, f64) {
    let mut m = 0.0;
    for (a, b) in x.iter().zip(w) {
        m += a * b;
    }
    let mut v = 0.0;
    for (a, b) in x.iter().zip(w) {
        let d = a - m;
        v += b * d * d;
    }
    (m, v.max(0.0).sqrt())
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
    sigma: f64,
    scheme: Scheme,
    trigger: Trigger,
    neff_ratio: f64,
    max_weight_factor: f64,
    jitter: f64,
    floor: f64,
    model_var: [f64; 2],
    shrink: f64,
    ema: Option<[f64; 2]>,
    mean: [f64; 3],
    chol: [[f64; 3]; 3],
    adaptive: Option<AdaptiveParams>,
    name: &'static str,
}

impl ParticleFilter {
    /// A filter with particles drawn uniformly in `params.ranges`, V = W = 0.
    /// `adaptive-pf` uses `params.adaptive`; every other method a fixed
    /// count and σ. Call [`CalibParams::validate`] first.
    pub fn new(params: &CalibParams) -> Self {
        let n = params.initial_particles();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(params.seed);
        let Ranges {
            r_right,
            r_left,
            wheel_base,
        } = params.ranges.clone();
        let mut draw = |[lo, hi]: [f64; 2]| -> Vec<f64> {
            (0..n)
                .map(|_| lo + (hi - lo) * rng.random::<f64>())
                .collect()
        };
        let rr = draw(r_right);
        let rl = draw(r_left);
        let d = draw(wheel_base);
        let adaptive = (params.method == Method::AdaptivePf).then(|| params.adaptive.clone());
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
            sigma: params.noise.param_sigma,
            scheme: params.resampler,
            trigger: params.trigger,
            neff_ratio: params.neff_ratio,
            max_weight_factor: params.max_weight_factor,
            jitter: params.noise.velocity_jitter,
            floor: params.noise.sigma_floor,
            model_var: [
                params.noise.model_sigma_v.powi(2),
                params.noise.model_sigma_w.powi(2),
            ],
            shrink: params.noise.kernel_shrink,
            ema: None,
            mean: [0.0; 3],
            chol: [[0.0; 3]; 3],
            adaptive,
            name: if params.method == Method::AdaptivePf {
                "adaptive-pf"
            } else {
                "pf"
            },
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

    /// Predict (eq. 2–3): random walk on the parameters, then V and W from the
    /// wheel rates. Returns the prior weighted-mean velocities (V_O, W_O).
    fn predict(&mut self, s: &CalibStep) -> (f64, f64) {
        let (wr, wl) = (s.omega_right, s.omega_left);
        let sigma = self.sigma;
        let norm = self.weights.normalized();
        let Particles { v, w, rr, rl, d } = &mut self.p;
        let rng = &mut self.rng;
        let (mut vo, mut wo) = (0.0, 0.0);
        for i in 0..rr.len() {
            if sigma > 0.0 {
                let (a, b, c): (f64, f64, f64) = (
                    StandardNormal.sample(rng),
                    StandardNormal.sample(rng),
                    StandardNormal.sample(rng),
                );
                rr[i] = (rr[i] + sigma * a).max(MIN_LENGTH);
                rl[i] = (rl[i] + sigma * b).max(MIN_LENGTH);
                d[i] = (d[i] + sigma * c).max(MIN_LENGTH);
            }
            let (sr, sl) = (wr * rr[i], wl * rl[i]);
            v[i] = 0.5 * (sr + sl);
            w[i] = (sr - sl) / d[i];
            vo += norm[i] * v[i];
            wo += norm[i] * w[i];
        }
        if self.jitter > 0.0 {
            let j = self.jitter;
            for i in 0..v.len() {
                v[i] += j * (2.0 * rng.random::<f64>() - 1.0);
                w[i] += j * (2.0 * rng.random::<f64>() - 1.0);
            }
        }
        (vo, wo)
    }

    /// Update (eq. 4): add each usable measurement's Gaussian log-likelihood.
    fn reweight(&mut self, s: &CalibStep) {
        let lw = self.weights.log_mut();
        for m in s.measurements().iter().filter(|m| usable(m)) {
            let (x, model) = match m.kind {
                Kind::V => (&self.p.v, self.model_var[0]),
                Kind::W => (&self.p.w, self.model_var[1]),
            };
            let k = 0.5 / (m.sigma.max(self.floor).powi(2) + model);
            let z = m.value;
            for (l, xi) in lw.iter_mut().zip(x) {
                let e = z - xi;
                *l -= k * e * e;
            }
        }
        self.weights.normalize();
    }

    /// The particle count the next resampling draws.
    fn target_count(&mut self, est: &Estimate) -> usize {
        let n = self.p.len();
        let Some(a) = &self.adaptive else {
            return n;
        };
        match a.rule {
            CountRule::Fixed => n,
            CountRule::Dispersion => a.dispersion_count(est.std_r_right.max(est.std_r_left)),
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

    fn resample(&mut self, n_new: usize) {
        self.resampler.resample(
            self.scheme,
            self.weights.normalized(),
            n_new,
            &mut self.rng,
            &mut self.ancestors,
        );
        self.spare.gather(&self.p, &self.ancestors);
        std::mem::swap(&mut self.p, &mut self.spare);
        self.weights.reset_uniform(n_new);
        if self.shrink < 1.0 {
            self.kernel();
        }
    }

    /// Liu–West kernel move of the resampled parameters (see
    /// `NoiseParams::kernel_shrink`), with the pre-resampling weighted mean
    /// and covariance factor stored by [`ParticleFilter::moments`].
    fn kernel(&mut self) {
        let a = self.shrink;
        let h = (1.0 - a * a).sqrt();
        let (m, l) = (self.mean, self.chol);
        let Particles { rr, rl, d, .. } = &mut self.p;
        let rng = &mut self.rng;
        for i in 0..rr.len() {
            let e: [f64; 3] = [
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
            ];
            let j0 = l[0][0] * e[0];
            let j1 = l[1][0] * e[0] + l[1][1] * e[1];
            let j2 = l[2][0] * e[0] + l[2][1] * e[1] + l[2][2] * e[2];
            rr[i] = (a * rr[i] + (1.0 - a) * m[0] + h * j0).max(MIN_LENGTH);
            rl[i] = (a * rl[i] + (1.0 - a) * m[1] + h * j1).max(MIN_LENGTH);
            d[i] = (a * d[i] + (1.0 - a) * m[2] + h * j2).max(MIN_LENGTH);
        }
    }

    /// Weighted mean and Cholesky factor of the weighted covariance of
    /// (R_R, R_L, D); a degenerate covariance falls back to its diagonal.
    fn moments(&mut self, mean: [f64; 3]) {
        let w = self.weights.normalized();
        let cols = [&self.p.rr, &self.p.rl, &self.p.d];
        let mut c = [[0.0f64; 3]; 3];
        for i in 0..w.len() {
            let x = [
                cols[0][i] - mean[0],
                cols[1][i] - mean[1],
                cols[2][i] - mean[2],
            ];
            for r in 0..3 {
                for k in 0..=r {
                    c[r][k] += w[i] * x[r] * x[k];
                }
            }
        }
        let mut l = [[0.0f64; 3]; 3];
        let mut ok = true;
        for r in 0..3 {
            for k in 0..=r {
                let mut s = c[r][k];
                for j in 0..k {
                    s -= l[r][j] * l[k][j];
                }
                if r == k {
                    if !(s > 0.0) {
                        ok = false;
                        break;
                    }
                    l[r][r] = s.sqrt();
                } else {
                    l[r][k] = s / l[k][k];
                }
            }
        }
        if !ok {
            l = [[0.0; 3]; 3];
            for r in 0..3 {
                l[r][r] = c[r][r].max(0.0).sqrt();
            }
        }
        self.mean = mean;
        self.chol = l;
    }

    fn summarize(&self, t: f64) -> Estimate {
        let w = self.weights.normalized();
        let (r_right, std_r_right) = mean_std(&self.p.rr, w);
        let (r_left, std_r_left) = mean_std(&self.p.rl, w);
        let (wheel_base, std_wheel_base) = mean_std(&self.p.d, w);
        let (v, _) = mean_std(&self.p.v, w);
        let (wz, _) = mean_std(&self.p.w, w);
        Estimate {
            t,
            r_right,
            r_left,
            wheel_base,
            std_r_right,
            std_r_left,
            std_wheel_base,
            v,
            w: wz,
            particles: self.p.len(),
            process_sigma: self.sigma,
            resampled: false,
            weights_reset: self.weights.was_reset(),
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
        let (vo, wo) = self.predict(s);
        self.reweight(s);
        let mut est = self.summarize(s.t1);
        if let Some(a) = &self.adaptive {
            if let Some(e) = a.residuals(s, vo, wo, self.floor) {
                a.average(&mut self.ema, e, s.dt());
                self.sigma = a.sigma_of(self.ema.unwrap_or(e));
            }
        }
        if self
            .trigger
            .fires(&self.weights, self.neff_ratio, self.max_weight_factor)
        {
            if self.shrink < 1.0 {
                self.moments([est.r_right, est.r_left, est.wheel_base]);
            }
            let n_new = self.target_count(&est);
            self.resample(n_new);
            est.resampled = true;
        }
        est.process_sigma = self.sigma;
        est
    }

    fn name(&self) -> &'static str {
        self.name
    }
}
