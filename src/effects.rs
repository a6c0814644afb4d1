//! Named, parameterised departures of the real robot from its nominal model
//! (design.md's effect table). The simulator injects them; `diagnose` uses the
//! same names as candidate causes. A SPEC is `NAME` or `NAME:key=value,...`.

use serde::{Deserialize, Serialize};
use std::fmt;

/// One effect with its parameters (units in the field docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum Effect {
    /// True radii = nominal · (1 + right/left) (relative).
    RadiusScale {
        /// Relative change of the right radius.
        right: f64,
        /// Relative change of the left radius.
        left: f64,
    },
    /// True wheel base = nominal · (1 + scale).
    WheelBaseScale {
        /// Relative change of the wheel base.
        scale: f64,
    },
    /// Radii jump by `right`/`left` (m) at `time` (s from the start).
    RadiusStep {
        /// When the step happens (s from the start of the recording).
        time: f64,
        /// Change of the right radius (m).
        right: f64,
        /// Change of the left radius (m).
        left: f64,
    },
    /// Radii change linearly by `right`/`left` m per hour.
    RadiusDrift {
        /// Right radius drift (m/h).
        right: f64,
        /// Left radius drift (m/h).
        left: f64,
    },
    /// Encoders over-read with speed: ω_meas = ω (1 + k |ω|).
    EncoderGain {
        /// Gain (s/rad, i.e. per rad/s).
        k: f64,
    },
    /// The encoder stream is late relative to the laser by `delay` (s).
    Latency {
        /// Delay (s).
        delay: f64,
    },
    /// The true laser mounting differs from the nominal one by (x, y, yaw).
    LaserOffset {
        /// Forward offset (m).
        x: f64,
        /// Leftward offset (m).
        y: f64,
        /// Yaw offset (rad).
        yaw: f64,
    },
    /// Constant gyro offset (rad/s).
    GyroBias {
        /// Bias (rad/s).
        bias: f64,
    },
    /// Wheels skid in turns: D_eff = D (1 + k |W|).
    TurnSlip {
        /// Slip coefficient (s/rad).
        k: f64,
    },
}

/// Every effect name, in table order.
pub const EFFECT_NAMES: [&str; 9] = [
    "radius_scale",
    "wheel_base_scale",
    "radius_step",
    "radius_drift",
    "encoder_gain",
    "latency",
    "laser_offset",
    "gyro_bias",
    "turn_slip",
];

/// A SPEC that does not parse.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("effect spec '{spec}': {message}")]
pub struct EffectSpecError {
    /// The offending spec.
    pub spec: String,
    /// What is wrong.
    pub message: String,
}

