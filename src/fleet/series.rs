//! A parameter's history as a weighted least-squares fit: an offset, a
//! common rate over time and one offset change at each step,
//! `y_i = a + b·t_i + Σ_k c_k·[t_i ≥ s_k]`, each point weighted by `1/σ_i²`
//! (a trend is a regression on time with its
//! confidence, a step a change-point beyond the combined uncertainty).

use nalgebra::{DMatrix, DVector};

/// One calibrated value of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// When it was recorded (days).
    pub day: f64,
    /// The estimate (m).
    pub value: f64,
    /// Its standard deviation (m).
    pub std: f64,
}

/// The weighted fit of a series with given steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// `[a, b, c_1, …]`: offset (m), rate (m/day), step sizes (m).
    pub coef: Vec<f64>,
    /// Their covariance from the points' σ alone.
    pub cov: DMatrix<f64>,
    /// Σ ((y − ŷ)/σ)².
    pub chi2: f64,
    /// Points minus coefficients.
    pub dof: usize,
}

impl Fit {
    /// The Birge ratio \[Birge1932\] squared: the reduced χ² when above 1, else 1. A
    /// scatter wider than the points' σ says they are too small; the
    /// coefficients' std are widened by its square root.
    pub fn scale(&self) -> f64 {
        if self.dof == 0 {
            return 1.0;
        }
        (self.chi2 / self.dof as f64).max(1.0)
    }

    /// Coefficient `k`'s std, widened by the Birge ratio.
    pub fn std(&self, k: usize) -> f64 {
        (self.cov[(k, k)] * self.scale()).sqrt()
    }
}

/// Fits `points` (sorted by day or not) with a step at each of `steps`
/// (days: a point at or after `s` is after the step). `None` when the
/// normal equations are singular (fewer distinct days than coefficients,
/// a step with no point on one side) or a σ is not positive.
pub fn fit(points: &[Point], steps: &[f64]) -> Option<Fit> {
    let n = points.len();
    let m = 2 + steps.len();
    if n < m || points.iter().any(|p| !(p.std > 0.0)) {
        return None;
    }
    let design = DMatrix::from_fn(n, m, |i, k| match k {
        0 => 1.0,
        1 => points[i].day,
        _ => f64::from(u8::from(points[i].day >= steps[k - 2])),
    });
    let w = DVector::from_iterator(n, points.iter().map(|p| 1.0 / (p.std * p.std)));
    let y = DVector::from_iterator(n, points.iter().map(|p| p.value));
    let mut xtwx = DMatrix::zeros(m, m);
    let mut xtwy = DVector::zeros(m);
    for i in 0..n {
        let row = design.row(i);
        xtwx += w[i] * row.transpose() * row;
        xtwy += w[i] * y[i] * row.transpose();
    }
    let cov = xtwx.try_inverse()?;
    if !cov.iter().all(|v| v.is_finite()) || (0..m).any(|k| !(cov[(k, k)] > 0.0)) {
        return None;
    }
    let coef = &cov * xtwy;
    let resid = &y - &design * &coef;
    let chi2 = (0..n).map(|i| resid[i] * resid[i] * w[i]).sum();
    Some(Fit {
        coef: coef.iter().copied().collect(),
        cov,
        chi2,
        dof: n - m,
    })
}

/// The candidate step days of `points`: every distinct day that leaves at
/// least `min_side` points before it and at least `min_side` from it on.
pub fn candidate_steps(points: &[Point], min_side: usize) -> Vec<f64> {
    let mut days: Vec<f64> = points.iter().map(|p| p.day).collect();
    days.sort_by(f64::total_cmp);
    days.dedup();
    days.into_iter()
        .filter(|&d| {
            let before = points.iter().filter(|p| p.day < d).count();
            before >= min_side && points.len() - before >= min_side
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(a: f64, b: f64, days: &[f64]) -> Vec<Point> {
        days.iter()
            .map(|&d| Point {
                day: d,
                value: a + b * d,
                std: 1e-3,
            })
            .collect()
    }

    #[test]
    fn an_exact_line_is_fitted_exactly_with_the_textbook_rate_std() {
        let days = [0.0, 1.0, 2.0, 3.0];
        let f = fit(&line(0.3, -2e-4, &days), &[]).unwrap();
        assert!((f.coef[0] - 0.3).abs() < 1e-12 && (f.coef[1] + 2e-4).abs() < 1e-12);
        assert!(f.chi2 < 1e-18 && f.dof == 2);
        // σ_b² = σ² / Σ (t − t̄)² = 1e-6 / 5 for days 0..3.
        assert!((f.std(1) - (1e-6f64 / 5.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn a_step_with_no_point_after_it_is_not_fitted() {
        assert!(fit(&line(0.3, 0.0, &[0.0, 1.0, 2.0]), &[5.0]).is_none());
        let c = candidate_steps(&line(0.3, 0.0, &[0.0, 1.0, 2.0, 3.0, 4.0]), 2);
        assert_eq!(c, vec![2.0, 3.0]);
    }
}
