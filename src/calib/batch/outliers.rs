//! Outlier rejection. Censi et al.'s solver (`solver2.cpp`): after each
//! fit, an interval is dropped when its translation residual or its rotation
//! residual lies above that residual's (1 − f) quantile; four rounds of
//! f = 1 % by default. Here the residuals are normalised by their covariance
//! (χ² of the translation block, e_θ²/σ_θ²), which orders them as Censi's
//! |e_xy| and |e_θ| when all intervals share one σ.
//!
//! A fixed fraction removes at most one interval of a hundred per round,
//! whatever the data hold: a scan matcher that stalls on a few fast
//! stretches (it reports a fraction of the travel, with a confident
//! covariance) leaves intervals that carry several per cent of the radii.
//! [`consistent`] therefore also drops every interval whose whitened χ²,
//! in units of the kept intervals' typical χ² (median / the median of χ²₃),
//! lies beyond the χ²₃ quantile of `1 − p`: a robust scale, as in
//! \[Rousseeuw1987\], so the threshold follows the recording's own spread
//! rather than covariances that may be too small for it.

use super::model::P3;
use crate::stats::chi2_quantile;
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

/// The full whitened χ² `eᵀ Σ⁻¹ e` of a residual (∞ for a singular Σ).
pub fn chi2(e: P3, cov: &Matrix3<f64>) -> f64 {
    let v = nalgebra::Vector3::from(e);
    cov.try_inverse()
        .map(|i| (v.transpose() * i * v)[0])
        .unwrap_or(f64::INFINITY)
}

/// Which intervals are consistent with the rest: `false` for those whose χ²
/// over the robust scale (the median χ² of those in `kept`, over the median
/// of χ²₃) exceeds the χ²₃ quantile of `1 − probability`, the largest first
/// and at most `max_fraction` of all: a recording whose residuals are far
/// from Gaussian everywhere (heavy tails, errors that grow with speed) is
/// not cut down to its quietest part. All kept when `probability` is 0 or
/// fewer than 10 intervals are kept.
pub fn consistent(
    residuals: &[P3],
    covs: &[Matrix3<f64>],
    kept: &[bool],
    probability: f64,
    max_fraction: f64,
) -> Vec<bool> {
    let c: Vec<f64> = residuals
        .iter()
        .zip(covs)
        .map(|(e, s)| chi2(*e, s))
        .collect();
    let mut k: Vec<f64> = c
        .iter()
        .zip(kept)
        .filter(|(x, k)| **k && x.is_finite())
        .map(|(x, _)| *x)
        .collect();
    let mut out = vec![true; c.len()];
    if !(probability > 0.0) || k.len() < 10 {
        return out;
    }
    k.sort_by(f64::total_cmp);
    let scale = (k[k.len() / 2] / chi2_quantile(0.5, 3)).max(f64::MIN_POSITIVE);
    let limit = chi2_quantile(1.0 - probability, 3);
    let mut beyond: Vec<usize> = (0..c.len()).filter(|&i| !(c[i] / scale <= limit)).collect();
    beyond.sort_by(|&a, &b| c[b].total_cmp(&c[a]));
    let most = (max_fraction * c.len() as f64).floor() as usize;
    beyond.into_iter().take(most).for_each(|i| out[i] = false);
    out
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

    #[test]
    fn drops_what_lies_beyond_the_robust_spread_whatever_the_covariances_claim() {
        // 200 residuals of σ 1 mm judged with a covariance claiming 0.1 mm
        // (χ² ≈ 100 each), and four stalls of 50 mm: the scale follows the
        // data, so the ordinary ones stay and only the stalls go.
        let covs = vec![Matrix3::identity() * 1e-8; 204];
        let mut e: Vec<P3> = (0..200)
            .map(|i| {
                let a = (i as f64 * 0.7).sin();
                let b = (i as f64 * 1.3).cos();
                [1e-3 * a, 1e-3 * b, 1e-3 * (a - b)]
            })
            .collect();
        e.extend([[0.05, 0.0, 0.0]; 4]);
        let k = consistent(&e, &covs, &vec![true; 204], 1e-3, 0.1);
        assert!(k[..200].iter().all(|x| *x));
        assert!(k[200..].iter().all(|x| !*x));
        // At most a tenth: of 34 beyond (30 of 10–12.9 mm and the four
        // stalls), the 20 largest go: the stalls and the 16 largest of 30.
        let mut many = e.clone();
        (0..30).for_each(|i| many[i] = [0.01 + 1e-4 * i as f64, 0.0, 0.0]);
        let k = consistent(&many, &covs, &vec![true; 204], 1e-3, 0.1);
        assert_eq!(k.iter().filter(|x| !**x).count(), 20);
        assert!(k[200..].iter().all(|x| !*x));
        assert!(k[..14].iter().all(|x| *x) && k[14..30].iter().all(|x| !*x));
        // Off, or too few to judge: all kept.
        assert!(consistent(&e, &covs, &vec![true; 204], 0.0, 0.1)
            .iter()
            .all(|x| *x));
        assert!(consistent(&e[..9], &covs[..9], &[true; 9], 1e-3, 0.1)
            .iter()
            .all(|x| *x));
    }
}
