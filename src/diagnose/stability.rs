//! Whether what the model holds constant stays constant: a latency that
//! changes during the run, a laser knocked on its mounting during the run,
//! and a slip that happens only on part of the floor. All are faults
//! outside the effect table; each is tested on the residuals the selected
//! model leaves.
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
//!
//! Floor: the ICP motions are chained into a path; the forward-velocity
//! residual relative to the speed is averaged per pass through each cell of
//! a grid over that path, and the passes are compared across cells by a
//! one-way analysis of variance (a slippery patch is the same patch at every
//! pass; the pass-to-pass scatter within a cell is the noise it is judged
//! against).

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
    /// Grid cell of the floor test (m).
    pub cell: f64,
    /// Smallest difference of relative speed residual between the slippery
    /// and the other cells reported (relative).
    pub slip_floor: f64,
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
            cell: 3.0,
            slip_floor: 0.05,
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

/// Relative speed residual of one pass through one cell.
struct Pass {
    cell: (i64, i64),
    mean: f64,
}

/// Passes of the chained ICP path through the grid cells, each with its mean
/// relative forward-velocity residual (rows slower than `min_speed` m/s skipped).
fn passes(all: Part, x: &Departures, cell: f64, min_speed: f64) -> Vec<Pass> {
    let phys = all.physical(x);
    let nominal = Departures::default();
    let (mut px, mut py, mut th) = (0.0f64, 0.0f64, 0.0f64);
    let mut out: Vec<Pass> = Vec::new();
    let (mut cur, mut sum, mut n) = ((i64::MIN, i64::MIN), 0.0, 0usize);
    for (i, r) in all.icp.iter().enumerate() {
        let dt = r.t1 - r.t0;
        let (c, s) = (th.cos(), th.sin());
        px += (c * r.z[0] - s * r.z[1]) * dt;
        py += (s * r.z[0] + c * r.z[1]) * dt;
        th += r.z[2] * dt;
        let here = ((px / cell).floor() as i64, (py / cell).floor() as i64);
        if here != cur {
            if n >= 5 {
                out.push(Pass {
                    cell: cur,
                    mean: sum / n as f64,
                });
            }
            (cur, sum, n) = (here, 0.0, 0);
        }
        let v = all.replay.body(&nominal, r.t0, r.t1).0;
        if v.abs() >= min_speed {
            sum += phys[0][i] / v;
            n += 1;
        }
    }
    if n >= 5 {
        out.push(Pass {
            cell: cur,
            mean: sum / n as f64,
        });
    }
    out
}

/// Slip on part of the floor: cells whose passes share a different relative
/// speed residual than the rest, beyond chance (one-way ANOVA over cells
/// with ≥ 2 passes) and the floor.
pub fn floor_slip(all: Part, x: &Departures, s: &StabilitySettings) -> Option<Fault> {
    let ps = passes(all, x, s.cell, 0.2);
    let mut cells: BTreeMap<(i64, i64), Vec<f64>> = BTreeMap::new();
    for p in &ps {
        cells.entry(p.cell).or_default().push(p.mean);
    }
    cells.retain(|_, v| v.len() >= 2);
    let k = cells.len();
    let n: usize = cells.values().map(Vec::len).sum();
    if k < 3 || n <= k {
        return None;
    }
    let grand = cells.values().flatten().sum::<f64>() / n as f64;
    let means: BTreeMap<(i64, i64), f64> = cells
        .iter()
        .map(|(c, v)| (*c, v.iter().sum::<f64>() / v.len() as f64))
        .collect();
    let between: f64 = cells
        .iter()
        .map(|(c, v)| v.len() as f64 * (means[c] - grand).powi(2))
        .sum();
    let within: f64 = cells
        .iter()
        .map(|(c, v)| v.iter().map(|y| (y - means[c]).powi(2)).sum::<f64>())
        .sum();
    let f = (between / (k - 1) as f64) / (within / (n - k) as f64).max(1e-300);
    // F(k−1, n−k) tail through the χ² approximation of (k−1)·F for large n − k.
    let p = chi2_sf(f * (k - 1) as f64, k - 1);
    // The slippery cells: those more than halfway from the best to the worst.
    let (lo, hi) = means
        .values()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| {
            (l.min(*m), h.max(*m))
        });
    if !(p < s.alpha && hi - lo > s.slip_floor && n - k >= 10) {
        return None;
    }
    let mid = 0.5 * (lo + hi);
    let slippery: Vec<(i64, i64)> = means
        .iter()
        .filter(|(_, m)| **m < mid)
        .map(|(c, _)| *c)
        .collect();
    let inside: Vec<f64> = slippery.iter().map(|c| means[c]).collect();
    let outside: Vec<f64> = means
        .iter()
        .filter(|(_, m)| **m >= mid)
        .map(|(_, m)| *m)
        .collect();
    let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let slip = avg(&outside) - avg(&inside);
    let (xs, ys): (Vec<i64>, Vec<i64>) = slippery.iter().copied().unzip();
    let bbox = |v: &[i64]| {
        (
            *v.iter().min().unwrap_or(&0) as f64 * s.cell,
            (*v.iter().max().unwrap_or(&0) + 1) as f64 * s.cell,
        )
    };
    let (x0, x1) = bbox(&xs);
    let (y0, y1) = bbox(&ys);
    let mut parameters = BTreeMap::new();
    parameters.insert("slip".to_string(), slip);
    parameters.insert("cells".to_string(), slippery.len() as f64);
    Some(Fault {
        name: "floor_slip".into(),
        parameters,
        evidence: format!(
            "the forward-speed residual differs between places of the path, the same at every \
             pass (one-way ANOVA over {k} cells of {} m, {n} passes: F = {f:.1}, p = {p:.1e}); \
             the wheels over-read by {:.1} % in x {x0:.0}…{x1:.0} m, y {y0:.0}…{y1:.0} m of the \
             scan-matched path (origin at its start)",
            s.cell,
            100.0 * slip
        ),
        fix: "the floor there lets the wheels spin (wet, dusty, a ramp): odometry over it \
              cannot be calibrated by constants; weight the scan matching there or avoid the area"
            .into(),
    })
}
