//! The weak prior term of each registration: where it is centred (the
//! odometry, or its blend with the constant-velocity guess by the learned
//! errors of both, see `prior_model`), how tight it is, and the matched
//! motions that teach the error model.

use super::prior::Velocity;
use super::PriorSource;
use crate::geom::Pose2;
use crate::icp::prior_model::PriorModel;
use serde::{Deserialize, Serialize};

/// Spread and learning of the prior term. Units: m, rad.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PriorTermSettings {
    /// Translation σ (m) of the given prior, per pair; 0 = no prior term.
    pub sigma_xy: f64,
    /// Heading σ (rad) of the given prior, per pair; 0 = none.
    pub sigma_theta: f64,
    /// Forgetting rate of the learned error model; 0 = centred on the
    /// odometry with `sigma_xy`.
    pub blend_rate: f64,
    /// Smallest conditioning of a pair that trains the model, and of the
    /// pair a constant-velocity guess comes from for it to take part.
    pub blend_conditioning: f64,
    /// Smallest and largest learned translation σ (m).
    pub sigma_bounds: [f64; 2],
}

impl Default for PriorTermSettings {
    fn default() -> Self {
        Self {
            sigma_xy: 0.02,
            sigma_theta: 0.5,
            blend_rate: 0.05,
            blend_conditioning: 0.03,
            sigma_bounds: [0.005, 0.1],
        }
    }
}

/// The prior term of the current pair and the error model behind it.
#[derive(Debug, Clone, Default)]
pub struct PriorTerm {
    set: PriorTermSettings,
    /// Learned errors of the odometry and constant-velocity predictions.
    model: PriorModel,
    /// The current pair's given prior (when it is the guess) and
    /// constant-velocity guess, for the model.
    given: Option<Pose2>,
    cv: Option<Pose2>,
    /// The current pair's translation σ (m).
    sigma: f64,
}

impl PriorTerm {
    /// A term with nothing learned.
    pub fn new(set: PriorTermSettings) -> Self {
        Self {
            set,
            sigma: set.sigma_xy,
            ..Default::default()
        }
    }

    /// The prior term's centre for a pair guessed at `prior` (from
    /// `source`): the odometry `given`, or its blend with the
    /// constant-velocity guess `cv` when the `last` valid motion was one the
    /// scans fully measured (see `PriorModel::prior`). Records the pair's
    /// given prior, guess and σ for the model and the registration.
    pub fn centre(
        &mut self,
        prior: Pose2,
        given: Option<Pose2>,
        cv: Option<Pose2>,
        source: PriorSource,
        last: Option<Velocity>,
    ) -> Pose2 {
        self.given = given.filter(|_| source == PriorSource::Given);
        self.cv = cv;
        self.sigma = self.set.sigma_xy;
        match self.given {
            Some(g) if self.set.blend_rate > 0.0 => {
                let p = &self.set;
                let measured = last.is_some_and(|v| v.cond >= p.blend_conditioning && v.agreed);
                let [lo, hi] = p.sigma_bounds;
                let cv = cv.as_ref().filter(|_| measured);
                let (c, s) = self.model.prior(&g, cv, p.sigma_xy, (lo, hi));
                self.sigma = s;
                c
            }
            _ => prior,
        }
    }

    /// Inverse variances (1/m², 1/m², 1/rad²) of the term for a
    /// registration from a guess of `source`, on (`hold`) or off: the
    /// pair's σ for the given prior, the configured one for a substitute.
    pub fn precision(&self, source: PriorSource, hold: bool) -> [f64; 3] {
        if !hold {
            return [0.0; 3];
        }
        let prec = |s: f64| if s > 0.0 { 1.0 / (s * s) } else { 0.0 };
        let pt = prec(if source == PriorSource::Given {
            self.sigma
        } else {
            self.set.sigma_xy
        });
        [pt, pt, prec(self.set.sigma_theta)]
    }

    /// Trains the prediction error model on a matched `motion` the scans
    /// measured in every direction (`conditioning`); the odometry only when
    /// the winning match started from it (`source`).
    pub fn learn(&mut self, motion: &Pose2, source: PriorSource, conditioning: f64) {
        let p = &self.set;
        if p.blend_rate > 0.0 && conditioning >= p.blend_conditioning {
            let odo = self.given.filter(|_| source == PriorSource::Given);
            self.model
                .record(motion, odo.as_ref(), self.cv.as_ref(), p.blend_rate);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom;
    use nalgebra::Matrix3;

    fn measured(cond: f64) -> Option<Velocity> {
        Some(Velocity {
            cond,
            agreed: true,
            inc: geom::pose(0.1, 0.0, 0.0),
            dt: 0.1,
            t1: 0.0,
            cov: Matrix3::zeros(),
        })
    }

    #[test]
    fn precision_follows_the_source_and_the_switch() {
        let t = PriorTerm::new(PriorTermSettings::default());
        assert_eq!(t.precision(PriorSource::Given, false), [0.0; 3]);
        let p = t.precision(PriorSource::Given, true);
        assert!((p[0] - 2500.0).abs() < 1e-9 && p[0] == p[1] && (p[2] - 4.0).abs() < 1e-12);
        let off = PriorTerm::new(PriorTermSettings {
            sigma_xy: 0.0,
            ..Default::default()
        });
        assert_eq!(off.precision(PriorSource::Substituted, true)[0], 0.0);
    }

    #[test]
    fn the_centre_blends_in_the_guess_once_both_errors_are_learned() {
        let mut t = PriorTerm::new(PriorTermSettings::default());
        let odo = geom::pose(0.20, 0.0, 0.0);
        let cv = geom::pose(0.10, 0.0, 0.0);
        // A substituted pair is centred on its guess, not on the odometry.
        let c = t.centre(cv, Some(odo), Some(cv), PriorSource::Substituted, None);
        assert_eq!(c, cv);
        // Nothing learned yet: the odometry with the configured σ.
        let c = t.centre(odo, Some(odo), Some(cv), PriorSource::Given, measured(1.0));
        assert_eq!((c, t.sigma), (odo, 0.02));
        // Both predictions equally wrong (5 cm either side): halfway.
        for _ in 0..20 {
            t.centre(odo, Some(odo), Some(cv), PriorSource::Given, None);
            t.learn(&geom::pose(0.15, 0.0, 0.0), PriorSource::Given, 1.0);
        }
        let c = t.centre(odo, Some(odo), Some(cv), PriorSource::Given, measured(1.0));
        assert!((geom::xyt(&c)[0] - 0.15).abs() < 1e-9, "{c:?}");
        // A guess from a poorly measured pair takes no part: the odometry,
        // with its learned σ.
        let c = t.centre(odo, Some(odo), Some(cv), PriorSource::Given, measured(0.0));
        assert_eq!(c, odo);
        // (x and y pooled: 5 cm in x alone is 5/√2 cm per axis).
        assert!((t.sigma - 0.05 / 2f64.sqrt()).abs() < 1e-9, "{}", t.sigma);
        // Poorly measured pairs teach nothing.
        let before = t.model;
        t.learn(&geom::pose(9.0, 0.0, 0.0), PriorSource::Given, 0.0);
        assert_eq!(t.model.odometry.get(), before.odometry.get());
    }
}
