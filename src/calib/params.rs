//! Configuration of a calibration run: method, resampling, particles, seed,
//! initial ranges and noise, with the defaults of \[Farina\]; and what each
//! filter is built from ([`PfSettings`], [`KalmanSettings`]): only its own
//! settings, in the robot's units.
//!
//! Lengths that scale with the robot (process noise, eq. 11's clamps, the
//! dispersion per particle, KLD bins, the change detector's spread, the
//! forward speed's model σ) are configured in wheel radii: a filter built
//! for a robot multiplies them by the mean radius it starts from, so the
//! same settings serve a 20 mm and a 320 mm wheel. The defaults are
//! \[Farina\]'s metres on its 0.32 m wheels, divided by 0.32.

use super::adaptive::AdaptiveParams;
use super::change::{ChangeParams, DetectorParams};
use super::resample::Scheme;
use super::trigger::Trigger;
use super::units::{PAPER_RADIUS_M, SQRT_PAPER_STEP};
use serde::{Deserialize, Serialize};

/// Most particles a filter may be asked for (`--particles`, `adaptive.n_max`).
pub const MAX_PARTICLES: usize = 1_000_000;

/// Which form of the filters runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// odocal's filters: the settings as configured.
    #[default]
    Odocal,
    /// \[Farina\]'s Adaptive-PF as published: no Liu–West move
    /// (`kernel_shrink` = 1), no model σ, no Student-t likelihood, no change
    /// detector, no observability scaling of D's noise, eq. 11 on the
    /// instantaneous residuals in its printed form (m/s and rad/s added),
    /// and every noise value in the paper's metres whatever the robot's
    /// size. The measurement front end (time offset, mounting, intervals)
    /// is not part of the filter and stays.
    Published,
}

/// Calibration method (the words of `odocal calibrate --method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The Adaptive-PF of \[Farina\] (adaptive particle count and process noise).
    #[default]
    AdaptivePf,
    /// Particle filter with a fixed count and fixed process noise.
    Pf,
    /// Dual Kalman filter (Wan & Nelson).
    Dkf,
    /// Augmented extended Kalman filter.
    Akf,
    /// No calibration: the nominal parameters.
    None,
    /// Joint maximum-likelihood batch estimate of the kinematics, the laser
    /// mounting and the time offset ([`super::batch`]); not an online filter.
    Batch,
}

impl Method {
    /// Every method, in the order of the paper's Table II plus the PF.
    pub const ALL: [Method; 5] = [
        Method::AdaptivePf,
        Method::Pf,
        Method::Dkf,
        Method::Akf,
        Method::None,
    ];

    /// The name used on the command line, in JSON and tables.
    pub fn as_str(&self) -> &'static str {
        match self {
            Self::AdaptivePf => "adaptive-pf",
            Self::Pf => "pf",
            Self::Dkf => "dkf",
            Self::Akf => "akf",
            Self::None => "none",
            Self::Batch => "batch",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .chain([Method::Batch])
            .find(|x| x.as_str() == s)
            .ok_or_else(|| format!("unknown method {s:?} (adaptive-pf|pf|dkf|akf|none|batch)"))
    }
}

/// Initial uniform ranges `[lo, hi]` of the parameters (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ranges {
    /// Right wheel radius range (m).
    pub r_right: [f64; 2],
    /// Left wheel radius range (m).
    pub r_left: [f64; 2],
    /// Wheel base range (m).
    pub wheel_base: [f64; 2],
}

impl Default for Ranges {
    fn default() -> Self {
        Self {
            r_right: [0.305, 0.335],
            r_left: [0.305, 0.335],
            wheel_base: [0.55, 0.75],
        }
    }
}

impl Ranges {
    /// Ranges of ± `rel` (relative) around nominal parameters.
    pub fn around(r_right: f64, r_left: f64, wheel_base: f64, rel: f64) -> Self {
        let r = |x: f64| [x * (1.0 - rel), x * (1.0 + rel)];
        Self {
            r_right: r(r_right),
            r_left: r(r_left),
            wheel_base: r(wheel_base),
        }
    }

