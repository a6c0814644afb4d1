//! How much better the extended model predicts the held-out part than the
//! nominal one: σ-normalised and per-stream RMSE, and the trajectory error
//! against a reference.

use super::data::{Part, GROUPS};
use super::trajectory::{trajectory_gain, TrajectoryGain};
use crate::effects::Departures;
use crate::recording::StampedPose;
use serde::Serialize;
use std::collections::BTreeMap;

/// Held-out RMSE of one stream before/after, in its physical unit (m/s, rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StreamGain {
    /// Held-out rows.
    pub n: usize,
    /// RMSE with the nominal model.
    pub before: f64,
    /// RMSE with the extended model.
    pub after: f64,
}

/// Prediction gain on the held-out part (design.md JSON keys). The RMSE is
/// of σ-normalised residuals (each stream divided by its measurement σ times
/// the stream's noise scale fitted on the training part), pooled over streams.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gain {
    /// Normalised RMSE with the nominal model.
    pub heldout_rmse_before: f64,
    /// Normalised RMSE with the extended model.
    pub heldout_rmse_after: f64,
    /// (before − after) / before.
    pub relative: f64,
    /// Per-stream RMSE in physical units.
    pub streams: BTreeMap<String, StreamGain>,
    /// Relative-pose error against the reference on the held-out part
    /// (absent without a reference).
    pub trajectory: Option<TrajectoryGain>,
}

/// The gain of `after` over the nominal model on the `held` part, the
/// normalised residuals divided by the training noise `scale` per stream;
/// the trajectory error is over windows of `window` s from `split` on.
pub fn heldout_gain(
    held: Part,
    reference: &[StampedPose],
    after: &Departures,
    scale: &[f64; 4],
    split: f64,
    window: f64,
) -> Gain {
    let nominal = Departures::default();
    let mut eb: [Vec<f64>; 4] = Default::default();
    let mut ea: [Vec<f64>; 4] = Default::default();
    held.normalised(&nominal, &mut eb);
    held.normalised(after, &mut ea);
    let (rb, ra) = (pooled(&eb, scale), pooled(&ea, scale));
    let pb = held.physical(&nominal);
    let pa = held.physical(after);
    let streams = (0..4)
        .filter(|g| !pb[*g].is_empty())
        .map(|g| {
            (
                GROUPS[g].to_string(),
                StreamGain {
                    n: pb[g].len(),
                    before: rms(&pb[g]),
                    after: rms(&pa[g]),
                },
            )
        })
        .collect();
    Gain {
        heldout_rmse_before: rb,
        heldout_rmse_after: ra,
        relative: if rb > 0.0 { (rb - ra) / rb } else { 0.0 },
        streams,
        trajectory: trajectory_gain(held.replay, reference, &nominal, after, split, window),
    }
}

/// RMS of normalised residuals divided by their stream's `scale`, pooled
/// over the streams.
fn pooled(e: &[Vec<f64>; 4], scale: &[f64; 4]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for g in 0..4 {
        s += e[g].iter().map(|v| (v / scale[g]).powi(2)).sum::<f64>();
        n += e[g].len();
    }
    (s / n.max(1) as f64).sqrt()
}

/// Root mean square (0 for an empty series).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}
