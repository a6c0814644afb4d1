//! The tachometer session of \[Paryanto\], simulated: the chair's wheels are spun at a
//! few steady speeds, the encoder chain's rpm reading is written down beside a
//! laser tachometer's. The tachometer is an independent instrument with its
//! own error — a scale error drawn once per session (its calibration), a
//! reading noise (the speed wanders while the two are read) and a display
//! resolution — so the table it gives is not the truth, and neither is the
//! correction fitted to it ([`super::fit_tachometer`]).

use super::encoder::{rad_s_to_rpm, rpm_to_rad_s, EncoderChain};
use super::error::ClassicError;
use super::tacho::TachoReading;
use crate::robot::DiffDrive;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// A laser tachometer's errors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TachometerSensor {
    /// σ of the relative scale error, drawn once per session.
    pub scale_sigma: f64,
    /// σ of each reading's noise (rpm).
    pub reading_sigma_rpm: f64,
    /// Display resolution (rpm); readings are rounded to it; 0 = none.
    pub resolution_rpm: f64,
}

impl Default for TachometerSensor {
    /// A handheld laser tachometer's data sheet: ±(0.05 % + 1 digit) with a
    /// 0.1 rpm digit below 1000 rpm; σ 0.05 % of scale, 0.05 rpm of noise.
    fn default() -> Self {
        Self {
            scale_sigma: 5e-4,
            reading_sigma_rpm: 0.05,
            resolution_rpm: 0.1,
        }
    }
}

impl TachometerSensor {
    /// An instrument without error (the truth), for tests and checks.
    pub fn exact() -> Self {
        Self {
            scale_sigma: 0.0,
            reading_sigma_rpm: 0.0,
            resolution_rpm: 0.0,
        }
    }

    /// Checks that every σ and the resolution are finite and ≥ 0.
    pub fn validate(&self) -> Result<(), ClassicError> {
        let ok = [
            self.scale_sigma,
            self.reading_sigma_rpm,
            self.resolution_rpm,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0);
        if ok {
            Ok(())
        } else {
            Err(ClassicError::invalid(
                "tachometer",
                "scale_sigma, reading_sigma_rpm and resolution_rpm must be finite and ≥ 0",
            ))
        }
    }
}

/// Gaussian draw of σ `s` (0 when `s` is 0, so an exact sensor draws nothing).
fn normal(rng: &mut StdRng, s: f64) -> f64 {
    if s > 0.0 {
        let z: f64 = rng.sample(StandardNormal);
        s * z
    } else {
        0.0
    }
}

/// The table a session gives: at each true wheel speed (rpm) the tachometer's
/// reading and both encoders' readings through `chain`. The encoders over-read
/// as the `encoder_gain` effect describes, ω_meas = ω (1 + k |ω|) (k in s/rad;
/// 0 = an encoder that counts true rotation). Deterministic for a given `seed`.
pub fn tachometer_session(
    chain: &EncoderChain,
    [k_right, k_left]: [f64; 2],
    sensor: &TachometerSensor,
    speeds_rpm: &[f64],
    seed: u64,
) -> Vec<TachoReading> {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x0074_6163_686f);
    let scale = 1.0 + normal(&mut rng, sensor.scale_sigma);
    let encoder = |rpm: f64, k: f64| {
        let w = rpm_to_rad_s(rpm);
        chain.rpm_reading(rad_s_to_rpm(w * (1.0 + k * w.abs())))
    };
    speeds_rpm
        .iter()
        .map(|&t| {
            let read = t * scale + normal(&mut rng, sensor.reading_sigma_rpm);
            let q = sensor.resolution_rpm;
            TachoReading {
                tachometer_rpm: if q > 0.0 {
                    (read / q).round() * q
                } else {
                    read
                },
                right_encoder_rpm: encoder(t, k_right),
                left_encoder_rpm: encoder(t, k_left),
            }
        })
        .collect()
}

/// `n` speeds (rpm) spread evenly over the wheel rates a chair of model
/// `nominal` runs at: from 0.8 × an in-place turn's at `turn_rate` (rad/s) to
/// 1.2 × a straight's at `speed` (m/s), so the fitted correction is used
/// inside the range it was measured on.
pub fn session_speeds(nominal: &DiffDrive, speed: f64, turn_rate: f64, n: usize) -> Vec<f64> {
    let r = 0.5 * (nominal.r_right + nominal.r_left);
    let straight = rad_s_to_rpm(speed / r);
    let turn = rad_s_to_rpm(turn_rate * 0.5 * nominal.wheel_base / r);
    let (lo, hi) = (0.8 * turn.min(straight), 1.2 * turn.max(straight));
    (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n.max(2) - 1) as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_sensor_reads_the_truth_and_a_real_one_does_not() {
        let chain = EncoderChain::default();
        let speeds = [33.0, 72.0, 137.0];
        let exact = tachometer_session(&chain, [0.0; 2], &TachometerSensor::exact(), &speeds, 1);
        for (r, s) in exact.iter().zip(speeds) {
            assert_eq!(r.tachometer_rpm, s);
            // 600 pulses × 5 per wheel turn over 1 s: whole pulses of 0.02 rpm.
            assert!((r.right_encoder_rpm - s).abs() <= 0.02 + 1e-12);
        }
        let sensor = TachometerSensor {
            scale_sigma: 0.01,
            ..TachometerSensor::default()
        };
        let a = tachometer_session(&chain, [0.0; 2], &sensor, &speeds, 1);
        let b = tachometer_session(&chain, [0.0; 2], &sensor, &speeds, 2);
        assert_eq!(a, tachometer_session(&chain, [0.0; 2], &sensor, &speeds, 1));
        assert_ne!(a, b);
        // Readings are whole tenths of an rpm and off the truth.
        for r in &a {
            assert!((r.tachometer_rpm * 10.0 - (r.tachometer_rpm * 10.0).round()).abs() < 1e-9);
        }
        assert!(a.iter().zip(speeds).any(|(r, s)| r.tachometer_rpm != s));
    }

    #[test]
    fn session_speeds_span_turns_and_straights() {
        let d = DiffDrive {
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.65,
        };
        // 0.4 m/s on 0.32 m wheels: 1.25 rad/s = 11.94 rpm; a 0.5 rad/s turn
        // in place: 0.5 · 0.325 / 0.32 = 0.508 rad/s = 4.85 rpm.
        let s = session_speeds(&d, 0.4, 0.5, 6);
        assert_eq!(s.len(), 6);
        assert!((s[0] - 0.8 * 4.849).abs() < 1e-3, "{s:?}");
        assert!((s[5] - 1.2 * 11.937).abs() < 1e-3, "{s:?}");
    }
}
