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
    for _ in 0..max_iter {
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
            break;
        }
    }
    let (info, _) = normal(d, &p);
    Fit {
        p,
        info,
        chi2: cost,
    }
}
