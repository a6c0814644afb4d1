//! Whether what the model holds constant stays constant in time: a latency
//! that changes during the run and a laser knocked on its mounting during
//! the run, faults outside the effect table tested on the residuals the
//! selected model leaves (slip on part of the floor, which changes with
//! place, is [`super::floor`]'s).
//!
//! Knock: when the laser-mounting watch fires on the scan-matched motions
//! (the lean of the motions changes, [`super::mount`]), a laser mounting
//! change (x, y, yaw) from a time before that firing on, on top of the
//! selected model, at the split time that explains the residuals best
//! ([`super::split::search_split`], linearised); reported when it lowers
//! BIC by the margin (the three sizes and the time counted) and turns the
//! laser by more than `knock_floor_rad` (the scan matching leans by a few
//! 10⁻³ rad from one stretch of wall to the next).
//!
//! Latency: a replay whose encoder delay is off by δτ leaves a residual
//! δτ · dV/dt (and δτ · dW/dt): the delay error is regressed on the
//! predicted accelerations in consecutive time windows, and the windows'
//! estimates are tested for one common value (χ², K − 1 degrees of freedom,
//! Newey–West standard errors within each window).

use super::data::Part;
use super::diagnosis::Fault;
use super::fit::Fit;
use super::split::{search_split, SplitRange};
use super::stats::chi2_sf;
use crate::effects::Departures;
use std::collections::BTreeMap;

/// Settings of the stability tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilitySettings {
    /// Time windows for the latency.
    pub windows: usize,
    /// Smallest change of delay reported (s).
    pub latency_floor: f64,
    /// Share of the windows' scatter a single change must explain.
    pub change_share: f64,
    /// Family level of each test.
    pub alpha: f64,
    /// BIC margin of a knocked laser.
    pub knock_margin: f64,
    /// Smallest turn of a knocked laser reported (rad).
    pub knock_floor_rad: f64,
    /// Newey–West span (s).
    pub lag_seconds: f64,
}

impl Default for StabilitySettings {
    fn default() -> Self {
        Self {
            windows: 12,
            latency_floor: 0.02,
            change_share: 0.7,
            alpha: 1e-3,
            knock_margin: 10.0,
            knock_floor_rad: 0.01,
            lag_seconds: 3.0,
        }
    }
}

/// Residual, σ, predicted acceleration and time of each ICP row, forward
/// velocity and turn rate stacked.
struct AccelRows {
    t: Vec<f64>,
    y: Vec<f64>,
    sigma: Vec<f64>,
    accel: Vec<f64>,
}

fn accel_rows(all: Part, x: &Departures) -> AccelRows {
    let phys = all.physical(x);
    let nominal = Departures::default();
    let n = all.icp.len();
    let mids: Vec<f64> = all.icp.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let pred: Vec<(f64, f64)> = all
        .icp
        .iter()
        .map(|r| all.replay.body(&nominal, r.t0, r.t1))
        .collect();
    let mut out = AccelRows {
        t: Vec::new(),
        y: Vec::new(),
        sigma: Vec::new(),
        accel: Vec::new(),
    };
    for (g, comp) in [(0usize, 0usize), (2, 1)] {
        for i in 1..n.saturating_sub(1) {
            let dt = mids[i + 1] - mids[i - 1];
            if !(dt > 0.0 && dt < 1.0) {
                continue;
            }
            let f = |k: usize| if comp == 0 { pred[k].0 } else { pred[k].1 };
            out.t.push(mids[i]);
            out.y.push(phys[g][i]);
            out.sigma.push(all.icp[i].sigma[g]);
            out.accel.push((f(i + 1) - f(i - 1)) / dt);
        }
    }
    out
}

/// Weighted slope of y on a (through the origin) with a Newey–West
/// standard error over `lags` rows: (slope, stderr).
fn slope(y: &[f64], a: &[f64], s: &[f64], lags: usize) -> Option<(f64, f64)> {
    let sxx: f64 = a.iter().zip(s).map(|(x, s)| (x / s).powi(2)).sum();
    if !(sxx > 0.0) || y.len() < 20 {
        return None;
    }
    let sxy: f64 = y
        .iter()
        .zip(a)
        .zip(s)
        .map(|((y, x), s)| y * x / (s * s))
        .sum();
    let b = sxy / sxx;
    let g: Vec<f64> = y
        .iter()
        .zip(a)
        .zip(s)
        .map(|((y, x), s)| (x / s) * (y - b * x) / s)
        .collect();
    let mut v: f64 = g.iter().map(|v| v * v).sum();
    for l in 1..=lags.min(g.len() - 1) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        v += 2.0 * w * (l..g.len()).map(|i| g[i] * g[i - l]).sum::<f64>();
    }
    Some((b, v.max(0.0).sqrt() / sxx))
}

