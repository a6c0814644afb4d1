//! What the online front end used and found, as `calibrate` reports it:
//! the time offset with its std and when it settled, the laser mounting and
//! where it came from, where the filters started, and each fit of the window.

use crate::calib::batch::Valued;
use crate::robot::DiffDrive;
use serde::Serialize;

/// One fit of the window.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Solve {
    /// Stream time of the fit (s, laser clock): the end of its last interval.
    pub t: f64,
    /// Intervals in the window.
    pub intervals: usize,
    /// The time offset found (s), if estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_offset: Option<Valued>,
    /// The mounting found `[x m, y m, yaw rad]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laser: Option<[f64; 3]>,
    /// The kinematics found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kinematics: Option<DiffDrive>,
    /// How much larger than the scan matcher's σ's its residuals were, per
    /// `[x, y, θ]` of the laser (the factors every interval's covariance is
    /// scaled by until the next fit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_scale: Option<[f64; 3]>,
    /// Why the fit gave nothing, if it did not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
}

/// The time offset the filters read the wheels at (JSON `time_offset`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OffsetReport {
    /// Wheel stamp minus laser stamp of one instant (s), at the last fit.
    pub value: f64,
    /// Its std (s).
    pub std: f64,
    /// Stream time (s) of the first fit from which every fit lies within
    /// twice the last fit's std (and 1 ms) of the last value; `None` when
    /// only the last fit does.
    pub converged_s: Option<f64>,
    /// `estimated`, or `default` (0, not estimated).
    pub source: &'static str,
}

/// The laser mounting the filters used at the end (JSON `laser`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaserReport {
    /// Forward offset (m), with the window's std when estimated.
    pub x: Valued,
    /// Left offset (m).
    pub y: Valued,
    /// Yaw (rad).
    pub yaw: Valued,
    /// `estimated`, or the stated mounting's source (it was kept).
    pub source: String,
    /// What the data said of the stated mounting, when one was stated and
    /// the window was fitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<String>,
    /// Whether the last fit contradicted the stated mounting (its χ² beyond
    /// the limit), whether or not the estimate was then used.
    pub contradicted: bool,
}

/// What the online front end did (flattened into `calibrate`'s JSON).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OnlineReport {
    /// The route the observations took, in words.
    pub route: String,
    /// The time offset.
    pub time_offset: OffsetReport,
    /// The laser mounting.
    pub laser: LaserReport,
    /// Where the filters started: the warm-up's estimate (or the nominal
    /// values) and the stream time it was had at.
    pub warmup: Option<WarmupReport>,
    /// Every fit of the window.
    pub solves: Vec<Solve>,
}

/// Where the filters started.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WarmupReport {
    /// Stream time (s) at which the filters started.
    pub t: f64,
    /// `warm-up` (the window's estimate) or `nominal`.
    pub from: &'static str,
    /// The centre of the filters' initial belief.
    pub centre: DiffDrive,
    /// The half-width of their initial search, relative to the centre.
    pub search: f64,
}

impl OffsetReport {
    /// The report of a series of fits' offsets `(t, value, std)`, the last
    /// being the one in use.
    pub fn of(fits: &[(f64, Valued)]) -> Option<Self> {
        let &(_, last) = fits.last()?;
        let tol = 2.0 * last.std + 1e-3;
        let first_settled = (0..fits.len())
            .find(|&k| {
                fits[k..]
                    .iter()
                    .all(|(_, v)| (v.value - last.value).abs() <= tol)
            })
            .filter(|&k| k + 1 < fits.len() || fits.len() == 1);
        Some(Self {
            value: last.value,
            std: last.std,
            converged_s: first_settled.map(|k| fits[k].0),
            source: "estimated",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offset_settles_at_the_first_fit_that_stays_near_the_last() {
        let v = |value: f64, std: f64| Valued { value, std };
        let fits = [
            (20.0, v(-0.30, 0.05)),
            (35.0, v(-0.17, 0.01)),
            (50.0, v(-0.30, 0.01)),
            (65.0, v(-0.182, 0.004)),
            (80.0, v(-0.180, 0.004)),
        ];
        let r = OffsetReport::of(&fits).unwrap();
        assert_eq!((r.value, r.std), (-0.180, 0.004));
        // Within 2·0.004 + 0.001 = 9 ms of −0.180 from 65 s on.
        assert_eq!(r.converged_s, Some(65.0));
        // Only the last fit near it: not settled.
        let late = [(20.0, v(0.0, 0.01)), (35.0, v(-0.18, 0.004))];
        assert_eq!(OffsetReport::of(&late).unwrap().converged_s, None);
        assert!(OffsetReport::of(&[]).is_none());
        // The tolerance is twice the last std plus 1 ms: 8.5 ms off a last
        // fit of std 4 ms is within it (9 ms), so the first fit has settled.
        let edge = [(20.0, v(-0.1715, 0.01)), (35.0, v(-0.180, 0.004))];
        assert_eq!(OffsetReport::of(&edge).unwrap().converged_s, Some(20.0));
    }
}
