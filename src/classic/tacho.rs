//! The tachometer calibration of \[Paryanto\]: each wheel's encoder rpm against a laser
//! tachometer, fitted per wheel as `true = slope · encoder + intercept`
//! (least squares, encoder reading as regressor), then applied to encoder rates.

#[cfg(test)]
use super::encoder::EncoderChain;
use super::encoder::{rad_s_to_rpm, rpm_to_rad_s};
use super::error::{check_finite, ClassicError};
use crate::recording::WheelSample;
use serde::Serialize;

/// One row of the tachometer table (rpm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TachoReading {
    /// Wheel speed measured by the tachometer (rpm).
    pub tachometer_rpm: f64,
    /// Right encoder reading (rpm).
    pub right_encoder_rpm: f64,
    /// Left encoder reading (rpm).
    pub left_encoder_rpm: f64,
}

/// A straight-line fit `y = slope · x + intercept` with its residuals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearFit {
    /// Slope (dimensionless).
    pub slope: f64,
    /// Intercept (rpm).
    pub intercept: f64,
    /// y − fit at each row (rpm).
    pub residuals: Vec<f64>,
    /// RMS of the residuals (rpm).
    pub rms_residual: f64,
    /// RMS of the raw discrepancy y − x before correction (rpm).
    pub rms_before: f64,
    /// Slope of the fit through the origin (`y = s · x`), for comparison.
    pub slope_through_origin: f64,
    /// Smallest |x| in the table (rpm): below it the correction fades to zero.
    pub x_min: f64,
}

impl LinearFit {
    /// Ordinary least squares of `y` on `x`; needs two distinct x values.
    pub fn fit(x: &[f64], y: &[f64]) -> Result<Self, ClassicError> {
        const M: &str = "tachometer fit";
        if x.len() != y.len() || x.len() < 2 {
            return Err(ClassicError::TooFew {
                method: M,
                what: "rows",
                needed: 2,
                got: x.len().min(y.len()),
            });
        }
        check_finite(M, "value", x.iter().chain(y).copied())?;
        let n = x.len() as f64;
        let mx = x.iter().sum::<f64>() / n;
        let my = y.iter().sum::<f64>() / n;
        let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
        let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
        if sxx <= 1e-12 * (1.0 + mx * mx) {
            return Err(ClassicError::invalid(M, "all encoder readings are equal"));
        }
        let slope = sxy / sxx;
        let intercept = my - slope * mx;
        let residuals: Vec<f64> = x
            .iter()
            .zip(y)
            .map(|(a, b)| b - (slope * a + intercept))
            .collect();
        let rms = |v: &mut dyn Iterator<Item = f64>| (v.map(|r| r * r).sum::<f64>() / n).sqrt();
        let x2: f64 = x.iter().map(|a| a * a).sum();
        Ok(Self {
            slope,
            intercept,
            rms_residual: rms(&mut residuals.iter().copied()),
            rms_before: rms(&mut x.iter().zip(y).map(|(a, b)| b - a)),
            residuals,
            slope_through_origin: x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>() / x2,
            x_min: x.iter().fold(f64::INFINITY, |m, a| m.min(a.abs())),
        })
    }

    /// Corrects a reading `x` (rpm). The fit is odd-symmetric (reverse turns
    /// are corrected like forward ones) and, below the slowest calibrated speed,
    /// fades linearly to 0 so a standing wheel stays standing.
    pub fn apply(&self, x: f64) -> f64 {
        let a = x.abs();
        let y = if a >= self.x_min || self.x_min <= 0.0 {
            self.slope * a + self.intercept
        } else {
            (self.slope * self.x_min + self.intercept) * a / self.x_min
        };
        y * x.signum()
    }
}

/// The per-wheel tachometer corrections.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TachoCalibration {
    /// Right wheel: tachometer rpm as a function of encoder rpm.
    pub right: LinearFit,
    /// Left wheel.
    pub left: LinearFit,
}

