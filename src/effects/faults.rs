//! Departures outside the effect table that the simulator can hide in a
//! recording so the diagnosis can be tested on them blind: wiring faults
//! (swapped joints, an encoder counting backwards), an out-of-round wheel,
//! slip on part of the floor, a latency that changes during the run and a
//! laser knocked on its mounting during the run (the recording's
//! `/tf_static` keeps the mounting it had at the start).
//! The diagnosis never fits them as table effects; it names those it
//! recognises under their own names (design.md). One is physics rather than
//! a fault: tyres that deflect under load (`tyre_load`), whose standing
//! part a diagnosis should read as a radius scale. A SPEC is `NAME` or
//! `NAME:key=value,...`, like an effect's; `simulate --effect` takes both.

use serde::{Deserialize, Serialize};
use std::fmt;

use super::EffectSpecError;

/// One fault with its parameters (units in the field docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "fault", rename_all = "snake_case")]
pub enum FaultEffect {
    /// The joint named left carries the right encoder and vice versa.
    SwappedWheels,
    /// The left encoder counts backwards.
    ReversedLeftEncoder,
    /// The right encoder counts backwards.
    ReversedRightEncoder,
    /// Wheel radius r (1 + a cos φ) over the wheel's own angle φ (rad):
    /// once-per-revolution wobble of relative amplitude a.
    WheelOutOfRound {
        /// Relative amplitude of the right wheel.
        right: f64,
        /// Relative amplitude of the left wheel.
        left: f64,
    },
    /// Where the robot's x (world frame, m) lies in [x_min, x_max] the
    /// wheels spin `slip` (relative) faster than they roll.
    FloorSlip {
        /// Start of the slippery band (m).
        x_min: f64,
        /// End of the slippery band (m).
        x_max: f64,
        /// Extra wheel rotation, relative (0.05 = 5 %).
        slip: f64,
    },
    /// From `time` (s) on, the encoder stream is `delay` s later than before.
    LatencyChange {
        /// When the latency changes (s from the start).
        time: f64,
        /// Extra delay from then on (s).
        delay: f64,
    },
    /// From `time` (s) on, the laser sits on the robot moved by (dx, dy)
    /// (m, forward and leftward in the base frame) and turned by `dyaw`
    /// (rad) from where it was mounted: a knock.
    LaserKnock {
        /// When the laser is knocked (s from the start).
        time: f64,
        /// Forward shift of the mounting (m).
        dx: f64,
        /// Leftward shift of the mounting (m).
        dy: f64,
        /// Turn of the mounting (rad).
        dyaw: f64,
    },
    /// Tyres whose rolling radius follows their load: each drive wheel's
    /// radius shrinks by its tyre's deflection F / `stiffness`, the load F
    /// its share of `mass` · g by where the centre of mass sits across the
    /// axle (`com_y`), plus the load the turn moves onto the outer wheel
    /// (`mass` · v ω · `height` / wheel base). A linear tyre whose rolling
    /// radius drops by its whole deflection: a model of the physics, not a
    /// law of the effect table.
    TyreLoad {
        /// Mass the two drive wheels carry (kg).
        mass: f64,
        /// Centre of mass left of the axle's middle (m).
        com_y: f64,
        /// Height of the centre of mass above the ground (m).
        height: f64,
        /// Vertical stiffness of one tyre (N/m).
        stiffness: f64,
    },
}

/// Standard gravity (m/s²).
const G: f64 = 9.80665;

/// Parameter keys of a fault with their (lo, hi) ranges.
type Keys = &'static [(&'static str, f64, f64)];

/// Every fault name, with its parameter keys and (lo, hi) ranges.
const TABLE: [(&str, Keys); 8] = [
    ("swapped_wheels", &[]),
    ("reversed_left_encoder", &[]),
    ("reversed_right_encoder", &[]),
    (
        "wheel_out_of_round",
        &[("right", -0.2, 0.2), ("left", -0.2, 0.2)],
    ),
    (
        "floor_slip",
        &[
            ("x_min", -1e4, 1e4),
            ("x_max", -1e4, 1e4),
            ("slip", -0.5, 0.5),
        ],
    ),
    (
        "latency_change",
        &[("time", 0.0, 86400.0), ("delay", -1.0, 1.0)],
    ),
    // A knock moves the laser on its bracket, not off the robot: ≤ 0.5 m
    // and ≤ 0.5 rad (29°).
    (
        "laser_knock",
        &[
            ("time", 0.0, 86400.0),
            ("dx", -0.5, 0.5),
            ("dy", -0.5, 0.5),
            ("dyaw", -0.5, 0.5),
        ],
    ),
    // A wheelchair with its user to a delivery robot: up to 1 t on the two
    // wheels, tyres from soft pneumatics (10 kN/m) to solid rubber.
    (
        "tyre_load",
        &[
            ("mass", 0.0, 1000.0),
            ("com_y", -0.5, 0.5),
            ("height", 0.0, 2.0),
            ("stiffness", 1e4, 1e8),
        ],
    ),
];

