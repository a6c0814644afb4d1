//! The calibrator configurations seed 000's tables compare.

use crate::calib::{CalibParams, Method, Scheme, Trigger};

/// False-alarm probability of the change detector in the radius-step
/// experiment, for every filter.
pub const CHANGING_FALSE_ALARM: f64 = 1e-4;

/// Seed 000's Table II configurations: adaptive-pf, pf, dkf, akf, none.
pub fn table2_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    Method::ALL
        .iter()
        .map(|&m| {
            (
                m.as_str().to_string(),
                CalibParams {
                    method: m,
                    ..base.clone()
                },
            )
        })
        .collect()
}

/// Seed 000's Table I configurations: the fixed PF with 4 schemes × 3 triggers.
pub fn table1_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    let mut out = vec![];
    for s in Scheme::ALL {
        for t in Trigger::ALL {
            out.push((
                format!("{}/{}", s.as_str(), t.as_str()),
                CalibParams {
                    method: Method::Pf,
                    resampler: s,
                    trigger: t,
                    ..base.clone()
                },
            ));
        }
    }
    out
}

/// The radius-step experiment's configurations: every online filter with
/// the change detector (the same test for all three, at a false-alarm
/// probability of 1e-4 so that the Kalman filters' wider covariance does
/// not mute it) and, labelled `METHOD, no detector`, without it (the fixed
/// PF has none, as in seed 000); then `none`.
pub fn changing_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    let mut out = vec![];
    for m in [Method::AdaptivePf, Method::Dkf, Method::Akf] {
        for enabled in [true, false] {
            let mut p = CalibParams {
                method: m,
                ..base.clone()
            };
            p.change.enabled = enabled;
            p.change.kalman = enabled;
            p.change.false_alarm = CHANGING_FALSE_ALARM;
            let label = match enabled {
                true => m.as_str().to_string(),
                false => format!("{}, no detector", m.as_str()),
            };
            out.push((label, p));
        }
    }
    for m in [Method::Pf, Method::None] {
        out.push((
            m.as_str().to_string(),
            CalibParams {
                method: m,
                ..base.clone()
            },
        ));
    }
    out
}
