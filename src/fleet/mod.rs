//! Fleet calibration's math: one calibration per
//! recording, then per robot a time series of each parameter with its
//! uncertainty, and the alarms it supports — a slow trend (tyre wear: a
//! regression of radius on time with its confidence), a step between
//! recordings (a new user, a repair: a change-point beyond the recordings'
//! combined uncertainty), a wiring or mounting fault (a laser mounting the
//! scans contradict in `min_side` consecutive recordings: a knocked laser)
//! and a recording that cannot support calibration (what the
//! single-recording checks refuse).
//! No files here: `pipeline::fleet` reads, caches and writes.

mod analyse;
pub mod series;

pub use analyse::{analyse_robot, RobotAnalysis, Step, Trend};

use crate::robot::DiffDrive;
use serde::{Deserialize, Serialize};

/// Thresholds of the fleet's alarms (TOML table `[fleet]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FleetParams {
    /// A step is reported when it lowers the series' χ² (scaled by the
    /// Birge ratio) by more than this: 25 is a 5σ change for one extra
    /// coefficient.
    pub step_chi2: f64,
    /// Smallest step reported (m).
    pub min_step_m: f64,
    /// A radius trend is reported as wear when its rate is this many std
    /// from zero.
    pub wear_sigma: f64,
    /// Smallest wear rate reported (m/day).
    pub min_wear_m_per_day: f64,
    /// Fewest calibrated recordings a trend or a step is judged on.
    pub min_recordings: usize,
    /// Fewest calibrated recordings on each side of a step, and in a run of
    /// recordings whose stated laser mounting the scans contradict for that
    /// run to be a fault.
    pub min_side: usize,
    /// At most this many steps per parameter and robot.
    pub max_steps: usize,
}

impl Default for FleetParams {
    fn default() -> Self {
        Self {
            step_chi2: 25.0,
            min_step_m: 5e-4,
            wear_sigma: 4.0,
            min_wear_m_per_day: 1e-5,
            min_recordings: 4,
            min_side: 2,
            max_steps: 3,
        }
    }
}

impl FleetParams {
    /// Checks the thresholds; the message names the bad value.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("step_chi2", self.step_chi2),
            ("wear_sigma", self.wear_sigma),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("fleet.{name} must be a positive number, got {v}"));
            }
        }
        for (name, v) in [
            ("min_step_m", self.min_step_m),
            ("min_wear_m_per_day", self.min_wear_m_per_day),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("fleet.{name} must be ≥ 0, got {v}"));
            }
        }
        if self.min_side == 0 || self.min_recordings < 3 {
            return Err(format!(
                "fleet.min_side must be ≥ 1 and fleet.min_recordings ≥ 3 (a rate needs a \
                 degree of freedom), got {} and {}",
                self.min_side, self.min_recordings
            ));
        }
        Ok(())
    }
}

/// Why a recording gave no calibration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Refusal {
    /// The wheels' wiring or the estimate's plausibility check failed.
    Fault,
    /// The data cannot support calibration (too little motion, unreadable).
    Insufficient,
}

/// What one recording gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "lowercase")]
pub enum Outcome {
    /// A calibration.
    Calibrated {
        /// The estimate (m).
        #[serde(rename = "final")]
        params: DiffDrive,
        /// Its std (m).
        std: DiffDrive,
        /// What the scans said of the recording's stated laser mounting when
        /// they contradicted it (the online front end's check); `None` when
        /// it was consistent, estimated or not checked.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mounting: Option<String>,
    },
    /// A refusal, with the single-recording check's message.
    Refused {
        /// Fault or insufficient data.
        kind: Refusal,
        /// The message the calibration refused with.
        message: String,
    },
}

/// One recording of a robot, placed in time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// The recording (path as given).
    pub recording: String,
    /// When it started (days since the fleet's epoch).
    pub day: f64,
    /// What its calibration gave.
    #[serde(flatten)]
    pub outcome: Outcome,
}

/// What an alarm is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AlarmKind {
    /// A radius trend over days.
    Wear,
    /// A change between recordings.
    Step,
    /// A wiring or mounting fault, or an implausible estimate.
    Fault,
    /// A recording that cannot support calibration.
    Insufficient,
}

impl AlarmKind {
    /// The word used in tables and JSON.
    pub fn word(self) -> &'static str {
        match self {
            Self::Wear => "wear",
            Self::Step => "step",
            Self::Fault => "fault",
            Self::Insufficient => "insufficient",
        }
    }
}

/// An alarm with its evidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alarm {
    /// The robot.
    pub robot: String,
    /// What it is.
    pub kind: AlarmKind,
    /// The day it starts (a step: the first recording after it; wear: the
    /// last recording of the trend).
    pub day: f64,
    /// The recording at that day.
    pub recording: String,
    /// The evidence in words (rates ± std, the step, the check that failed).
    pub evidence: String,
    /// The evidence's numbers by name (m, m/day, counts).
    pub values: std::collections::BTreeMap<String, f64>,
}

/// How much the recordings' std are off, per parameter (`[r_right, r_left,
/// wheel_base]`): the square root of the median (the upper one of an even count), over the robots with
/// `min_recordings` calibrations, of the reduced χ² of each robot's fit
/// (trend and steps) with the std as reported. The filters' std are a
/// spread of their posterior, not the scatter between recordings; the
/// fleet measures that scatter on itself, the median keeping a robot with
/// an event from widening everyone's. `[1, 1, 1]` without such robots;
/// each factor is kept within [0.1, 10].
pub fn std_factors(robots: &[(String, Vec<Entry>)], p: &FleetParams) -> [f64; 3] {
    let mut factors = [1.0; 3];
    for (k, name) in analyse::PARAMETERS.iter().enumerate() {
        let mut chi2: Vec<f64> = robots
            .iter()
            .map(|(r, e)| analyse_robot(r, e, p, [1.0; 3]))
            .filter_map(|a| {
                a.trends
                    .into_iter()
                    .find(|t| t.parameter == *name)?
                    .reduced_chi2
            })
            .filter(|c| c.is_finite())
            .collect();
        if chi2.is_empty() {
            continue;
        }
        let median = crate::diagnose::stats::median(&mut chi2);
        factors[k] = median.sqrt().clamp(0.1, 10.0);
    }
    factors
}

/// The fleet analysed: the std factors ([`std_factors`]) and every robot.
pub fn analyse_fleet(
    robots: &[(String, Vec<Entry>)],
    p: &FleetParams,
) -> ([f64; 3], Vec<RobotAnalysis>) {
    let f = std_factors(robots, p);
    let all = robots
        .iter()
        .map(|(r, e)| analyse_robot(r, e, p, f))
        .collect();
    (f, all)
}
