//! Covariance of a converged match: the Hessian of the point-to-surface error
//! at the solution, scaled by the residual variance, times an inflation factor.
//!
//! Why this form rather than Censi's closed form \[Censi2007\]: with closest points on the
//! reference polyline the residual of a correspondence is (to first order) its
//! distance along the surface normal, so the information of a correspondence is
//! `Jᵀ J` with `J = nᵀ [I | R' p]` (point-to-line), which is also what Censi's
//! estimate reduces to when the correspondence search itself is ignored. Using
//! the point-to-point Jacobian `[I | R' p]` instead would claim information
//! along walls that the data do not hold (a corridor would look constrained).
//! The remaining over-confidence — neighbouring residuals are correlated (the
//! same reference segment serves several source points) and the reference scan
//! is noisy too — is corrected by one factor, fitted on simulated runs with
//! known truth so that the mean NEES over a run is 3 (see `IcpParams::cov_inflation`).

use super::metric::{self, Placement};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Smallest residual standard deviation trusted (m): noise-free synthetic
/// data would otherwise claim an exact pose.
pub const MIN_RESIDUAL_STD: f64 = 1e-3;

/// One correspondence of the final iteration.
#[derive(Debug, Clone, Copy)]
pub struct Correspondence {
    /// Source point in its own frame (m).
    pub p: [f64; 2],
    /// Closest reference point (m).
    pub q: [f64; 2],
    /// Surface normal at `q`, if known.
    pub normal: Option<[f64; 2]>,
    /// Point-to-line residual `nᵀ (R p + t − q)` (m) at the pose it was
    /// associated at.
    pub residual: f64,
    /// Robust weight in [0, 1] of that residual.
    pub weight: f64,
    /// Variance (rad²) of the reference line's direction (0 when exact).
    pub tilt_var: f64,
}

/// Covariance and conditioning of one match.
#[derive(Debug, Clone, Copy)]
pub struct Uncertainty {
    /// Covariance of (x, y, θ) in m², m·rad, rad².
    pub cov: Matrix3<f64>,
    /// Smallest over largest eigenvalue of the information, θ scaled by the
    /// RMS point range so that all three axes are in metres.
    pub conditioning: f64,
    /// Unit direction (x, y, θ·L) of the smallest eigenvalue.
    pub weak_direction: [f64; 3],
    /// Weighted RMS residual (m).
    pub rms: f64,
    /// The information (inverse covariance, of x, y, θ) the scan measured
    /// beyond what its lines' direction noise alone would show (see
    /// [`measured`]): zero along a direction the geometry leaves free even
    /// where noisy line fits make `cov` look finite there.
    pub measured: Matrix3<f64>,
}

/// Weighted sums over the correspondences at one pose.
struct Information {
    /// `Σ w J Jᵀ`.
    h: Matrix3<f64>,
    /// `Σ w e²` (m²).
    ss: f64,
    /// Residual degrees of freedom, `Σ w` per residual.
    dof: f64,
    /// `Σ w`.
    wsum: f64,
    /// `Σ w |R p|²` (m²), for the RMS range.
    r2sum: f64,
    /// `Σ w σ_α² J_α J_αᵀ`: the expected part of `h` that is the lines'
    /// direction noise (see [`measured`]).
    floor: Matrix3<f64>,
}

/// Estimates the uncertainty of pose `[x, y, θ]` from its correspondences;
/// `None` when the information matrix is singular or not finite.
pub fn estimate(corrs: &[Correspondence], pose: [f64; 3], inflation: f64) -> Option<Uncertainty> {
    let Information {
        h,
        ss,
        dof,
        wsum,
        r2sum,
        floor,
    } = information(corrs, pose);
    if !(dof > 3.0) || !(wsum > 0.0) {
        return None;
    }
    let var = (ss / (dof - 3.0)).max(MIN_RESIDUAL_STD * MIN_RESIDUAL_STD);
    let cov = h.try_inverse()? * (var * inflation);
    let (conditioning, weak_direction) = conditioning(&h, r2sum / wsum);
    let m = measured(&h, &floor) / (var * inflation);
    let u = Uncertainty {
        cov: (cov + cov.transpose()) * 0.5,
        conditioning,
        weak_direction,
        rms: (ss / dof).sqrt(),
        measured: (m + m.transpose()) * 0.5,
    };
    let finite = u.cov.iter().chain(u.measured.iter()).all(|x| x.is_finite());
    (finite && u.conditioning.is_finite()).then_some(u)
}

