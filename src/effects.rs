//! Named, parameterised departures of the real robot from its nominal model
//! (design.md's effect table). The simulator injects them; `diagnose` uses the
//! same names as candidate causes. A SPEC is `NAME` or `NAME:key=value,...`.
//!
//! Each effect is defined here once: its variant of [`Effect`] (the values),
//! its row of [`EffectKind::params`] (SPEC keys, units, defaults, how the
//! diagnosis estimates each), and its share of [`Departures`] (what all the
//! effects amount to at a time, and the laws by which that changes the
//! robot, forward for the simulator and inverse for the diagnosis).

pub mod change;
mod departures;
mod faults;

pub use departures::{invert_gain, Departures, Step};
pub use faults::{FaultEffect, FAULT_NAMES};

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

/// The kind of an effect, without its values: one row of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EffectKind {
    /// [`Effect::RadiusScale`].
    RadiusScale,
    /// [`Effect::WheelBaseScale`].
    WheelBaseScale,
    /// [`Effect::RadiusStep`].
    RadiusStep,
    /// [`Effect::RadiusDrift`].
    RadiusDrift,
    /// [`Effect::EncoderGain`].
    EncoderGain,
    /// [`Effect::Latency`].
    Latency,
    /// [`Effect::LaserOffset`].
    LaserOffset,
    /// [`Effect::GyroBias`].
    GyroBias,
    /// [`Effect::TurnSlip`].
    TurnSlip,
}

/// How the diagnosis estimates a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Estimate {
    /// Fitted by least squares; the value is its finite-difference step
    /// (in the parameter's unit).
    Fitted(f64),
    /// Searched on a grid before the fit and held during it: one degree of
    /// freedom in the BIC, no standard error.
    Searched,
}

/// One parameter of an effect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    /// SPEC key, also the field name in JSON.
    pub key: &'static str,
    /// Unit (`1` for relative changes).
    pub unit: &'static str,
    /// Default magnitude: typical and clearly visible.
    pub default: f64,
    /// Whether a SPEC must give it ≥ 0.
    pub non_negative: bool,
    /// The physical range a SPEC may give (in `unit`), and why.
    pub bounds: Bounds,
    /// How the diagnosis estimates it.
    pub estimate: Estimate,
}

/// The range of values a SPEC may give a parameter, and why beyond it the
/// departure is not a calibration effect any more.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Lowest value.
    pub lo: f64,
    /// Highest value.
    pub hi: f64,
    /// Why, for the refusal message.
    pub why: &'static str,
}

impl Param {
    /// A parameter fitted by least squares with finite-difference `step`.
    const fn fitted(key: &'static str, unit: &'static str, default: f64, step: f64) -> Self {
        Self {
            key,
            unit,
            default,
            non_negative: false,
            bounds: Bounds {
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                why: "",
            },
            estimate: Estimate::Fitted(step),
        }
    }

    /// A parameter the diagnosis searches on a grid.
    const fn searched(key: &'static str, unit: &'static str, default: f64) -> Self {
        Self {
            key,
            unit,
            default,
            non_negative: false,
            bounds: Bounds {
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                why: "",
            },
            estimate: Estimate::Searched,
        }
    }

    /// The same parameter, required to be ≥ 0.
    const fn non_negative(self) -> Self {
        Self {
            non_negative: true,
            ..self
        }
    }

    /// The same parameter, limited to [`lo`, `hi`] for the reason `why`.
    const fn within(self, lo: f64, hi: f64, why: &'static str) -> Self {
        Self {
            bounds: Bounds { lo, hi, why },
            ..self
        }
    }

    /// Whether the diagnosis fits it by least squares (a free parameter).
    pub fn is_free(&self) -> bool {
        matches!(self.estimate, Estimate::Fitted(_))
    }
}

/// Why the radius and wheel-base scales stop at ±50 %.
const WHY_SCALE: &str = "a wheel 50 % larger or smaller than nominal is another robot, not a \
     calibration error";
