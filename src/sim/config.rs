//! Simulation settings: one plain struct per part, all with defaults for the
//! LMS111 wheelchair, (de)serialisable, validated once by [`SimConfig::validate`].

use super::world::WorldSpec;
use super::SimError;
use serde::{Deserialize, Serialize};

/// Everything a simulation run needs besides the robot and the effects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    /// What the chair drives.
    pub scenario: ScenarioConfig,
    /// Which world it drives in (default: the scenario's own).
    pub world: WorldConfig,
    /// The laser scanner.
    pub laser: LaserConfig,
    /// The wheel encoders.
    pub encoder: EncoderConfig,
    /// The yaw-rate gyro.
    pub gyro: GyroConfig,
    /// The LOAM-like reference trajectory.
    pub reference: ReferenceConfig,
    /// Length of the run (s); paths are looped when the run is longer.
    pub duration_s: f64,
    /// Seed of every random process (sensor noise, random walks).
    pub seed: u64,
    /// Rate (Hz) at which the true motion is integrated (exact arcs per step).
    pub integration_hz: f64,
    /// Faults outside the effect table hidden in the run (`simulate --effect`
    /// takes their SPECs too); left out of the settings written when none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<crate::effects::FaultEffect>,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            scenario: ScenarioConfig::default(),
            world: WorldConfig::default(),
            laser: LaserConfig::default(),
            encoder: EncoderConfig::default(),
            gyro: GyroConfig::default(),
            reference: ReferenceConfig::default(),
            duration_s: 120.0,
            seed: 1,
            integration_hz: 1000.0,
            faults: Vec::new(),
        }
    }
}

/// Which scenario to drive and the chair's motion limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Built-in scenario (`corridor-loop`, `hall`, `square`, `square-ccw`,
    /// `figure-eight`, `random-walk`); ignored when `custom` is set.
    pub name: String,
    /// A scenario read from JSON (waypoints), replacing the built-in one.
    pub custom: Option<ScenarioSpec>,
    /// Cruise speed on straight stretches (m/s).
    pub cruise_speed: f64,
    /// Turn rate used in curves and in-place turns (rad/s).
    pub turn_rate: f64,
    /// Hard limit on |v| (m/s).
    pub max_speed: f64,
    /// Hard limit on |w| (rad/s).
    pub max_turn_rate: f64,
    /// Hard limit on |dv/dt| (m/s²).
    pub max_accel: f64,
    /// Hard limit on |dw/dt| (rad/s²).
    pub max_angular_accel: f64,
    /// Standstill at the start of the run (s).
    pub start_hold_s: f64,
    /// Standstill before and after each in-place turn of stop-and-turn runs (s).
    pub corner_pause_s: f64,
    /// Smallest allowed distance (m) from the planned path to any wall.
    pub min_clearance: f64,
}

impl Default for ScenarioConfig {
    fn default() -> Self {
        Self {
            name: "corridor-loop".into(),
            custom: None,
            cruise_speed: 0.8,
            turn_rate: 0.6,
            max_speed: 1.0,
            max_turn_rate: 1.0,
            max_accel: 0.5,
            max_angular_accel: 1.0,
            start_hold_s: 1.0,
            corner_pause_s: 0.5,
            min_clearance: 0.5,
        }
    }
}

/// A scenario as written in a JSON file: waypoints (m, world frame) driven in
/// order from the first one, either smoothly (corners rounded) or stopping
/// and turning in place at each (UMBmark style).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Label for messages and the truth file.
    pub name: String,
    /// The world: a built-in name or an inline map (default `square-room`).
    pub world: Option<WorldRef>,
    /// Waypoints `[x, y]` (m); at least two.
    pub waypoints: Vec<[f64; 2]>,
    /// Drive back to the first waypoint and loop (true), or stop at the last.
    pub closed: bool,
    /// Stop and turn in place at every waypoint instead of rounding corners.
    pub stop_and_turn: bool,
    /// Radius (m) of the rounded corners in smooth mode.
    pub corner_radius: f64,
}

impl Default for ScenarioSpec {
    fn default() -> Self {
        Self {
            name: "custom".into(),
            world: None,
            waypoints: Vec::new(),
            closed: true,
            stop_and_turn: false,
            corner_radius: 1.0,
        }
    }
}

impl ScenarioSpec {
    /// Parses a scenario JSON file's text (file reading is the caller's).
    pub fn from_json(text: &str) -> Result<Self, SimError> {
        serde_json::from_str(text).map_err(|e| SimError::Scenario(format!("scenario JSON: {e}")))
    }
}

/// A world named (built-in) or given inline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum WorldRef {
    /// A built-in world's name.
    Name(String),
    /// An inline map.
    Map(WorldSpec),
}

/// Overrides the scenario's world.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorldConfig {
    /// A built-in world name or an inline map; `None` keeps the scenario's world.
    pub world: Option<WorldRef>,
}

/// The SICK LMS111: 270° field of view, 0.5° or 0.25° steps, 25 or 50 Hz,
/// 0.5–20 m, about 12 mm range noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserConfig {
    /// Scan rate (Hz).
    pub rate_hz: f64,
    /// Angle between beams (deg): 0.5 gives 541 beams, 0.25 gives 1081.
    pub resolution_deg: f64,
    /// Field of view (deg), centred on the laser x axis.
    pub fov_deg: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m); farther walls give no echo (+inf).
    pub range_max: f64,
    /// Standard deviation of the Gaussian range noise (m).
    pub noise_sigma: f64,
    /// Cast each beam from the pose at its own time within the sweep (true),
    /// or the whole scan from the pose at its stamp.
    pub sweep_motion: bool,
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self {
            rate_hz: 50.0,
            resolution_deg: 0.5,
            fov_deg: 270.0,
            range_min: 0.5,
            range_max: 20.0,
            noise_sigma: 0.012,
            sweep_motion: true,
        }
    }
}