/// The weighted information at `pose`: per correspondence with a normal the
/// point-to-line `J` and `e` of `metric` (one degree of freedom), without one
/// the point-to-point rows `[I | ∂(R p)/∂θ]` and `R p + t − q` (two).
fn information(corrs: &[Correspondence], pose: [f64; 3]) -> Information {
    let at = Placement::new(pose);
    let mut h = Matrix3::zeros();
    let mut floor = Matrix3::zeros();
    let (mut ss, mut dof, mut wsum, mut r2sum) = (0.0, 0.0, 0.0, 0.0);
    for k in corrs {
        let m = at.apply(k.p);
        let rp = m.rp;
        wsum += k.weight;
        r2sum += k.weight * (rp[0] * rp[0] + rp[1] * rp[1]);
        match k.normal {
            Some(n) => {
                let (e, j) = metric::residual_and_jacobian(&m, k.q, n);
                h += k.weight * j * j.transpose();
                // A tilt δα turns n by δα n⊥: J moves by δα J(n⊥).
                let ja = metric::jacobian(rp, [-n[1], n[0]]);
                floor += (k.weight * k.tilt_var) * ja * ja.transpose();
                ss += k.weight * e * e;
                dof += k.weight;
            }
            None => {
                let r = [m.x[0] - k.q[0], m.x[1] - k.q[1]];
                let dth = metric::rotation_derivative(rp);
                let jx = Vector3::new(1.0, 0.0, dth[0]);
                let jy = Vector3::new(0.0, 1.0, dth[1]);
                h += k.weight * (jx * jx.transpose() + jy * jy.transpose());
                ss += k.weight * (r[0] * r[0] + r[1] * r[1]);
                dof += 2.0 * k.weight;
            }
        }
    }
    Information {
        h,
        ss,
        dof,
        wsum,
        r2sum,
        floor,
    }
}

/// Information beyond the noise floor counts only from this many times the
/// floor: fewer than that and the direction is not told apart from the
/// lines' direction noise. The floor is smaller than that noise: along a
/// simulated featureless corridor (two straight walls 2.5 m apart, 90 s at
/// the wheelchair's laser) the axis shows 2.4–3.5 times it (10th–97th
/// percentile of the pairs, median 2.8), so this factor sits just above the
/// noise and a door lifts a pair over it or not.
pub const MEASURED_FACTOR: f64 = 4.0;

/// The information `h` (`Σ w J Jᵀ`) less its part that is the reference
/// lines' direction noise. A line fitted through noisy points has a normal
/// `n + δα n⊥` with `E[δα²] = σ_α²`, so `E[J Jᵀ] = J₀ J₀ᵀ + σ_α² J(n⊥) J(n⊥)ᵀ`:
/// along a straight wall, every fitted line's random tilt adds information
/// along the wall that the wall does not hold (`floor` = the sum of those
/// terms). In the generalised eigenbasis of `h` against `floor`
/// (`h v = λ floor v`), a direction keeps `λ − 1` times the floor where
/// `λ ≥ MEASURED_FACTOR`, else nothing. Without a floor (exact lines), `h`.
pub fn measured(h: &Matrix3<f64>, floor: &Matrix3<f64>) -> Matrix3<f64> {
    let eps = 1e-12 * h.trace().max(0.0);
    let Some(l) = (floor + Matrix3::identity() * eps).cholesky() else {
        return *h;
    };
    let l = l.l();
    let Some(li) = l.try_inverse() else {
        return *h;
    };
    let w = li * h * li.transpose();
    let eig = SymmetricEigen::new((w + w.transpose()) * 0.5);
    let g = eig.eigenvalues.map(|lam| {
        if lam >= MEASURED_FACTOR {
            lam - 1.0
        } else {
            0.0
        }
    });
    let u = eig.eigenvectors;
    l * u * Matrix3::from_diagonal(&g) * u.transpose() * l.transpose()
}