    /// The three ranges in state order (R_R, R_L, D).
    pub fn all(&self) -> [[f64; 2]; 3] {
        [self.r_right, self.r_left, self.wheel_base]
    }
}

/// Noise settings shared by the filters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseParams {
    /// σ of the Gaussian random walk on R_R, R_L, D, in wheel radii per √s
    /// (a step of dt draws σ·√dt): the fixed PF's process noise and the
    /// Adaptive-PF's σ until its first measurement. 10⁻³: a radius may
    /// wander 0.1 % in a second, 0.8 % in a minute. (The 0.5 mm per
    /// iteration of \[Farina\] on 0.32 m wheels, 1.1 % per √s at 50 Hz, keeps
    /// a filter without its adaptive rule several millimetres wide on a real
    /// robot; `preset = "published"` uses it.)
    pub param_sigma: f64,
    /// Half-width of the uniform jitter on each particle's V (m/s) and W
    /// (rad/s) after prediction ([Farina, Sec. III] mentions such jitter without a
    /// value; 0 = none, which only removes noise from the weights).
    pub velocity_jitter: f64,
    /// Measurement σ below this (m/s or rad/s), including σ = 0, is clamped
    /// to it; a σ of ∞ or NaN removes the measurement.
    pub sigma_floor: f64,
    /// σ of the velocity model itself, in wheel radii per second (× the
    /// radius: m/s): added in quadrature to every V measurement's σ
    /// (encoder quantisation, slip, timing), the analytic form of
    /// \[Farina\]'s jitter on V. The Kalman baselines use the same model
    /// noise: the AKF as the process noise of V, the DKF in its parameter
    /// filter's measurement variance.
    pub model_sigma_v: f64,
    /// σ of the turn-rate model (rad/s: a turn rate does not scale with the
    /// robot), added in quadrature to W's σ (and used by the Kalman
    /// baselines as for V).
    pub model_sigma_w: f64,
    /// Liu–West kernel shrinkage `a` applied at each resampling of the
    /// particle filters: θ ← a·θ + (1−a)·θ̄ + sqrt(1−a²)·L·ε with L the
    /// Cholesky factor of the weighted parameter covariance. Keeps the
    /// particles diverse without inflating the posterior (mean and covariance
    /// preserved); 1 = off.
    pub kernel_shrink: f64,
    /// Degrees of freedom ν of the Student-t measurement likelihood that
    /// makes the filters robust to outlier velocity measurements (scan
    /// matching failures): each measurement's precision is scaled by the
    /// variational-Bayes weight `min(1, (ν+1)/(ν+ν̃²/S))` of its normalised
    /// innovation against the filter's prediction (Piché, Särkkä, Hartikainen
    /// 2012). 0 = the plain Gaussian likelihood.
    pub robust_dof: f64,
    /// Turn rate (rad/s) below which the wheel base is only partly
    /// observable, with `obs = min(1, |W|/observability_turn_rate)`: the
    /// random walk of D is scaled by `obs` (a straight run carries no
    /// information about D), and every filter predicts W with the wheel base
    /// `obs·D + (1 − obs)·(D̄/(R̄_R + R̄_L))·(R_R + R_L)` (the Kalman filters
    /// through its Jacobian), so that in a straight run D is not pulled
    /// along (it would run away, dragged by a radius ratio still being
    /// learned) while a common scale of radii and D stays invisible to W, as
    /// it physically is: only V may observe that scale, or a gyro pinning W
    /// biases the radii. 0 = off.
    pub observability_turn_rate: f64,
    /// Kalman baselines: σ of the parameter random walk, in wheel radii
    /// per √s.
    pub kalman_param_sigma: f64,
    /// Dual Kalman filter: σ of its state filter's prior on V around the
    /// wheel-rate prediction (m/s); loose against any measurement, so the
    /// state estimate the parameter filter learns from follows the
    /// measurements (a bound on a speed error, not a length: not scaled).
    pub kalman_velocity_sigma: f64,
    /// The same on W (rad/s).
    pub kalman_turn_sigma: f64,
    /// Dual Kalman filter: a residual of its parameter filter beyond this
    /// many σ of its prior predictive (`hᵀPh` + the measurement's variance)
    /// has its variance raised until it stands at this many, so that one
    /// interval the model cannot explain moves the prediction by at most
    /// this many of its own σ (less the further out it lies); 0 = off.
    pub kalman_gate: f64,
}

