//! One step's measurements of each velocity fused into one, for the
//! particle filters' likelihood and every filter's change detector.
//!
//! A step may carry several measurements of the same velocity (ICP's W and
//! the gyro's W). Their own errors are independent, so they are combined by
//! their precisions; the velocity model's error (encoder quantisation, slip)
//! is one error shared by all of them and is added once, to the fused value.
//! Adding it to each measurement instead would count it as independent
//! evidence once per measurement: with ICP and gyro both measuring W, W's
//! precision came out up to twice what the data support.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::robust::student_t_weight;
use super::steps::{usable, CalibStep, Kind};

/// A fused velocity measurement: value and the variance of its measurement
/// error alone (the model's variance not included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fused {
    /// Inverse-variance mean of the measurements (m/s or rad/s).
    pub value: f64,
    /// `1 / Σ_j t_j/σ_j²` (squared unit of `value`).
    pub var: f64,
}

/// How to weigh the measurements against the filter's prediction.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Prediction {
    /// Predicted (V, W) at the filter's mean.
    pub value: [f64; 2],
    /// Variance of the prediction from the parameters' spread.
    pub var: [f64; 2],
    /// Variance of the velocity model itself (added once per velocity).
    pub model_var: [f64; 2],
}

/// Fuses the step's usable measurements per velocity (index 0 = V, 1 = W):
/// each σ floored at `floor`, its precision scaled by its Student-t weight
/// `t_j` (ν = `dof`, [`student_t_weight`]): the innovation against the
/// prediction, with the model's variance added to the measurement's and the
/// parameter spread as the prior's.
pub(crate) fn fuse(s: &CalibStep, pred: &Prediction, floor: f64, dof: f64) -> [Option<Fused>; 2] {
    let mut acc = [[0.0f64; 2]; 2];
    for m in s.measurements().iter().filter(|m| usable(m)) {
        let k = match m.kind {
            Kind::V => 0,
            Kind::W => 1,
        };
        let r = m.sigma.max(floor).powi(2);
        let nu = m.value - pred.value[k];
        let t = student_t_weight(nu, r + pred.model_var[k], pred.var[k], dof);
        acc[k][0] += t / r;
        acc[k][1] += t / r * m.value;
    }
    acc.map(|[p, pz]| {
        (p > 0.0 && p.is_finite()).then(|| Fused {
            value: pz / p,
            var: 1.0 / p,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_measurements_of_one_velocity_combine_by_precision_without_the_model() {
        // Hand-computed: W = 0.10 ± 0.01 and W = 0.13 ± 0.02 combine to
        // (0.10/1e-4 + 0.13/4e-4)/(1/1e-4 + 1/4e-4) = 0.106 with variance
        // 1/(1e4 + 2.5e3) = 8e-5; V alone keeps its own σ² (floored).
        let s = CalibStep::new(0.0, 0.02, 3.0, 3.0)
            .with(Kind::W, 0.10, 0.01)
            .with(Kind::V, 0.9, 0.0)
            .with(Kind::W, 0.13, 0.02);
        let pred = Prediction {
            value: [0.9, 0.1],
            var: [0.0; 2],
            model_var: [1e-4; 2],
        };
        let [v, w] = fuse(&s, &pred, 1e-3, 0.0);
        let w = w.unwrap();
        assert!((w.value - 0.106).abs() < 1e-12 && (w.var - 8e-5).abs() < 1e-15);
        let v = v.unwrap();
        assert!((v.value - 0.9).abs() < 1e-15 && (v.var - 1e-6).abs() < 1e-18);
        // No measurement of a velocity: nothing fused.
        let only_v = CalibStep::new(0.0, 0.02, 3.0, 3.0).with(Kind::V, 1.0, 0.05);
        assert!(fuse(&only_v, &pred, 1e-3, 0.0)[1].is_none());
    }

    #[test]
    fn the_weight_reads_the_innovation_against_every_variance() {
        // ν = 0.4 rad/s, noise σ² + model = 1e-4 + 2e-4 = 3e-4, prior
        // (prediction) 3e-4: the variational fixed point, found by bisection
        // (one sign change on (0, 1]), is t = 0.00946304; the inlier (ν = 0)
        // keeps t = 1.
        let s = CalibStep::new(0.0, 0.02, 3.0, 3.0)
            .with(Kind::W, 0.10, 0.01)
            .with(Kind::W, 0.50, 0.01);
        let pred = Prediction {
            value: [0.0, 0.1],
            var: [0.0, 3e-4],
            model_var: [2e-4; 2],
        };
        let w = fuse(&s, &pred, 1e-3, 4.0)[1].unwrap();
        let t = 0.009_463_038;
        assert!((w.value - (0.10 + t * 0.50) / (1.0 + t)).abs() < 1e-9);
        assert!((w.var - 1e-4 / (1.0 + t)).abs() < 1e-13);
    }

    #[test]
    fn an_outlier_loses_weight_against_the_prediction() {
        // ν = 1 rad/s against S ≈ 1e-4 + 1e-4: the Student-t weight
        // (4+1)/(4+5000) leaves the fused value near the inlier.
        let s = CalibStep::new(0.0, 0.02, 3.0, 3.0)
            .with(Kind::W, 0.10, 0.01)
            .with(Kind::W, 1.10, 0.01);
        let pred = Prediction {
            value: [0.0, 0.1],
            var: [0.0; 2],
            model_var: [1e-4; 2],
        };
        let w = fuse(&s, &pred, 1e-3, 4.0)[1].unwrap();
        let t = 5.0 / (4.0 + 1.0 / 2e-4);
        assert!((w.value - (0.10 + t * 1.10) / (1.0 + t)).abs() < 1e-12);
    }
}
