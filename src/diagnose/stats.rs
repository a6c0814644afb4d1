//! Small statistics used by the diagnosis (its normal and χ² tails are
//! [`crate::stats`]'s): the Ljung–Box whiteness test \[LjungBox1978\], a linear trend test, cross-correlation and
//! robust centre and scale.

use serde::Serialize;

pub use crate::stats::{chi2_sf, normal_two_sided};

/// Tests that a normalised residual series (≈ N(0, 1) if the model is right)
/// carries no structure: its mean, a linear trend in time and its
/// autocorrelation (Ljung–Box).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StructureTest {
    /// Number of values tested.
    pub n: usize,
    /// Mean of the values and its two-sided p-value (σ estimated).
    pub mean: f64,
    /// p-value of the mean.
    pub mean_p: f64,
    /// Slope per unit time (normalised units per s) and its p-value.
    pub trend: f64,
    /// p-value of the trend.
    pub trend_p: f64,
    /// Ljung–Box Q over `lags` lags and its p-value (χ²_lags).
    pub ljung_box: f64,
    /// Lags used by Ljung–Box.
    pub lags: usize,
    /// p-value of Ljung–Box.
    pub ljung_box_p: f64,
}

impl StructureTest {
    /// The smallest of the three p-values.
    pub fn min_p(&self) -> f64 {
        self.mean_p.min(self.trend_p).min(self.ljung_box_p)
    }

    /// Runs the three tests on values `z` at times `t` (s); `None` below 8 values.
    pub fn run(t: &[f64], z: &[f64], max_lags: usize) -> Option<Self> {
        let n = z.len();
        if n < 8 || t.len() != n {
            return None;
        }
        let nf = n as f64;
        let mean = z.iter().sum::<f64>() / nf;
        let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / nf;
        let sd = var.max(1e-300).sqrt();
        // Mean tested against the unit variance of normalised values or the
        // sample variance, whichever is larger (robust to mis-scaled σ).
        let mean_p = normal_two_sided(mean * nf.sqrt() / sd.max(1.0));
        // Trend: least-squares slope on centred time.
        let tm = t.iter().sum::<f64>() / nf;
        let stt: f64 = t.iter().map(|x| (x - tm).powi(2)).sum();
        let (trend, trend_p) = if stt > 0.0 {
            let b = t
                .iter()
                .zip(z)
                .map(|(x, y)| (x - tm) * (y - mean))
                .sum::<f64>()
                / stt;
            let res = t
                .iter()
                .zip(z)
                .map(|(x, y)| (y - mean - b * (x - tm)).powi(2))
                .sum::<f64>()
                / (nf - 2.0);
            let se = (res.max(1.0) / stt).sqrt();
            (b, normal_two_sided(b / se))
        } else {
            (0.0, 1.0)
        };
        let lags = max_lags.min(n / 4).max(1);
        let c0: f64 = z.iter().map(|v| (v - mean).powi(2)).sum();
        let mut q = 0.0;
        if c0 > 0.0 {
            for k in 1..=lags {
                let ck: f64 = (k..n).map(|i| (z[i] - mean) * (z[i - k] - mean)).sum();
                let rho = ck / c0;
                q += rho * rho / (nf - k as f64);
            }
            q *= nf * (nf + 2.0);
        }
        Some(Self {
            n,
            mean,
            mean_p,
            trend,
            trend_p,
            ljung_box: q,
            lags,
            ljung_box_p: chi2_sf(q, lags),
        })
    }
}

/// Normalised cross-correlation of `a` with `b` shifted by each lag in
/// `-max_lag..=max_lag` samples: `corr(a[i], b[i − lag])`.
pub fn cross_correlation(a: &[f64], b: &[f64], max_lag: usize) -> Vec<(i64, f64)> {
    let n = a.len().min(b.len());
    let ma = a[..n].iter().sum::<f64>() / n.max(1) as f64;
    let mb = b[..n].iter().sum::<f64>() / n.max(1) as f64;
    let sa = a[..n].iter().map(|x| (x - ma).powi(2)).sum::<f64>().sqrt();
    let sb = b[..n].iter().map(|x| (x - mb).powi(2)).sum::<f64>().sqrt();
    let m = max_lag as i64;
    (-m..=m)
        .map(|lag| {
            let mut s = 0.0;
            for i in 0..n as i64 {
                let j = i - lag;
                if j >= 0 && (j as usize) < n {
                    s += (a[i as usize] - ma) * (b[j as usize] - mb);
                }
            }
            let c = if sa > 0.0 && sb > 0.0 {
                s / (sa * sb)
            } else {
                0.0
            };
            (lag, c)
        })
        .collect()
}

/// Median of `v` (sorted in place; the upper one of an even count; 0 when empty).
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Robust centre and scale (median, 1.4826·MAD) of a series.
pub fn robust(v: &[f64]) -> (f64, f64) {
    let mut a = v.to_vec();
    let m = median(&mut a);
    let mut d: Vec<f64> = v.iter().map(|x| (x - m).abs()).collect();
    (m, 1.4826 * median(&mut d))
}

/// Mean, RMS, standard deviation and extreme of a series.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct SeriesStats {
    /// Number of values.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
    /// Standard deviation.
    pub std: f64,
    /// Largest absolute value.
    pub max_abs: f64,
}

impl SeriesStats {
    /// Statistics of `x` (all zero when empty).
    pub fn of(x: &[f64]) -> Self {
        if x.is_empty() {
            return Self::default();
        }
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let ms = x.iter().map(|v| v * v).sum::<f64>() / n;
        Self {
            n: x.len(),
            mean,
            rms: ms.sqrt(),
            std: (ms - mean * mean).max(0.0).sqrt(),
            max_abs: x.iter().fold(0.0, |m, v| m.max(v.abs())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_distr::{Distribution, Normal};

    #[test]
    fn white_noise_passes_and_a_sine_fails() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let nd = Normal::new(0.0, 1.0).unwrap();
        let t: Vec<f64> = (0..300).map(|i| i as f64).collect();
        let z: Vec<f64> = t.iter().map(|_| nd.sample(&mut rng)).collect();
        let s = StructureTest::run(&t, &z, 10).unwrap();
        assert!(s.min_p() > 0.001, "{s:?}");
        let y: Vec<f64> = t
            .iter()
            .map(|x| 0.8 * (x / 4.0).sin() + nd.sample(&mut rng))
            .collect();
        assert!(StructureTest::run(&t, &y, 10).unwrap().ljung_box_p < 1e-6);
        let d: Vec<f64> = t
            .iter()
            .map(|x| x / 200.0 + rng.random_range(-1.0..1.0))
            .collect();
        assert!(StructureTest::run(&t, &d, 10).unwrap().trend_p < 1e-6);
    }

    #[test]
    fn cross_correlation_peaks_at_the_shift() {
        let a: Vec<f64> = (0..200).map(|i| ((i * 7919) % 113) as f64).collect();
        let b: Vec<f64> = (0..200).map(|i| a[(i + 3).min(199)]).collect();
        let cc = cross_correlation(&b, &a, 5);
        let best = cc.iter().max_by(|x, y| x.1.total_cmp(&y.1)).unwrap();
        assert_eq!(best.0, -3);
    }
}
