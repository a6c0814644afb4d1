//! The diagnosis driver and its result: verdict, causes with estimates,
//! held-out gain, structure tests and the residual series for plots.

use super::data::{gyro_rows, icp_rows, GyroRow, IcpRow, Part, GROUPS};
use super::fit::Fit;
use super::model::{Extension, Replay};
use super::select::{forward, named, CandidateScore, SelectSettings};
use super::stats::{cross_correlation, SeriesStats, StructureTest};
use super::trajectory::{trajectory_gain, TrajectoryGain};
use super::{DiagnoseError, DiagnoseParams, Measured};
use crate::robot::RobotConfig;
use serde::Serialize;
use std::collections::BTreeMap;

/// What the diagnosis concludes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Named causes explain the discrepancy.
    Explained,
    /// The nominal model agrees with the measurements within their noise.
    NoDiscrepancy,
    /// The residuals hold structure that no candidate explains.
    Unexplained,
}

/// One named cause with its estimate (design.md JSON keys).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cause {
    /// Effect name (design.md's table).
    pub effect: String,
    /// Estimated parameters (units of the effect table).
    pub parameters: BTreeMap<String, f64>,
    /// Their standard errors (a radius step's time has none: grid-searched).
    pub stderr: BTreeMap<String, f64>,
    /// BIC improvement when the effect entered the model.
    pub delta_bic: f64,
}

/// Held-out RMSE of one stream before/after, in its physical unit (m/s, rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StreamGain {
    /// Held-out rows.
    pub n: usize,
    /// RMSE with the nominal model.
    pub before: f64,
    /// RMSE with the extended model.
    pub after: f64,
}

/// Prediction gain on the held-out part (design.md JSON keys). The RMSE is
/// of σ-normalised residuals (each stream divided by its measurement σ times
/// the stream's noise scale fitted on the training part), pooled over streams.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gain {
    /// Normalised RMSE with the nominal model.
    pub heldout_rmse_before: f64,
    /// Normalised RMSE with the extended model.
    pub heldout_rmse_after: f64,
    /// (before − after) / before.
    pub relative: f64,
    /// Per-stream RMSE in physical units.
    pub streams: BTreeMap<String, StreamGain>,
    /// Relative-pose error against the reference on the held-out part
    /// (absent without a reference).
    pub trajectory: Option<TrajectoryGain>,
}

/// Residual series and regressors for the report's plots (one entry per ICP
/// row or gyro window, in time order).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ResidualSeries {
    /// Start of the held-out part (s).
    pub split: f64,
    /// ICP interval midpoints (s).
    pub t: Vec<f64>,
    /// Predicted forward speed V (m/s, nominal model).
    pub speed: Vec<f64>,
    /// Predicted turn rate W (rad/s, nominal model).
    pub turn_rate: Vec<f64>,
    /// |V|·|W| (m/s · rad/s).
    pub speed_turn: Vec<f64>,
    /// dV/dt (m/s²).
    pub accel: Vec<f64>,
    /// dW/dt (rad/s²).
    pub turn_accel: Vec<f64>,
    /// ICP V residual before/after (m/s).
    pub v_before: Vec<f64>,
    /// After the extension.
    pub v_after: Vec<f64>,
    /// ICP lateral residual before/after (m/s).
    pub lateral_before: Vec<f64>,
    /// After the extension.
    pub lateral_after: Vec<f64>,
    /// ICP W residual before/after (rad/s).
    pub w_before: Vec<f64>,
    /// After the extension.
    pub w_after: Vec<f64>,
    /// Gyro window midpoints (s).
    pub gyro_t: Vec<f64>,
    /// Gyro residual before/after (rad/s).
    pub gyro_before: Vec<f64>,
    /// After the extension.
    pub gyro_after: Vec<f64>,
    /// Cross-correlation of the V residual (before) with dV/dt at lags (s):
    /// a peak away from zero lag or a strong zero-lag value hints at latency.
    pub lag_v_accel: Vec<(f64, f64)>,
    /// Same for the W residual with dW/dt.
    pub lag_w_accel: Vec<(f64, f64)>,
}

