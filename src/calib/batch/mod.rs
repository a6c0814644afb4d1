//! Joint maximum-likelihood batch calibration of a differential drive and
//! its laser \[Censi2013\] (Censi, Franchi, Marchionni, Oriolo, "Simultaneous calibration
//! of odometry and sensor parameters for mobile robots", IEEE T-RO 29(2),
//! 2013): the wheel radii r_R, r_L, the wheel base b, the laser mounting
//! ℓ = `base_from_laser` and, when the wheel samples carry time, the time
//! offset δ between the wheel and laser streams.
//!
//! Input: intervals, each with the laser's displacement `s_k` in the laser
//! frame at its start (with a covariance, or none: then σ's are estimated
//! from the residuals as Censi's solver does) and the wheels' motion over
//! it. Steps: a closed-form start (`closed_form`, Sec. IV), then
//! Levenberg–Marquardt on the likelihood (`solve`, Sec. V) with Censi's
//! outlier rejection (`outliers`), the covariance as the inverse Fisher
//! information, and observability and sanity checks (`report`).

mod closed_form;
mod estimate;
mod intervals;
mod model;
mod outliers;
mod report;
mod solve;
#[cfg(test)]
mod tests;

pub use estimate::{closed_form_start, estimate, estimate_with_laser, residual_scales};
pub use intervals::{aggregate, IntervalBuilder, LaserMotion};
pub use model::{inverse, oplus, Unknowns, P3};
pub use report::{BatchEstimate, Correlation, LaserValued, Valued};

use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// The unknowns' names, in the order of every vector and matrix.
pub const NAMES: [&str; 7] = [
    "r_right",
    "r_left",
    "wheel_base",
    "laser_x",
    "laser_y",
    "laser_yaw",
    "time_offset",
];

/// The wheels' motion over an interval.
#[derive(Debug, Clone, PartialEq)]
pub enum WheelMotion {
    /// Sub-steps `(Δφ_L, Δφ_R)` (rad) in order, without absolute time (a
    /// Censi tuple is one sub-step, `T·phi_l, T·phi_r`).
    Steps(Vec<[f64; 2]>),
    /// The interval's laser times `t0..t1` (s); the increments are read on
    /// the problem's [`WheelTrack`], shifted by the time offset.
    Span {
        /// Start (s, laser clock).
        t0: f64,
        /// End (s, laser clock).
        t1: f64,
    },
}

/// One interval of the batch problem.
#[derive(Debug, Clone, PartialEq)]
pub struct Interval {
    /// Laser displacement `[x, y, θ]` (m, m, rad) in the laser frame at the
    /// interval's start.
    pub s: P3,
    /// Its covariance (m², rad²); `None` for all intervals of a problem: the
    /// σ's are estimated from the residuals.
    pub cov: Option<Matrix3<f64>>,
    /// Duration (s), for the excitation summary.
    pub duration: f64,
    /// The wheels' motion.
    pub wheels: WheelMotion,
}

/// Integrated wheel angles (rad) over wheel-clock time (s), sorted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WheelTrack {
    /// Stamps (s).
    pub t: Vec<f64>,
    /// Left wheel angle (rad).
    pub left: Vec<f64>,
    /// Right wheel angle (rad).
    pub right: Vec<f64>,
}

impl WheelTrack {
    /// The median spacing of the samples (s); 0 with fewer than two.
    pub fn period(&self) -> f64 {
        let mut d: Vec<f64> = self.t.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }
}

/// A batch problem: the intervals and, when they are time spans, the wheel
/// track they are read from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Problem {
    /// The intervals.
    pub intervals: Vec<Interval>,
    /// Wheel angles over time (for [`WheelMotion::Span`] intervals).
    pub track: Option<WheelTrack>,
}

/// Settings of the batch calibration (`[calib.batch]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BatchParams {
    /// Outlier-rejection rounds (Censi's solver: 4).
    pub outlier_iterations: usize,
    /// Fraction rejected per round in each of the translation and rotation
    /// residuals (Censi's solver: 0.01).
    pub outlier_fraction: f64,
    /// Probability beyond which an interval's χ², in units of the kept
    /// intervals' typical χ², is an outlier (`outliers::consistent`); 0 =
    /// Censi's fixed fraction alone.
    pub outlier_probability: f64,
    /// At most this fraction of the intervals is dropped by that rule.
    pub outlier_max_fraction: f64,
    /// Estimate the time offset when the intervals carry wheel time.
    pub time_offset: bool,
    /// Levenberg–Marquardt iteration limit per fit.
    pub max_iterations: usize,
    /// Fewest intervals accepted.
    pub min_intervals: usize,
    /// A radius or the wheel base with a std above this fraction of its
    /// nominal value is weak.
    pub weak_relative: f64,
    /// The laser position with a std above this fraction of the nominal
    /// wheel base is weak.
    pub weak_laser_position: f64,
    /// The laser yaw with a std above this is weak (rad).
    pub weak_laser_yaw: f64,
    /// A normalised Fisher-information eigenvalue below this makes the
    /// problem singular.
    pub singular: f64,
    /// Scan-to-scan motions are composed into intervals of at least this
    /// long (s) ...
    pub interval_s: f64,
    /// ... or turning at least this much (rad).
    pub interval_rad: f64,
    /// A time offset beyond this (s) is refused; one beyond a wheel period
    /// but within it is reported with a note (a scanner whose data arrive
    /// late is stamped late: the LEGO robot's scans 0.46 s, the Mines
    /// rover's 0.18 s). Beyond ~1 s the intervals (≈ 1 s) no longer overlap
    /// the wheel motion they are compared with.
    pub max_time_offset_s: f64,
}

impl Default for BatchParams {
    fn default() -> Self {
        Self {
            outlier_iterations: 4,
            outlier_fraction: 0.01,
            outlier_probability: 1e-3,
            outlier_max_fraction: 0.1,
            time_offset: true,
            max_iterations: 50,
            min_intervals: 10,
            weak_relative: 0.01,
            weak_laser_position: 0.05,
            weak_laser_yaw: 0.02,
            singular: 1e-10,
            interval_s: 1.0,
            interval_rad: 0.3,
            max_time_offset_s: 1.0,
        }
    }
}

/// Why the batch calibration gives no result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BatchError {
    /// Too little or unusable input.
    #[error("{0}")]
    Input(String),
    /// The motion cannot determine the parameters: what is missing.
    #[error("the motion cannot determine the calibration: {0}")]
    Unobservable(String),
    /// The estimate is not physically plausible: what and why.
    #[error("calibration refused: {0}")]
    Implausible(String),
}