impl Effect {
    /// The table name of this effect.
    pub fn name(&self) -> &'static str {
        match self {
            Self::RadiusScale { .. } => "radius_scale",
            Self::WheelBaseScale { .. } => "wheel_base_scale",
            Self::RadiusStep { .. } => "radius_step",
            Self::RadiusDrift { .. } => "radius_drift",
            Self::EncoderGain { .. } => "encoder_gain",
            Self::Latency { .. } => "latency",
            Self::LaserOffset { .. } => "laser_offset",
            Self::GyroBias { .. } => "gyro_bias",
            Self::TurnSlip { .. } => "turn_slip",
        }
    }

    /// Parameters as (key, value) pairs in table order.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Self::RadiusScale { right, left } => vec![("right", right), ("left", left)],
            Self::WheelBaseScale { scale } => vec![("scale", scale)],
            Self::RadiusStep { time, right, left } => {
                vec![("time", time), ("right", right), ("left", left)]
            }
            Self::RadiusDrift { right, left } => vec![("right", right), ("left", left)],
            Self::EncoderGain { k } => vec![("k", k)],
            Self::Latency { delay } => vec![("delay", delay)],
            Self::LaserOffset { x, y, yaw } => vec![("x", x), ("y", y), ("yaw", yaw)],
            Self::GyroBias { bias } => vec![("bias", bias)],
            Self::TurnSlip { k } => vec![("k", k)],
        }
    }

    /// The effect with its default (typical, clearly visible) magnitude.
    pub fn default_for(name: &str) -> Option<Self> {
        Some(match name {
            "radius_scale" => Self::RadiusScale {
                right: 0.01,
                left: -0.01,
            },
            "wheel_base_scale" => Self::WheelBaseScale { scale: 0.03 },
            "radius_step" => Self::RadiusStep {
                time: 55.0,
                right: 0.004,
                left: 0.002,
            },
            "radius_drift" => Self::RadiusDrift {
                right: -0.01,
                left: -0.005,
            },
            "encoder_gain" => Self::EncoderGain { k: 0.02 },
            "latency" => Self::Latency { delay: 0.04 },
            "laser_offset" => Self::LaserOffset {
                x: 0.05,
                y: 0.02,
                yaw: 0.02,
            },
            "gyro_bias" => Self::GyroBias { bias: 0.005 },
            "turn_slip" => Self::TurnSlip { k: 0.1 },
            _ => return None,
        })
    }

    /// Sets one named parameter; false when the effect has no such key.
    fn set(&mut self, key: &str, v: f64) -> bool {
        let slot: &mut f64 = match (self, key) {
            (Self::RadiusScale { right, .. }, "right") => right,
            (Self::RadiusScale { left, .. }, "left") => left,
            (Self::WheelBaseScale { scale }, "scale") => scale,
            (Self::RadiusStep { time, .. }, "time") => time,
            (Self::RadiusStep { right, .. }, "right") => right,
            (Self::RadiusStep { left, .. }, "left") => left,
            (Self::RadiusDrift { right, .. }, "right") => right,
            (Self::RadiusDrift { left, .. }, "left") => left,
            (Self::EncoderGain { k }, "k") => k,
            (Self::Latency { delay }, "delay") => delay,
            (Self::LaserOffset { x, .. }, "x") => x,
            (Self::LaserOffset { y, .. }, "y") => y,
            (Self::LaserOffset { yaw, .. }, "yaw") => yaw,
            (Self::GyroBias { bias }, "bias") => bias,
            (Self::TurnSlip { k }, "k") => k,
            _ => return false,
        };
        *slot = v;
        true
    }

    /// Parses `NAME` or `NAME:key=value,key=value`; keys not given keep their
    /// default. Values must be finite; `latency` delay must be ≥ 0 and
    /// `radius_step` time ≥ 0.
    pub fn parse(spec: &str) -> Result<Self, EffectSpecError> {
        let err = |m: String| EffectSpecError {
            spec: spec.to_string(),
            message: m,
        };
        let (name, rest) = match spec.split_once(':') {
            Some((n, r)) => (n.trim(), Some(r)),
            None => (spec.trim(), None),
        };
        let mut e = Self::default_for(name).ok_or_else(|| {
            err(format!(
                "unknown effect '{name}' (known: {})",
                EFFECT_NAMES.join(", ")
            ))
        })?;
        if let Some(rest) = rest {
            for kv in rest.split(',').filter(|s| !s.trim().is_empty()) {
                let (k, v) = kv
                    .split_once('=')
                    .ok_or_else(|| err(format!("expected key=value, got '{kv}'")))?;
                let v: f64 = v
                    .trim()
                    .parse()
                    .map_err(|_| err(format!("'{}' is not a number", v.trim())))?;
                if !v.is_finite() {
                    return Err(err(format!("{} must be finite", k.trim())));
                }
                if !e.set(k.trim(), v) {
                    let keys: Vec<_> = e.params().iter().map(|p| p.0).collect();
                    return Err(err(format!(
                        "{name} has no parameter '{}' (parameters: {})",
                        k.trim(),
                        keys.join(", ")
                    )));
                }
            }
        }
        match e {
            Self::Latency { delay } if delay < 0.0 => Err(err("delay must be ≥ 0 s".into())),
            Self::RadiusStep { time, .. } if time < 0.0 => Err(err("time must be ≥ 0 s".into())),
            _ => Ok(e),
        }
    }
}

impl fmt::Display for Effect {
    /// Formats as a SPEC that [`Effect::parse`] reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.name())?;
        for (i, (k, v)) in self.params().iter().enumerate() {
            write!(f, "{}{k}={v}", if i == 0 { ':' } else { ',' })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_effect_round_trips_through_its_spec() {
        for name in EFFECT_NAMES {
            let e = Effect::default_for(name).unwrap();
            assert_eq!(e.name(), name);
            assert_eq!(Effect::parse(&e.to_string()).unwrap(), e);
            assert_eq!(Effect::parse(name).unwrap(), e);
        }
    }

    #[test]
    fn spec_sets_given_keys() {
        assert_eq!(
            Effect::parse("radius_step:time=55,right=0.004,left=0.002").unwrap(),
            Effect::RadiusStep {
                time: 55.0,
                right: 0.004,
                left: 0.002
            }
        );
        assert_eq!(
            Effect::parse("latency:delay=0.04").unwrap(),
            Effect::Latency { delay: 0.04 }
        );
    }

    #[test]
    fn bad_specs_are_refused_with_a_reason() {
        for bad in [
            "wobble",
            "latency:delay",
            "latency:delay=abc",
            "latency:delay=nan",
            "latency:delay=-1",
            "latency:lag=0.1",
            "turn_slip:k=inf",
        ] {
            assert!(Effect::parse(bad).is_err(), "{bad} should fail");
        }
    }
}
