//! The maximum-likelihood refinement [Censi2013, Sec. V]: Levenberg–Marquardt
//! over the unknowns minimising Σ_k e_kᵀ Σ_k⁻¹ e_k with e_k = s_k − ŝ_k
//! ([`super::model`]). The Jacobian is by central differences (the model
//! composes arcs and, with a time offset, interpolates wheel angles; a
//! difference quotient needs no second derivation to keep in step with it).

use super::model::{increments, predicted, residual, Unknowns, P3};
use super::{Interval, WheelTrack};
use nalgebra::{DMatrix, DVector, Matrix3};

/// The data of a fit: intervals, their whitening (the transposed Cholesky
/// factor of Σ_k⁻¹), the wheel track and the difference steps.
pub struct Data<'a> {
    /// The intervals used.
    pub intervals: Vec<&'a Interval>,
    /// `Lᵀ` with `Σ_k⁻¹ = L Lᵀ`, one per interval.
    pub whiten: Vec<Matrix3<f64>>,
    /// Wheel angles over time, for intervals given as time spans.
    pub track: Option<&'a WheelTrack>,
    /// Central-difference step of each unknown (its unit).
    pub step: Vec<f64>,
    /// Which unknowns are fitted (the others are held where they start).
    pub free: Vec<bool>,
}

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The unknowns at the optimum.
    pub p: Vec<f64>,
    /// The Fisher information JᵀΣ⁻¹J at the optimum.
    pub info: DMatrix<f64>,
    /// Σ e_kᵀ Σ_k⁻¹ e_k at the optimum.
    pub chi2: f64,
    /// The iterations taken (each forms the normal equations once; the last
    /// one's step was small or refused at every damping), at most `max_iter`.
    pub iterations: usize,
    /// Whether it stopped because no step was worth taking (else at
    /// `max_iter`, still improving).
    pub converged: bool,
}

/// The residual `s − ŝ` of one interval at `p`.
pub fn raw_residual(
    iv: &Interval,
    track: Option<&WheelTrack>,
    p: &[f64],
    buf: &mut Vec<[f64; 2]>,
) -> P3 {
    let u = Unknowns::from_slice(p);
    increments(iv, track, u.time_offset, buf);
    residual(iv.s, predicted(buf, &u))
}

fn chi2(d: &Data, p: &[f64]) -> f64 {
    let mut buf = Vec::new();
    d.intervals
        .iter()
        .zip(&d.whiten)
        .map(|(iv, w)| {
            let e = raw_residual(iv, d.track, p, &mut buf);
            (w * nalgebra::Vector3::from(e)).norm_squared()
        })
        .sum()
}

/// Normal equations JᵀJ and Jᵀr of the whitened residuals at `p`.
fn normal(d: &Data, p: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
    let n = p.len();
    let mut h = DMatrix::zeros(n, n);
    let mut g = DVector::zeros(n);
    let mut buf = Vec::new();
    let mut q = p.to_vec();
    let mut jac = nalgebra::OMatrix::<f64, nalgebra::U3, nalgebra::Dyn>::zeros(n);
    for (iv, w) in d.intervals.iter().zip(&d.whiten) {
        let e0 = nalgebra::Vector3::from(raw_residual(iv, d.track, p, &mut buf));
        for j in 0..n {
            if !d.free[j] {
                jac.set_column(j, &nalgebra::Vector3::zeros());
                continue;
            }
            q[j] = p[j] + d.step[j];
            let ep = raw_residual(iv, d.track, &q, &mut buf);
            q[j] = p[j] - d.step[j];
            let em = raw_residual(iv, d.track, &q, &mut buf);
            q[j] = p[j];
            let mut col = [
                ep[0] - em[0],
                ep[1] - em[1],
                crate::geom::wrap_angle(ep[2] - em[2]),
            ];
            col.iter_mut().for_each(|c| *c /= 2.0 * d.step[j]);
            jac.set_column(j, &(w * nalgebra::Vector3::from(col)));
        }
        let r = w * e0;
        h += jac.transpose() * &jac;
        g += jac.transpose() * r;
    }
    // A held unknown: a unit diagonal and no gradient, so its step is 0.
    for j in (0..n).filter(|&j| !d.free[j]) {
        h[(j, j)] = 1.0;
    }
    (h, g)
}

