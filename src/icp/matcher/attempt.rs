//! One registration of the prepared source from one initial guess, with the
//! prior term's share taken out of its estimate and its verdict, before the
//! matcher's state changes.

use super::acceptance::Acceptance;
use super::split::{info_split, prior_conflict, split_estimate};
use super::PriorSource;
use crate::geom::{self, Pose2};
use crate::icp::reference::Reference;
use crate::icp::register::{register, RegisterSettings, Registration, Scratch};
use crate::motion::PairFailure;
use nalgebra::Matrix3;

/// One registration and its verdict.
pub struct Attempt {
    /// The registration itself.
    pub reg: Registration,
    /// Pose of the current scan in the reference frame.
    pub ref_from_cur: Pose2,
    /// Covariance of `ref_from_cur`: the scan's, or with a prior term, that
    /// of the estimate of [`split_estimate`].
    pub cov: Matrix3<f64>,
    /// Motion since the last scan.
    pub motion: Pose2,
    /// Why the registration does not measure the pair, if it does not.
    pub failure: Option<PairFailure>,
    /// The initial guess (motion since the last scan) it started from.
    pub init: Pose2,
    /// Where that guess came from.
    pub source: PriorSource,
    /// Squared Mahalanobis distance between the prior term's centre and
    /// what the scan alone says (see [`prior_conflict`]); 0 without a prior
    /// term.
    pub conflict: f64,
    /// The scan-only pose `[x, y, θ]` and `K = (I + C P)⁻¹` in the
    /// reference frame (see [`info_split`]).
    pub split: Option<([f64; 3], Matrix3<f64>)>,
}

impl Attempt {
    /// Whether this attempt succeeded and beats `best`: `best` failed, or
    /// this one has more inliers.
    pub fn improves_on(&self, best: &Attempt) -> bool {
        self.failure.is_none() && (best.failure.is_some() || self.reg.inliers > best.reg.inliers)
    }
}

/// What every registration of a pair reads.
pub struct Inputs<'a> {
    /// The scan or map matched against.
    pub reference: &'a Reference,
    /// The source points (base frame of the current scan).
    pub src: &'a [[f64; 2]],
    /// Their own surface normals (NaN where none was fitted).
    pub normals: &'a [[f64; 2]],
    /// Pose of the last scan in the reference frame.
    pub ref_from_last: Pose2,
    /// The gates of the verdict.
    pub accept: &'a Acceptance,
}

/// Registers the source from the guess `prior` (motion since the last
/// scan, from `source`) with `set` (its prior term centred on the guess).
/// With a prior term, the estimate is the scan's own only as far as the
/// scan measured it ([`split_estimate`]).
pub fn attempt(
    inp: &Inputs,
    prior: &Pose2,
    source: PriorSource,
    set: &RegisterSettings,
    scratch: &mut Scratch,
) -> Attempt {
    let init = geom::xyt(&(inp.ref_from_last * prior));
    let reg = register(inp.reference, inp.src, inp.normals, init, set, scratch);
    let conflict = reg.uncertainty.map_or(0.0, |u| {
        prior_conflict(&reg.pose, &init, &set.prior_precision, &u.cov)
    });
    let prec = &set.prior_precision;
    let split = reg
        .uncertainty
        .map(|u| info_split(&reg.pose, &init, prec, &u.cov, &u.measured));
    let held = prec.iter().any(|&v| v > 0.0);
    let (pose, cov) = match (reg.uncertainty, &split) {
        (Some(u), Some(sp)) if held => {
            split_estimate(sp, &init, prec, &u.measured).unwrap_or((reg.pose, u.cov))
        }
        (Some(u), _) => (reg.pose, u.cov),
        _ => (reg.pose, Matrix3::zeros()),
    };
    let ref_from_cur = geom::pose(pose[0], pose[1], pose[2]);
    let motion = geom::between(&inp.ref_from_last, &ref_from_cur);
    let matchable = inp.normals.iter().filter(|n| n[0].is_finite()).count();
    let failure = inp.accept.verdict(&reg, matchable, &motion, prior, source);
    Attempt {
        reg,
        ref_from_cur,
        cov,
        motion,
        failure,
        init: *prior,
        source,
        conflict,
        split,
    }
}

