//! The `changing` experiment's time plots (seed 000, Figs. 5 and 6b): run 0
//! of the Monte Carlo replayed with the Adaptive-PF and the Kalman filters,
//! their radius estimates against the truth and the Adaptive-PF's particle
//! count over time.

use super::{synthetic_run, MonteCarloParams};
use crate::calib::{build, run, CalibParams, CalibrationRun, Method};
use crate::experiments::output::draw_lines;
use crate::pipeline::PipelineError;
use crate::viz::plot::{LineChart, Series};
use std::path::Path;

/// At most this many points per plotted series.
const MAX_POINTS: usize = 2000;

/// Every `k`-th row of a history so that at most [`MAX_POINTS`] remain.
fn thin<T: Copy>(rows: &[T]) -> impl Iterator<Item = T> + '_ {
    let k = rows.len().div_ceil(MAX_POINTS).max(1);
    rows.iter().step_by(k).copied()
}

/// Particle counts of the Adaptive-PF around the radius step: before it,
/// the peak after it, and at the end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleCounts {
    /// Count just before the step.
    pub before: usize,
    /// Largest count after the step.
    pub peak: usize,
    /// Count at the end of the run.
    pub end: usize,
}

/// Replays run 0 with every configuration, draws `png` and returns the
/// Adaptive-PF's particle counts (None without an Adaptive-PF row).
pub fn changing_figure(
    mc: &MonteCarloParams,
    configs: &[(String, CalibParams)],
    png: &Path,
) -> Result<Option<ParticleCounts>, PipelineError> {
    let nominal = mc.nominal_drive();
    let (st, data) = synthetic_run(mc, mc.seed);
    let runs: Vec<(&str, CalibrationRun)> = configs
        .iter()
        // The fixed PF's estimate swings by ±10 mm and would flatten every
        // other curve; its figures are in the table, as are the Kalman
        // filters' runs without the detector.
        .filter(|(_, p)| !matches!(p.method, Method::None | Method::Pf))
        .filter(|(_, p)| p.change.enabled || p.method == Method::AdaptivePf)
        .map(|(label, p)| {
            let mut cal =
                build(p, nominal).map_err(|e| PipelineError::BadArgument(e.to_string()))?;
            Ok((label.as_str(), run(cal.as_mut(), &st, nominal)))
        })
        .collect::<Result<_, PipelineError>>()?;
    let mm = |x: f64| 1e3 * x;
    let radius = |right: bool| {
        let mut s: Vec<Series> = runs
            .iter()
            .map(|(label, r)| {
                let pts = thin(&r.history)
                    .map(|h| [h.t, mm(if right { h.r_right } else { h.r_left })])
                    .collect();
                Series::new(*label, pts)
            })
            .collect();
        let t_end = runs
            .iter()
            .filter_map(|(_, r)| r.history.last().map(|h| h.t))
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
    };
    let pf = runs.iter().find(|(l, _)| *l == Method::AdaptivePf.as_str());
    let mut chart = LineChart::new(
        "Radii step at 55 s, run 0 of the Monte Carlo (seed 000, Figs. 5 and 6b)",
        "time (s)",
    )
    .panel("R_R (mm)", radius(true))
    .panel("R_L (mm)", radius(false));
    if let Some((label, r)) = pf {
        let pts = thin(&r.history)
            .map(|h| [h.t, h.particles as f64])
            .collect();
        chart = chart.panel("particles", vec![Series::new(*label, pts)]);
    }
    draw_lines(png, &chart)?;
    let step = mc.synth.radius_step.map_or(f64::INFINITY, |s| s.time);
    Ok(pf.map(|(_, r)| {
        let h = &r.history;
        let k = h.partition_point(|x| x.t < step);
        ParticleCounts {
            before: h[..k].last().map_or(0, |x| x.particles),
            peak: h[k..].iter().map(|x| x.particles).max().unwrap_or(0),
            end: h.last().map_or(0, |x| x.particles),
        }
    }))
}
