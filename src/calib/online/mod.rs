//! What the online filters are fed on a real robot: the scan matcher's
//! motions composed into intervals, each read against the wheels at the
//! current estimate of the time offset between the two clocks and moved into
//! the base frame with the current laser mounting.
//!
//! A robot stamps its scans late (a driver stamps on arrival), sits its
//! laser elsewhere than its description says, and starts from nominal wheel
//! values that may be far off. None of that is known before the stream, and
//! a robot running live has no whole recording to fit first. So the front
//! end fits the joint model of \[Censi2013\] (radii, wheel base, laser
//! mounting, time offset; [`crate::calib::batch`]) over a sliding window of
//! the stream: once after a warm-up, then every few seconds of new data, as
//! a sliding-window estimator of the clock offset does in visual-inertial
//! odometry \[Qin2018\]. The filters keep estimating the radii and the wheel
//! base themselves; the window gives them
//! - the time offset, by which every interval's wheel rates are read;
//! - the laser mounting, by which each laser displacement becomes a base
//!   motion (the stated one unless the data contradict it);
//! - where the filters start: the warm-up's estimate, so that nominal
//!   values 20 % off (or none at all) are found.
//!
//! `window` holds the window, `front` decides when to fit and turns
//! intervals into velocity observations, `report` says what was used.

mod front;
mod report;
mod velocity;
mod window;

pub use front::{FrontEnd, Mounted, Started};
pub use report::{LaserReport, OffsetReport, OnlineReport, Solve};
pub use velocity::{base_motion, velocity};
pub use window::GeometryWindow;

use serde::{Deserialize, Serialize};

/// How the laser mounting the filters use is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MountChoice {
    /// The stated mounting (recording or robot file) unless the window's
    /// estimate contradicts it; the estimate when none is stated.
    #[default]
    Check,
    /// The stated mounting, whatever the data say.
    Stated,
    /// The window's estimate, always.
    Estimate,
}

/// Settings of the online front end (`[calib.online]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnlineParams {
    /// Scan-to-scan motions are composed into velocity observations of at
    /// least this long (s) … (0: every matched pair is one observation).
    /// Over ~1 s the wheels' timing noise (stamp jitter, tick quantisation)
    /// is small against the motion; over one 0.1 s scan pair it is not, and
    /// noise in the wheel rates draws the radii towards zero (regression
    /// dilution).
    pub interval_s: f64,
    /// … or turning at least this much (rad).
    pub interval_rad: f64,
    /// The first fit of the window after this much of the stream (s).
    pub warmup_s: f64,
    /// Without a fit by then (s), the filters start from the nominal values,
    /// the stated mounting and a zero time offset (and later fits still
    /// correct the offset and the mounting).
    pub warmup_max_s: f64,
    /// Stream time (s) between failed warm-up fits (at least; the window
    /// must also have grown by a quarter).
    pub retry_s: f64,
    /// The window's length (s) once the first fit has succeeded (until
    /// then it grows from the stream's start).
    pub window_s: f64,
    /// Most intervals the window holds.
    pub max_intervals: usize,
    /// Stream time (s) between fits once started.
    pub resolve_s: f64,
    /// Estimate the time offset (else 0: one clock).
    pub time_offset: bool,
    /// How the mounting is chosen.
    pub mount: MountChoice,
    /// A stated mounting is contradicted when its χ² against the window's
    /// estimate exceeds the χ²₃ quantile of `1 −` this.
    pub mount_probability: f64,
    /// Half-width of the particle filters' initial search around the
    /// warm-up's estimate, relative to it.
    pub search_warm: f64,
    /// Half-width around the nominal values when no warm-up fit was had.
    pub search_nominal: f64,
}