#[cfg(test)]
mod tests {
    use super::super::split::CONFLICT;
    use super::*;
    use crate::icp::preprocess::ScanPoints;
    use crate::icp::Metric;

    /// A room corner seen from `at`: two walls, 2 cm spacing, linked.
    fn corner(at: &Pose2) -> ScanPoints {
        let wall_a = (0..100).map(|i| [3.0, -1.0 + 0.02 * i as f64]);
        let wall_b = (0..100).map(|i| [1.0 - 0.02 * i as f64, 1.5]);
        let inv = at.inverse();
        let pts: Vec<[f64; 2]> = wall_a
            .chain(wall_b)
            .map(|p| {
                let q = inv * nalgebra::Point2::new(p[0], p[1]);
                [q.x, q.y]
            })
            .collect();
        let mut link = vec![true; pts.len()];
        link[99] = false;
        let range = pts.iter().map(|p| p[0].hypot(p[1])).collect();
        ScanPoints { pts, link, range }
    }

    fn settings(prior_precision: [f64; 3]) -> RegisterSettings {
        RegisterSettings {
            threshold: 0.5,
            max_gap: 0.5,
            min_normal_cos: 0.5f64.cos(),
            min_kappa: 0.005,
            max_iterations: 60,
            convergence: 1e-5,
            min_correspondences: 15,
            cov_inflation: 1.7,
            metric: Metric::default(),
            prior_precision,
        }
    }

    #[test]
    fn a_known_motion_is_recovered_and_a_contradicted_prior_named() {
        let truth = geom::pose(0.1, -0.05, 0.03);
        let mut reference = Reference::new(8, 0.3);
        reference.set(&corner(&Pose2::identity()));
        let mut own = Reference::new(8, 0.3);
        let cur = corner(&truth);
        own.set_lines(&cur);
        let normals: Vec<_> = (0..cur.pts.len())
            .map(|i| own.normal(i).unwrap_or([f64::NAN; 2]))
            .collect();
        let accept = Acceptance::default();
        let inp = Inputs {
            reference: &reference,
            src: &cur.pts,
            normals: &normals,
            ref_from_last: Pose2::identity(),
            accept: &accept,
        };
        let mut scratch = Scratch::default();
        let guess = geom::pose(0.08, 0.0, 0.0);
        let a = attempt(
            &inp,
            &guess,
            PriorSource::None,
            &settings([0.0; 3]),
            &mut scratch,
        );
        assert_eq!(a.failure, None);
        let [x, y, t] = geom::xyt(&geom::between(&truth, &a.motion));
        assert!(x.hypot(y) < 1e-6 && t.abs() < 1e-6, "{x} {y} {t}");
        assert_eq!(
            (a.conflict, a.init, a.source),
            (0.0, guess, PriorSource::None)
        );
        // A tight prior term (1 cm) 10 cm off: the scans contradict it;
        // matched again without it, the motion is the scans'.
        let wrong = geom::pose(0.2, -0.05, 0.03);
        let tight = settings([1e4, 1e4, 1e4]);
        let b = attempt(&inp, &wrong, PriorSource::Given, &tight, &mut scratch);
        assert!(b.conflict > CONFLICT, "{}", b.conflict);
        let c = attempt(
            &inp,
            &wrong,
            PriorSource::Given,
            &settings([0.0; 3]),
            &mut scratch,
        );
        let [x, y, t] = geom::xyt(&geom::between(&truth, &c.motion));
        assert!(x.hypot(y) < 1e-6 && t.abs() < 1e-6, "{x} {y} {t}");
        assert!(c.failure.is_none() && c.conflict == 0.0);
    }
}
