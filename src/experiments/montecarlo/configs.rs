//! The calibrator configurations seed 000's tables compare.

use crate::calib::{CalibParams, Method, Scheme, Trigger};

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
