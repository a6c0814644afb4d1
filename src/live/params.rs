//! `[live]`: how `odocal live` joins the network and how long it waits.

use serde::{Deserialize, Serialize};

/// Settings of a live run (`[live]` in the configuration file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiveParams {
    /// The DDS domain; unset: `$ROS_DOMAIN_ID`, else 0.
    pub domain_id: Option<u16>,
    /// Talk over 127.0.0.1 only (also when `$ROS_LOCALHOST_ONLY` is 1 or
    /// `$ROS_AUTOMATIC_DISCOVERY_RANGE` is `LOCALHOST`).
    pub localhost_only: bool,
    /// Messages held between the network and the calibration; a message
    /// arriving when it is full is dropped and counted (memory stays flat
    /// when the calibration falls behind).
    pub queue: usize,
    /// Largest message accepted (bytes); a larger one is refused and counted.
    pub max_message_bytes: usize,
    /// How long to wait for the first scans and wheel messages (s); 0 waits
    /// until stopped.
    pub wait_s: f64,
    /// Once scans and wheels flow, how long the static transforms and the
    /// gyro are given to arrive before the run starts without them (s).
    pub settle_s: f64,
    /// A stream silent this long (s) while the scans go on is reported in
    /// the status; the gyro is then left out for the rest of the run, and
    /// scans beyond the wheels' last sample by more than this are dropped
    /// (their motion has no wheel data to compare with).
    pub silence_s: f64,
    /// Diagnostics published per second (at least 1).
    pub diagnostics_hz: f64,
    /// Parent frame of the published odometry.
    pub odom_frame: String,
    /// Child frame of the published odometry.
    pub base_frame: String,
    /// A radius or wheel base whose std exceeds this fraction of its value
    /// leaves the status at WARN ("not converged").
    pub converged_rel_std: f64,
}

impl Default for LiveParams {
    fn default() -> Self {
        Self {
            domain_id: None,
            localhost_only: false,
            queue: 4096,
            max_message_bytes: 8 << 20,
            wait_s: 0.0,
            settle_s: 1.0,
            silence_s: 3.0,
            diagnostics_hz: 1.0,
            odom_frame: "odom".into(),
            base_frame: "base_link".into(),
            converged_rel_std: 0.005,
        }
    }
}

impl LiveParams {
    /// Checks the values; the message names the bad one.
    pub fn validate(&self) -> Result<(), String> {
        if let Some(d) = self.domain_id.filter(|d| *d > 232) {
            return Err(format!(
                "live.domain_id must be a ROS 2 domain (0 to 232), got {d}"
            ));
        }
        if self.queue == 0 {
            return Err("live.queue must be at least 1 message".into());
        }
        if self.max_message_bytes < 64 {
            return Err(format!(
                "live.max_message_bytes must be at least 64, got {}",
                self.max_message_bytes
            ));
        }
        for (name, v) in [
            ("wait_s", self.wait_s),
            ("settle_s", self.settle_s),
            ("silence_s", self.silence_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("live.{name} must be ≥ 0 s, got {v}"));
            }
        }
        if !(self.diagnostics_hz.is_finite() && self.diagnostics_hz >= 1.0) {
            return Err(format!(
                "live.diagnostics_hz must be at least 1, got {}",
                self.diagnostics_hz
            ));
        }
        if !(self.converged_rel_std.is_finite() && self.converged_rel_std > 0.0) {
            return Err(format!(
                "live.converged_rel_std must be positive, got {}",
                self.converged_rel_std
            ));
        }
        Ok(())
    }

    /// The domain: the configured one, else `$ROS_DOMAIN_ID` (`env`), else
    /// 0; a `$ROS_DOMAIN_ID` that is no domain id is an error naming it.
    pub fn domain(&self, env: Option<&str>) -> Result<u16, String> {
        if let Some(d) = self.domain_id {
            return Ok(d);
        }
        match env.map(str::trim).filter(|s| !s.is_empty()) {
            None => Ok(0),
            Some(s) => s.parse::<u16>().ok().filter(|d| *d <= 232).ok_or_else(|| {
                format!("ROS_DOMAIN_ID={s:?} is not a domain id (0 to 232); unset it or set [live] domain_id")
            }),
        }
    }

    /// Whether to stay on 127.0.0.1: configured, or as the ROS 2
    /// environment variables say (`localhost_only`, `discovery_range`).
    pub fn localhost(&self, localhost_only: Option<&str>, discovery_range: Option<&str>) -> bool {
        self.localhost_only
            || localhost_only.is_some_and(|v| v.trim() == "1")
            || discovery_range.is_some_and(|v| v.trim().eq_ignore_ascii_case("LOCALHOST"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_domain_comes_from_the_file_then_the_environment() {
        let mut p = LiveParams::default();
        assert_eq!(p.domain(None), Ok(0));
        assert_eq!(p.domain(Some("42")), Ok(42));
        assert!(p
            .domain(Some("zero"))
            .unwrap_err()
            .contains("ROS_DOMAIN_ID"));
        assert!(p.domain(Some("300")).is_err());
        p.domain_id = Some(7);
        assert_eq!(p.domain(Some("42")), Ok(7));
        assert!(!p.localhost(None, None));
        assert!(p.localhost(Some("1"), None));
        assert!(!p.localhost(Some("0"), Some("SUBNET")));
        assert!(p.localhost(None, Some("localhost")));
    }

    #[test]
    fn bad_values_are_refused_by_name() {
        let p = LiveParams {
            silence_s: -1.0,
            ..LiveParams::default()
        };
        assert!(p.validate().unwrap_err().contains("silence_s"));
        let p = LiveParams {
            diagnostics_hz: 0.5,
            ..LiveParams::default()
        };
        assert!(p.validate().unwrap_err().contains("diagnostics_hz"));
        let p = LiveParams {
            domain_id: Some(233),
            ..LiveParams::default()
        };
        assert!(p.validate().unwrap_err().contains("domain_id"));
        assert!(LiveParams::default().validate().is_ok());
    }
}
