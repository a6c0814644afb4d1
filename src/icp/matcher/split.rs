//! How much of a registration's estimate the scan measured and how much the
//! prior term supplied: the scan-only optimum recovered from the fused one,
//! its conflict with the prior term (a χ² test on the innovation), and the
//! estimate that owes to the scan only what it measured.

use crate::geom::{self, Pose2};
use crate::motion::InfoSplit;
use nalgebra::{Matrix3, Vector3};

/// Squared Mahalanobis distance (3 dof) beyond which the scans contradict the
/// prior term: the χ² 99.9 % quantile.
pub const CONFLICT: f64 = 16.27;

/// Squared Mahalanobis distance (3 dof) between the centre `init` of a prior
/// term of precision `prec` (diagonal, 1/m², 1/m², 1/rad²) and the scan-only
/// estimate, given the registration's result `pose` (prior term included) and
/// the scan-only covariance `cov`, all in the reference frame. At the
/// optimum of scan + prior, the scan-only optimum is `pose + cov·P·off`
/// (`off` = `pose − init`, `P` = diag(`prec`)), and its innovation against
/// the prior, of covariance `cov + P⁻¹`, has the squared distance
/// `offᵀ P off + (P off)ᵀ cov (P off)` — no inversion of a possibly
/// infinite prior variance needed.
pub fn prior_conflict(
    pose: &[f64; 3],
    init: &[f64; 3],
    prec: &[f64; 3],
    cov: &Matrix3<f64>,
) -> f64 {
    let off = Vector3::new(
        pose[0] - init[0],
        pose[1] - init[1],
        geom::wrap_angle(pose[2] - init[2]),
    );
    let poff = Vector3::new(prec[0] * off.x, prec[1] * off.y, prec[2] * off.z);
    let d2 = off.dot(&poff) + poff.dot(&(cov * poff));
    if d2.is_finite() {
        d2
    } else {
        0.0
    }
}

/// The information split of a registration's `pose` (all in the reference
/// frame) between the scan and a prior term centred at `init` with
/// precision `prec` (diagonal, 1/m², 1/m², 1/rad²), given the scan-only
/// covariance `cov` of the registration's cost and the information `info`
/// the scan measured beyond its lines' direction noise
/// (`Uncertainty::measured`): the scan-only optimum `own = pose + cov·P·off`
/// (`off` = `pose − init`, as in [`prior_conflict`]) and
/// `K = (info + P)⁻¹ info`, the share of each direction the scan measured.
/// `K = I` without a prior term; where the result is not finite, `own` is
/// the pose and the share 0.
pub fn info_split(
    pose: &[f64; 3],
    init: &[f64; 3],
    prec: &[f64; 3],
    cov: &Matrix3<f64>,
    info: &Matrix3<f64>,
) -> ([f64; 3], Matrix3<f64>) {
    if prec.iter().all(|&p| p == 0.0) {
        return (*pose, Matrix3::identity());
    }
    let off = Vector3::new(
        pose[0] - init[0],
        pose[1] - init[1],
        geom::wrap_angle(pose[2] - init[2]),
    );
    let p = Matrix3::from_diagonal(&Vector3::from(*prec));
    let own = Vector3::from(*pose) + cov * p * off;
    let k = (info + p).try_inverse().map(|s| s * info);
    match k {
        Some(k) if k.iter().all(|v| v.is_finite()) && own.iter().all(|v| v.is_finite()) => {
            ([own.x, own.y, geom::wrap_angle(own.z)], k)
        }
        _ => (*pose, Matrix3::zeros()),
    }
}

/// The estimate that follows from a split (`own`, `k`) and the prior
/// term's centre `init`: `init + K (own − init)` (θ wrapped), i.e. the
/// scan's own estimate only as far as the scan measured it, and its
/// covariance `(info + P)⁻¹` (`P` = diag(`prec`)). Where the scan's lines
/// hold more information than they measure (noise-tilted fits along a
/// wall), this, not the registration's optimum, is the pair's motion.
pub fn split_estimate(
    (own, k): &([f64; 3], Matrix3<f64>),
    init: &[f64; 3],
    prec: &[f64; 3],
    info: &Matrix3<f64>,
) -> Option<([f64; 3], Matrix3<f64>)> {
    let d = Vector3::new(
        own[0] - init[0],
        own[1] - init[1],
        geom::wrap_angle(own[2] - init[2]),
    );
    let x = Vector3::from(*init) + k * d;
    let cov = (info + Matrix3::from_diagonal(&Vector3::from(*prec))).try_inverse()?;
    let ok = x.iter().chain(cov.iter()).all(|v| v.is_finite());
    ok.then(|| {
        (
            [x.x, x.y, geom::wrap_angle(x.z)],
            (cov + cov.transpose()) * 0.5,
        )
    })
}