/// Why a step's time stops at one day.
const WHY_TIME: &str = "beyond the longest simulation (one day, 86400 s)";
/// Why a radius step stops at ±10 cm.
const WHY_STEP: &str = "a radius change over 10 cm is a wheel swap, not a calibration effect";
/// Why a radius drift stops at ±10 cm/h.
const WHY_DRIFT: &str = "tyre wear or inflation loss beyond 10 cm per hour is a failure, not drift";
/// Why the encoder gain and turn slip stop at ±1 s/rad.
const WHY_GAIN: &str = "at 1 rad/s the encoders would already read double";
/// Why the latency stops at 1 s.
const WHY_LATENCY: &str = "a delay over a second is a clock error, not a sensor latency";
/// Why a laser offset stops at ±1 m.
const WHY_MOUNT: &str = "a laser a metre off its nominal mount means a wrong robot file";
/// Why a laser yaw offset stops at ±π.
const WHY_YAW: &str = "an angle beyond ±π wraps around";
/// Why a gyro bias stops at ±0.5 rad/s.
const WHY_BIAS: &str = "MEMS gyros specify biases well below 0.5 rad/s (≈ 29°/s)";
/// Why turn slip stops at ±1 s/rad.
const WHY_SLIP: &str = "at 1 rad/s the effective wheel base would already double";

impl EffectKind {
    /// Every kind, in table order.
    pub const ALL: [Self; 9] = [
        Self::RadiusScale,
        Self::WheelBaseScale,
        Self::RadiusStep,
        Self::RadiusDrift,
        Self::EncoderGain,
        Self::Latency,
        Self::LaserOffset,
        Self::GyroBias,
        Self::TurnSlip,
    ];

    /// The table name (SPEC `NAME`, JSON `effect`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::RadiusScale => "radius_scale",
            Self::WheelBaseScale => "wheel_base_scale",
            Self::RadiusStep => "radius_step",
            Self::RadiusDrift => "radius_drift",
            Self::EncoderGain => "encoder_gain",
            Self::Latency => "latency",
            Self::LaserOffset => "laser_offset",
            Self::GyroBias => "gyro_bias",
            Self::TurnSlip => "turn_slip",
        }
    }

    /// The parameters, in table order (the order of [`Effect::values`]).
    pub const fn params(self) -> &'static [Param] {
        match self {
            Self::RadiusScale => {
                const {
                    &[
                        Param::fitted("right", "1", 0.01, 1e-5).within(-0.5, 0.5, WHY_SCALE),
                        Param::fitted("left", "1", -0.01, 1e-5).within(-0.5, 0.5, WHY_SCALE),
                    ]
                }
            }
            Self::WheelBaseScale => {
                const { &[Param::fitted("scale", "1", 0.03, 1e-5).within(-0.5, 0.5, WHY_SCALE)] }
            }
            Self::RadiusStep => {
                const {
                    &[
                        Param::searched("time", "s", 55.0)
                            .non_negative()
                            .within(0.0, 86400.0, WHY_TIME),
                        Param::fitted("right", "m", 0.004, 1e-6).within(-0.1, 0.1, WHY_STEP),
                        Param::fitted("left", "m", 0.002, 1e-6).within(-0.1, 0.1, WHY_STEP),
                    ]
                }
            }
            Self::RadiusDrift => {
                const {
                    &[
                        Param::fitted("right", "m/h", -0.01, 1e-4).within(-0.1, 0.1, WHY_DRIFT),
                        Param::fitted("left", "m/h", -0.005, 1e-4).within(-0.1, 0.1, WHY_DRIFT),
                    ]
                }
            }
            Self::EncoderGain => {
                const { &[Param::fitted("k", "s/rad", 0.02, 1e-5).within(-1.0, 1.0, WHY_GAIN)] }
            }
            Self::Latency => {
                const {
                    &[Param::fitted("delay", "s", 0.04, 1e-4)
                        .non_negative()
                        .within(0.0, 1.0, WHY_LATENCY)]
                }
            }
            Self::LaserOffset => {
                const {
                    &[
                        Param::fitted("x", "m", 0.05, 1e-5).within(-1.0, 1.0, WHY_MOUNT),
                        Param::fitted("y", "m", 0.02, 1e-5).within(-1.0, 1.0, WHY_MOUNT),
                        Param::fitted("yaw", "rad", 0.02, 1e-5).within(
                            -std::f64::consts::PI,
                            std::f64::consts::PI,
                            WHY_YAW,
                        ),
                    ]
                }
            }
            Self::GyroBias => {
                const { &[Param::fitted("bias", "rad/s", 0.005, 1e-6).within(-0.5, 0.5, WHY_BIAS)] }
            }
            Self::TurnSlip => {
                const { &[Param::fitted("k", "s/rad", 0.1, 1e-5).within(-1.0, 1.0, WHY_SLIP)] }
            }
        }
    }

    /// The effect of this kind with `v` in [`Self::params`] order.
    ///
    /// # Panics
    /// If `v` holds fewer values than the kind has parameters.
    pub fn effect(self, v: &[f64]) -> Effect {
        match self {
            Self::RadiusScale => Effect::RadiusScale {
                right: v[0],
                left: v[1],
            },
            Self::WheelBaseScale => Effect::WheelBaseScale { scale: v[0] },
            Self::RadiusStep => Effect::RadiusStep {
                time: v[0],
                right: v[1],
                left: v[2],
            },
            Self::RadiusDrift => Effect::RadiusDrift {
                right: v[0],
                left: v[1],
            },
            Self::EncoderGain => Effect::EncoderGain { k: v[0] },
            Self::Latency => Effect::Latency { delay: v[0] },
            Self::LaserOffset => Effect::LaserOffset {
                x: v[0],
                y: v[1],
                yaw: v[2],
            },
            Self::GyroBias => Effect::GyroBias { bias: v[0] },
            Self::TurnSlip => Effect::TurnSlip { k: v[0] },
        }
    }

    /// The kind of a table name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The effect of this kind at its default magnitude.
    pub fn default_effect(self) -> Effect {
        let v: Vec<f64> = self.params().iter().map(|p| p.default).collect();
        self.effect(&v)
    }
}