/// The whole diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// `explained`, `no-discrepancy` or `unexplained`.
    pub verdict: Verdict,
    /// Named causes (empty unless explained), from the final joint fit.
    pub causes: Vec<Cause>,
    /// Held-out gain of the extension.
    pub gain: Gain,
    /// Whether structure remains after the extension (explained verdicts).
    pub remaining_structure: bool,
    /// Effects the training data selected but the held-out part did not
    /// confirm (the held-out χ² dropped by less than the margin).
    pub heldout_rejected: Vec<Cause>,
    /// Every candidate tried in every selection round.
    pub candidates: Vec<CandidateScore>,
    /// Structure tests per stream on binned residuals, nominal model.
    pub structure_before: BTreeMap<String, StructureTest>,
    /// Same, extended model.
    pub structure_after: BTreeMap<String, StructureTest>,
    /// Residual statistics per stream (physical units), nominal model, all rows.
    pub stats_before: BTreeMap<String, SeriesStats>,
    /// Same, extended model.
    pub stats_after: BTreeMap<String, SeriesStats>,
    /// Noise scale per stream fitted on the training part (σ_actual / σ_given).
    pub noise_scale: BTreeMap<String, f64>,
    /// Rows used: training, held-out, rejected as outliers.
    pub rows: BTreeMap<String, usize>,
    /// Residual series for plots (not in the JSON summary).
    #[serde(skip)]
    pub series: ResidualSeries,
}

/// Physical residuals (measured − predicted) per group.
fn physical(replay: &Replay, icp: &[IcpRow], gyro: &[GyroRow], x: &Extension) -> [Vec<f64>; 4] {
    let mut out: [Vec<f64>; 4] = Default::default();
    for r in icp {
        let p = replay.icp(x, r.t0, r.t1);
        out[0].push(r.z[0] - p.v);
        out[1].push(r.z[1] - p.l);
        out[2].push(r.z[2] - p.w);
    }
    for g in gyro {
        out[3].push(g.w - replay.gyro(x, g.t0, g.t1));
    }
    out
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Robust centre and scale (median, 1.4826·MAD) of a series.
fn robust(v: &[f64]) -> (f64, f64) {
    let mut a = v.to_vec();
    let m = median(&mut a);
    let mut d: Vec<f64> = v.iter().map(|x| (x - m).abs()).collect();
    (m, 1.4826 * median(&mut d))
}

/// Binned normalised residuals (per bin: Σ e / (scale √n)) and bin times.
fn binned(mids: &[f64], e: &[f64], scale: f64, bin: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut t, mut z) = (Vec::new(), Vec::new());
    let Some(&t0) = mids.first() else {
        return (t, z);
    };
    let (mut k, mut s, mut n, mut ts) = (0i64, 0.0, 0usize, 0.0);
    for (m, v) in mids.iter().zip(e) {
        let kk = ((m - t0) / bin).floor() as i64;
        if kk != k && n > 0 {
            t.push(ts / n as f64);
            z.push(s / (scale * (n as f64).sqrt()));
            (s, n, ts) = (0.0, 0, 0.0);
        }
        k = kk;
        s += v;
        n += 1;
        ts += m;
    }
    if n > 0 {
        t.push(ts / n as f64);
        z.push(s / (scale * (n as f64).sqrt()));
    }
    (t, z)
}

fn structure(
    all: Part,
    x: &Extension,
    scale: &[f64; 4],
    p: &DiagnoseParams,
) -> BTreeMap<String, StructureTest> {
    let mut e: [Vec<f64>; 4] = Default::default();
    all.normalised(x, &mut e);
    let mi: Vec<f64> = all.icp.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let mg: Vec<f64> = all.gyro.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let mut out = BTreeMap::new();
    for g in 0..4 {
        let mids = if g < 3 { &mi } else { &mg };
        let (t, z) = binned(mids, &e[g], scale[g], p.bin_seconds);
        if let Some(s) = StructureTest::run(&t, &z, p.ljung_box_lags) {
            out.insert(GROUPS[g].to_string(), s);
        }
    }
    out
}

