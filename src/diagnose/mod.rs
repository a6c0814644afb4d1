//! Diagnosis: where the nominal model disagrees with the measurements, which
//! physical effect (design.md's table) explains it, and how much better the
//! extended model predicts data it was not fitted on.
//!
//! Steps: replay the model on the measured wheel angles ([`model::Replay`]);
//! residuals of ICP velocities and gyro rate ([`data`]); fit every candidate
//! effect on the training part by weighted Levenberg–Marquardt ([`fit`]);
//! forward selection by BIC with a margin and a Wald test ([`select`]);
//! held-out gain ([`gain`]) and whiteness/trend tests ([`residuals`]) decide
//! the verdict ([`run`] drives the steps, [`diagnosis`] holds the result).
//!
//! σ handling: each stream's σ (ICP covariance; gyro 1/√samples per window)
//! sets the relative weights; one scale factor per stream (ICP forward,
//! lateral, turn rate; gyro) is profiled out of the likelihood, so a
//! mis-scaled ICP covariance changes neither the estimates nor the BIC.

pub mod data;
pub mod diagnosis;
pub mod encoder_table;
pub mod faults;
pub mod fit;
pub mod floor;
pub mod free;
pub mod gain;
pub mod gyro_check;
pub mod instrument;
pub mod load;
pub mod model;
pub mod mount;
pub mod odometry;
pub mod onset;
pub mod remaining;
pub mod residuals;
pub mod resolution;
pub mod run;
pub mod select;
pub mod series;
pub mod split;
pub mod stability;
pub mod stats;
pub mod synthetic;
pub mod trajectory;

pub use diagnosis::{Cause, Diagnosis, Fault, Remaining, Verdict};
pub use gain::{Gain, StreamGain};
pub use select::CandidateScore;
pub use series::ResidualSeries;

use crate::effects::{Effect, EFFECT_NAMES};
use crate::motion::Motion;
use crate::recording::{GyroSample, Recording, StampedPose, WheelSample};
use crate::robot::RobotConfig;
use serde::{Deserialize, Serialize};

/// Settings of the diagnosis (`--config` TOML table, `--holdout`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DiagnoseParams {
    /// Fraction of the time span held out at the end for the gain (0–0.9).
    pub holdout: f64,
    /// Minimum BIC improvement for an effect to enter the model.
    pub bic_margin: f64,
    /// Minimum drop of the held-out χ² (σ-normalised squared residuals) that
    /// each selected effect must bring, in order of selection; effects that
    /// fit the training part but do not predict the held-out part are
    /// reported as rejected, not as causes.
    pub heldout_margin: f64,
    /// Maximum Wald p-value of an entering effect's parameters.
    pub alpha: f64,
    /// Family-wise level of the residual structure tests (mean, trend,
    /// Ljung–Box over every stream).
    pub structure_alpha: f64,
    /// Bin width (s) of the residuals fed to the structure tests.
    pub bin_seconds: f64,
    /// Lags of the Ljung–Box test (in bins).
    pub ljung_box_lags: usize,
    /// Gyro averaging window (s).
    pub gyro_window: f64,
    /// Width (s) of the centred moving average applied to the wheel angle
    /// stream before replay (reduces and evens out encoder quantisation).
    pub wheel_smoothing: f64,
    /// Window (s) of the held-out relative-pose error against a reference.
    pub trajectory_window: f64,
    /// Consecutive ICP motions are chained into intervals of at least this
    /// many seconds before comparison (0 = every scan pair on its own); for
    /// wheel or odometry streams stamped in bursts.
    pub min_interval: f64,
    /// Time kept free at both ends of the wheel stream (s), bounding latency.
    pub margin: f64,
    /// Residuals beyond this many robust σ of the fitted model are
    /// outliers: rows are first screened against the nominal model at four
    /// times this (gross scan-matching failures only, so a large effect keeps
    /// its evidence), then against the model selected on them.
    pub outlier_sigma: f64,
    /// Span (s) of serial correlation the structure tests allow for
    /// (Newey–West lags): scan matching errors stay correlated while the
    /// robot sees the same geometry.
    pub structure_lag: f64,
    /// Sizes below which a leftover structure is not reported (what scan
    /// matching alone leaves on null recordings).
    pub floors: remaining::Floors,
    /// Scan-to-scan ICP's own error per pair, against which a leftover
    /// structure is checked before it is called the robot's.
    pub instrument: instrument::Instrument,
    /// The gyro's turn scale checked against the scan matching before the
    /// fit (a gyro scale is a fault of the gyro, not an effect of the table).
    pub gyro_check: gyro_check::GyroCheck,
    /// Tyres whose radius follows their load told apart from an encoder
    /// gain (the same law at one speed).
    pub load: load::LoadSettings,
    /// Maximum number of effects selected.
    pub max_effects: usize,
    /// Levenberg–Marquardt iterations per fit.
    pub max_iter: usize,
    /// Candidate effect names (default: every effect of the table).
    pub candidates: Vec<String>,
}

