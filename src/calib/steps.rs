//! Alignment of the input streams into filter steps: one step per velocity
//! observation interval, with the wheel rates averaged over exactly that
//! interval (from interpolated wheel angles) and the gyro averaged over it.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::motion::VelocityObs;
use crate::recording::{GyroSample, WheelSample};
use serde::{Deserialize, Serialize};

/// Which body velocity a measurement observes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kind {
    /// Forward velocity V (m/s).
    V,
    /// Turn rate W (rad/s).
    W,
}

/// One scalar velocity measurement with its own standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// What it measures.
    pub kind: Kind,
    /// Measured value (m/s for V, rad/s for W).
    pub value: f64,
    /// Standard deviation, same unit as `value`. ∞ or NaN: the filters ignore
    /// the measurement; 0 is clamped to a floor by each filter.
    pub sigma: f64,
}

/// At most this many measurements per step (ICP V and W, gyro W, one spare).
pub const MAX_MEASUREMENTS: usize = 4;

/// One filter step over `[t0, t1]`: mean wheel rates and the measurements that
/// refer to the same interval (possibly none: predict only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibStep {
    /// Interval start (s).
    pub t0: f64,
    /// Interval end (s).
    pub t1: f64,
    /// Mean right wheel rate over the interval (rad/s).
    pub omega_right: f64,
    /// Mean left wheel rate over the interval (rad/s).
    pub omega_left: f64,
    len: u8,
    buf: [Measurement; MAX_MEASUREMENTS],
}

const EMPTY: Measurement = Measurement {
    kind: Kind::V,
    value: 0.0,
    sigma: f64::INFINITY,
};

impl CalibStep {
    /// A step without measurements (predict only).
    pub fn new(t0: f64, t1: f64, omega_right: f64, omega_left: f64) -> Self {
        Self {
            t0,
            t1,
            omega_right,
            omega_left,
            len: 0,
            buf: [EMPTY; MAX_MEASUREMENTS],
        }
    }

    /// Adds a measurement; returns `false` (and drops it) when the step is full.
    pub fn push(&mut self, m: Measurement) -> bool {
        if (self.len as usize) < MAX_MEASUREMENTS {
            self.buf[self.len as usize] = m;
            self.len += 1;
            true
        } else {
            false
        }
    }

    /// Builder form of [`CalibStep::push`].
    pub fn with(mut self, kind: Kind, value: f64, sigma: f64) -> Self {
        self.push(Measurement { kind, value, sigma });
        self
    }

    /// The measurements of this step.
    pub fn measurements(&self) -> &[Measurement] {
        &self.buf[..self.len as usize]
    }

    /// Interval length (s).
    pub fn dt(&self) -> f64 {
        self.t1 - self.t0
    }
}

/// Whether a measurement carries usable information (finite value, finite σ).
pub fn usable(m: &Measurement) -> bool {
    m.value.is_finite() && m.sigma.is_finite() && m.sigma >= 0.0
}

/// Longest predict-only step (s) used to fill gaps without observations.
pub const MAX_GAP_STEP: f64 = 0.1;

/// Builds the filter steps. Observations must be sorted by `t0`; those outside
/// the wheel samples' time span, with `t1 ≤ t0` or non-finite values are
/// dropped. Gaps between observations (and before the first / after the last)
/// become predict-only steps of at most [`MAX_GAP_STEP`], so the steps cover
/// the whole wheel stream. Each step gets the ICP `V`, `W` (with their σ) and,
/// where the gyro covers it, the mean gyro rate with σ = `gyro_sigma`/√k for k
/// samples inside (`gyro_sigma` is the per-sample σ, rad/s).
pub fn steps(
    obs: &[VelocityObs],
    wheels: &[WheelSample],
    gyro: &[GyroSample],
    gyro_sigma: f64,
) -> Vec<CalibStep> {
    let mut b = super::StepBuilder::new(true, gyro_sigma);
    wheels.iter().for_each(|w| b.push_wheel(*w));
    b.end_wheels();
    gyro.iter().for_each(|g| b.push_gyro(*g));
    b.end_gyro();
    obs.iter().for_each(|o| b.push_obs(*o));
    let mut out = Vec::with_capacity(obs.len() + 16);
    b.poll(true, &mut |s| out.push(s));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wheels() -> Vec<WheelSample> {
        // right turns at 2 rad/s, left at 1 rad/s, sampled at 10 Hz for 2 s.
        (0..=20)
            .map(|i| {
                let t = i as f64 * 0.1;
                WheelSample {
                    stamp: t,
                    left: t,
                    right: 2.0 * t,
                }
            })
            .collect()
    }

    #[test]
    fn rates_are_averaged_over_the_observation_interval() {
        let obs = [VelocityObs {
            t0: 0.25,
            t1: 0.87,
            v: 0.5,
            w: 0.1,
            sigma_v: 0.01,
            sigma_w: 0.02,
        }];
        let gyro: Vec<_> = (0..=200)
            .map(|i| GyroSample {
                stamp: i as f64 * 0.01,
                wz: i as f64 * 0.01, // wz = t
            })
            .collect();
        let s = steps(&obs, &wheels(), &gyro, 0.01);
        let o = s.iter().find(|s| s.t0 == 0.25).unwrap();
        assert!((o.omega_right - 2.0).abs() < 1e-12 && (o.omega_left - 1.0).abs() < 1e-12);
        let m = o.measurements();
        assert_eq!(m.len(), 3);
        let g = m[0];
        assert_eq!(g.kind, Kind::W);
        assert!((g.value - 0.56).abs() < 1e-12, "mean of t over [0.25,0.87]");
        let k = gyro
            .iter()
            .filter(|s| s.stamp > 0.25 && s.stamp < 0.87)
            .count();
        assert!((60..=63).contains(&k));
        assert!((g.sigma - 0.01 / (k as f64).sqrt()).abs() < 1e-12);
        assert_eq!(m[1].kind, Kind::V);
        // Steps tile the wheel span without overlap.
        assert_eq!(s.first().unwrap().t0, 0.0);
        assert_eq!(s.last().unwrap().t1, 2.0);
        for w in s.windows(2) {
            assert!((w[0].t1 - w[1].t0).abs() < 1e-12);
            assert!(w[0].dt() <= MAX_GAP_STEP + 1e-12 || w[0].t0 == 0.25);
        }
    }

    #[test]
    fn an_observation_without_a_forward_measurement_gives_only_its_turn_rate() {
        let obs = [VelocityObs {
            t0: 0.25,
            t1: 0.87,
            v: 0.5,
            w: 0.1,
            sigma_v: f64::INFINITY,
            sigma_w: 0.02,
        }];
        let s = steps(&obs, &wheels(), &[], 0.01);
        let m = s.iter().find(|s| s.t0 == 0.25).unwrap().measurements();
        assert_eq!(m.len(), 1);
        assert_eq!((m[0].kind, m[0].value, m[0].sigma), (Kind::W, 0.1, 0.02));
    }

    #[test]
    fn observations_outside_the_wheel_span_are_dropped() {
        let o = |t0, t1| VelocityObs {
            t0,
            t1,
            v: 0.0,
            w: 0.0,
            sigma_v: 1.0,
            sigma_w: 1.0,
        };
        let s = steps(
            &[o(-1.0, 0.1), o(1.9, 2.5), o(1.0, 1.0)],
            &wheels(),
            &[],
            0.01,
        );
        assert!(s.iter().all(|s| s.measurements().is_empty()));
        assert!(steps(&[o(0.0, 1.0)], &wheels()[..1], &[], 0.01).is_empty());
    }
}