/// Smallest over largest eigenvalue of the information `h` with θ in metres
/// at the RMS range `L = √mean_r2` (`D H D`, `D = diag(1, 1, 1/L)`), and the
/// unit eigenvector of the smallest.
fn conditioning(h: &Matrix3<f64>, mean_r2: f64) -> (f64, [f64; 3]) {
    let l = mean_r2.sqrt().max(1e-3);
    let d = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0 / l));
    let eig = SymmetricEigen::new(d * h * d);
    let (mut imin, mut imax) = (0, 0);
    for i in 1..3 {
        if eig.eigenvalues[i] < eig.eigenvalues[imin] {
            imin = i;
        }
        if eig.eigenvalues[i] > eig.eigenvalues[imax] {
            imax = i;
        }
    }
    let v = eig.eigenvectors.column(imin);
    (
        eig.eigenvalues[imin] / eig.eigenvalues[imax],
        [v[0], v[1], v[2]],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall(y: f64, n: usize) -> Vec<Correspondence> {
        (0..n)
            .map(|i| Correspondence {
                p: [i as f64 * 0.1 - 2.0, y],
                q: [
                    i as f64 * 0.1 - 2.0,
                    y + if i % 2 == 0 { 0.01 } else { -0.01 },
                ],
                normal: Some([0.0, 1.0]),
                residual: if i % 2 == 0 { -0.01 } else { 0.01 },
                weight: 1.0,
                tilt_var: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_corridor_is_weak_along_its_axis() {
        let mut c = wall(1.0, 40);
        c.extend(wall(-1.0, 40));
        let u = estimate(&c, [0.0; 3], 1.0);
        // two parallel walls: x is not constrained at all
        assert!(u.is_none() || u.unwrap().conditioning < 1e-9);
        // add an end wall: well conditioned, x variance ~ σ²/n_end
        c.extend((0..20).map(|i| Correspondence {
            p: [3.0, i as f64 * 0.1 - 1.0],
            q: [
                3.0 + if i % 2 == 0 { 0.01 } else { -0.01 },
                i as f64 * 0.1 - 1.0,
            ],
            normal: Some([1.0, 0.0]),
            residual: if i % 2 == 0 { -0.01 } else { 0.01 },
            weight: 1.0,
            tilt_var: 0.0,
        }));
        let u = estimate(&c, [0.0; 3], 1.0).unwrap();
        assert!(u.conditioning > 1e-3);
        let var = 1e-4 * 100.0 / 97.0;
        assert!(
            (u.cov[(0, 0)] - var / 20.0).abs() / (var / 20.0) < 0.05,
            "{}",
            u.cov
        );
        assert!((u.rms - 0.01).abs() < 1e-9);
    }

    #[test]
    fn tilt_noise_along_a_wall_is_not_measured_information() {
        // Two walls whose fitted normals are tilted by ±0.15 rad of noise
        // (tilt variance 0.15²): the tilts look like information along x.
        let tilt = 0.15f64;
        let mut c: Vec<Correspondence> = [1.0, -1.0]
            .iter()
            .flat_map(|&y| wall(y, 40))
            .enumerate()
            .map(|(i, mut k)| {
                let a = if i % 3 == 0 { tilt } else { -0.7 * tilt };
                k.normal = Some([-a.sin(), a.cos()]);
                k.tilt_var = tilt * tilt;
                k
            })
            .collect();
        let u = estimate(&c, [0.0; 3], 1.0).unwrap();
        assert!(u.cov[(0, 0)].is_finite() && u.conditioning > 1e-4, "{u:?}");
        // Measured: (almost) nothing along x, y as before.
        let full = u.cov.try_inverse().unwrap();
        assert!(
            u.measured[(0, 0)] < 0.1 * full[(0, 0)],
            "{} vs {full}",
            u.measured
        );
        assert!(
            u.measured[(1, 1)] > 0.5 * full[(1, 1)],
            "{} vs {full}",
            u.measured
        );
        // An end wall measures x: it keeps its information there.
        c.extend((0..20).map(|i| Correspondence {
            p: [3.0, i as f64 * 0.1 - 1.0],
            q: [3.0, i as f64 * 0.1 - 1.0],
            normal: Some([1.0, 0.0]),
            residual: if i % 2 == 0 { -0.01 } else { 0.01 },
            weight: 1.0,
            tilt_var: tilt * tilt,
        }));
        let u = estimate(&c, [0.0; 3], 1.0).unwrap();
        let full = u.cov.try_inverse().unwrap();
        assert!(
            u.measured[(0, 0)] > 0.5 * full[(0, 0)],
            "{} vs {full}",
            u.measured
        );
    }

    fn corr(p: [f64; 2], q: [f64; 2], normal: Option<[f64; 2]>, weight: f64) -> Correspondence {
        Correspondence {
            p,
            q,
            normal,
            residual: 0.0,
            weight,
            tilt_var: 0.0,
        }
    }

    #[test]
    fn point_to_point_information_by_hand() {
        // Points (2, 0), (0, 1), (−1, 0), (0, −1) and, at weight 0.5, (1, 1),
        // at the identity, each 1 cm short of its match along x. Rows
        // (1, 0, −p_y) and (0, 1, p_x) give h = [[4.5, 0, −0.5], [0, 4.5, 1.5],
        // [−0.5, 1.5, 8]]; Σw|e|² = 4.5e-4 over 2·4.5 = 9 degrees of freedom,
        // so σ² = 4.5e-4/(9 − 3) = 7.5e-5 and the RMS residual √(4.5e-4/9).
        let c: Vec<Correspondence> = [
            ([2.0, 0.0], 1.0),
            ([0.0, 1.0], 1.0),
            ([-1.0, 0.0], 1.0),
            ([0.0, -1.0], 1.0),
            ([1.0, 1.0], 0.5),
        ]
        .iter()
        .map(|&(p, w)| corr(p, [p[0] - 0.01, p[1]], None, w))
        .collect();
        let h = Matrix3::new(4.5, 0.0, -0.5, 0.0, 4.5, 1.5, -0.5, 1.5, 8.0);
        for inflation in [1.0, 2.0] {
            let u = estimate(&c, [0.0; 3], inflation).unwrap();
            let var = 7.5e-5 * inflation;
            assert!(
                (u.cov * h - Matrix3::identity() * var).norm() < 1e-15,
                "{}",
                u.cov * h
            );
            assert!((u.measured * var - h).norm() < 1e-9, "{}", u.measured);
            assert!((u.rms - 5e-5f64.sqrt()).abs() < 1e-15, "{}", u.rms);
            // The RMS range is √(Σw|p|²/Σw) = √(8/4.5) = 4/3 m: in metres h is
            // 4.5 I plus (−0.375, 1.125) coupling x and y to the angle,
            // eigenvalues 4.5 and 4.5 ± √(0.375² + 1.125²).
            let s = (0.375f64.powi(2) + 1.125f64.powi(2)).sqrt();
            let want = (4.5 - s) / (4.5 + s);
            assert!((u.conditioning - want).abs() < 1e-12, "{}", u.conditioning);
        }
        // A match at 1e200 m: no finite residual variance, no covariance.
        let mut far = c.clone();
        far[0].q = [1e200, 0.0];
        assert!(estimate(&far, [0.0; 3], 1.0).is_none());
    }

    #[test]
    fn three_degrees_of_freedom_give_no_covariance_and_four_the_floor() {
        // A point-to-point match at (1, 0) (rows (1, 0, 0), (0, 1, 1)) and
        // point-to-line ones, normal (1, 0), at (0, 1) and (0, −1) (rows
        // (1, 0, −1), (1, 0, 1)), all exact. Three degrees of freedom leave
        // none for the residual: no covariance. Four: σ² at its floor 1e-6
        // and h = [[3, 0, 0], [0, 1, 1], [0, 1, 3]].
        let mut c = vec![
            corr([1.0, 0.0], [1.0, 0.0], None, 1.0),
            corr([0.0, 1.0], [0.0, 1.0], Some([1.0, 0.0]), 1.0),
        ];
        assert!(estimate(&c, [0.0; 3], 1.0).is_none());
        c.push(corr([0.0, -1.0], [0.0, -1.0], Some([1.0, 0.0]), 1.0));
        let u = estimate(&c, [0.0; 3], 1.0).unwrap();
        let h = Matrix3::new(3.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 3.0);
        assert!(
            (u.cov * h - Matrix3::identity() * 1e-6).norm() < 1e-18,
            "{}",
            u.cov * h
        );
        assert_eq!(u.rms, 0.0);
    }

    #[test]
    fn conditioning_turns_the_angle_into_metres_at_the_rms_range() {
        // h = diag(4, 1, 8) at an RMS range of 2 m is diag(4, 1, 2) in
        // metres: 1/4, weakest along y. At a range of 0.3 m, diag(1, 9,
        // 0.36) is diag(1, 9, 4): 1/9, weakest along x. A range below a
        // millimetre counts as one: diag(4, 1, 8e6).
        let (k, v) = conditioning(&Matrix3::from_diagonal(&Vector3::new(4.0, 1.0, 8.0)), 4.0);
        assert!(
            (k - 0.25).abs() < 1e-15 && (v[1].abs() - 1.0).abs() < 1e-12,
            "{k} {v:?}"
        );
        let (k, v) = conditioning(&Matrix3::from_diagonal(&Vector3::new(1.0, 9.0, 0.36)), 0.09);
        assert!(
            (k - 1.0 / 9.0).abs() < 1e-12 && (v[0].abs() - 1.0).abs() < 1e-12,
            "{k} {v:?}"
        );
        let (k, v) = conditioning(&Matrix3::from_diagonal(&Vector3::new(4.0, 1.0, 8.0)), 1e-8);
        assert!(
            (k - 1.0 / 8e6).abs() < 1e-18 && (v[1].abs() - 1.0).abs() < 1e-12,
            "{k} {v:?}"
        );
    }

    #[test]
    fn measured_information_keeps_what_stands_four_times_above_the_floor() {
        // Against a unit floor, h = diag(10, 2, 5) keeps λ − 1 where λ ≥ 4:
        // diag(9, 0, 4). Against floor diag(2, 1, 1) the x axis stands at
        // 10/2 = 5 floors and keeps 4 of them, 8: diag(8, 0, 4). No floor:
        // all of h. A floor that is no variance (negative): h as it is.
        let h = Matrix3::from_diagonal(&Vector3::new(10.0, 2.0, 5.0));
        let diag = |a, b, c| Matrix3::from_diagonal(&Vector3::new(a, b, c));
        for (floor, want) in [
            (Matrix3::identity(), diag(9.0, 0.0, 4.0)),
            (diag(2.0, 1.0, 1.0), diag(8.0, 0.0, 4.0)),
            (Matrix3::zeros(), h),
            // No tilt noise in θ (a singular floor): θ keeps all of its 5.
            (diag(1.0, 1.0, 0.0), diag(9.0, 0.0, 5.0)),
        ] {
            let got = measured(&h, &floor);
            assert!((got - want).norm() < 1e-9, "{floor} {got}");
        }
        assert_eq!(measured(&h, &-Matrix3::identity()), h);
        // Units do not matter: a millionth of h against a millionth of the
        // floor keeps a millionth.
        for floor in [Matrix3::zeros(), diag(2.0, 1.0, 1.0)] {
            let got = measured(&(h * 1e-6), &(floor * 1e-6)) * 1e6;
            let want = measured(&h, &floor);
            assert!((got - want).norm() < 1e-6, "{got} vs {want}");
        }
        // Turned 0.3 rad in the (x, y) plane, with the floor turned alike:
        // the same information, turned.
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3).into_inner();
        let got = measured(
            &(r * h * r.transpose()),
            &(r * diag(2.0, 1.0, 1.0) * r.transpose()),
        );
        let want = r * diag(8.0, 0.0, 4.0) * r.transpose();
        assert!((got - want).norm() < 1e-9, "{got} vs {want}");
    }

    #[test]
    fn information_sums_by_hand() {
        // At pose (0.5, −0.2, 0): a point-to-line match of (1, 0) (moved to
        // (1.5, −0.2)) against (1.5, −0.25) with normal (0.6, 0.8), weight
        // 0.5 and tilt variance 0.01: e = 0.8·0.05 = 0.04,
        // J = (0.6, 0.8, n·(0, 1)) = (0.6, 0.8, 0.8), and along
        // n⊥ = (−0.8, 0.6): (−0.8, 0.6, 0.6). A point-to-point match of
        // (0, 2) (moved to (0.5, 1.8)) against (0.49, 1.82), weight 1:
        // e = (0.01, −0.02), rows (1, 0, −2) and (0, 1, 0).
        let c = [
            Correspondence {
                tilt_var: 0.01,
                ..corr([1.0, 0.0], [1.5, -0.25], Some([0.6, 0.8]), 0.5)
            },
            corr([0.0, 2.0], [0.49, 1.82], None, 1.0),
        ];
        let i = information(&c, [0.5, -0.2, 0.0]);
        let j = Vector3::new(0.6, 0.8, 0.8);
        let (jx, jy) = (Vector3::new(1.0, 0.0, -2.0), Vector3::new(0.0, 1.0, 0.0));
        let h: Matrix3<f64> = 0.5 * j * j.transpose() + jx * jx.transpose() + jy * jy.transpose();
        assert!((i.h - h).norm() < 1e-15, "{}", i.h);
        let ja = Vector3::new(-0.8, 0.6, 0.6);
        let floor: Matrix3<f64> = 0.005 * ja * ja.transpose();
        assert!((i.floor - floor).norm() < 1e-15, "{}", i.floor);
        assert!(
            (i.ss - (0.5 * 0.04f64.powi(2) + 5e-4)).abs() < 1e-15,
            "{}",
            i.ss
        );
        assert_eq!((i.dof, i.wsum), (2.5, 1.5));
        assert!((i.r2sum - 4.5).abs() < 1e-15, "{}", i.r2sum);
    }
}