fn has_structure(tests: &BTreeMap<String, StructureTest>, alpha: f64) -> bool {
    let m = (3 * tests.len()).max(1) as f64;
    tests.values().any(|s| s.min_p() < alpha / m)
}

fn stats(res: &[Vec<f64>; 4]) -> BTreeMap<String, SeriesStats> {
    (0..4)
        .filter(|g| !res[*g].is_empty())
        .map(|g| (GROUPS[g].to_string(), SeriesStats::of(&res[g])))
        .collect()
}

/// Runs replay, selection, gain and tests (params already validated).
pub fn run(
    robot: &RobotConfig,
    m: &Measured,
    p: &DiagnoseParams,
) -> Result<Diagnosis, DiagnoseError> {
    let origin = m.origin();
    let replay = Replay::new(robot, m.wheels, origin, p.wheel_smoothing);
    let span = replay
        .span()
        .filter(|s| replay.len() >= 2 && s.1 > s.0)
        .ok_or_else(|| DiagnoseError::TooLittleData("fewer than 2 wheel samples".into()))?;
    let merged = super::data::merge_motions(m.motions, p.min_interval);
    let mut icp = icp_rows(&merged, span, p.margin);
    let mut gyro = gyro_rows(m.gyro, span, p.margin, p.gyro_window);
    // Outliers: far from the nominal model in robust σ units.
    let nominal = Extension::default();
    let before_rej = (icp.len(), gyro.len());
    {
        let all = Part {
            replay: &replay,
            icp: &icp,
            gyro: &gyro,
        };
        let mut e: [Vec<f64>; 4] = Default::default();
        all.normalised(&nominal, &mut e);
        let rb: Vec<(f64, f64)> = e.iter().map(|v| robust(v)).collect();
        let bad = |g: usize, v: f64| {
            let (c, s) = rb[g];
            s > 0.0 && ((v - c) / s).abs() > p.outlier_sigma
        };
        let keep_icp: Vec<bool> = (0..icp.len())
            .map(|i| !(0..3).any(|g| bad(g, e[g][i])))
            .collect();
        let keep_gyro: Vec<bool> = (0..gyro.len()).map(|i| !bad(3, e[3][i])).collect();
        let mut it = keep_icp.iter();
        icp.retain(|_| *it.next().unwrap());
        let mut it = keep_gyro.iter();
        gyro.retain(|_| *it.next().unwrap());
    }
    let rejected = before_rej.0 - icp.len() + before_rej.1 - gyro.len();
    if icp.len() < 50 {
        return Err(DiagnoseError::TooLittleData(format!(
            "{} usable ICP motions inside the wheel stream (need ≥ 50)",
            icp.len()
        )));
    }
    let t_end = icp.last().map(|r| r.t1).unwrap_or(span.1).max(span.1);
    let t_start = icp[0].t0.min(span.0);
    let split = t_start + (1.0 - p.holdout) * (t_end - t_start);
    let n_icp_train = icp.partition_point(|r| r.t1 <= split);
    let n_gyro_train = gyro.partition_point(|r| r.t1 <= split);
    let i_ho = icp.partition_point(|r| r.t0 < split);
    let g_ho = gyro.partition_point(|r| r.t0 < split);
    if n_icp_train < 30 || icp.len() - i_ho < 10 {
        return Err(DiagnoseError::TooLittleData(
            "too few ICP motions in the training or held-out part".into(),
        ));
    }
    let train = Part {
        replay: &replay,
        icp: &icp[..n_icp_train],
        gyro: &gyro[..n_gyro_train],
    };
    let held = Part {
        replay: &replay,
        icp: &icp[i_ho..],
        gyro: &gyro[g_ho..],
    };
    let all = Part {
        replay: &replay,
        icp: &icp,
        gyro: &gyro,
    };
    let usable: Vec<String> = p
        .candidates
        .iter()
        .filter(|c| c.as_str() != "gyro_bias" || train.gyro.len() >= 20)
        .cloned()
        .collect();
    let settings = SelectSettings {
        candidates: usable.clone(),
        bic_margin: p.bic_margin,
        alpha: p.alpha,
        max_effects: p.max_effects,
        max_iter: p.max_iter,
        step_range: (t_start - origin + 1.0, split - origin - 1.0),
        step_min_rows: 30,
    };
    // Held-out confirmation of the nested models, in order of selection.
    let sse = |x: &Extension, scale: &[f64; 4]| {
        let mut e: [Vec<f64>; 4] = Default::default();
        held.normalised(x, &mut e);
        (0..4)
            .map(|g| e[g].iter().map(|v| (v / scale[g]).powi(2)).sum::<f64>())
            .sum::<f64>()
    };
    let confirmed = |sel: &super::select::Selection| {
        let mut kept = 0;
        for (k, step) in sel.steps.iter().enumerate() {
            let prev = if k == 0 {
                Extension::default()
            } else {
                Extension::from_effects(&sel.steps[k - 1].effects)
            };
            let drop =
                sse(&prev, &step.scale) - sse(&Extension::from_effects(&step.effects), &step.scale);
            if drop < p.heldout_margin {
                break;
            }
            kept = k + 1;
        }
        kept
    };
    let cause = |f: &Fit, i: usize, delta_bic: f64| {
        let (parameters, stderr) = named(f, i);
        Cause {
            effect: f.effects[i].name().to_string(),
            parameters,
            stderr,
            delta_bic,
        }
    };
    // An effect the held-out part does not confirm is vetoed and the
    // selection restarts without it, so a spurious first choice (one that
    // fits the training part by accident) cannot hide a real cause behind it.
    let mut usable = usable;
    let mut heldout_rejected: Vec<Cause> = Vec::new();
    let (sel, kept) = loop {
        let sel = forward(train, &usable, &settings);
        let kept = confirmed(&sel);
        if kept == sel.steps.len() {
            break (sel, kept);
        }
        let f = &sel.steps[kept];
        heldout_rejected.push(cause(f, kept, sel.delta_bic[kept]));
        let name = f.effects[kept].name();
        usable.retain(|c| c != name);
    };
    let model: &Fit = if kept == 0 {
        &sel.nominal
    } else {
        &sel.steps[kept - 1]
    };
    let xm = Extension::from_effects(&model.effects);
    // Gain on the held-out part, normalised by the final training scales.
    let scale = model.scale;
    let mut eb: [Vec<f64>; 4] = Default::default();
    let mut ea: [Vec<f64>; 4] = Default::default();
    held.normalised(&nominal, &mut eb);
    held.normalised(&xm, &mut ea);
    let pooled = |e: &[Vec<f64>; 4]| {
        let (mut s, mut n) = (0.0, 0usize);
        for g in 0..4 {
            s += e[g].iter().map(|v| (v / scale[g]).powi(2)).sum::<f64>();
            n += e[g].len();
        }
        (s / n.max(1) as f64).sqrt()
    };
    let (rb, ra) = (pooled(&eb), pooled(&ea));
    let pb = physical(&replay, held.icp, held.gyro, &nominal);
    let pa = physical(&replay, held.icp, held.gyro, &xm);
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let streams = (0..4)
        .filter(|g| !pb[*g].is_empty())
        .map(|g| {
            (
                GROUPS[g].to_string(),
                StreamGain {
                    n: pb[g].len(),
                    before: rms(&pb[g]),
                    after: rms(&pa[g]),
                },
            )
        })
        .collect();
    let gain = Gain {
        heldout_rmse_before: rb,
        heldout_rmse_after: ra,
        relative: if rb > 0.0 { (rb - ra) / rb } else { 0.0 },
        streams,
        trajectory: trajectory_gain(
            &replay,
            m.reference,
            &nominal,
            &xm,
            split,
            p.trajectory_window,
        ),
    };
    // Structure tests on all rows.
    let structure_before = structure(all, &nominal, &sel.nominal.scale, p);
    let structure_after = structure(all, &xm, &scale, p);
    let remaining = has_structure(&structure_after, p.structure_alpha);
    let causes: Vec<Cause> = (0..model.effects.len())
        .map(|i| {
            let (parameters, stderr) = named(model, i);
            Cause {
                effect: model.effects[i].name().to_string(),
                parameters,
                stderr,
                delta_bic: sel.delta_bic[i],
            }
        })
        .collect();
    let verdict = if !causes.is_empty() {
        Verdict::Explained
    } else if has_structure(&structure_before, p.structure_alpha) {
        Verdict::Unexplained
    } else {
        Verdict::NoDiscrepancy
    };
    let all_b = physical(&replay, &icp, &gyro, &nominal);
    let all_a = physical(&replay, &icp, &gyro, &xm);
    let series = series(&replay, &icp, &gyro, &all_b, &all_a, split);
    let mut rows = BTreeMap::new();
    rows.insert("icp_train".to_string(), n_icp_train);
    rows.insert("icp_heldout".to_string(), icp.len() - i_ho);
    rows.insert("gyro_train".to_string(), n_gyro_train);
    rows.insert("gyro_heldout".to_string(), gyro.len() - g_ho);
    rows.insert("outliers".to_string(), rejected);
    Ok(Diagnosis {
        verdict,
        causes,
        gain,
        remaining_structure: remaining,
        heldout_rejected,
        candidates: sel.tried,
        structure_before,
        structure_after,
        stats_before: stats(&all_b),
        stats_after: stats(&all_a),
        noise_scale: (0..4)
            .filter(|g| train.counts()[*g] > 0)
            .map(|g| (GROUPS[g].to_string(), scale[g]))
            .collect(),
        rows,
        series,
    })
}