impl LaserConfig {
    /// Number of beams per scan (`fov / resolution + 1`).
    pub fn beams(&self) -> usize {
        (self.fov_deg / self.resolution_deg).round() as usize + 1
    }
}

/// Wheel encoders (ticks per revolution come from the robot config).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EncoderConfig {
    /// JointState rate (Hz).
    pub rate_hz: f64,
}

impl Default for EncoderConfig {
    fn default() -> Self {
        Self { rate_hz: 100.0 }
    }
}

/// A z-axis gyro (MPU9250-like).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GyroConfig {
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// White noise standard deviation (rad/s).
    pub noise_sigma: f64,
}

impl Default for GyroConfig {
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            noise_sigma: 0.002,
        }
    }
}

/// A LOAM-like reference trajectory of the base.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReferenceConfig {
    /// Pose rate (Hz).
    pub rate_hz: f64,
    /// Position noise standard deviation per axis (m).
    pub position_sigma: f64,
    /// Heading noise standard deviation (rad).
    pub heading_sigma: f64,
}

impl Default for ReferenceConfig {
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            position_sigma: 0.005,
            heading_sigma: 0.002,
        }
    }
}

impl SimConfig {
    /// Checks every value once; the simulation relies on it afterwards.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |m: String| Err(SimError::Config(m));
        let positive = [
            ("duration_s", self.duration_s),
            ("integration_hz", self.integration_hz),
            ("laser.rate_hz", self.laser.rate_hz),
            ("laser.resolution_deg", self.laser.resolution_deg),
            ("laser.fov_deg", self.laser.fov_deg),
            ("laser.range_max", self.laser.range_max),
            ("encoder.rate_hz", self.encoder.rate_hz),
            ("gyro.rate_hz", self.gyro.rate_hz),
            ("reference.rate_hz", self.reference.rate_hz),
            ("scenario.cruise_speed", self.scenario.cruise_speed),
            ("scenario.turn_rate", self.scenario.turn_rate),
            ("scenario.max_speed", self.scenario.max_speed),
            ("scenario.max_turn_rate", self.scenario.max_turn_rate),
            ("scenario.max_accel", self.scenario.max_accel),
            (
                "scenario.max_angular_accel",
                self.scenario.max_angular_accel,
            ),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} must be a positive number, got {v}"));
            }
        }
        let non_negative = [
            ("laser.range_min", self.laser.range_min),
            ("laser.noise_sigma", self.laser.noise_sigma),
            ("gyro.noise_sigma", self.gyro.noise_sigma),
            ("reference.position_sigma", self.reference.position_sigma),
            ("reference.heading_sigma", self.reference.heading_sigma),
            ("scenario.start_hold_s", self.scenario.start_hold_s),
            ("scenario.corner_pause_s", self.scenario.corner_pause_s),
            ("scenario.min_clearance", self.scenario.min_clearance),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} must be ≥ 0 and finite, got {v}"));
            }
        }
        if self.duration_s > 24.0 * 3600.0 {
            return bad(format!(
                "duration_s {} s is over the cap of one day (86400 s): a day of the \
                 default sensors already writes a 9 GB bag and a 1.2 GB truth file",
                self.duration_s
            ));
        }
        if self.integration_hz < 200.0 {
            return bad("integration_hz must be ≥ 200".into());
        }
        let s = &self.scenario;
        if s.cruise_speed > s.max_speed || s.turn_rate > s.max_turn_rate {
            return bad("cruise_speed/turn_rate must not exceed max_speed/max_turn_rate".into());
        }
        let l = &self.laser;
        if l.range_min >= l.range_max || l.fov_deg > 360.0 || l.beams() < 2 || l.beams() > 100_000 {
            return bad("laser: need range_min < range_max, fov ≤ 360°, 2..100000 beams".into());
        }
        if self.integration_hz < l.rate_hz.max(self.encoder.rate_hz).max(self.gyro.rate_hz) {
            return bad("integration_hz must be at least every sensor's rate".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_round_trips_through_json() {
        let c = SimConfig::default();
        c.validate().unwrap();
        assert_eq!(c.laser.beams(), 541);
        let back: SimConfig = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn bad_values_are_refused() {
        let c = SimConfig {
            duration_s: f64::NAN,
            ..Default::default()
        };
        assert!(c.validate().is_err());
        let mut c = SimConfig::default();
        c.laser.range_min = 30.0;
        assert!(c.validate().is_err());
        let mut c = SimConfig::default();
        c.scenario.cruise_speed = 2.0;
        assert!(c.validate().is_err());
        assert!(serde_json::from_str::<SimConfig>(r#"{"seeed": 3}"#).is_err());
    }

    #[test]
    fn scenario_json_names_a_world_or_carries_one() {
        let s = ScenarioSpec::from_json(
            r#"{"waypoints": [[1,1],[3,1]], "world": "hall", "stop_and_turn": true}"#,
        )
        .unwrap();
        assert_eq!(s.world, Some(WorldRef::Name("hall".into())));
        let s = ScenarioSpec::from_json(
            r#"{"waypoints": [[1,1],[3,1]], "world": {"segments": [[0,0,5,0]]}}"#,
        )
        .unwrap();
        assert!(matches!(s.world, Some(WorldRef::Map(_))));
        assert!(ScenarioSpec::from_json(r#"{"points": []}"#).is_err());
    }
}
