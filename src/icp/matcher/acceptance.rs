//! Whether a pair is measured: enough points to try, and a registration that
//! has enough inliers, converged, is well conditioned, agrees with an
//! informative prior and could have been driven in the time between the
//! scans. A pair that is not carries the prior as motion, with a covariance
//! as wide as the gates.

use super::PriorSource;
use crate::geom::{self, Pose2};
use crate::icp::limits::SpeedLimits;
use crate::icp::register::Registration;
use crate::motion::{InfoSplit, Motion, PairFailure};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The gates a pair passes. Units: m, rad, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AcceptSettings {
    /// Fewest valid points a scan needs to be matched.
    pub min_points: usize,
    /// Fewest correspondences, absolute.
    pub min_correspondences: usize,
    /// Fewest correspondences as a fraction of the matchable source points.
    pub min_inlier_fraction: f64,
    /// Smallest conditioning of a well-posed registration.
    pub degenerate_ratio: f64,
    /// Largest translation deviation from the prior (m), on top of
    /// `prior_rel_tol` × prior translation.
    pub prior_trans_tol: f64,
    /// Relative slack on the prior translation.
    pub prior_rel_tol: f64,
    /// Largest rotation deviation from the prior (rad).
    pub prior_rot_tol: f64,
    /// What the robot can drive per second.
    pub limits: SpeedLimits,
}

impl Default for AcceptSettings {
    fn default() -> Self {
        Self {
            min_points: 20,
            min_correspondences: 15,
            min_inlier_fraction: 0.3,
            degenerate_ratio: 1e-4,
            prior_trans_tol: 0.25,
            prior_rel_tol: 0.5,
            prior_rot_tol: 0.35,
            limits: SpeedLimits::default(),
        }
    }
}

/// The gates of a pair.
#[derive(Debug, Clone, Copy, Default)]
pub struct Acceptance {
    set: AcceptSettings,
}

impl Acceptance {
    /// Gates with these settings.
    pub fn new(set: AcceptSettings) -> Self {
        Self { set }
    }

    /// Why a prepared scan of `points` valid points cannot be matched, if it
    /// cannot: too few points (in it or in the reference), or a beam count
    /// other than the previous scan's (`beams_changed`).
    pub fn scan_failure(
        &self,
        points: usize,
        beams_changed: bool,
        reference_empty: bool,
    ) -> Option<PairFailure> {
        if points < self.set.min_points {
            Some(PairFailure::TooFewPoints)
        } else if beams_changed {
            Some(PairFailure::Inconsistent)
        } else if reference_empty {
            Some(PairFailure::TooFewPoints)
        } else {
            None
        }
    }

    /// What is wrong with a registration `reg` whose source had `matchable`
    /// points with a surface of their own (only those can ever be matched:
    /// clutter, isolated returns and open ends never are), giving `motion`
    /// from the guess `prior` of `source`; `None` when nothing is.
    pub fn verdict(
        &self,
        reg: &Registration,
        matchable: usize,
        motion: &Pose2,
        prior: &Pose2,
        source: PriorSource,
    ) -> Option<PairFailure> {
        let p = &self.set;
        let min_inliers =
            (p.min_correspondences as f64).max(p.min_inlier_fraction * matchable as f64);
        if (reg.inliers as f64) < min_inliers {
            Some(PairFailure::TooFewCorrespondences)
        } else if !reg.converged {
            Some(PairFailure::NotConverged)
        } else if reg
            .uncertainty
            .is_none_or(|u| u.conditioning < p.degenerate_ratio)
        {
            Some(PairFailure::Degenerate)
        } else if !self.agrees_with_prior(motion, prior, source) {
            Some(PairFailure::Implausible)
        } else {
            None
        }
    }

    /// Whether a matched motion agrees with an informative prior.
    pub fn agrees_with_prior(&self, motion: &Pose2, prior: &Pose2, source: PriorSource) -> bool {
        if source == PriorSource::None {
            return true;
        }
        let p = &self.set;
        let [dx, dy, dth] = geom::xyt(&geom::between(prior, motion));
        let prior_len = prior.translation.vector.norm();
        (dx * dx + dy * dy).sqrt() <= p.prior_trans_tol + p.prior_rel_tol * prior_len
            && dth.abs() <= p.prior_rot_tol
    }

    /// Whether a matched motion is within the robot's speed and turn-rate
    /// limits over `dt`, allowing 3σ of its covariance plus a small slack.
    pub fn within_limits(&self, motion: &Pose2, cov: &Matrix3<f64>, dt: f64) -> bool {
        self.set.limits.within(geom::xyt(motion), cov, dt)
    }

    /// The flag of a successful match: a geometrically sound match that the
    /// robot could not have driven in dt (`time_ok` false: bursts of scans
    /// stamped milliseconds apart) means the stamps are wrong, not the
    /// geometry; the first match after failed pairs is `bridged`.
    pub fn flag(&self, time_ok: bool, bridged: bool) -> Option<PairFailure> {
        if !time_ok {
            Some(PairFailure::BadTime)
        } else if bridged {
            Some(PairFailure::Bridged)
        } else {
            None
        }
    }