fn series(
    replay: &Replay,
    icp: &[IcpRow],
    gyro: &[GyroRow],
    b: &[Vec<f64>; 4],
    a: &[Vec<f64>; 4],
    split: f64,
) -> ResidualSeries {
    let x0 = Extension::default();
    let t: Vec<f64> = icp.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect();
    let pred: Vec<(f64, f64)> = icp.iter().map(|r| replay.body(&x0, r.t0, r.t1)).collect();
    let n = t.len();
    let deriv = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..n)
            .map(|i| {
                let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n - 1));
                let dt = t[i1] - t[i0];
                if dt > 0.0 {
                    (f(i1) - f(i0)) / dt
                } else {
                    0.0
                }
            })
            .collect()
    };
    let accel = deriv(&|i| pred[i].0);
    let turn_accel = deriv(&|i| pred[i].1);
    let dt_med = {
        let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        median(&mut d)
    };
    let lagged = |res: &[f64], reg: &[f64]| {
        cross_correlation(res, reg, 10)
            .into_iter()
            .map(|(l, c)| (l as f64 * dt_med, c))
            .collect()
    };
    ResidualSeries {
        split,
        speed: pred.iter().map(|p| p.0).collect(),
        turn_rate: pred.iter().map(|p| p.1).collect(),
        speed_turn: pred.iter().map(|p| p.0.abs() * p.1.abs()).collect(),
        lag_v_accel: lagged(&b[0], &accel),
        lag_w_accel: lagged(&b[2], &turn_accel),
        accel,
        turn_accel,
        t,
        v_before: b[0].clone(),
        v_after: a[0].clone(),
        lateral_before: b[1].clone(),
        lateral_after: a[1].clone(),
        w_before: b[2].clone(),
        w_after: a[2].clone(),
        gyro_t: gyro.iter().map(|r| 0.5 * (r.t0 + r.t1)).collect(),
        gyro_before: b[3].clone(),
        gyro_after: a[3].clone(),
    }
}