impl Default for DiagnoseParams {
    fn default() -> Self {
        Self {
            holdout: 0.3,
            bic_margin: 10.0,
            heldout_margin: 10.0,
            alpha: 1e-3,
            structure_alpha: 1e-3,
            bin_seconds: 1.0,
            ljung_box_lags: 10,
            gyro_window: 0.1,
            wheel_smoothing: 0.1,
            trajectory_window: 5.0,
            min_interval: 0.0,
            margin: 0.25,
            outlier_sigma: 8.0,
            structure_lag: 3.0,
            floors: remaining::Floors::default(),
            instrument: instrument::Instrument::default(),
            gyro_check: gyro_check::GyroCheck::default(),
            load: load::LoadSettings::default(),
            max_effects: 4,
            max_iter: 30,
            candidates: EFFECT_NAMES.iter().map(|s| s.to_string()).collect(),
        }
    }
}

impl DiagnoseParams {
    /// Checks ranges and candidate names once.
    pub fn validate(&self) -> Result<(), DiagnoseError> {
        let bad = |m: String| Err(DiagnoseError::Params(m));
        if !(self.holdout > 0.0 && self.holdout <= 0.9) {
            return bad(format!("holdout must be in (0, 0.9], got {}", self.holdout));
        }
        for (k, v) in [
            ("bic_margin", self.bic_margin),
            ("heldout_margin", self.heldout_margin),
            ("bin_seconds", self.bin_seconds),
            ("gyro_window", self.gyro_window),
            ("trajectory_window", self.trajectory_window),
            ("outlier_sigma", self.outlier_sigma),
            ("structure_lag", self.structure_lag),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{k} must be positive, got {v}"));
            }
        }
        for (k, v) in [
            ("alpha", self.alpha),
            ("structure_alpha", self.structure_alpha),
        ] {
            if !(v > 0.0 && v < 1.0) {
                return bad(format!("{k} must be in (0, 1), got {v}"));
            }
        }
        if !(self.wheel_smoothing.is_finite() && self.wheel_smoothing >= 0.0) {
            return bad(format!(
                "wheel_smoothing must be ≥ 0 s, got {}",
                self.wheel_smoothing
            ));
        }
        if !(self.min_interval.is_finite() && self.min_interval >= 0.0) {
            return bad(format!(
                "min_interval must be ≥ 0 s, got {}",
                self.min_interval
            ));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return bad(format!("margin must be ≥ 0 s, got {}", self.margin));
        }
        self.instrument.validate().map_err(DiagnoseError::Params)?;
        self.gyro_check.validate().map_err(DiagnoseError::Params)?;
        self.load.validate().map_err(DiagnoseError::Params)?;
        if self.max_iter == 0 || self.ljung_box_lags == 0 {
            return bad("max_iter and ljung_box_lags must be ≥ 1".into());
        }
        for c in &self.candidates {
            if !EFFECT_NAMES.contains(&c.as_str()) {
                return bad(format!(
                    "unknown candidate '{c}' (known: {})",
                    EFFECT_NAMES.join(", ")
                ));
            }
        }
        Ok(())
    }
}

/// Why a diagnosis could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// A setting is out of range.
    #[error("diagnose config: {0}")]
    Params(String),
    /// Not enough usable data in a stream or part.
    #[error("not enough data to diagnose: {0}")]
    TooLittleData(String),
}

/// The measured streams the diagnosis compares with the model. `motions` are
/// ICP motions already in the base frame, converted with the NOMINAL laser
/// mount (what `icp` writes); failed pairs are skipped.
#[derive(Debug, Clone, Copy)]
pub struct Measured<'a> {
    /// Wheel angles (rad), the model's input.
    pub wheels: &'a [WheelSample],
    /// Scan-matching motions (base frame, nominal mount) with covariances.
    pub motions: &'a [Motion],
    /// Gyro yaw rates (may be empty).
    pub gyro: &'a [GyroSample],
    /// Reference poses (may be empty); used for the trajectory gain.
    pub reference: &'a [StampedPose],
}

impl<'a> Measured<'a> {
    /// The streams of a recording plus its ICP motions.
    pub fn new(rec: &'a Recording, motions: &'a [Motion]) -> Self {
        Self {
            wheels: &rec.wheels,
            motions,
            gyro: &rec.gyro,
            reference: &rec.reference,
        }
    }

    /// Earliest stamp of any stream: the origin of radius-step times and drifts.
    pub fn origin(&self) -> f64 {
        let mut t = f64::INFINITY;
        if let Some(w) = self.wheels.first() {
            t = t.min(w.stamp);
        }
        if let Some(m) = self.motions.iter().map(|m| m.t0).reduce(f64::min) {
            t = t.min(m);
        }
        if let Some(g) = self.gyro.first() {
            t = t.min(g.stamp);
        }
        t
    }
}

/// Runs the whole diagnosis of the nominal `robot` against the measurements.
pub fn diagnose(
    robot: &RobotConfig,
    measured: &Measured,
    params: &DiagnoseParams,
) -> Result<Diagnosis, DiagnoseError> {
    params.validate()?;
    run::run(robot, measured, params)
}

/// The fitted extension of a diagnosis as effects (SPEC-printable).
pub fn fitted_effects(d: &Diagnosis) -> Vec<Effect> {
    d.causes
        .iter()
        .filter_map(|c| {
            let spec = c
                .parameters
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(",");
            Effect::parse(&format!("{}:{spec}", c.effect)).ok()
        })
        .collect()
}
