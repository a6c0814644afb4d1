//! KISS-ICP's adaptive correspondence threshold [Vizzo2023, eqs. 4–6],
//! in 2D: the deviation between the predicted (prior) and estimated motion of
//! every pair becomes a displacement bound; the running RMS of those bounds is
//! σ, and correspondences farther than 3σ are outliers.

use crate::geom::{xyt, Pose2};

/// Running estimate of how wrong the motion prior tends to be.
#[derive(Debug, Clone)]
pub struct AdaptiveThreshold {
    initial: f64,
    min: f64,
    max: f64,
    min_motion: f64,
    range: f64,
    sum_sq: f64,
    count: usize,
}

impl AdaptiveThreshold {
    /// `initial` gate (m) until a model error is seen, clamped to [`min`, `max`];
    /// deviations below `min_motion` (m) are ignored; `range` (m) is the lever
    /// arm that turns a rotation error into a point displacement.
    pub fn new(initial: f64, min: f64, max: f64, min_motion: f64, range: f64) -> Self {
        Self {
            initial,
            min,
            max,
            min_motion,
            range,
            sum_sq: 0.0,
            count: 0,
        }
    }

    /// Model error of one pair (eq. 5): translation error plus the chord a
    /// point at `range` moves through under the rotation error.
    pub fn model_error(&self, deviation: &Pose2) -> f64 {
        let [x, y, t] = xyt(deviation);
        (x * x + y * y).sqrt() + 2.0 * self.range * (t / 2.0).sin().abs()
    }

    /// Records the deviation `inv(predicted) ⊕ estimated` of a successful pair.
    pub fn update(&mut self, deviation: &Pose2) {
        let e = self.model_error(deviation);
        if e.is_finite() && e > self.min_motion {
            self.sum_sq += e * e;
            self.count += 1;
        }
    }

    /// Current correspondence gate 3σ (m), clamped.
    pub fn threshold(&self) -> f64 {
        let t = if self.count == 0 {
            self.initial
        } else {
            3.0 * (self.sum_sq / self.count as f64).sqrt()
        };
        t.clamp(self.min, self.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    #[test]
    fn gate_follows_the_rms_model_error() {
        let mut a = AdaptiveThreshold::new(1.0, 0.05, 2.0, 0.001, 5.0);
        assert_eq!(a.threshold(), 1.0);
        a.update(&pose(0.1, 0.0, 0.0));
        a.update(&pose(0.0, 0.0, 0.0)); // below min_motion: ignored
        assert!((a.threshold() - 0.3).abs() < 1e-12);
        a.update(&pose(0.0, 0.0, 0.02));
        let e = 2.0 * 5.0 * 0.01f64.sin();
        let want = 3.0 * ((0.01 + e * e) / 2.0f64).sqrt();
        assert!((a.threshold() - want).abs() < 1e-12);
        let mut b = AdaptiveThreshold::new(1.0, 0.2, 2.0, 0.001, 5.0);
        b.update(&pose(0.01, 0.0, 0.0));
        assert_eq!(b.threshold(), 0.2);
    }
}