impl Default for NoiseParams {
    fn default() -> Self {
        Self {
            param_sigma: 1e-3,
            velocity_jitter: 0.0,
            sigma_floor: 1e-3,
            model_sigma_v: 0.01 / PAPER_RADIUS_M,
            model_sigma_w: 0.01,
            kernel_shrink: 0.8,
            robust_dof: 4.0,
            observability_turn_rate: 0.05,
            kalman_param_sigma: 1e-5 / PAPER_RADIUS_M / SQRT_PAPER_STEP,
            kalman_velocity_sigma: 0.05,
            kalman_turn_sigma: 0.05,
            kalman_gate: 3.0,
        }
    }
}

impl NoiseParams {
    /// The noise in metres for a robot whose lengths are `unit` (m) wheel
    /// radii, the random walks per √s multiplied by `sqrt_s` (√s: 1 keeps
    /// them per √s; √0.02 gives the paper's per-iteration values).
    pub fn in_metres(&self, unit: f64, sqrt_s: f64) -> Self {
        Self {
            param_sigma: self.param_sigma * unit * sqrt_s,
            model_sigma_v: self.model_sigma_v * unit,
            kalman_param_sigma: self.kalman_param_sigma * unit * sqrt_s,
            ..self.clone()
        }
    }
}

/// Everything a calibration run needs besides its data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CalibParams {
    /// Which calibrator.
    pub method: Method,
    /// Resampling scheme of the particle filters.
    pub resampler: Scheme,
    /// When the particle filters resample.
    pub trigger: Trigger,
    /// Initial particle count; `None` = the 5000 (pf) or 8000 (adaptive-pf) of \[Farina\].
    pub particles: Option<usize>,
    /// Seed of every random draw (same seed, same numbers).
    pub seed: u64,
    /// Which form of the filters runs.
    pub preset: Preset,
    /// Initial uniform ranges of R_R, R_L, D; `None`: \[Farina\]'s
    /// wheelchair ranges for a filter built alone, and for `calibrate`
    /// where the online front end starts the filters ([`super::online`]).
    pub ranges: Option<Ranges>,
    /// Process and measurement noise.
    pub noise: NoiseParams,
    /// Adaptive-PF rules.
    pub adaptive: AdaptiveParams,
    /// Adaptive-PF change detector (re-convergence after a radius jump).
    pub change: ChangeParams,
    /// N_eff trigger threshold as a fraction of N ([Farina, Sec. IV]: 0.5).
    pub neff_ratio: f64,
    /// Max-weight trigger threshold as a multiple of 1/N.
    pub max_weight_factor: f64,
    /// Observability and plausibility checks before a result is reported.
    pub checks: super::sanity::CheckParams,
    /// The batch calibration's settings (`--method batch`), also the
    /// online front end's window fit.
    pub batch: super::batch::BatchParams,
    /// The online front end: time offset, mounting, intervals, start.
    pub online: super::online::OnlineParams,
}

impl Default for CalibParams {
    fn default() -> Self {
        Self {
            method: Method::AdaptivePf,
            resampler: Scheme::Systematic,
            trigger: Trigger::Neff,
            particles: None,
            seed: 0,
            preset: Preset::Odocal,
            ranges: None,
            noise: NoiseParams::default(),
            adaptive: AdaptiveParams::default(),
            change: ChangeParams::default(),
            neff_ratio: 0.5,
            max_weight_factor: 2.0,
            checks: Default::default(),
            batch: Default::default(),
            online: Default::default(),
        }
    }
}