/// Every fault name.
pub const FAULT_NAMES: [&str; 8] = [
    TABLE[0].0, TABLE[1].0, TABLE[2].0, TABLE[3].0, TABLE[4].0, TABLE[5].0, TABLE[6].0, TABLE[7].0,
];

impl FaultEffect {
    /// Its name (SPEC `NAME`).
    pub fn name(&self) -> &'static str {
        TABLE[self.index()].0
    }

    fn index(&self) -> usize {
        match self {
            Self::SwappedWheels => 0,
            Self::ReversedLeftEncoder => 1,
            Self::ReversedRightEncoder => 2,
            Self::WheelOutOfRound { .. } => 3,
            Self::FloorSlip { .. } => 4,
            Self::LatencyChange { .. } => 5,
            Self::LaserKnock { .. } => 6,
            Self::TyreLoad { .. } => 7,
        }
    }

    /// Parameter values in the table's key order.
    pub fn values(&self) -> Vec<f64> {
        match *self {
            Self::WheelOutOfRound { right, left } => vec![right, left],
            Self::FloorSlip { x_min, x_max, slip } => vec![x_min, x_max, slip],
            Self::LatencyChange { time, delay } => vec![time, delay],
            Self::LaserKnock { time, dx, dy, dyaw } => vec![time, dx, dy, dyaw],
            Self::TyreLoad {
                mass,
                com_y,
                height,
                stiffness,
            } => vec![mass, com_y, height, stiffness],
            _ => Vec::new(),
        }
    }

    /// Parses `NAME` or `NAME:key=value,...`; every key must be given.
    pub fn parse(spec: &str) -> Result<Self, EffectSpecError> {
        let err = |m: String| EffectSpecError {
            spec: spec.to_string(),
            message: m,
        };
        let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
        let name = name.trim();
        let Some(i) = TABLE.iter().position(|(n, _)| *n == name) else {
            return Err(err(format!("unknown fault '{name}'")));
        };
        let keys = TABLE[i].1;
        let mut v = vec![f64::NAN; keys.len()];
        for kv in rest.split(',').filter(|s| !s.trim().is_empty()) {
            let (k, x) = kv
                .split_once('=')
                .ok_or_else(|| err(format!("expected key=value, got '{kv}'")))?;
            let j = keys
                .iter()
                .position(|p| p.0 == k.trim())
                .ok_or_else(|| err(format!("{name} has no parameter '{}'", k.trim())))?;
            let x: f64 = x
                .trim()
                .parse()
                .map_err(|_| err(format!("'{}' is not a number", x.trim())))?;
            let (lo, hi) = (keys[j].1, keys[j].2);
            if !(lo..=hi).contains(&x) {
                return Err(err(format!("{} = {x} is outside [{lo}, {hi}]", keys[j].0)));
            }
            v[j] = x;
        }
        if let Some(j) = v.iter().position(|x| x.is_nan()) {
            return Err(err(format!("{name} needs {}", keys[j].0)));
        }
        Ok(match i {
            0 => Self::SwappedWheels,
            1 => Self::ReversedLeftEncoder,
            2 => Self::ReversedRightEncoder,
            3 => Self::WheelOutOfRound {
                right: v[0],
                left: v[1],
            },
            4 => Self::FloorSlip {
                x_min: v[0],
                x_max: v[1],
                slip: v[2],
            },
            5 => Self::LatencyChange {
                time: v[0],
                delay: v[1],
            },
            6 => Self::LaserKnock {
                time: v[0],
                dx: v[1],
                dy: v[2],
                dyaw: v[3],
            },
            _ => Self::TyreLoad {
                mass: v[0],
                com_y: v[1],
                height: v[2],
                stiffness: v[3],
            },
        })
    }

    /// The rolling radii (right, left) (m) of wheels of unloaded radii
    /// `radii` on an axle `wheel_base` m long, while the body moves at `v`
    /// (m/s) and turns at `w` (rad/s): each radius less its tyre's
    /// deflection under its load (never below zero load: a wheel lifting
    /// off is outside the model).
    pub fn loaded_radii(&self, radii: (f64, f64), wheel_base: f64, v: f64, w: f64) -> (f64, f64) {
        match *self {
            Self::TyreLoad {
                mass,
                com_y,
                height,
                stiffness,
            } => {
                // The centre of mass left of the middle loads the left wheel;
                // turning left (ω > 0), the centrifugal force at the centre of
                // mass's height loads the outer, right wheel.
                let share = mass * G * com_y / wheel_base;
                let transfer = mass * v * w * height / wheel_base;
                let right = (0.5 * mass * G - share + transfer).max(0.0);
                let left = (0.5 * mass * G + share - transfer).max(0.0);
                // In a turn hard enough to flatten a tyre to half its radius
                // the model stops (the run is refused beyond a fifth standing).
                let rolled = |r: f64, f: f64| r - (f / stiffness).min(0.5 * r);
                (rolled(radii.0, right), rolled(radii.1, left))
            }
            _ => radii,
        }
    }

    /// True wheel rates (right, left) (rad/s) that roll the rims at the rates
    /// `rates` of round wheels, given the wheels' true angles `angles` (rad)
    /// and the robot's world position `x` (m).
    pub fn wheel_rates(&self, rates: (f64, f64), angles: (f64, f64), x: f64) -> (f64, f64) {
        match *self {
            Self::WheelOutOfRound { right, left } => (
                rates.0 / (1.0 + right * angles.0.cos()),
                rates.1 / (1.0 + left * angles.1.cos()),
            ),
            Self::FloorSlip { x_min, x_max, slip } if (x_min..=x_max).contains(&x) => {
                (rates.0 * (1.0 + slip), rates.1 * (1.0 + slip))
            }
            _ => rates,
        }
    }

    /// Extra encoder delay (s) at true time `t`.
    pub fn extra_delay(&self, t: f64) -> f64 {
        match *self {
            Self::LatencyChange { time, delay } if t >= time => delay,
            _ => 0.0,
        }
    }

    /// How far the laser's mounting has moved by true time `t` (s):
    /// (forward m, leftward m, yaw rad), added to the mounting's own.
    pub fn mount_shift(&self, t: f64) -> [f64; 3] {
        match *self {
            Self::LaserKnock {
                time, dx, dy, dyaw, ..
            } if t >= time => [dx, dy, dyaw],
            _ => [0.0; 3],
        }
    }

    /// The (right, left) angles the wiring reports for true ones.
    pub fn wire(&self, angles: (f64, f64)) -> (f64, f64) {
        match self {
            Self::SwappedWheels => (angles.1, angles.0),
            Self::ReversedLeftEncoder => (angles.0, -angles.1),
            Self::ReversedRightEncoder => (-angles.0, angles.1),
            _ => angles,
        }
    }
}

