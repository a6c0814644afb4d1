//! The heading gain of \[Paryanto\]: turn the robot by a known angle several times,
//! compare with the heading its odometry estimates, and scale the estimated
//! heading change by `gain`. Equivalent to dividing the wheel base by `gain`.
//!
//! Two estimators: the ratio of means of \[Paryanto\], `mean(actual)/mean(estimated)`
//! (90/28 = 3.21 on its data, rounded to 3.2), and least squares through the
//! origin, `Σ a·e / Σ e²`, which weights the larger estimates more.

use super::error::{check_finite, ClassicError};
use serde::Serialize;

/// One in-place turn (degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HeadingTrial {
    /// Angle actually turned (deg).
    pub actual_deg: f64,
    /// Angle the odometry estimated (deg).
    pub estimated_deg: f64,
}

/// The fitted gain and its spread.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeadingGain {
    /// Number of trials.
    pub trials: usize,
    /// mean(actual)/mean(estimated): the estimator of \[Paryanto\] and the one applied.
    pub gain: f64,
    /// Least squares through the origin: Σ a·e / Σ e².
    pub gain_least_squares: f64,
    /// actual/estimated of each trial.
    pub per_trial: Vec<f64>,
    /// Sample standard deviation of the per-trial gains.
    pub per_trial_std: f64,
    /// Standard error of the mean-ratio gain (delta method on mean(estimated)).
    pub gain_stderr: f64,
    /// Residual heading error of each trial after applying `gain`: actual − gain·estimated (deg).
    pub residuals_deg: Vec<f64>,
    /// Largest |residual| (deg).
    pub max_abs_residual_deg: f64,
}

/// Fits the heading gain; needs two trials with non-zero estimates.
pub fn fit_heading_gain(trials: &[HeadingTrial]) -> Result<HeadingGain, ClassicError> {
    const M: &str = "heading gain";
    if trials.len() < 2 {
        return Err(ClassicError::TooFew {
            method: M,
            what: "trials",
            needed: 2,
            got: trials.len(),
        });
    }
    check_finite(
        M,
        "angle",
        trials.iter().flat_map(|t| [t.actual_deg, t.estimated_deg]),
    )?;
    if trials.iter().any(|t| t.estimated_deg == 0.0) {
        return Err(ClassicError::invalid(M, "an estimated angle is 0"));
    }
    let n = trials.len() as f64;
    let ma = trials.iter().map(|t| t.actual_deg).sum::<f64>() / n;
    let me = trials.iter().map(|t| t.estimated_deg).sum::<f64>() / n;
    let gain = ma / me;
    let ae: f64 = trials.iter().map(|t| t.actual_deg * t.estimated_deg).sum();
    let ee: f64 = trials
        .iter()
        .map(|t| t.estimated_deg * t.estimated_deg)
        .sum();
    let per_trial: Vec<f64> = trials
        .iter()
        .map(|t| t.actual_deg / t.estimated_deg)
        .collect();
    let mp = per_trial.iter().sum::<f64>() / n;
    let per_trial_std =
        (per_trial.iter().map(|g| (g - mp).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se_e = (trials
        .iter()
        .map(|t| (t.estimated_deg - me).powi(2))
        .sum::<f64>()
        / (n - 1.0))
        .sqrt()
        / n.sqrt();
    let residuals_deg: Vec<f64> = trials
        .iter()
        .map(|t| t.actual_deg - gain * t.estimated_deg)
        .collect();
    Ok(HeadingGain {
        trials: trials.len(),
        gain,
        gain_least_squares: ae / ee,
        per_trial,
        per_trial_std,
        gain_stderr: gain * se_e / me.abs(),
        max_abs_residual_deg: residuals_deg.iter().fold(0.0, |m, r| m.max(r.abs())),
        residuals_deg,
    })
}

impl HeadingGain {
    /// The wheel base (m) that makes odometry turn by `gain` × its estimate.
    pub fn effective_wheel_base(&self, nominal: f64) -> f64 {
        nominal / self.gain
    }
}