impl CalibParams {
    /// The initial ranges: as configured, else \[Farina\]'s wheelchair's.
    pub fn ranges(&self) -> Ranges {
        self.ranges.clone().unwrap_or_default()
    }

    /// These settings with the preset applied: [`Preset::Published`]
    /// switches every departure from \[Farina\] off.
    pub fn with_preset(&self) -> Self {
        let mut p = self.clone();
        if p.preset == Preset::Published {
            p.noise.param_sigma = 5e-4 / PAPER_RADIUS_M / SQRT_PAPER_STEP;
            p.noise.kernel_shrink = 1.0;
            p.noise.model_sigma_v = 0.0;
            p.noise.model_sigma_w = 0.0;
            p.noise.robust_dof = 0.0;
            p.noise.observability_turn_rate = 0.0;
            p.adaptive.residual_tau = 0.0;
            p.change.enabled = false;
        }
        p
    }

    /// The length (m) the radius-relative settings are multiplied by,
    /// eq. 11's turn lever (m) and the factor on the per-√s random walks,
    /// for a filter starting in `ranges`: the mean nominal radius, half the
    /// wheel base and 1 (the filters scale by √dt); under the published
    /// preset the paper's own (0.32 m, 1 as printed, and its per-iteration
    /// values: √0.02).
    pub fn units(&self, ranges: &Ranges) -> Units {
        let mid = |[lo, hi]: [f64; 2]| 0.5 * (lo + hi);
        match self.preset {
            Preset::Published => Units {
                length: PAPER_RADIUS_M,
                lever: 1.0,
                sqrt_s: SQRT_PAPER_STEP,
                per_step: true,
            },
            Preset::Odocal => Units {
                length: 0.5 * (mid(ranges.r_right) + mid(ranges.r_left)),
                lever: 0.5 * mid(ranges.wheel_base),
                sqrt_s: 1.0,
                per_step: false,
            },
        }
    }

    /// What a particle filter is built from.
    pub fn pf_settings(&self) -> PfSettings {
        let p = self.with_preset();
        let ranges = p.ranges();
        let u = p.units(&ranges);
        let adaptive_pf = p.method == Method::AdaptivePf;
        PfSettings {
            adaptive_pf,
            particles: p.initial_particles(),
            seed: p.seed,
            resampler: p.resampler,
            trigger: p.trigger,
            neff_ratio: p.neff_ratio,
            max_weight_factor: p.max_weight_factor,
            noise: p.noise.in_metres(u.length, u.sqrt_s),
            adaptive: adaptive_pf.then(|| p.adaptive.in_metres(u.length, u.lever, u.sqrt_s)),
            detector: (adaptive_pf && p.change.enabled).then(|| p.change.detector(u.length)),
            per_step: u.per_step,
            ranges,
        }
    }

    /// What a Kalman filter is built from.
    pub fn kalman_settings(&self) -> KalmanSettings {
        let p = self.with_preset();
        let ranges = p.ranges();
        let u = p.units(&ranges);
        KalmanSettings {
            noise: p.noise.in_metres(u.length, u.sqrt_s),
            detector: (p.change.enabled && p.change.kalman).then(|| p.change.detector(u.length)),
            per_step: u.per_step,
            ranges,
        }
    }

    /// Initial particle count for the method.
    pub fn initial_particles(&self) -> usize {
        self.particles.unwrap_or(match self.method {
            Method::AdaptivePf => 8000,
            _ => 5000,
        })
    }