    /// A failed pair: the prior as motion, covariance as wide as the gates.
    pub fn failed(&self, t0: f64, t1: f64, prior: &Pose2, f: PairFailure) -> Motion {
        let p = &self.set;
        let st = p.prior_trans_tol + p.prior_rel_tol * prior.translation.vector.norm();
        let cov = Matrix3::from_diagonal(&Vector3::new(st * st, st * st, p.prior_rot_tol.powi(2)));
        // Nothing of it was measured by the scan.
        let [dx, dy, dtheta] = geom::xyt(prior);
        Motion {
            failure: Some(f),
            split: Some(InfoSplit {
                scan_share: [0.0; 3],
                scan_only: [dx, dy, dtheta],
            }),
            ..Motion::from_increment(t0, t1, prior, cov)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icp::covariance::Uncertainty;

    fn registration(inliers: usize, converged: bool, conditioning: f64) -> Registration {
        Registration {
            pose: [0.0; 3],
            iterations: 4,
            converged,
            inliers,
            uncertainty: Some(Uncertainty {
                cov: Matrix3::identity() * 1e-6,
                conditioning,
                weak_direction: [1.0, 0.0, 0.0],
                rms: 0.01,
                measured: Matrix3::identity() * 1e6,
            }),
        }
    }

    #[test]
    fn scans_without_enough_points_or_with_another_layout_are_not_tried() {
        let a = Acceptance::default();
        assert_eq!(
            a.scan_failure(19, false, false),
            Some(PairFailure::TooFewPoints)
        );
        assert_eq!(
            a.scan_failure(20, true, false),
            Some(PairFailure::Inconsistent)
        );
        assert_eq!(
            a.scan_failure(20, false, true),
            Some(PairFailure::TooFewPoints)
        );
        assert_eq!(a.scan_failure(20, false, false), None);
    }

    #[test]
    fn each_gate_names_its_failure() {
        let a = Acceptance::default();
        let m = geom::pose(0.1, 0.0, 0.0);
        let ok = registration(100, true, 0.1);
        assert_eq!(a.verdict(&ok, 200, &m, &m, PriorSource::Given), None);
        // 30 % of 400 matchable points is 120; 15 at least.
        let few = Some(PairFailure::TooFewCorrespondences);
        assert_eq!(a.verdict(&ok, 400, &m, &m, PriorSource::Given), few);
        let f = registration(14, true, 0.1);
        assert_eq!(a.verdict(&f, 0, &m, &m, PriorSource::Given), few);
        let f = registration(100, false, 0.1);
        let nc = Some(PairFailure::NotConverged);
        assert_eq!(a.verdict(&f, 200, &m, &m, PriorSource::Given), nc);
        let f = registration(100, true, 1e-5);
        let deg = Some(PairFailure::Degenerate);
        assert_eq!(a.verdict(&f, 200, &m, &m, PriorSource::Given), deg);
        let f = Registration {
            uncertainty: None,
            ..ok.clone()
        };
        assert_eq!(a.verdict(&f, 200, &m, &m, PriorSource::Given), deg);
        // 0.5 m off a 0.1 m prior: beyond 0.25 + 0.5 × 0.1 m, unless the
        // prior says nothing.
        let far = geom::pose(0.6, 0.0, 0.0);
        let imp = Some(PairFailure::Implausible);
        assert_eq!(a.verdict(&ok, 200, &far, &m, PriorSource::Given), imp);
        assert_eq!(a.verdict(&ok, 200, &far, &m, PriorSource::None), None);
    }

    #[test]
    fn agreement_grows_with_the_prior_and_bounds_the_turn() {
        let a = Acceptance::default();
        let p = geom::pose(1.0, 0.0, 0.0);
        let g = PriorSource::Given;
        assert!(a.agrees_with_prior(&geom::pose(1.74, 0.0, 0.0), &p, g));
        assert!(!a.agrees_with_prior(&geom::pose(1.76, 0.0, 0.0), &p, g));
        assert!(!a.agrees_with_prior(&geom::pose(1.0, 0.0, 0.36), &p, g));
        assert!(a.within_limits(&p, &Matrix3::zeros(), 0.5));
        assert!(!a.within_limits(&p, &Matrix3::zeros(), 0.3));
    }

    #[test]
    fn failed_pairs_carry_the_prior_with_the_gates_as_covariance() {
        let a = Acceptance::default();
        let p = geom::pose(0.2, 0.0, 0.1);
        let m = a.failed(1.0, 1.1, &p, PairFailure::NotConverged);
        assert_eq!(m.failure, Some(PairFailure::NotConverged));
        assert_eq!([m.dx, m.dy, m.dtheta], geom::xyt(&p));
        let st = 0.25 + 0.5 * 0.2;
        assert!((m.cov[(0, 0)] - st * st).abs() < 1e-15 && m.cov[(0, 1)] == 0.0);
        assert!((m.cov[(2, 2)] - 0.35 * 0.35).abs() < 1e-15);
        assert_eq!(m.split.unwrap().scan_share, [0.0; 3]);
        assert_eq!(a.flag(false, true), Some(PairFailure::BadTime));
        assert_eq!(a.flag(true, true), Some(PairFailure::Bridged));
        assert_eq!(a.flag(true, false), None);
    }
}
