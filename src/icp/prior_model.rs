//! How far the two predictions of a pair's motion — the given prior (wheel
//! odometry increment) and the constant-velocity guess — are from what the
//! scans then measured, learned online per recording, and the prior term's
//! centre and spread that follow from it.
//!
//! Along a corridor the scan leaves the axis loose and the prior term decides
//! the motion there. A fixed σ centred on the odometry trusts every log's
//! odometry alike; here each prediction's error is a robust running variance
//! of (prediction − matched motion) over the pairs the scans did measure, and
//! the term is centred on the two predictions weighted by the inverse of
//! those variances (its spread stays `prior_sigma_xy`: a prior tightened by
//! the fused variance pulls the constrained directions too); centred on the
//! odometry alone, its spread is the odometry's learned error. Only pairs the
//! scans pin down in every direction are counted, and the constant-velocity
//! guess takes part only when it comes from such a pair: a velocity the
//! prior term itself set along a corridor would otherwise be carried on
//! (a robot that speeds up in a corridor stays slow for seconds).

use crate::geom::{self, Pose2};

/// Matched pairs before a running variance is trusted; until then the
/// configured σ (odometry) or no weight at all (constant velocity) applies.
const WARM_UP: usize = 10;
/// Errors beyond this many running σ count as this many σ: one bad pair
/// (a slip, a catch-up jump) cannot blow a variance up.
const CLIP_SIGMAS: f64 = 3.0;

/// Robust exponentially weighted mean of squared errors of one prediction
/// (m², per axis of the pair frame, x and y pooled).
#[derive(Debug, Clone, Copy, Default)]
pub struct RunningVariance {
    var: f64,
    n: usize,
}

impl RunningVariance {
    /// Adds one error (m, both axes) with forgetting `rate` in (0, 1].
    pub fn update(&mut self, err: [f64; 2], rate: f64) {
        let mut e2 = 0.5 * (err[0] * err[0] + err[1] * err[1]);
        if !e2.is_finite() {
            return;
        }
        if self.n >= WARM_UP {
            e2 = e2.min(CLIP_SIGMAS * CLIP_SIGMAS * self.var);
        }
        self.n += 1;
        // Plain mean during the warm-up, exponential forgetting after.
        let a = rate.max(1.0 / self.n as f64);
        self.var += a * (e2 - self.var);
    }

    /// The variance (m²) once warmed up.
    pub fn get(&self) -> Option<f64> {
        (self.n >= WARM_UP).then_some(self.var)
    }
}

/// Online error model of the odometry and constant-velocity predictions.
#[derive(Debug, Clone, Copy, Default)]
pub struct PriorModel {
    /// Odometry increment − matched motion.
    pub odometry: RunningVariance,
    /// Constant-velocity guess − matched motion.
    pub constant_velocity: RunningVariance,
}

impl PriorModel {
    /// Records one matched pair: the motion the scans measured and the two
    /// predictions that were available for it.
    pub fn record(&mut self, matched: &Pose2, odo: Option<&Pose2>, cv: Option<&Pose2>, rate: f64) {
        let err = |p: &Pose2| {
            let d = matched.translation.vector - p.translation.vector;
            [d.x, d.y]
        };
        if let Some(o) = odo {
            self.odometry.update(err(o), rate);
        }
        if let Some(c) = cv {
            self.constant_velocity.update(err(c), rate);
        }
    }

    /// The prior term's centre and translation σ (m) for a pair with the
    /// odometry increment `odo` and, if any, the constant-velocity guess
    /// `cv`. Once both variances are learned (each held within `(lo, hi)`²)
    /// and `cv` is given, the
    /// translation is their inverse-variance mean (the heading stays the
    /// odometry's) with the configured σ `sigma`; otherwise the odometry,
    /// with its learned σ within `(lo, hi)` (`sigma` until learned).
    pub fn prior(
        &self,
        odo: &Pose2,
        cv: Option<&Pose2>,
        sigma: f64,
        (lo, hi): (f64, f64),
    ) -> (Pose2, f64) {
        let vars = self.odometry.get().zip(self.constant_velocity.get());
        match (cv, vars) {
            (Some(c), Some((vo, vc))) => {
                let (vo, vc) = (vo.clamp(lo * lo, hi * hi), vc.clamp(lo * lo, hi * hi));
                let wo = vc / (vo + vc);
                let t = odo.translation.vector * wo + c.translation.vector * (1.0 - wo);
                (geom::pose(t.x, t.y, geom::heading(odo)), sigma)
            }
            _ => {
                let s = self
                    .odometry
                    .get()
                    .map_or(sigma, |v| v.sqrt().clamp(lo, hi));
                (*odo, s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_variance_learns_the_error_spread_and_resists_outliers() {
        let mut v = RunningVariance::default();
        let mut rng = 12345u64;
        let mut next = || {
            // xorshift, mapped to a symmetric ±1 uniform.
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        assert!(v.get().is_none());
        for i in 0..4000 {
            // Uniform ±0.03 m: variance 3e-4 m²; a 5 m outlier every 100.
            let e = if i % 100 == 99 {
                [5.0, 5.0]
            } else {
                [0.03 * next(), 0.03 * next()]
            };
            v.update(e, 0.02);
        }
        let var = v.get().unwrap();
        assert!((var.sqrt() - 0.0173).abs() < 0.006, "σ {}", var.sqrt());
    }

    #[test]
    fn blend_weights_the_better_prediction() {
        let mut m = PriorModel::default();
        let odo = geom::pose(0.20, 0.0, 0.1);
        let cv = geom::pose(0.10, 0.0, 0.0);
        let b = (0.005, 0.1);
        // Before anything is learned: the odometry, with the configured σ.
        let (c, s) = m.prior(&odo, Some(&cv), 0.02, b);
        assert_eq!((geom::xyt(&c), s), (geom::xyt(&odo), 0.02));
        // Odometry errors 3× those of the constant velocity: weights 1 : 9.
        for k in 0..50 {
            let sgn = if k % 2 == 0 { 1.0 } else { -1.0 };
            let truth = geom::pose(0.1, 0.0, 0.0);
            let o = geom::pose(0.1 + 0.03 * sgn, 0.03 * sgn, 0.0);
            let c = geom::pose(0.1 + 0.01 * sgn, -0.01 * sgn, 0.0);
            m.record(&truth, Some(&o), Some(&c), 0.05);
        }
        let (c, s) = m.prior(&odo, Some(&cv), 0.02, b);
        assert_eq!(s, 0.02);
        let [x, y, th] = geom::xyt(&c);
        assert!((x - (0.1 * 0.20 + 0.9 * 0.10)).abs() < 1e-9, "{x}");
        assert!(y.abs() < 1e-12 && (th - 0.1).abs() < 1e-12);
        // Without a constant-velocity guess: the odometry, with its learned σ.
        let (c, s) = m.prior(&odo, None, 0.02, b);
        assert_eq!(geom::xyt(&c), geom::xyt(&odo));
        assert!((s - 0.03).abs() < 1e-9, "{s}");
    }
}