    /// Checks every field once; the message names the bad one.
    pub fn validate(&self) -> Result<(), super::CalibError> {
        let bad = |m: &str| Err(super::CalibError::Config(m.to_string()));
        for (name, [lo, hi]) in ["r_right", "r_left", "wheel_base"]
            .iter()
            .zip(self.ranges().all())
        {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
                return bad(&format!("ranges.{name} must be finite with 0 < lo ≤ hi"));
            }
        }
        let n = &self.noise;
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !(nonneg(n.param_sigma)
            && nonneg(n.velocity_jitter)
            && nonneg(n.kalman_param_sigma)
            && nonneg(n.model_sigma_v)
            && nonneg(n.model_sigma_w)
            && nonneg(n.robust_dof)
            && nonneg(n.kalman_gate)
            && nonneg(n.observability_turn_rate)
            && n.kernel_shrink > 0.0
            && n.kernel_shrink <= 1.0
            && n.sigma_floor > 0.0
            && n.sigma_floor.is_finite()
            && n.kalman_velocity_sigma > 0.0
            && n.kalman_velocity_sigma.is_finite())
        {
            return bad("noise: sigmas must be finite and ≥ 0 (sigma_floor, kalman_velocity_sigma > 0), 0 < kernel_shrink ≤ 1");
        }
        if self.initial_particles() == 0 {
            return bad("particles must be ≥ 1");
        }
        if self.initial_particles() > MAX_PARTICLES || self.adaptive.n_max > MAX_PARTICLES {
            return bad(&format!(
                "particles {} (adaptive.n_max {}) is over the cap of {MAX_PARTICLES}: each \
                 particle costs memory and time at every step, and 10⁶ already resolve the \
                 radii far below their noise",
                self.initial_particles(),
                self.adaptive.n_max
            ));
        }
        if !(self.neff_ratio > 0.0 && self.neff_ratio <= 1.0) {
            return bad("neff_ratio must be in (0, 1]");
        }
        if !(self.max_weight_factor.is_finite() && self.max_weight_factor > 0.0) {
            return bad("max_weight_factor must be > 0");
        }
        self.adaptive.validate().or_else(|m| bad(&m))?;
        self.online.validate().or_else(|m| bad(&m))?;
        self.change.validate().or_else(|m| bad(&m))
    }
}

/// Everything a particle filter is built from, in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct PfSettings {
    /// The Adaptive-PF's rules (else a fixed count and σ).
    pub adaptive_pf: bool,
    /// Initial particle count.
    pub particles: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Resampling scheme.
    pub resampler: Scheme,
    /// When to resample.
    pub trigger: Trigger,
    /// N_eff trigger threshold as a fraction of N.
    pub neff_ratio: f64,
    /// Max-weight trigger threshold as a multiple of 1/N.
    pub max_weight_factor: f64,
    /// Process and measurement noise (m, m/s, rad/s).
    pub noise: NoiseParams,
    /// The Adaptive-PF's rules (m), for `adaptive-pf`.
    pub adaptive: Option<AdaptiveParams>,
    /// The change detector, when it runs.
    pub detector: Option<DetectorParams>,
    /// Whether the random walks are per step (the paper's) rather than
    /// per √s.
    pub per_step: bool,
    /// Where the particles are drawn.
    pub ranges: Ranges,
}

/// Everything a Kalman filter is built from, in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct KalmanSettings {
    /// Process and measurement noise (m, m/s, rad/s).
    pub noise: NoiseParams,
    /// The change detector, when it runs for the Kalman filters.
    pub detector: Option<DetectorParams>,
    /// Whether the random walk is per step rather than per √s.
    pub per_step: bool,
    /// The initial belief: the ranges' centre and uniform variance.
    pub ranges: Ranges,
}

/// The units a filter's settings are turned into metres and steps with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Length (m) the radius-relative settings are multiplied by.
    pub length: f64,
    /// Eq. 11's turn lever (m).
    pub lever: f64,
    /// Factor on the per-√s random walks.
    pub sqrt_s: f64,
    /// Whether the random walks are then per step.
    pub per_step: bool,
}
