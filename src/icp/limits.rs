//! The robot's speed and turn-rate limits: whether a motion could have been
//! driven in the time it took. The plausibility gate of every match, and the
//! check of motions read from a file.

use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// Largest plausible speed and turn rate, with slacks. Units: m, rad, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpeedLimits {
    /// Largest plausible speed (m/s).
    pub max_speed: f64,
    /// Largest plausible turn rate (rad/s).
    pub max_turn_rate: f64,
    /// Slack on `max_speed` × dt beyond 3σ of the motion (m).
    pub speed_slack: f64,
    /// Slack on `max_turn_rate` × dt beyond 3σ of the motion (rad).
    pub turn_slack: f64,
}

impl Default for SpeedLimits {
    fn default() -> Self {
        Self {
            max_speed: 3.0,
            max_turn_rate: 3.0,
            speed_slack: 0.01,
            turn_slack: 0.01,
        }
    }
}

impl SpeedLimits {
    /// Whether a motion (dx, dy, dθ in m, m, rad) over `dt` s is within the
    /// limits, allowing 3σ of its covariance `cov` (x, y pooled) plus the
    /// slacks.
    pub fn within(&self, motion: [f64; 3], cov: &Matrix3<f64>, dt: f64) -> bool {
        let [x, y, th] = motion;
        let st = (cov[(0, 0)] + cov[(1, 1)]).max(0.0).sqrt();
        let sr = cov[(2, 2)].max(0.0).sqrt();
        (x * x + y * y).sqrt() <= self.max_speed * dt + 3.0 * st + self.speed_slack
            && th.abs() <= self.max_turn_rate * dt + 3.0 * sr + self.turn_slack
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_turn_rate_and_covariance_widen_the_gate() {
        let l = SpeedLimits::default();
        let zero = Matrix3::zeros();
        // 3 m/s over 0.1 s is 0.3 m, plus 1 cm of slack.
        assert!(l.within([0.3, 0.0, 0.0], &zero, 0.1));
        assert!(l.within([0.0, 0.309, 0.0], &zero, 0.1));
        assert!(!l.within([0.32, 0.0, 0.0], &zero, 0.1));
        assert!(!l.within([0.0, 0.0, 0.32], &zero, 0.1));
        assert!(l.within([0.0, 0.0, -0.3], &zero, 0.1));
        // σ = 1 cm in x and y pooled (√2 cm): 3σ more.
        let cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 1e-4, 0.0));
        assert!(l.within([0.35, 0.0, 0.0], &cov, 0.1));
        // NaN never passes.
        assert!(!l.within([f64::NAN, 0.0, 0.0], &zero, 0.1));
    }
}