/// Fits both wheels' corrections from the tachometer table.
pub fn fit_tachometer(rows: &[TachoReading]) -> Result<TachoCalibration, ClassicError> {
    let t: Vec<f64> = rows.iter().map(|r| r.tachometer_rpm).collect();
    let r: Vec<f64> = rows.iter().map(|r| r.right_encoder_rpm).collect();
    let l: Vec<f64> = rows.iter().map(|r| r.left_encoder_rpm).collect();
    Ok(TachoCalibration {
        right: LinearFit::fit(&r, &t)?,
        left: LinearFit::fit(&l, &t)?,
    })
}

impl TachoCalibration {
    /// Corrected wheel rates (rad/s) from encoder rates (rad/s).
    pub fn correct_rates(&self, right_rad_s: f64, left_rad_s: f64) -> (f64, f64) {
        (
            rpm_to_rad_s(self.right.apply(rad_s_to_rpm(right_rad_s))),
            rpm_to_rad_s(self.left.apply(rad_s_to_rpm(left_rad_s))),
        )
    }

    /// The wheel stream with each interval's rates corrected and re-integrated
    /// (same stamps; angles start where the input starts).
    pub fn correct_wheels(&self, wheels: &[WheelSample]) -> Vec<WheelSample> {
        let mut out = Vec::with_capacity(wheels.len());
        let Some(first) = wheels.first() else {
            return out;
        };
        out.push(*first);
        let (mut prev, mut acc) = (*first, *first);
        for s in &wheels[1..] {
            let dt = s.stamp - prev.stamp;
            if dt > 0.0 {
                let (r, l) =
                    self.correct_rates((s.right - prev.right) / dt, (s.left - prev.left) / dt);
                acc = WheelSample {
                    stamp: s.stamp,
                    right: acc.right + r * dt,
                    left: acc.left + l * dt,
                };
                prev = *s;
            }
            out.push(WheelSample {
                stamp: s.stamp,
                ..acc
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::tacho_session::{tachometer_session, TachometerSensor};
    use super::*;

    #[test]
    fn encoder_gain_is_undone_within_the_fit_residual() {
        let speeds = [33.0, 53.0, 72.0, 92.0, 114.0, 137.0];
        let exact = TachometerSensor::exact();
        let t = tachometer_session(&EncoderChain::default(), [0.003, 0.004], &exact, &speeds, 0);
        assert!(t
            .iter()
            .all(|r| r.right_encoder_rpm > r.tachometer_rpm
                && r.left_encoder_rpm > r.right_encoder_rpm));
        let c = fit_tachometer(&t).unwrap();
        assert!(c.right.slope < 1.0 && c.left.slope < c.right.slope);
        // A wheel at 100 rpm (true) reads high; the correction brings it back
        // to within the fit's largest residual plus one quantum.
        let w = rpm_to_rad_s(100.0);
        let (r, l) = c.correct_rates(w * (1.0 + 0.003 * w), w * (1.0 + 0.004 * w));
        let tol = rpm_to_rad_s(c.left.residuals.iter().fold(0.0f64, |m, v| m.max(v.abs())) + 0.02);
        assert!((r - w).abs() < tol && (l - w).abs() < tol, "{r} {l} {w}");
    }

    #[test]
    fn exact_line_is_recovered_and_zero_stays_zero() {
        let x = [10.0, 20.0, 40.0];
        let y: Vec<f64> = x.iter().map(|a| 0.95 * a + 1.5).collect();
        let f = LinearFit::fit(&x, &y).unwrap();
        assert!((f.slope - 0.95).abs() < 1e-12 && (f.intercept - 1.5).abs() < 1e-10);
        assert!(f.rms_residual < 1e-10);
        assert_eq!(f.apply(0.0), 0.0);
        assert!((f.apply(-20.0) + 20.5).abs() < 1e-10);
        assert!((f.apply(5.0) - 0.5 * f.apply(10.0)).abs() < 1e-10);
        assert!(LinearFit::fit(&[1.0, 1.0], &[2.0, 3.0]).is_err());
        assert!(LinearFit::fit(&[1.0], &[2.0]).is_err());
        assert!(LinearFit::fit(&[1.0, f64::NAN], &[2.0, 3.0]).is_err());
    }
}