/// A latency that changes during the run: per-window delays about the
/// model's `latency` (s), when they differ beyond chance and the floor.
pub fn latency_change(all: Part, x: &Departures, s: &StabilitySettings) -> Option<Fault> {
    let r = accel_rows(all, x);
    let (t0, t1) =
        r.t.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(*t), b.max(*t))
            });
    if !(t1 > t0) || s.windows < 2 {
        return None;
    }
    let width = (t1 - t0) / s.windows as f64;
    let mut est = Vec::new();
    for k in 0..s.windows {
        let (a, b) = (t0 + k as f64 * width, t0 + (k + 1) as f64 * width);
        let idx: Vec<usize> = (0..r.t.len())
            .filter(|&i| r.t[i] >= a && r.t[i] < b + 1e-9)
            .collect();
        let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<_>>();
        let rows_per_s = idx.len() as f64 / width;
        let lags = (s.lag_seconds * rows_per_s).ceil() as usize;
        if let Some((c, se)) = slope(&pick(&r.y), &pick(&r.accel), &pick(&r.sigma), lags.max(1)) {
            if se > 0.0 && se.is_finite() {
                est.push((0.5 * (a + b), x.latency + c, se));
            }
        }
    }
    if est.len() < 4 {
        return None;
    }
    let w: f64 = est.iter().map(|e| 1.0 / (e.2 * e.2)).sum();
    let mean = est.iter().map(|e| e.1 / (e.2 * e.2)).sum::<f64>() / w;
    let chi2: f64 = est.iter().map(|e| ((e.1 - mean) / e.2).powi(2)).sum();
    let p = chi2_sf(chi2, est.len() - 1);
    // A change, not scatter: one split into two runs of ≥ 2 windows each
    // must carry most of the windows' weighted scatter.
    let (split, r2, before, after) = best_split(&est)?;
    if !(p < s.alpha && r2 > s.change_share && (after - before).abs() > s.latency_floor) {
        return None;
    }
    let mut parameters = BTreeMap::new();
    parameters.insert("delay_before".to_string(), before);
    parameters.insert("delay_after".to_string(), after);
    parameters.insert("time".to_string(), split - all.replay.origin);
    let windows = est
        .iter()
        .map(|e| {
            format!(
                "{:.0} s: {:+.3} ± {:.3} s",
                e.0 - all.replay.origin,
                e.1,
                e.2
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    Some(Fault {
        name: "latency_change".into(),
        parameters,
        evidence: format!(
            "the encoder delay fitted per window differs beyond chance (χ² = {chi2:.1}, \
             {} dof, p = {p:.1e}) and changes at about {:.0} s ({:.0} % of the scatter): \
             {windows}",
            est.len() - 1,
            split - all.replay.origin,
            100.0 * r2
        ),
        fix: "the wheel and laser clocks drift or the driver buffers differently over \
              time: stamp the encoders at acquisition (or synchronise the clocks); one \
              constant latency does not describe this run"
            .into(),
    })
}

/// The split of the windows' delays (time, value, stderr) into two runs of
/// at least two windows that leaves the least weighted scatter: its time,
/// the share of the scatter it explains, and the two runs' weighted means.
fn best_split(est: &[(f64, f64, f64)]) -> Option<(f64, f64, f64, f64)> {
    let wmean = |v: &[(f64, f64, f64)]| {
        let w: f64 = v.iter().map(|e| 1.0 / (e.2 * e.2)).sum();
        v.iter().map(|e| e.1 / (e.2 * e.2)).sum::<f64>() / w
    };
    let rss =
        |v: &[(f64, f64, f64)], m: f64| v.iter().map(|e| ((e.1 - m) / e.2).powi(2)).sum::<f64>();
    let total = rss(est, wmean(est));
    if !(total > 0.0) {
        return None;
    }
    (2..=est.len() - 2)
        .map(|k| {
            let (a, b) = est.split_at(k);
            let (ma, mb) = (wmean(a), wmean(b));
            let left = rss(a, ma) + rss(b, mb);
            (0.5 * (a[k - 1].0 + b[0].0), 1.0 - left / total, ma, mb)
        })
        .max_by(|x, y| x.1.total_cmp(&y.1))
}

/// A laser knocked during the run: when the laser-mounting watch
/// ([`super::mount`], its default settings, the same as `calibrate`'s) fires
/// on the scan-matched `motions`, the mounting change from the split time
/// before that firing on, on top of `model`, when it lowers BIC by the
/// margin and turns the laser beyond the floor.
pub fn laser_knock(
    all: Part,
    model: &Fit,
    motions: &[crate::motion::Motion],
    s: &StabilitySettings,
) -> Option<Fault> {
    let p = super::mount::MountParams::default();
    let mut watch = super::mount::MountWatch::new(&p);
    let fired = motions.iter().find_map(|m| watch.motion(m))?;
    let e = crate::effects::Effect::LaserOffset {
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
    };
    let c = all.counts();
    let n: usize = c.iter().sum();
    let origin = all.replay.origin;
    let range = SplitRange {
        time: (fired - watch.lag_s() - origin, fired - origin),
        min_rows: 100,
    };
    let f = search_split(all, model, &e, range)?;
    let delta_bic = f.drop - 4.0 * (n as f64).ln();
    let [dx, dy, dyaw] = [f.params[0], f.params[1], f.params[2]];
    if !(delta_bic > s.knock_margin && dyaw.abs() > s.knock_floor_rad) {
        return None;
    }
    let mut parameters = BTreeMap::new();
    parameters.insert("time".to_string(), f.time);
    parameters.insert("dx".to_string(), dx);
    parameters.insert("dy".to_string(), dy);
    parameters.insert("dyaw".to_string(), dyaw);
    Some(Fault {
        name: "laser_knock".into(),
        parameters,
        evidence: format!(
            "from {:.1} s on (between {:.1} and {:.1} s) the scan matching moves as a laser \
             mounted {:+.1} ± {:.1} mm forward, {:+.1} ± {:.1} mm left and turned {:+.2} ± \
             {:.2}° from before would (ΔBIC {delta_bic:.1} on top of the model)",
            f.time,
            f.interval.0,
            f.interval.1,
            1e3 * dx,
            1e3 * f.stderr[0],
            1e3 * dy,
            1e3 * f.stderr[1],
            dyaw.to_degrees(),
            f.stderr[2].to_degrees()
        ),
        fix: "the laser moved on its bracket during the run: fasten it and measure its \
              mounting again; the recording before and after is two mountings, calibrate \
              each part on its own"
            .into(),
    })
}
