//! A check of the prior's scale: over the pairs the scans measured, the
//! distance and the turn the prior (odometry) gives against the matched ones.
//!
//! Wheel odometry integrated with another robot's kinematics is off by the
//! ratio of the radii in its distances and of radius over wheel base in its
//! turns (the wheelchair's 0.32 m radii and 0.65 m wheel base on a rover with
//! 77 mm wheels 0.33 m apart: 4.2× and 2.1×); a recording's own odometry is
//! off by its calibration. The scans correct a prior that is somewhat off, so
//! the motions can look fine while the prior's kinematics are not the
//! robot's. The check reports the two ratios beside the matching; it never
//! changes it.

use serde::Serialize;

/// Share of a direction's estimate the scan must own for the pair to count
/// for that direction (a corridor's axis, held by the prior, does not).
const MEASURED_SHARE: f64 = 0.9;
/// Pairs whose prior and matched distance are both below this (m) stand
/// still: their matched noise would pull the distance ratio down.
const MIN_STEP_M: f64 = 0.01;
/// The same for turns (rad).
const MIN_TURN_RAD: f64 = 0.01;
/// Matched distance (m) and turn (rad) below which a ratio is not reported.
const MIN_DISTANCE_M: f64 = 2.0;
const MIN_TURNS_RAD: f64 = std::f64::consts::PI;
/// A ratio outside this band (the band `calibrate` refuses estimates
/// outside) says the prior's scale is not the scans'.
pub const PLAUSIBLE_RATIO: [f64; 2] = [0.8, 1.25];

/// Sums of the prior's and the matched distances and turns.
#[derive(Debug, Clone, Default)]
pub struct ScaleCheck {
    prior_m: f64,
    matched_m: f64,
    prior_rad: f64,
    matched_rad: f64,
    pairs: usize,
}

impl ScaleCheck {
    /// Adds one matched pair: the prior's increment and the matched one,
    /// each `[dx, dy, dθ]` (m, m, rad) in the base frame at the pair's
    /// start, and the matched estimate's scan share per direction.
    pub fn add(&mut self, prior: [f64; 3], matched: [f64; 3], share: [f64; 3]) {
        if !prior.iter().chain(&matched).all(|v| v.is_finite()) {
            return;
        }
        let mut counted = false;
        if share[0] >= MEASURED_SHARE && share[1] >= MEASURED_SHARE {
            let (p, m) = (prior[0].hypot(prior[1]), matched[0].hypot(matched[1]));
            if p.max(m) >= MIN_STEP_M {
                self.prior_m += p;
                self.matched_m += m;
                counted = true;
            }
        }
        if share[2] >= MEASURED_SHARE {
            let (p, m) = (prior[2].abs(), matched[2].abs());
            if p.max(m) >= MIN_TURN_RAD {
                self.prior_rad += p;
                self.matched_rad += m;
                counted = true;
            }
        }
        self.pairs += usize::from(counted);
    }

    /// The ratios, each when the scans measured enough of that motion
    /// ([`MIN_DISTANCE_M`], [`MIN_TURNS_RAD`]); `None` when neither.
    pub fn result(&self) -> Option<PriorScale> {
        let ratio = |p: f64, m: f64, min: f64| (m >= min).then(|| p / m);
        let distance_ratio = ratio(self.prior_m, self.matched_m, MIN_DISTANCE_M);
        let turn_ratio = ratio(self.prior_rad, self.matched_rad, MIN_TURNS_RAD);
        (distance_ratio.is_some() || turn_ratio.is_some()).then_some(PriorScale {
            distance_ratio,
            turn_ratio,
            distance_m: self.matched_m,
            turn_rad: self.matched_rad,
            pairs: self.pairs,
        })
    }
}

/// What the check found (JSON `prior_scale` of `odocal icp`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PriorScale {
    /// The prior's distance over the matched one, on the pairs whose
    /// translation the scans measured.
    pub distance_ratio: Option<f64>,
    /// The same for the turns (absolute heading increments).
    pub turn_ratio: Option<f64>,
    /// Matched distance counted (m).
    pub distance_m: f64,
    /// Matched turns counted (rad).
    pub turn_rad: f64,
    /// Pairs counted for either.
    pub pairs: usize,
}

impl PriorScale {
    /// Whether a ratio lies outside `PLAUSIBLE_RATIO`.
    pub fn off(&self) -> bool {
        let [lo, hi] = PLAUSIBLE_RATIO;
        [self.distance_ratio, self.turn_ratio]
            .iter()
            .flatten()
            .any(|r| !(lo..=hi).contains(r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A prior whose distances are 4× and turns 2× the matched ones, on a
    /// drive with stops and a corridor stretch the scans cannot measure.
    #[test]
    fn finds_the_ratios_and_ignores_standing_and_unmeasured_pairs() {
        let mut c = ScaleCheck::default();
        for k in 0..400 {
            let matched = [0.05, 0.0, if k % 2 == 0 { 0.03 } else { -0.02 }];
            let prior = [matched[0] * 4.0, 0.0, matched[2] * 2.0];
            c.add(prior, matched, [1.0, 1.0, 1.0]);
            // Standing: matched noise against a still prior.
            c.add([0.0; 3], [0.002, -0.001, 0.001], [1.0, 1.0, 1.0]);
            // A corridor: the translation is the prior's alone.
            c.add([0.5, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 1.0, 1.0]);
        }
        let s = c.result().unwrap();
        assert!((s.distance_ratio.unwrap() - 4.0).abs() < 1e-9, "{s:?}");
        assert!((s.turn_ratio.unwrap() - 2.0).abs() < 1e-9, "{s:?}");
        assert_eq!(s.pairs, 400);
        assert!(s.off());
    }

    #[test]
    fn too_little_motion_gives_no_ratio() {
        let mut c = ScaleCheck::default();
        for _ in 0..30 {
            c.add([0.05, 0.0, 0.0], [0.05, 0.0, 0.0], [1.0, 1.0, 1.0]);
        }
        assert!(c.result().is_none());
        for _ in 0..30 {
            c.add([0.05, 0.0, 0.0], [0.05, 0.0, 0.0], [1.0, 1.0, 1.0]);
        }
        let s = c.result().unwrap();
        assert_eq!((s.distance_ratio, s.turn_ratio), (Some(1.0), None));
        assert!(!s.off());
    }
}
