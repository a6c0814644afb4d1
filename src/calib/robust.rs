//! The robust (Student-t) measurement weight shared by the calibrators.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Precision scale of one measurement under a Student-t likelihood with `dof`
/// degrees of freedom, given its normalised innovation squared `nis = ν²/S`
/// against the filter's prediction: the variational-Bayes weight
/// `(dof + 1)/(dof + nis)` \[Piche2012\], capped at 1 so
/// that inliers keep the full Gaussian precision and only outliers (scan
/// matching failures) lose weight. `dof = 0` (or a non-finite `nis`) gives 1.
pub fn student_t_weight(nis: f64, dof: f64) -> f64 {
    if !(dof > 0.0) || !nis.is_finite() {
        return 1.0;
    }
    ((dof + 1.0) / (dof + nis.max(0.0))).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inliers_keep_full_weight_and_outliers_fade() {
        assert_eq!(student_t_weight(0.5, 4.0), 1.0);
        assert_eq!(student_t_weight(1.0, 4.0), 1.0);
        assert!((student_t_weight(9.0, 4.0) - 5.0 / 13.0).abs() < 1e-15);
        assert!(student_t_weight(2500.0, 4.0) < 0.003);
        assert_eq!(student_t_weight(2500.0, 0.0), 1.0);
    }
}
