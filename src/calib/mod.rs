//! Online odometry calibration: estimate the wheel radii R_R, R_L and the
//! wheel base D of a differential drive from wheel rates and measured body
//! velocities (ICP, gyro). The Adaptive-PF of \[Farina\], a fixed particle filter,
//! Kalman baselines (dual and augmented) and the nominal model share one
//! [`Calibrator`] trait; [`run`] drives any of them over aligned [`steps`].

mod adaptive;
mod akf;
pub mod batch;
mod change;
mod dkf;
mod evidence;
mod fuse;
mod kalman;
mod kernels;
mod nominal;
pub mod online;
mod params;
mod pf;
mod pool;
mod resample;
mod robust;
mod run;
mod runner;
mod sanity;
mod step_builder;
mod steps;
pub mod synth;
mod trigger;
mod units;
mod weights;

pub use adaptive::{occupied_bins, AdaptiveParams, CountRule};
pub use akf::AugmentedKf;
pub use change::{ChangeDetector, ChangeParams, DetectorParams, Jump};
pub use dkf::DualKf;
pub use evidence::{Evidence, Wiring};
pub use nominal::Nominal;
pub use params::{
    CalibParams, KalmanSettings, Method, NoiseParams, PfSettings, Preset, Ranges, Units,
    MAX_PARTICLES,
};
pub use pf::{ParticleFilter, Particles};
pub use pool::NormalPool;
pub use resample::{inverse_cdf, resample, sorted_uniforms, Resampler, Scheme};
pub use robust::student_t_weight;
pub use run::{CalibSummary, CalibrationRun, Multipliers, OdometryScale};
pub use runner::{run, run_observed, Runner};
pub use sanity::{implausible, observability, CheckParams, Observability, ParamObservability};
pub use step_builder::StepBuilder;
pub use steps::{steps, usable, CalibStep, Kind, Measurement, MAX_GAP_STEP, MAX_MEASUREMENTS};
pub use trigger::Trigger;
pub use units::{PAPER_RADIUS_M, PAPER_STEP_S, SQRT_PAPER_STEP};
pub use weights::{fast_exp, Weights};

use crate::robot::DiffDrive;
use serde::Serialize;

/// Errors of the calibration module.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibError {
    /// A configuration value is out of range (names the field).
    #[error("calibration config: {0}")]
    Config(String),
    /// Nothing to calibrate from.
    #[error("no calibration steps (no wheel data overlapping the observations)")]
    NoSteps,
}

/// The calibrator's output after one step: parameter means and standard
/// deviations (m), the filter's velocities, and bookkeeping. It serialises
/// as a row of the calibration history (design.md's columns, in order:
/// `t, r_right, r_left, wheel_base, std_r_right, std_r_left,
/// std_wheel_base, particles, process_sigma`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// End of the step (s).
    pub t: f64,
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
    /// σ of the right radius (m).
    pub std_r_right: f64,
    /// σ of the left radius (m).
    pub std_r_left: f64,
    /// σ of the wheel base (m).
    pub std_wheel_base: f64,
    /// Estimated forward velocity over the step (m/s).
    #[serde(skip)]
    pub v: f64,
    /// Estimated turn rate over the step (rad/s).
    #[serde(skip)]
    pub w: f64,
    /// Particles used (0 for the Kalman filters and `none`).
    pub particles: usize,
    /// Process noise σ on the parameters used for the next step (m).
    pub process_sigma: f64,
    /// Whether the step resampled.
    #[serde(skip)]
    pub resampled: bool,
    /// Whether every weight underflowed and the weights were reset.
    #[serde(skip)]
    pub weights_reset: bool,
    /// Whether the change detector fired at this step on a change
    /// ([`ChangeDetector`], [`change::Jump::settled`]).
    #[serde(skip)]
    pub changed: bool,
    /// Whether the change detector fired at this step against a belief
    /// still narrowing: the filter re-spread itself; not a change.
    #[serde(skip)]
    pub respread: bool,
}

impl Estimate {
    /// The estimated kinematics.
    pub fn drive(&self) -> DiffDrive {
        DiffDrive {
            r_right: self.r_right,
            r_left: self.r_left,
            wheel_base: self.wheel_base,
        }
    }

    /// The standard deviations of the three parameters (m), in the fields of
    /// the parameters they belong to.
    pub fn std(&self) -> DiffDrive {
        DiffDrive {
            r_right: self.std_r_right,
            r_left: self.std_r_left,
            wheel_base: self.std_wheel_base,
        }
    }

    /// The calibration history row of this estimate, in the column order of
    /// the history CSV: `t, r_right, r_left, wheel_base, std_r_right,
    /// std_r_left, std_wheel_base, particles, process_sigma`.
    pub fn history_row(&self) -> [f64; 9] {
        [
            self.t,
            self.r_right,
            self.r_left,
            self.wheel_base,
            self.std_r_right,
            self.std_r_left,
            self.std_wheel_base,
            self.particles as f64,
            self.process_sigma,
        ]
    }
}

/// An online calibrator: consumes one aligned step, returns its estimate.
pub trait Calibrator {
    /// Processes one step (predict from the wheel rates, update with the
    /// step's measurements) and returns the current estimate.
    fn step(&mut self, step: &CalibStep) -> Estimate;
    /// The method's name (design.md: adaptive-pf | pf | dkf | akf | none).
    fn name(&self) -> &'static str;
    /// The particle cloud after the last step, for display; `None` for
    /// calibrators without particles.
    fn cloud(&self) -> Option<CloudView<'_>> {
        None
    }
}

/// A particle filter's cloud after a step: each particle's R_R and R_L (m)
/// and its normalised weight (same lengths).
#[derive(Debug, Clone, Copy)]
pub struct CloudView<'a> {
    /// Right wheel radii (m).
    pub r_right: &'a [f64],
    /// Left wheel radii (m).
    pub r_left: &'a [f64],
    /// Normalised weights (sum 1).
    pub weights: &'a [f64],
}

/// Builds the calibrator `params.method` names, after validating `params`.
/// `nominal` is what `none` returns (the filters start from `params.ranges()`).
pub fn build(
    params: &CalibParams,
    nominal: DiffDrive,
) -> Result<Box<dyn Calibrator + Send>, CalibError> {
    params.validate()?;
    Ok(match params.method {
        Method::AdaptivePf | Method::Pf => Box::new(ParticleFilter::new(&params.pf_settings())),
        Method::Dkf => Box::new(DualKf::new(&params.kalman_settings())),
        Method::Akf => Box::new(AugmentedKf::new(&params.kalman_settings())),
        Method::None => Box::new(Nominal::new(nominal)),
        Method::Batch => {
            return Err(CalibError::Config(
                "method batch is not an online filter: use calib::batch::estimate".into(),
            ))
        }
    })
}
