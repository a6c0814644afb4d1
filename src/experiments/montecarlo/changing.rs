//! The `changing` experiment's time plots ([Farina, Figs. 5 and 6b]): run 0
//! of the Monte Carlo replayed with the Adaptive-PF and the Kalman filters,
//! their radius estimates against the truth, and the Adaptive-PF against the
//! same filter with a fixed count ([Farina, Fig. 5] compares with N = 3000):
//! both runs' radius error, particle count and time per step over time.

use super::configs::fixed_count_label;
use super::{synthetic_run, MonteCarloParams};
use crate::calib::synth::SynthData;
use crate::calib::{build, run_observed, CalibParams, CalibStep, CalibrationRun, Estimate, Method};
use crate::experiments::output::draw_lines;
use crate::experiments::stats::stat;
use crate::pipeline::PipelineError;
use crate::robot::DiffDrive;
use crate::viz::plot::{LineChart, Series};
use std::path::Path;
use std::time::Instant;

/// At most this many points per plotted series.
const MAX_POINTS: usize = 2000;

/// Every `k`-th row of a history so that at most [`MAX_POINTS`] remain.
fn thin<T: Copy>(rows: &[T]) -> impl Iterator<Item = T> + '_ {
    let k = rows.len().div_ceil(MAX_POINTS).max(1);
    rows.iter().step_by(k).copied()
}

/// What one replayed filter did around the radius step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunFigures {
    /// Particle count just before the step.
    pub before: usize,
    /// Largest count after the step.
    pub peak: usize,
    /// Count at the end of the run.
    pub end: usize,
    /// Mean |error| of R_R and R_L just before the step (mm).
    pub error_before_mm: f64,
    /// The same at the end of the run (mm).
    pub error_end_mm: f64,
    /// Mean wall time of the filter's step over the whole run (ms), as the
    /// table's ms/iter.
    pub ms_per_step: f64,
}

/// The Adaptive-PF of run 0 and the same filter with a fixed count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fig5 {
    /// The Adaptive-PF as configured (its count follows the cloud).
    pub adaptive: RunFigures,
    /// The same filter, detector included, with N fixed at
    /// [`super::configs::FIG5_FIXED_PARTICLES`].
    pub fixed: RunFigures,
}

/// One replayed filter: its label, run and wall time of each step (ms).
struct Replay<'a> {
    label: &'a str,
    run: CalibrationRun,
    step_ms: Vec<f64>,
}

/// Runs `p` over `steps`, timing each step.
fn replay<'a>(
    label: &'a str,
    p: &CalibParams,
    nominal: DiffDrive,
    steps: &[CalibStep],
) -> Result<Replay<'a>, PipelineError> {
    let mut cal = build(p, nominal).map_err(|e| PipelineError::BadArgument(e.to_string()))?;
    let mut step_ms = Vec::with_capacity(steps.len());
    let mut last = Instant::now();
    let run = run_observed(cal.as_mut(), steps, nominal, &mut |_, _| {
        let now = Instant::now();
        step_ms.push(1e3 * (now - last).as_secs_f64());
        last = now;
    });
    Ok(Replay {
        label,
        run,
        step_ms,
    })
}

/// Mean |error| of both radii of an estimate against the truth (mm).
fn radius_error_mm(h: &Estimate, data: &SynthData) -> f64 {
    let k = data.truth_at(h.t);
    0.5e3 * ((h.r_right - k.r_right).abs() + (h.r_left - k.r_left).abs())
}

/// Median step time of each 1 s window, at the window's end (s, ms). A
/// median, not a mean: on a shared machine the scheduler now and then
/// parks the process for milliseconds in the middle of a step that takes
/// tenths of one, and one such step would dominate its window's mean.
fn windowed_ms(r: &Replay<'_>) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let (mut window, mut t0) = (Vec::new(), None);
    for (h, &ms) in r.run.history.iter().zip(&r.step_ms) {
        let start = *t0.get_or_insert(h.t);
        window.push(ms);
        if h.t - start >= 1.0 {
            out.push([h.t, stat(std::mem::take(&mut window)).median]);
            t0 = None;
        }
    }
    out
}