impl fmt::Display for FaultEffect {
    /// Formats as a SPEC that [`FaultEffect::parse`] reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.name())?;
        let keys = TABLE[self.index()].1;
        for (i, (k, v)) in keys.iter().zip(self.values()).enumerate() {
            write!(f, "{}{}={v}", if i == 0 { ':' } else { ',' }, k.0)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_fault_round_trips_through_its_spec() {
        for spec in [
            "swapped_wheels",
            "reversed_left_encoder",
            "reversed_right_encoder",
            "wheel_out_of_round:right=0.01,left=0",
            "floor_slip:x_min=1,x_max=3,slip=0.05",
            "latency_change:time=40,delay=0.05",
            "laser_knock:time=30,dx=0.01,dy=-0.02,dyaw=0.035",
        ] {
            let f = FaultEffect::parse(spec).unwrap();
            assert_eq!(FaultEffect::parse(&f.to_string()).unwrap(), f, "{spec}");
        }
        assert!(FaultEffect::parse("floor_slip:x_min=1,slip=0.05").is_err());
        assert!(FaultEffect::parse("wheel_out_of_round:right=0.5,left=0").is_err());
        assert!(FaultEffect::parse("radius_scale").is_err());
    }

    #[test]
    fn a_knock_is_refused_beyond_the_bracket_and_moves_the_laser_from_its_time_on() {
        assert!(FaultEffect::parse("laser_knock:time=30,dx=0,dy=0").is_err());
        assert!(FaultEffect::parse("laser_knock:time=30,dx=0.6,dy=0,dyaw=0").is_err());
        assert!(FaultEffect::parse("laser_knock:time=30,dx=0,dy=0,dyaw=-0.6").is_err());
        assert!(FaultEffect::parse("laser_knock:time=-1,dx=0,dy=0,dyaw=0").is_err());
        let k = FaultEffect::parse("laser_knock:time=30,dx=0.01,dy=-0.02,dyaw=0.035").unwrap();
        assert_eq!(k.mount_shift(29.999), [0.0; 3]);
        assert_eq!(k.mount_shift(30.0), [0.01, -0.02, 0.035]);
        assert_eq!(k.extra_delay(100.0), 0.0);
        assert_eq!(k.wire((1.0, 2.0)), (1.0, 2.0));
    }

    #[test]
    fn an_out_of_round_wheel_turns_slower_where_its_radius_is_larger() {
        let f = FaultEffect::WheelOutOfRound {
            right: 0.01,
            left: 0.0,
        };
        let (r, l) = f.wheel_rates((2.0, 2.0), (0.0, 0.0), 0.0);
        assert!((r - 2.0 / 1.01).abs() < 1e-12 && l == 2.0);
        let s = FaultEffect::FloorSlip {
            x_min: 0.0,
            x_max: 1.0,
            slip: 0.1,
        };
        assert_eq!(s.wheel_rates((1.0, 2.0), (0.0, 0.0), 2.0), (1.0, 2.0));
        assert!((s.wheel_rates((1.0, 2.0), (0.0, 0.0), 0.5).1 - 2.2).abs() < 1e-12);
    }
}
