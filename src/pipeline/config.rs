//! The configuration file (`--config CFG.toml`) and robot file (`--robot`):
//! one table per stage, each the stage's own parameter struct with defaults.

use super::drive::MeasurementConfig;
use super::PipelineError;
use crate::calib::CalibParams;
use crate::diagnose::DiagnoseParams;
use crate::error::InputError;
use crate::eval::EvalOptions;
use crate::icp::IcpParams;
use crate::io::TopicConfig;
use crate::robot::RobotConfig;
use crate::sim::SimConfig;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Every stage's settings; a TOML file may give any subset of the tables.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// Topic names read from (and written to) ROS 2 bags.
    pub topics: TopicConfig,
    /// Simulator settings.
    pub sim: SimConfig,
    /// Scan matching settings.
    pub icp: IcpParams,
    /// Calibrator settings.
    pub calib: CalibParams,
    /// Which measurements feed the calibrator, and their σ.
    pub measurements: MeasurementConfig,
    /// Evaluation settings.
    pub eval: EvalOptions,
    /// Diagnosis settings.
    pub diagnose: DiagnoseParams,
    /// Fleet alarm thresholds.
    pub fleet: crate::fleet::FleetParams,
    /// `odocal live`: the network and its waits.
    pub live: crate::live::LiveParams,
}

fn read_text(path: &Path) -> Result<String, PipelineError> {
    crate::io::input::check_regular(path)?;
    std::fs::read_to_string(path).map_err(|e| {
        InputError::new(path.display().to_string(), format!("cannot read: {e}")).into()
    })
}

impl Config {
    /// Loads `path`, or the defaults when `None`. Unknown keys are refused.
    pub fn load(path: Option<&Path>) -> Result<Self, PipelineError> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        Self::parse(&read_text(path)?, &path.display().to_string())
    }

    /// Parses configuration text; `file` names it in errors, which give the
    /// line of the first problem. Unknown keys are refused.
    /// Every stage's settings are then validated once, so a bad value is
    /// refused here, naming the file, rather than turning into NaN later.
    pub fn parse(text: &str, file: &str) -> Result<Self, PipelineError> {
        let c: Self = toml::from_str(text).map_err(|e| {
            InputError::new(file, e.message().to_string()).at(span_position(text, e.span()))
        })?;
        c.validate()
            .map_err(|m| InputError::new(file, m).at("whole file"))?;
        Ok(c)
    }

    /// Checks every stage's settings; the message names the bad value.
    pub fn validate(&self) -> Result<(), String> {
        self.sim.validate().map_err(|e| e.to_string())?;
        self.icp.validate().map_err(|e| e.to_string())?;
        self.calib.validate().map_err(|e| e.to_string())?;
        self.diagnose.validate().map_err(|e| e.to_string())?;
        self.fleet.validate()?;
        self.live.validate()?;
        let m = &self.measurements;
        if !(m.gyro_sigma.is_finite() && m.gyro_sigma > 0.0) {
            return Err(format!(
                "measurements.gyro_sigma must be a positive rate in rad/s, got {}",
                m.gyro_sigma
            ));
        }
        let sync = &self.eval.sync;
        if !(sync.max_diff.is_finite() && sync.max_diff >= 0.0 && sync.offset.is_finite()) {
            return Err(format!(
                "eval.sync: max_diff must be ≥ 0 s and offset finite, got {} and {}",
                sync.max_diff, sync.offset
            ));
        }
        Ok(())
    }
}

/// Loads a robot file, or the wheelchair's kinematics (no laser mounting)
/// when `None` ([`super::Nominal::load`]).
pub fn load_robot(path: Option<&Path>) -> Result<RobotConfig, PipelineError> {
    Ok(super::Nominal::load(path)?.robot)
}

fn span_position(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    match span {
        Some(s) => format!(
            "line {}",
            text.as_bytes()[..s.start.min(text.len())]
                .split(|&b| b == b'\n')
                .count()
        ),
        None => "whole file".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_and_unknown_keys_fail_with_a_line() {
        let c = Config::default();
        let text = toml::to_string(&c).unwrap();
        assert_eq!(toml::from_str::<Config>(&text).unwrap(), c);
        let dir = std::env::temp_dir().join(format!("odocal-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.toml");
        std::fs::write(&p, "[topics]\nscan = \"/laser\"\n\n[icpp]\nx = 1\n").unwrap();
        let e = Config::load(Some(&p)).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("bad.toml"), "{e}");
        assert!(e.to_string().contains("line"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
