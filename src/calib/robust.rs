//! The robust (Student-t) measurement weight shared by the calibrators.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Precision scale λ of one scalar measurement under a Student-t likelihood
/// with `dof` degrees of freedom: the variational-Bayes fixed point of
/// \[Piche2012\]. The measurement `z` has innovation `nu` = z − x̂ against the
/// prior mean x̂ (variance `prior_var`) and noise variance `r`; with the
/// precision scaled by λ, the posterior of x has gain k = λP/(λP + r) and
/// variance P·r/(λP + r), and
///
/// `λ = (dof + 1) / (dof + E[(z − x)²]/r)`,
/// `E[(z − x)²] = ((1 − k)·ν)² + P·r/(λP + r)`,
///
/// iterated from λ = 1 (it decreases to the largest fixed point, the
/// function being increasing in λ), capped at 1 so that inliers keep the
/// full Gaussian precision. The residual is read against the *posterior*:
/// a wide prior (a wheel base nothing has observed yet) neither excuses an
/// outlier, which the innovation against the prior predictive `r + P` would
/// (the first interval of a turn, whose laser rotation and wheel rates
/// cover different spans, would then pull the unobserved parameter to the
/// edge of its cloud), nor penalises an inlier, which an innovation against
/// `r` alone would. With `prior_var` = 0 it is `(dof + 1)/(dof + ν²/r)`.
/// `dof = 0`, a variance `r` ≤ 0, or a non-finite input gives 1.
pub fn student_t_weight(nu: f64, r: f64, prior_var: f64, dof: f64) -> f64 {
    if !(dof > 0.0) || !(r > 0.0) || !nu.is_finite() || !r.is_finite() {
        return 1.0;
    }
    let p = if prior_var.is_finite() {
        prior_var.max(0.0)
    } else {
        0.0
    };
    let mut lambda = 1.0f64;
    for _ in 0..100 {
        let k = lambda * p / (lambda * p + r);
        let post = p * r / (lambda * p + r);
        let e = ((1.0 - k) * nu).powi(2) + post;
        let next = ((dof + 1.0) / (dof + e / r)).min(1.0);
        let done = (next - lambda).abs() < 1e-9;
        lambda = next;
        if done {
            break;
        }
    }
    lambda
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_a_prior_spread_it_is_the_innovation_weight() {
        // ν²/r = 0.5, 1 → capped at 1; 9 → 5/13; 2500 → 5/2504.
        assert_eq!(student_t_weight(0.5f64.sqrt(), 1.0, 0.0, 4.0), 1.0);
        assert_eq!(student_t_weight(1.0, 1.0, 0.0, 4.0), 1.0);
        assert!((student_t_weight(3.0, 1.0, 0.0, 4.0) - 5.0 / 13.0).abs() < 1e-12);
        assert!((student_t_weight(50.0, 1.0, 0.0, 4.0) - 5.0 / 2504.0).abs() < 1e-12);
        assert_eq!(student_t_weight(50.0, 1.0, 0.0, 0.0), 1.0);
        assert_eq!(student_t_weight(f64::NAN, 1.0, 0.0, 4.0), 1.0);
        // Inputs outside the law give 1 rather than a weight: an infinite
        // innovation (which would give 0) and a negative variance (which
        // would give 5/(4 − 9) = −1).
        assert_eq!(student_t_weight(f64::INFINITY, 1.0, 0.0, 4.0), 1.0);
        assert_eq!(student_t_weight(3.0, -1.0, 0.0, 4.0), 1.0);
    }

    #[test]
    fn an_outlier_under_a_wide_prior_is_read_against_the_posterior() {
        // ν = 0.037, r = 1e-5, P = 2.9e-5, dof 4: the fixed point found by
        // bisection of λ − min(1, 5/(4 + E(λ)/r)) (a single sign change on
        // (0, 1]), independently of the iteration: λ = 0.0437032. Against
        // the prior predictive (r + P) the same innovation would keep
        // 5/(4 + 0.037²/3.9e-5) = 0.1283.
        let w = student_t_weight(0.037, 1e-5, 2.9e-5, 4.0);
        assert!((w - 0.043_703_2).abs() < 1e-6, "{w}");
        // An inlier under the same wide prior keeps its full weight (at λ = 1:
        // k = 29/39, E/r = ((10/39)·0.005)²/1e-5 + 2.9/3.9 = 0.91 < 1), where
        // an innovation against r alone (ν²/r = 2.5) would give 5/6.5.
        assert_eq!(student_t_weight(0.005, 1e-5, 2.9e-5, 4.0), 1.0);
    }
}
