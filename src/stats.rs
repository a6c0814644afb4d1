//! The distribution functions the estimators and the diagnosis share: normal
//! and χ² tails and quantiles, from statrs (its `erfc` and inverse, the
//! regularised incomplete gamma function). Against tables its `erfc` is
//! within 1e-10 of the value (relative; 4e-11 at x = 1) and the normal
//! quantile within 1e-15: far below what a p-value or a threshold needs.
//!
//! statrs panics on a probability outside \[0, 1\] and on zero degrees of
//! freedom; these wrappers answer such input instead (NaN, or the tail of a
//! distribution that has no mass), so that a degenerate fit reaching a test
//! gives "never significant" rather than a panic.

use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

/// Complementary error function `erfc(x) = 1 − erf(x)`.
pub fn erfc(x: f64) -> f64 {
    statrs::function::erf::erfc(x)
}

/// Two-sided p-value `P(|Z| > |z|)` of a standard normal statistic.
pub fn normal_two_sided(z: f64) -> f64 {
    if z.is_nan() {
        return 1.0;
    }
    erfc(z.abs() / std::f64::consts::SQRT_2).min(1.0)
}

/// The standard normal quantile `Φ⁻¹(p)`: −∞ at 0, +∞ at 1, NaN outside
/// \[0, 1\].
pub fn inverse_normal_cdf(p: f64) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    Normal::standard().inverse_cdf(p)
}

/// Upper tail `P(χ²_k > q)`; 1 for `q ≤ 0`, NaN or `k = 0` (a test with no
/// degree of freedom is never significant).
pub fn chi2_sf(q: f64, k: usize) -> f64 {
    if q.is_nan() || q <= 0.0 || k == 0 {
        return 1.0;
    }
    ChiSquared::new(k as f64).map_or(1.0, |d| d.sf(q))
}

/// The χ²_k quantile of probability `p` (the value exceeded with probability
/// `1 − p`); NaN for `p` outside \[0, 1\] or `k = 0`.
pub fn chi2_quantile(p: f64, k: usize) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) || k == 0 {
        return f64::NAN;
    }
    ChiSquared::new(k as f64).map_or(f64::NAN, |d| d.inverse_cdf(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative difference.
    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn erfc_matches_tabulated_values() {
        // Abramowitz and Stegun, Table 7.1, and erfc(5) from the series
        // e^{−25}/(5√π) (1 − 1/50 + 3/2500 − …) = 1.5374597944e-12.
        for (x, v) in [
            (0.0, 1.0),
            (0.3, 0.671_373_240_540_872_9),
            (1.0, 0.157_299_207_050_285_13),
            (-1.0, 1.842_700_792_949_715),
            (5.0, 1.537_459_794_428_034_8e-12),
        ] {
            assert!(rel(erfc(x), v) < 1e-10, "x={x}: {} vs {v}", erfc(x));
        }
    }

    #[test]
    fn normal_quantiles_and_tails_match_tables() {
        // Φ⁻¹ from Abramowitz and Stegun, Table 26.5 (and R's qnorm).
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.99, 2.326_347_874_040_840_8),
            (0.95, 1.644_853_626_951_472_2),
            (0.01, -2.326_347_874_040_840_8),
            (0.1, -1.281_551_565_544_600_5),
            (1e-10, -6.361_340_902_404_056),
            (1.0 - 1e-6, 4.753_424_308_822_899),
        ] {
            let got = inverse_normal_cdf(p);
            assert!((got - z).abs() < 1e-9 * z.abs().max(1.0), "p={p}: {got}");
        }
        assert!(inverse_normal_cdf(1.5).is_nan());
        assert!(inverse_normal_cdf(f64::NAN).is_nan());
        assert_eq!(inverse_normal_cdf(0.0), f64::NEG_INFINITY);
        assert_eq!(inverse_normal_cdf(1.0), f64::INFINITY);
        assert!(rel(normal_two_sided(1.959_963_984_540_054), 0.05) < 1e-10);
        assert!(rel(normal_two_sided(-2.575_829_303_548_901), 0.01) < 1e-10);
        assert_eq!(normal_two_sided(f64::NAN), 1.0);
    }

    #[test]
    fn chi2_tails_match_tables_in_the_far_tail() {
        // χ²₁ = z²: P(χ²₁ > 10) = erfc(√5) = 0.001565402258002549, where the
        // Wilson–Hilferty approximation is 12 % high (0.00175).
        assert!(rel(chi2_sf(10.0, 1), 0.001_565_402_258_002_549) < 1e-10);
        // χ²₂ is exponential: P(χ²₂ > q) = e^{−q/2}.
        assert!(rel(chi2_sf(30.0, 2), (-15.0f64).exp()) < 1e-10);
        // Abramowitz and Stegun, Table 26.8: χ²_{10, 0.99} = 23.2093,
        // χ²_{3, 0.999} = 16.2662, χ²_{100, 0.99} = 135.807.
        assert!(rel(chi2_sf(23.209_251, 10), 0.01) < 1e-5);
        assert!(rel(chi2_quantile(0.99, 10), 23.209_251) < 1e-6);
        assert!(rel(chi2_quantile(0.999, 3), 16.266_236) < 1e-6);
        assert!(rel(chi2_quantile(0.99, 100), 135.806_7) < 1e-6);
        // What has no mass or no degree of freedom is never significant.
        assert_eq!(chi2_sf(0.0, 3), 1.0);
        assert_eq!(chi2_sf(-1.0, 3), 1.0);
        assert_eq!(chi2_sf(f64::NAN, 3), 1.0);
        assert_eq!(chi2_sf(5.0, 0), 1.0);
        assert!(chi2_quantile(1.5, 3).is_nan());
        assert!(chi2_quantile(0.5, 0).is_nan());
    }
}