/// The information split of the motion from the last scan (at
/// `ref_from_last`) to a pose registered in the reference frame, given that
/// pose's scan-only estimate and `K` there: the scan-only motion from the
/// last pose, and `K` turned into the base frame at the last scan.
pub fn motion_split(ref_from_last: &Pose2, (scan_pose, k): ([f64; 3], Matrix3<f64>)) -> InfoSplit {
    let own = geom::pose(scan_pose[0], scan_pose[1], scan_pose[2]);
    let (s, c) = geom::heading(ref_from_last).sin_cos();
    // Base-frame coordinates at the last scan: Rᵀ on x, y.
    let r = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
    let kb = r * k * r.transpose();
    InfoSplit {
        scan_share: std::array::from_fn(|i| kb[(i, i)].clamp(0.0, 1.0)),
        scan_only: geom::xyt(&geom::between(ref_from_last, &own)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prior_conflict_and_info_split_recover_the_scan_only_estimate() {
        // Scan-only estimate xs with covariance c, prior at init with
        // precision p: the fused optimum, then the closed form against the
        // explicit (xs − init)ᵀ (c + P⁻¹)⁻¹ (xs − init).
        let c = Matrix3::new(4e-4, 1e-4, 0.0, 1e-4, 1e-2, 2e-5, 0.0, 2e-5, 1e-4);
        let prec = [2500.0, 2500.0, 4.0];
        let pm = Matrix3::from_diagonal(&Vector3::from(prec));
        let init = Vector3::new(0.1, -0.2, 0.3);
        let xs = Vector3::new(0.13, -0.05, 0.29);
        let ci = c.try_inverse().unwrap();
        let fused = (ci + pm).try_inverse().unwrap() * (ci * xs + pm * init);
        let got = prior_conflict(&fused.into(), &init.into(), &prec, &c);
        let d = xs - init;
        let s = c + pm.try_inverse().unwrap();
        let want = (d.transpose() * s.try_inverse().unwrap() * d)[(0, 0)];
        assert!((got - want).abs() < 1e-9 * want, "{got} {want}");
        // The information split of that fused optimum recovers the
        // scan-only estimate, and K·xs + (I − K)·init is the fused optimum.
        let (own, k) = info_split(&fused.into(), &init.into(), &prec, &c, &ci);
        for i in 0..3 {
            assert!((own[i] - xs[i]).abs() < 1e-9, "{own:?} {xs}");
        }
        let back = k * xs + (Matrix3::identity() - k) * init;
        assert!((back - fused).norm() < 1e-9, "{back} {fused}");
        // Along the direction the scan measures poorly (y: variance 1e-2
        // against the prior's 4e-4), most of the estimate is the prior's.
        assert!(k[(1, 1)] < 0.1 && k[(0, 0)] > 0.5, "{k}");
        // No prior term: no conflict.
        assert_eq!(
            prior_conflict(&fused.into(), &init.into(), &[0.0; 3], &c),
            0.0
        );
    }

    #[test]
    fn the_split_estimate_is_the_fused_optimum_with_its_covariance() {
        // With the scan's measured information equal to its cost's, the
        // split estimate is the fused optimum itself, of covariance (C⁻¹ + P)⁻¹.
        let c = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-2, 1e-4));
        let ci = c.try_inverse().unwrap();
        let prec = [2500.0, 2500.0, 4.0];
        let pm = Matrix3::from_diagonal(&Vector3::from(prec));
        let init = [0.1, 0.0, 0.0];
        let xs = Vector3::new(0.12, 0.05, 0.01);
        let fused = (ci + pm).try_inverse().unwrap() * (ci * xs + pm * Vector3::from(init));
        let split = info_split(&fused.into(), &init, &prec, &c, &ci);
        let (x, cov) = split_estimate(&split, &init, &prec, &ci).unwrap();
        assert!((Vector3::from(x) - fused).norm() < 1e-9, "{x:?} {fused}");
        let want = (ci + pm).try_inverse().unwrap();
        assert!((cov - want).norm() < 1e-12, "{cov} {want}");
        // No prior term: the pose, all of it the scan's.
        let (own, k) = info_split(&[1.0, 2.0, 3.0], &init, &[0.0; 3], &c, &ci);
        assert_eq!((own, k), ([1.0, 2.0, 3.0], Matrix3::identity()));
    }

    #[test]
    fn the_motion_split_is_in_the_base_frame_of_the_last_scan() {
        // The last scan faces +y: the map's x is its −y.
        let last = geom::pose(1.0, 0.0, std::f64::consts::FRAC_PI_2);
        let k = Matrix3::from_diagonal(&Vector3::new(0.2, 0.9, 1.0));
        let s = motion_split(&last, ([1.0, 0.5, std::f64::consts::FRAC_PI_2], k));
        let [x, y, t] = s.scan_only;
        assert!((x - 0.5).abs() < 1e-12 && y.abs() < 1e-12 && t.abs() < 1e-12);
        let [a, b, c] = s.scan_share;
        assert!((a - 0.9).abs() < 1e-12 && (b - 0.2).abs() < 1e-12 && c == 1.0);
    }
}
