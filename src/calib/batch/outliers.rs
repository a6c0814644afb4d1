//! Outlier rejection as the solver of \[Censi2013\] does it (`solver2.cpp`): after
//! each fit, an interval is dropped when its translation residual or its
//! rotation residual lies above that residual's (1 − f) quantile; four
//! rounds of f = 1 % by default. Here the residuals are normalised by their
//! covariance (χ² of the translation block, e_θ²/σ_θ²), which orders them as
//! Censi's |e_xy| and |e_θ| when all intervals share one σ.

use super::model::P3;
use nalgebra::Matrix3;

/// The translation and rotation χ² of a residual.
pub fn chi2_parts(e: P3, cov: &Matrix3<f64>) -> (f64, f64) {
    let c2 = cov.fixed_view::<2, 2>(0, 0).into_owned();
    let v = nalgebra::Vector2::new(e[0], e[1]);
    let xy = c2
        .try_inverse()
        .map(|i| (v.transpose() * i * v)[0])
        .unwrap_or(f64::INFINITY);
    (xy, e[2] * e[2] / cov[(2, 2)])
}

/// The (1 − f) quantile of `v` by Censi's index, round((1 − f)·n).
fn quantile(v: &[f64], f: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = (((1.0 - f) * s.len() as f64).round() as usize).min(s.len() - 1);
    s[i]
}

/// Which of the intervals to keep: `false` for those above either quantile.
pub fn keep(residuals: &[P3], covs: &[Matrix3<f64>], fraction: f64) -> Vec<bool> {
    if residuals.is_empty() {
        return Vec::new();
    }
    let parts: Vec<(f64, f64)> = residuals
        .iter()
        .zip(covs)
        .map(|(e, c)| chi2_parts(*e, c))
        .collect();
    let xy: Vec<f64> = parts.iter().map(|p| p.0).collect();
    let th: Vec<f64> = parts.iter().map(|p| p.1).collect();
    let (qxy, qth) = (quantile(&xy, fraction), quantile(&th, fraction));
    parts.iter().map(|&(a, b)| a <= qxy && b <= qth).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_the_residuals_above_each_quantile() {
        let covs = vec![Matrix3::identity(); 1000];
        let mut e: Vec<P3> = (0..1000).map(|i| [i as f64 * 1e-3, 0.0, 0.0]).collect();
        e[3][2] = 10.0; // a rotation outlier
        let k = keep(&e, &covs, 0.01);
        // Censi's index round(0.99·1000) = 990: the nine translations above
        // the 991st are dropped, and the one rotation outlier.
        assert!(k[..990].iter().enumerate().all(|(i, &x)| x == (i != 3)));
        assert!(k[990] && k[991..].iter().all(|x| !x));
        assert_eq!(k.iter().filter(|x| !**x).count(), 10);
    }
}