/// Every effect name, in table order.
pub const EFFECT_NAMES: [&str; EffectKind::ALL.len()] = {
    let mut names = [""; EffectKind::ALL.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = EffectKind::ALL[i].name();
        i += 1;
    }
    names
};

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
    /// The kind of this effect.
    pub fn kind(&self) -> EffectKind {
        match self {
            Self::RadiusScale { .. } => EffectKind::RadiusScale,
            Self::WheelBaseScale { .. } => EffectKind::WheelBaseScale,
            Self::RadiusStep { .. } => EffectKind::RadiusStep,
            Self::RadiusDrift { .. } => EffectKind::RadiusDrift,
            Self::EncoderGain { .. } => EffectKind::EncoderGain,
            Self::Latency { .. } => EffectKind::Latency,
            Self::LaserOffset { .. } => EffectKind::LaserOffset,
            Self::GyroBias { .. } => EffectKind::GyroBias,
            Self::TurnSlip { .. } => EffectKind::TurnSlip,
        }
    }

    /// The parameter values in table order ([`EffectKind::params`]).
    pub fn values(&self) -> Vec<f64> {
        match *self {
            Self::RadiusScale { right, left } => vec![right, left],
            Self::WheelBaseScale { scale } => vec![scale],
            Self::RadiusStep { time, right, left } => vec![time, right, left],
            Self::RadiusDrift { right, left } => vec![right, left],
            Self::EncoderGain { k } => vec![k],
            Self::Latency { delay } => vec![delay],
            Self::LaserOffset { x, y, yaw } => vec![x, y, yaw],
            Self::GyroBias { bias } => vec![bias],
            Self::TurnSlip { k } => vec![k],
        }
    }

    /// The table name of this effect.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// Parameters as (key, value) pairs in table order.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        let keys = self.kind().params().iter().map(|p| p.key);
        keys.zip(self.values()).collect()
    }

    /// The effect with its default (typical, clearly visible) magnitude.
    pub fn default_for(name: &str) -> Option<Self> {
        EffectKind::from_name(name).map(EffectKind::default_effect)
    }

    /// Parses `NAME` or `NAME:key=value,key=value`; keys not given keep their
    /// default. Values must be finite and within each parameter's
    /// [`Bounds`] (e.g. `latency` delay in [0, 1] s, `radius_scale` ±50 %).
    pub fn parse(spec: &str) -> Result<Self, EffectSpecError> {
        let err = |m: String| EffectSpecError {
            spec: spec.to_string(),
            message: m,
        };
        let (name, rest) = match spec.split_once(':') {
            Some((n, r)) => (n.trim(), Some(r)),
            None => (spec.trim(), None),
        };
        let kind = EffectKind::from_name(name).ok_or_else(|| {
            err(format!(
                "unknown effect '{name}' (known: {})",
                EFFECT_NAMES.join(", ")
            ))
        })?;
        let params = kind.params();
        let mut values: Vec<f64> = params.iter().map(|p| p.default).collect();
        for kv in rest.into_iter().flat_map(|r| r.split(',')) {
            if kv.trim().is_empty() {
                continue;
            }
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
            let Some(i) = params.iter().position(|p| p.key == k.trim()) else {
                let keys: Vec<_> = params.iter().map(|p| p.key).collect();
                return Err(err(format!(
                    "{name} has no parameter '{}' (parameters: {})",
                    k.trim(),
                    keys.join(", ")
                )));
            };
            values[i] = v;
        }
        for (p, v) in params.iter().zip(&values) {
            if p.non_negative && *v < 0.0 {
                return Err(err(format!("{} must be ≥ 0 {}", p.key, p.unit)));
            }
            let b = p.bounds;
            if !(b.lo <= *v && *v <= b.hi) {
                return Err(err(format!(
                    "{name} {} = {v} is outside the physical range [{}, {}] ({}): {}",
                    p.key, b.lo, b.hi, p.unit, b.why
                )));
            }
        }
        Ok(kind.effect(&values))
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
    fn the_table_lists_every_kind_once_in_order() {
        for (i, k) in EffectKind::ALL.into_iter().enumerate() {
            assert_eq!(k as usize, i);
            assert_eq!(k.default_effect().kind(), k);
        }
    }

    #[test]
    fn the_table_holds_every_variant_of_effect() {
        // serde lists every variant it knows when it meets an unknown one.
        let err = serde_json::from_str::<Effect>(r#"{"effect": "?"}"#).unwrap_err();
        let msg = err.to_string();
        let known = msg.split("expected one of ").nth(1).unwrap();
        let variants: Vec<&str> = known.split('`').skip(1).step_by(2).collect();
        assert_eq!(variants, EFFECT_NAMES, "{msg}");
    }

    #[test]
    fn parameter_keys_name_the_fields_in_value_order() {
        for k in EffectKind::ALL {
            let params = k.params();
            let v: Vec<f64> = (1..=params.len()).map(|i| i as f64).collect();
            let e = k.effect(&v);
            assert_eq!(e.values(), v);
            let json = serde_json::to_value(e).unwrap();
            let fields = json.as_object().unwrap();
            assert_eq!(fields.len(), params.len() + 1, "{json}");
            assert_eq!(fields["effect"], k.name());
            for (p, x) in params.iter().zip(&v) {
                assert_eq!(fields[p.key].as_f64(), Some(*x), "{} {}", k.name(), p.key);
            }
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
        assert_eq!(
            Effect::parse("radius_step:time=-1").unwrap_err().message,
            "time must be ≥ 0 s"
        );
        assert_eq!(
            Effect::parse("latency:delay=-1").unwrap_err().message,
            "delay must be ≥ 0 s"
        );
    }
}