impl Default for OnlineParams {
    fn default() -> Self {
        Self {
            interval_s: 1.0,
            interval_rad: 0.3,
            warmup_s: 20.0,
            warmup_max_s: 90.0,
            retry_s: 3.0,
            window_s: 120.0,
            max_intervals: 3000,
            resolve_s: 15.0,
            time_offset: true,
            mount: MountChoice::Check,
            mount_probability: 1e-3,
            search_warm: 0.1,
            search_nominal: 0.2,
        }
    }
}

impl OnlineParams {
    /// Checks ranges; the message names the bad field.
    pub fn validate(&self) -> Result<(), String> {
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        let pos = |x: f64| x.is_finite() && x > 0.0;
        if !(nonneg(self.interval_s) && pos(self.interval_rad)) {
            return Err("online.interval_s must be ≥ 0 and online.interval_rad > 0".into());
        }
        if !(nonneg(self.warmup_s)
            && self.warmup_max_s.is_finite()
            && self.warmup_max_s >= self.warmup_s)
        {
            return Err("online.warmup_s must be ≥ 0 and ≤ online.warmup_max_s".into());
        }
        if !(pos(self.retry_s) && pos(self.window_s) && pos(self.resolve_s)) {
            return Err("online.retry_s, window_s and resolve_s must be > 0 s".into());
        }
        if self.max_intervals < 10 {
            return Err("online.max_intervals must be at least 10".into());
        }
        if !(self.mount_probability > 0.0 && self.mount_probability < 1.0) {
            return Err("online.mount_probability must be in (0, 1)".into());
        }
        let frac = |x: f64| x.is_finite() && x > 0.0 && x < 1.0;
        if !(frac(self.search_warm) && frac(self.search_nominal)) {
            return Err("online.search_warm and search_nominal must be in (0, 1)".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_setting_out_of_range_is_refused_by_name() {
        assert_eq!(OnlineParams::default().validate(), Ok(()));
        let bad = |f: fn(&mut OnlineParams)| {
            let mut p = OnlineParams::default();
            f(&mut p);
            p.validate().unwrap_err()
        };
        let interval = "online.interval_s must be ≥ 0 and online.interval_rad > 0";
        assert_eq!(bad(|p| p.interval_s = -0.1), interval);
        assert_eq!(bad(|p| p.interval_s = f64::NAN), interval);
        assert_eq!(bad(|p| p.interval_rad = 0.0), interval);
        let warmup = "online.warmup_s must be ≥ 0 and ≤ online.warmup_max_s";
        assert_eq!(bad(|p| p.warmup_s = -1.0), warmup);
        assert_eq!(bad(|p| p.warmup_max_s = 19.0), warmup);
        assert_eq!(bad(|p| p.warmup_max_s = f64::INFINITY), warmup);
        let times = "online.retry_s, window_s and resolve_s must be > 0 s";
        assert_eq!(bad(|p| p.retry_s = 0.0), times);
        assert_eq!(bad(|p| p.window_s = 0.0), times);
        assert_eq!(bad(|p| p.resolve_s = -1.0), times);
        assert_eq!(
            bad(|p| p.max_intervals = 9),
            "online.max_intervals must be at least 10"
        );
        let prob = "online.mount_probability must be in (0, 1)";
        assert_eq!(bad(|p| p.mount_probability = 0.0), prob);
        assert_eq!(bad(|p| p.mount_probability = 1.0), prob);
        let search = "online.search_warm and search_nominal must be in (0, 1)";
        assert_eq!(bad(|p| p.search_warm = 0.0), search);
        assert_eq!(bad(|p| p.search_nominal = 1.0), search);
        assert_eq!(bad(|p| p.search_warm = f64::NAN), search);
        // On the edges that are allowed.
        let mut edge = OnlineParams {
            interval_s: 0.0,
            warmup_s: 0.0,
            max_intervals: 10,
            ..OnlineParams::default()
        };
        assert_eq!(edge.validate(), Ok(()));
        edge.warmup_s = edge.warmup_max_s;
        assert_eq!(edge.validate(), Ok(()));
    }
}
