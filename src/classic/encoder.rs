//! The encoder chain of \[Paryanto\]: an incremental encoder (600 pulses/rev) driven by
//! the wheel through a 20:100 timing belt, read once per update period; the
//! microcontroller turns the pulse count of a period into an rpm reading.

use super::error::ClassicError;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Encoder, belt and read-out period.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EncoderChain {
    /// Encoder pulses per encoder-shaft revolution.
    pub pulses_per_rev: f64,
    /// Teeth of the pulley on the encoder shaft.
    pub encoder_teeth: f64,
    /// Teeth of the pulley on the wheel.
    pub wheel_teeth: f64,
    /// Update period over which pulses are counted (s).
    pub period_s: f64,
}

impl Default for EncoderChain {
    /// \[Paryanto\]: 600 pulses/rev, 20-tooth encoder pulley, 100-tooth wheel
    /// pulley (encoder turns 5× per wheel turn), 1 s update period.
    fn default() -> Self {
        Self {
            pulses_per_rev: 600.0,
            encoder_teeth: 20.0,
            wheel_teeth: 100.0,
            period_s: 1.0,
        }
    }
}

impl EncoderChain {
    /// Checks that every number is finite and positive.
    pub fn validate(&self) -> Result<(), ClassicError> {
        for (n, v) in [
            ("pulses_per_rev", self.pulses_per_rev),
            ("encoder_teeth", self.encoder_teeth),
            ("wheel_teeth", self.wheel_teeth),
            ("period_s", self.period_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ClassicError::invalid(
                    "encoder chain",
                    format!("{n} must be positive, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// Encoder-shaft revolutions per wheel revolution (5 in the seed).
    pub fn belt_ratio(&self) -> f64 {
        self.wheel_teeth / self.encoder_teeth
    }

    /// Pulses per wheel revolution (3000 in the seed); the `ticks_per_rev` of
    /// the robot configuration.
    pub fn pulses_per_wheel_rev(&self) -> f64 {
        self.pulses_per_rev * self.belt_ratio()
    }

    /// Wheel angle of one pulse (rad).
    pub fn wheel_rad_per_pulse(&self) -> f64 {
        2.0 * PI / self.pulses_per_wheel_rev()
    }

    /// Smallest non-zero rpm reading: one pulse per period (0.02 rpm in the seed).
    pub fn rpm_resolution(&self) -> f64 {
        60.0 / (self.pulses_per_wheel_rev() * self.period_s)
    }

    /// Whole pulses counted in one period at a steady wheel speed (rpm),
    /// truncated towards zero as a counter does.
    pub fn pulses_in_period(&self, wheel_rpm: f64) -> f64 {
        (wheel_rpm / 60.0 * self.period_s * self.pulses_per_wheel_rev()).trunc()
    }

    /// The rpm the microcontroller reports for a pulse count:
    /// `pulses / pulses_per_wheel_rev / period · 60`.
    pub fn rpm_from_pulses(&self, pulses: f64) -> f64 {
        pulses / self.pulses_per_wheel_rev() / self.period_s * 60.0
    }

    /// The quantised rpm reading of a steady wheel speed (rpm).
    pub fn rpm_reading(&self, wheel_rpm: f64) -> f64 {
        self.rpm_from_pulses(self.pulses_in_period(wheel_rpm))
    }
}

/// rpm → rad/s.
pub fn rpm_to_rad_s(rpm: f64) -> f64 {
    rpm * 2.0 * PI / 60.0
}

/// rad/s → rpm.
pub fn rad_s_to_rpm(w: f64) -> f64 {
    w * 60.0 / (2.0 * PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_chain_has_3000_pulses_per_wheel_turn() {
        let c = EncoderChain::default();
        c.validate().unwrap();
        assert_eq!(c.pulses_per_wheel_rev(), 3000.0);
        assert!((c.rpm_resolution() - 0.02).abs() < 1e-12);
        // 33.333 rpm over 1 s = 1666.67 pulses → 1666 → 33.32 rpm.
        assert!((c.rpm_reading(100.0 / 3.0) - 33.32).abs() < 1e-9);
        assert_eq!(c.rpm_reading(-10.005), -10.0);
        let short = EncoderChain { period_s: 0.1, ..c };
        assert!((short.rpm_resolution() - 0.2).abs() < 1e-12);
        assert!(EncoderChain { period_s: 0.0, ..c }.validate().is_err());
        assert!((rad_s_to_rpm(rpm_to_rad_s(42.0)) - 42.0).abs() < 1e-12);
    }
}
