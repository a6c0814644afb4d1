//! Summary statistics of an error array, with evo's definitions
//! (`evo.core.metrics.PE.get_statistic`): RMSE, mean, median (mean of the two
//! middle values for an even count), population standard deviation (÷ N),
//! minimum and maximum.

use serde::{Deserialize, Serialize};

/// Statistics of a set of non-negative errors, in the errors' unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// sqrt(mean(e²)).
    pub rmse: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median (numpy's: average of the two middle values for even N).
    pub median: f64,
    /// Population standard deviation (÷ N, numpy's default).
    pub std: f64,
    /// Smallest error.
    pub min: f64,
    /// Largest error.
    pub max: f64,
}

impl Stats {
    /// Statistics of `errors`; `None` when empty or when any value is not finite.
    pub fn of(errors: &[f64]) -> Option<Self> {
        if errors.is_empty() || errors.iter().any(|e| !e.is_finite()) {
            return None;
        }
        let n = errors.len() as f64;
        let mean = errors.iter().sum::<f64>() / n;
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let std = (errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n).sqrt();
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let m = sorted.len();
        let median = if m % 2 == 1 {
            sorted[m / 2]
        } else {
            (sorted[m / 2 - 1] + sorted[m / 2]) / 2.0
        };
        Some(Self {
            rmse,
            mean,
            median,
            std,
            min: sorted[0],
            max: sorted[m - 1],
        })
    }

    /// The same statistics with every value multiplied by `k` (unit change,
    /// e.g. rad → deg); exact for all six because each scales linearly.
    pub fn scaled(&self, k: f64) -> Self {
        Self {
            rmse: self.rmse * k,
            mean: self.mean * k,
            median: self.median * k,
            std: self.std * k,
            min: self.min * k,
            max: self.max * k,
        }
    }
}

/// Mean and population standard deviation (÷ N) of a non-empty slice.
pub(crate) fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_numpy_definitions() {
        // numpy: rmse 2.7386127875258306, mean 2.5, median 2.5, std 1.118033988749895
        let s = Stats::of(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert!((s.rmse - 2.7386127875258306).abs() < 1e-15);
        assert_eq!(s.mean, 2.5);
        assert_eq!(s.median, 2.5);
        assert!((s.std - 1.118033988749895).abs() < 1e-15);
        assert_eq!((s.min, s.max), (1.0, 4.0));
        let odd = Stats::of(&[5.0, 1.0, 2.0]).unwrap();
        assert_eq!(odd.median, 2.0);
        assert!(Stats::of(&[]).is_none());
        assert!(Stats::of(&[1.0, f64::NAN]).is_none());
    }
}
