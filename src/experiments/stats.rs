//! Median and mean of a metric over the runs of an experiment.

use serde::Serialize;

/// Median and mean of a metric over the runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stat {
    /// Median.
    pub median: f64,
    /// Mean.
    pub mean: f64,
}

/// Median (even count: mean of the middle two) and mean of `x`; NaN for none.
pub fn stat(mut x: Vec<f64>) -> Stat {
    if x.is_empty() {
        return Stat {
            median: f64::NAN,
            mean: f64::NAN,
        };
    }
    x.sort_by(f64::total_cmp);
    let k = x.len();
    let median = if k % 2 == 1 {
        x[k / 2]
    } else {
        0.5 * (x[k / 2 - 1] + x[k / 2])
    };
    Stat {
        median,
        mean: x.iter().sum::<f64>() / k as f64,
    }
}

/// Median and mean of the finite values (0 when there are none).
pub fn finite_stat(mut x: Vec<f64>) -> Stat {
    x.retain(|v| v.is_finite());
    if x.is_empty() {
        return Stat {
            median: 0.0,
            mean: 0.0,
        };
    }
    stat(x)
}

/// Sample standard deviation (n − 1 in the denominator, at least 1).
pub fn sample_std(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len().max(2) - 1) as f64).sqrt()
}