/// Levenberg–Marquardt from `p0` (Marquardt's diagonal scaling), until no
/// step changes any unknown by more than 1e-9 of its difference step's
/// scale, or `max_iter` iterations. Residuals e = s − ŝ(p), so the step
/// solves (H + λ diag H) Δ = Jᵀr with J = ∂e/∂p taken with its sign: ŝ
/// enters e negatively, hence `p − Δ`.
pub fn fit(d: &Data, p0: &[f64], max_iter: usize) -> Fit {
    let mut p = p0.to_vec();
    let mut cost = chi2(d, &p);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut converged = false;
    for _ in 0..max_iter {
        iterations += 1;
        let (h, g) = normal(d, &p);
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = h.clone();
            for i in 0..a.nrows() {
                a[(i, i)] += lambda * h[(i, i)].max(1e-300);
            }
            let Some(delta) = a.cholesky().map(|c| c.solve(&g)) else {
                lambda *= 10.0;
                continue;
            };
            let trial: Vec<f64> = p.iter().zip(delta.iter()).map(|(x, dx)| x - dx).collect();
            let c = chi2(d, &trial);
            if c.is_finite() && c <= cost {
                let small = delta.iter().zip(&d.step).all(|(dx, s)| dx.abs() < 1e-3 * s);
                p = trial;
                cost = c;
                lambda = (lambda / 10.0).max(1e-12);
                improved = !small;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            converged = true;
            break;
        }
    }
    let (info, _) = normal(d, &p);
    Fit {
        p,
        info,
        chi2: cost,
        iterations,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::batch::tests::{arc_by_hand, DRIVES};
    use crate::calib::batch::WheelMotion;
    use nalgebra::{Isometry2, Vector2};

    /// r_R, r_L, b, laser x, y, yaw.
    const TRUTH: [f64; 6] = [0.10, 0.11, 0.5, 0.2, 0.05, 0.3];

    /// Intervals of two sub-steps each, driven every way, with the laser
    /// displacement `ℓ⁻¹ o ℓ` of [`TRUTH`] exactly.
    fn exact_intervals() -> Vec<Interval> {
        let [rr, rl, b, lx, ly, lth] = TRUTH;
        let laser = Isometry2::new(Vector2::new(lx, ly), lth);
        DRIVES
            .iter()
            .map(|&(l, r)| {
                let inc = vec![[l, r], [0.5 * l, 0.8 * r]];
                let o = inc.iter().fold(Isometry2::identity(), |o, &[dl, dr]| {
                    o * arc_by_hand(dl, dr, rr, rl, b)
                });
                let d = laser.inverse() * o * laser;
                Interval {
                    s: [d.translation.x, d.translation.y, d.rotation.angle()],
                    cov: None,
                    duration: 1.0,
                    wheels: WheelMotion::Steps(inc),
                }
            })
            .collect()
    }

    fn data(ivs: &[Interval], whiten: Matrix3<f64>, free: [bool; 6]) -> Data<'_> {
        Data {
            intervals: ivs.iter().collect(),
            whiten: vec![whiten; ivs.len()],
            track: None,
            step: vec![1e-6; 6],
            free: free.to_vec(),
        }
    }

    #[test]
    fn the_fit_returns_to_the_unknowns_that_made_exact_intervals() {
        // From 5 % off every unknown (and 0.1 rad off the laser's yaw), the
        // fit lands on the truth with nothing left to explain.
        let ivs = exact_intervals();
        let d = data(&ivs, Matrix3::identity(), [true; 6]);
        let mut p0: Vec<f64> = TRUTH.iter().map(|x| 1.05 * x).collect();
        p0[5] += 0.1;
        let f = fit(&d, &p0, 50);
        for (g, w) in f.p.iter().zip(TRUTH) {
            assert!((g - w).abs() < 1e-8, "{:?}", f.p);
        }
        assert!(f.chi2 < 1e-16, "{}", f.chi2);
    }

    #[test]
    fn a_held_unknown_stays_where_it_starts_with_unit_information() {
        // The wheel base held at its true value: the rest still reach the
        // truth, the wheel base is untouched, and its row of the information
        // is (0, …, 1, …, 0).
        let ivs = exact_intervals();
        let d = data(
            &ivs,
            Matrix3::identity(),
            [true, true, false, true, true, true],
        );
        let mut p0: Vec<f64> = TRUTH.iter().map(|x| 0.97 * x).collect();
        p0[2] = TRUTH[2];
        let f = fit(&d, &p0, 50);
        assert_eq!(f.p[2], TRUTH[2]);
        for (g, w) in f.p.iter().zip(TRUTH) {
            assert!((g - w).abs() < 1e-8, "{:?}", f.p);
        }
        for j in 0..6 {
            let want = if j == 2 { 1.0 } else { 0.0 };
            assert_eq!(f.info[(2, j)], want, "{j}");
            assert_eq!(f.info[(j, 2)], want, "{j}");
        }
    }

    #[test]
    fn chi2_sums_the_whitened_residuals() {
        // Both wheels 2 rad with radii 0.1 and the laser at the base: the
        // model says 0.2 m straight ahead. Against s = (0.5, −0.1, 0.2) the
        // residual is (0.3, −0.1, 0.2); whitened by diag(2, 10, 0.5) it is
        // (0.6, −1, 0.1), so χ² = 0.36 + 1 + 0.01. No iteration: the start
        // is returned as it is.
        let ivs = [Interval {
            s: [0.5, -0.1, 0.2],
            cov: None,
            duration: 1.0,
            wheels: WheelMotion::Steps(vec![[2.0, 2.0]]),
        }];
        let d = data(
            &ivs,
            Matrix3::from_diagonal(&nalgebra::Vector3::new(2.0, 10.0, 0.5)),
            [true; 6],
        );
        let p = [0.1, 0.1, 0.5, 0.0, 0.0, 0.0];
        let f = fit(&d, &p, 0);
        assert_eq!(f.p, p);
        assert!((f.chi2 - 1.37).abs() < 1e-12, "{}", f.chi2);
        let e = raw_residual(&ivs[0], None, &p, &mut vec![]);
        for (g, w) in e.iter().zip([0.3, -0.1, 0.2]) {
            assert!((g - w).abs() < 1e-12, "{e:?}");
        }
    }

    #[test]
    fn the_information_of_a_straight_drive_by_hand() {
        // Both wheels 2 rad, radii 0.1, wheel base 0.5, laser at the base:
        // ŝ = (0.2, 0, 0). Against r_R it moves by ∂x = φ/2 = 1,
        // ∂y = d·(∂θ)/2 = 0.2·4/2 = 0.4 and ∂θ = φ/b = 4, so with r_R alone
        // free and unit whitening its information is 1 + 0.16 + 16 = 17.16;
        // every held unknown has a unit diagonal and no coupling. (The
        // difference quotient is good to about 1e-5 here: at the 1e-6 step
        // the turn is 4e-6 rad, where 1 − cos θ keeps few digits.)
        let ivs = [Interval {
            s: [0.2, 0.0, 0.0],
            cov: None,
            duration: 1.0,
            wheels: WheelMotion::Steps(vec![[2.0, 2.0]]),
        }];
        let d = data(
            &ivs,
            Matrix3::identity(),
            [true, false, false, false, false, false],
        );
        let f = fit(&d, &[0.1, 0.1, 0.5, 0.0, 0.0, 0.0], 0);
        assert!((f.info[(0, 0)] - 17.16).abs() < 1e-5, "{}", f.info);
        for i in 0..6 {
            for j in 0..6 {
                if i != j || i > 0 {
                    assert_eq!(f.info[(i, j)], if i == j { 1.0 } else { 0.0 }, "{i} {j}");
                }
            }
        }
    }

    #[test]
    fn the_fit_returns_from_a_far_start_that_needs_damping() {
        // Radii and wheel base 30 % off, the laser 0.3 m and a radian away:
        // undamped steps overshoot here, the damped ones still land on the
        // truth.
        let ivs = exact_intervals();
        let d = data(&ivs, Matrix3::identity(), [true; 6]);
        let p0 = [0.13, 0.077, 0.65, -0.1, 0.35, 1.3];
        let f = fit(&d, &p0, 200);
        for (g, w) in f.p.iter().zip(TRUTH) {
            assert!((g - w).abs() < 1e-8, "{:?}", f.p);
        }
    }

    /// A robot spinning in place, left wheel −2.5 rad and right +2.5 rad on
    /// radii 0.1, the laser at the base: it turns θ = 0.5/b, observed as
    /// θ* = 1 (so b = 0.5), and only the wheel base is free, from b = 1.2.
    /// The residual e(b) = 1 − 0.5/b with ∂e/∂b = 0.5/b² is whitened by `w`.
    fn spin(w: f64, max_iter: usize) -> Fit {
        let ivs = [Interval {
            s: [0.0, 0.0, 1.0],
            cov: None,
            duration: 1.0,
            wheels: WheelMotion::Steps(vec![[-2.5, 2.5]]),
        }];
        let d = data(
            &ivs,
            Matrix3::identity() * w,
            [false, false, true, false, false, false],
        );
        fit(&d, &[0.1, 0.1, 1.2, 0.0, 0.0, 0.0], max_iter)
    }

    #[test]
    fn a_step_that_overshoots_is_damped_until_it_lowers_the_cost() {
        // At b = 1.2: e = 1 − 0.5/1.2 = 7/12, ∂e/∂b = 0.5/1.44, so the
        // undamped step is e/(∂e/∂b) = 1.68, to b = −0.48 (a turn the other
        // way: costlier). Damped by λ·H (one unknown: diag H is H) the step
        // is 1.68/(1 + λ): λ = 0.001, 0.01 and 0.1 still land at b < 0
        // (−0.478, −0.463, −0.327; |e| > 2 > 7/12), λ = 1 lands at
        // 1.2 − 0.84 = 0.36 (e = −0.389, accepted). The next iteration starts
        // at λ = 0.1: the undamped step from 0.36 is (1 − 0.5/0.36)·0.36²/0.5
        // = −0.1008, damped −0.1008/1.1.
        let f = spin(1.0, 1);
        assert_eq!(f.iterations, 1);
        // Stopped by the limit with a step of 0.84 just taken.
        assert!(!f.converged);
        assert!((f.p[2] - 0.36).abs() < 1e-9, "{:?}", f.p);
        let f = spin(1.0, 2);
        assert_eq!(f.iterations, 2);
        assert!((f.p[2] - (0.36 + 0.1008 / 1.1)).abs() < 1e-9, "{:?}", f.p);
        // The held unknowns stay where they start.
        assert_eq!([f.p[0], f.p[1], f.p[3]], [0.1, 0.1, 0.0]);
    }

    #[test]
    fn the_damped_path_ends_after_its_first_small_step() {
        // The whole path from b = 1.2 (tools/lm_path_by_hand.py, with the
        // analytic derivative): steps 0.84, −9.2e-2, −4.3e-2, −5.1e-3,
        // −5.7e-5, −1.2e-8 (at λ = 0.1, 0.01, … after the first iteration's
        // λ = 1), then −1.2e-13, the first under 1e-3 of the 1e-6 difference
        // step: seven iterations, at b = 0.5.
        let f = spin(1.0, 50);
        assert_eq!(f.iterations, 7);
        assert!(f.converged);
        // With exactly seven allowed the seventh step is the small one: done.
        assert!(spin(1.0, 7).converged && !spin(1.0, 6).converged);
        assert!((f.p[2] - 0.5).abs() < 1e-12, "{:?}", f.p);
        assert!(f.chi2 < 1e-24, "{}", f.chi2);
        // Marquardt's damping λ·diag H makes the path independent of the
        // residuals' scale: whitened by 1e3 (H and Jᵀr 1e6 times larger, the
        // cost too) every step is the same and so is the count.
        for n in [1, 2, 50] {
            let (a, b) = (spin(1.0, n), spin(1e3, n));
            assert_eq!(a.iterations, b.iterations, "{n}");
            assert!((a.p[2] - b.p[2]).abs() < 1e-12, "{n}: {a:?} {b:?}");
        }
    }

    #[test]
    fn a_start_where_the_model_is_undefined_comes_back_as_it_is() {
        // A wheel base of 0 turns every arc by ±∞: no residual, no step;
        // the fit gives up at once instead of searching forever.
        let ivs = exact_intervals();
        let d = data(&ivs, Matrix3::identity(), [true; 6]);
        let p0 = [0.1, 0.11, 0.0, 0.2, 0.05, 0.3];
        let f = fit(&d, &p0, 10);
        assert_eq!(f.p, p0);
        assert!(f.chi2.is_nan());
    }
}
