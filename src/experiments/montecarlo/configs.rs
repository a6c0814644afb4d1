//! The calibrator configurations the tables of \[Farina\] compare.

use crate::calib::{CalibParams, CountRule, Method, Preset, Scheme, Trigger};

/// False-alarm probability of the change detector in the radius-step
/// experiment, for every filter.
pub const CHANGING_FALSE_ALARM: f64 = 1e-4;

/// The fixed particle count [Farina, Fig. 5] compares the adaptive one with.
pub const FIG5_FIXED_PARTICLES: usize = 3000;

/// Label of the radius-step experiment's Adaptive-PF with its count held at
/// [`FIG5_FIXED_PARTICLES`].
pub fn fixed_count_label() -> String {
    format!(
        "{}, fixed N = {FIG5_FIXED_PARTICLES}",
        Method::AdaptivePf.as_str()
    )
}

/// The configurations of [Farina, Table II]: adaptive-pf, pf, dkf, akf,
/// none, and the Adaptive-PF as published (`PUBLISHED_LABEL`), so that
/// what odocal's departures from the paper buy is measured.
pub fn table2_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    let mut out: Vec<(String, CalibParams)> = Method::ALL
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
        .collect();
    out.push((
        PUBLISHED_LABEL.to_string(),
        CalibParams {
            method: Method::AdaptivePf,
            preset: Preset::Published,
            ..base.clone()
        },
    ));
    out
}

/// Label of the Adaptive-PF under `preset = "published"` in Table II.
pub const PUBLISHED_LABEL: &str = "adaptive-pf-published";

/// The configurations of [Farina, Table I]: the fixed PF with 4 schemes × 3 triggers.
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
/// PF has none, as in \[Farina\]); then `none`. Right after the Adaptive-PF
/// comes the same filter, detector and every other setting kept, with its
/// count fixed at [`FIG5_FIXED_PARTICLES`] (the baseline of [Farina, Fig. 5]).
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
            out.push((label, p.clone()));
            if m == Method::AdaptivePf && enabled {
                let mut q = CalibParams {
                    particles: Some(FIG5_FIXED_PARTICLES),
                    ..p
                };
                q.adaptive.rule = CountRule::Fixed;
                out.push((fixed_count_label(), q));
            }
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