/// What `r` did around the step at `step` (s).
fn run_figures(r: &Replay<'_>, data: &SynthData, step: f64) -> RunFigures {
    let h = &r.run.history;
    let k = h.partition_point(|x| x.t < step);
    let err = |e: Option<&Estimate>| e.map_or(f64::NAN, |e| radius_error_mm(e, data));
    RunFigures {
        before: h[..k].last().map_or(0, |x| x.particles),
        peak: h[k..].iter().map(|x| x.particles).max().unwrap_or(0),
        end: h.last().map_or(0, |x| x.particles),
        error_before_mm: err(h[..k].last()),
        error_end_mm: err(h.last()),
        ms_per_step: r.run.summary.mean_iteration_ms,
    }
}

/// The estimates of R_R (`right`) or R_L of every replay against the truth (mm).
fn radius_series(runs: &[Replay<'_>], data: &SynthData, right: bool) -> Vec<Series> {
    let mm = |x: f64| 1e3 * x;
    let mut s: Vec<Series> = runs
        .iter()
        .map(|r| {
            let pts = thin(&r.run.history)
                .map(|h| [h.t, mm(if right { h.r_right } else { h.r_left })])
                .collect();
            Series::new(r.label, pts)
        })
        .collect();
    let t_end = runs
        .iter()
        .filter_map(|r| r.run.history.last().map(|h| h.t))
        .fold(0.0, f64::max);
    let truth = (0..=200)
        .map(|i| {
            let t = t_end * i as f64 / 200.0;
            let k = data.truth_at(t);
            [t, mm(if right { k.r_right } else { k.r_left })]
        })
        .collect();
    s.push(Series::new("truth", truth).dashed());
    s
}

/// The chart of run 0: both radii of every replay against the truth, then
/// the radius error, particle count and step time of the `pair` compared.
fn chart(runs: &[Replay<'_>], pair: &[&Replay<'_>], data: &SynthData) -> LineChart {
    let per_pair = |f: &dyn Fn(&Replay<'_>) -> Vec<[f64; 2]>| {
        pair.iter()
            .map(|r| Series::new(r.label, f(r)))
            .collect::<Vec<_>>()
    };
    LineChart::new(
        "Radii step at 55 s, run 0 of the Monte Carlo (Fariña et al., Figs. 5 and 6b)",
        "time (s)",
    )
    .panel("R_R (mm)", radius_series(runs, data, true))
    .panel("R_L (mm)", radius_series(runs, data, false))
    .panel(
        "radius error, mean of R_R and R_L (mm)",
        per_pair(&|r| {
            thin(&r.run.history)
                .map(|h| [h.t, radius_error_mm(&h, data)])
                .collect()
        }),
    )
    .panel(
        "particles",
        per_pair(&|r| {
            thin(&r.run.history)
                .map(|h| [h.t, h.particles as f64])
                .collect()
        }),
    )
    .panel(
        "time per step, median of each 1 s (ms)",
        per_pair(&windowed_ms),
    )
}

/// Replays run 0 with every configuration but the fixed PF and the Kalman
/// filters without the detector, draws `png` and returns the figures of
/// the Adaptive-PF and of the same filter with a fixed count (None without
/// both rows: [`super::changing_configs`] has them).
pub fn changing_figure(
    mc: &MonteCarloParams,
    configs: &[(String, CalibParams)],
    png: &Path,
) -> Result<Option<Fig5>, PipelineError> {
    let nominal = mc.nominal_drive();
    let (st, data) = synthetic_run(mc, mc.seed);
    let runs: Vec<Replay<'_>> = configs
        .iter()
        // The fixed PF's estimate swings by ±10 mm and would flatten every
        // other curve; its figures are in the table, as are the Kalman
        // filters' runs without the detector.
        .filter(|(_, p)| !matches!(p.method, Method::None | Method::Pf))
        .filter(|(_, p)| p.change.enabled || p.method == Method::AdaptivePf)
        .map(|(label, p)| replay(label, p, nominal, &st))
        .collect::<Result<_, _>>()?;
    let (adaptive, fixed) = (Method::AdaptivePf.as_str(), fixed_count_label());
    let pair: Vec<&Replay<'_>> = runs
        .iter()
        .filter(|r| r.label == adaptive || r.label == fixed)
        .collect();
    draw_lines(png, &chart(&runs, &pair, &data))?;
    let step = mc.synth.radius_step.map_or(f64::INFINITY, |s| s.time);
    let figures = |label: &str| {
        pair.iter()
            .find(|r| r.label == label)
            .map(|r| run_figures(r, &data, step))
    };
    Ok(figures(adaptive)
        .zip(figures(&fixed))
        .map(|(adaptive, fixed)| Fig5 { adaptive, fixed }))
}
