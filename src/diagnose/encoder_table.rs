//! Encoder-versus-tachometer tables ([Paryanto, Table I]): per wheel, does a
//! constant scale (ω_meas = s ω) or the speed-dependent gain of the effect
//! table (ω_meas = ω (1 + k |ω|)) explain the readings better, by BIC?

use serde::Serialize;

/// One wheel's two competing fits (rates in rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WheelGainFit {
    /// Constant scale s and its standard error.
    pub scale: f64,
    /// Standard error of `scale`.
    pub scale_se: f64,
    /// Speed-dependent gain k (s/rad) and its standard error.
    pub k: f64,
    /// Standard error of `k`.
    pub k_se: f64,
    /// Residual sum of squares of the scale model ((rad/s)²).
    pub rss_scale: f64,
    /// Residual sum of squares of the gain model ((rad/s)²).
    pub rss_gain: f64,
    /// BIC(scale) − BIC(gain) with the reading σ known (> 0 favours the gain).
    pub delta_bic: f64,
    /// The same with σ profiled out (unknown σ).
    pub delta_bic_profiled: f64,
    /// The same with relative errors (σ ∝ ω, profiled): what one would get
    /// if the readings' error grew with speed instead of being rounding.
    pub delta_bic_relative: f64,
}

/// Both wheels of a table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EncoderTableFit {
    /// Right wheel.
    pub right: WheelGainFit,
    /// Left wheel.
    pub left: WheelGainFit,
    /// σ of one reading difference used for `delta_bic` (rad/s).
    pub sigma: f64,
}

/// rpm → rad/s.
pub const RPM: f64 = std::f64::consts::TAU / 60.0;

/// Parses the CSV text (`#` comments, a header, then
/// `tachometer_rpm,right_encoder_rpm,left_encoder_rpm`) into rows (rpm).
pub fn parse_table(text: &str) -> Result<Vec<[f64; 3]>, String> {
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') || l.starts_with("tachometer") {
            continue;
        }
        let v: Vec<f64> = l
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("line {}: {e}", i + 1))?;
        if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
            return Err(format!("line {}: expected 3 finite numbers", i + 1));
        }
        rows.push([v[0], v[1], v[2]]);
    }
    Ok(rows)
}

/// One-regressor least squares of y on x (no intercept): (b, se with σ, rss).
fn ls(x: &[f64], y: &[f64], sigma: f64) -> (f64, f64, f64) {
    let sxx: f64 = x.iter().map(|v| v * v).sum();
    let b = x.iter().zip(y).map(|(a, c)| a * c).sum::<f64>() / sxx;
    let rss = x.iter().zip(y).map(|(a, c)| (c - b * a).powi(2)).sum();
    (b, sigma / sxx.sqrt(), rss)
}

fn wheel(t: &[f64], m: &[f64], sigma: f64) -> WheelGainFit {
    let n = t.len() as f64;
    // Scale: m = s t.  Gain: m − t = k t|t|.
    let (scale, scale_se, rss_scale) = ls(t, m, sigma);
    let x: Vec<f64> = t.iter().map(|v| v * v.abs()).collect();
    let d: Vec<f64> = m.iter().zip(t).map(|(a, b)| a - b).collect();
    let (k, k_se, rss_gain) = ls(&x, &d, sigma);
    // Relative errors: ratio q = m/t; scale: q = s; gain: q − 1 = k|t|.
    let q: Vec<f64> = m.iter().zip(t).map(|(a, b)| a / b).collect();
    let qm = q.iter().sum::<f64>() / n;
    let rss_rel_scale: f64 = q.iter().map(|v| (v - qm).powi(2)).sum();
    let abs_t: Vec<f64> = t.iter().map(|v| v.abs()).collect();
    let q1: Vec<f64> = q.iter().map(|v| v - 1.0).collect();
    let (_, _, rss_rel_gain) = ls(&abs_t, &q1, 1.0);
    // One parameter each: the ln n penalties cancel.
    WheelGainFit {
        scale,
        scale_se,
        k,
        k_se,
        rss_scale,
        rss_gain,
        delta_bic: (rss_scale - rss_gain) / (sigma * sigma),
        delta_bic_profiled: n * (rss_scale / rss_gain).ln(),
        delta_bic_relative: n * (rss_rel_scale / rss_rel_gain).ln(),
    }
}

/// Fits both wheels; `sigma_rpm` is the σ of (encoder − tachometer) in rpm
/// (readings rounded to whole rpm on both instruments: √(2/12) ≈ 0.41 rpm).
pub fn fit_table(rows: &[[f64; 3]], sigma_rpm: f64) -> Option<EncoderTableFit> {
    if rows.len() < 3 || sigma_rpm.is_nan() || sigma_rpm <= 0.0 {
        return None;
    }
    let t: Vec<f64> = rows.iter().map(|r| r[0] * RPM).collect();
    let right: Vec<f64> = rows.iter().map(|r| r[1] * RPM).collect();
    let left: Vec<f64> = rows.iter().map(|r| r[2] * RPM).collect();
    let sigma = sigma_rpm * RPM;
    Some(EncoderTableFit {
        right: wheel(&t, &right, sigma),
        left: wheel(&t, &left, sigma),
        sigma,
    })
}
