//! `odocal experiment resampling | montecarlo | montecarlo-scans | changing`:
//! the table, a chart of its medians and, for `changing`, run 0 over time.

use super::scans::ScanMonteCarloParams;
use super::{
    changing_configs, changing_figure, fixed_count_label, montecarlo, scan_montecarlo,
    table1_configs, table2_configs, Fig5, MonteCarloParams, MonteCarloTable, TableRow,
    FIG5_FIXED_PARTICLES,
};
use crate::calib::synth::RadiusStep;
use crate::calib::CalibParams;
use crate::experiments::inputs::ExperimentInputs;
use crate::experiments::output::{draw_bars, median_bars, ExperimentOutput, MedianPanel};
use crate::pipeline::PipelineError;
use std::path::Path;

/// What a Monte Carlo experiment runs: its settings, the configurations
/// compared and the title of its table.
struct Setup {
    mc: MonteCarloParams,
    configs: Vec<(String, CalibParams)>,
    title: &'static str,
}

/// The settings, configurations and title of experiment `name`.
fn setup(name: &str, inp: &ExperimentInputs<'_>) -> Setup {
    let base = inp.calib;
    let mut mc = MonteCarloParams {
        runs: inp.runs,
        seed: inp.seed,
        ..Default::default()
    };
    let (configs, title) = match name {
        "resampling" => (
            table1_configs(base),
            "Fariña et al. Table I: resampling scheme × trigger",
        ),
        "montecarlo" => (
            table2_configs(base),
            "Fariña et al. Table II: Adaptive-PF against the baselines",
        ),
        "montecarlo-scans" => (
            table2_configs(base),
            "Fariña et al. Table II end to end: simulated LMS111 scans, ICP, calibrators",
        ),
        _ => {
            // A new user boards at 55 s ([Farina, Fig. 6b]); runs long enough to re-converge.
            mc.synth.duration = mc.synth.duration.max(110.0);
            mc.synth.radius_step = Some(RadiusStep {
                time: 55.0,
                right: 0.004,
                left: 0.002,
            });
            (
                changing_configs(base),
                "Radii step at 55 s: convergence measured from the step",
            )
        }
    };
    Setup { mc, configs, title }
}

/// The panels of the chart: final radius errors and time per iteration.
const PANELS: [MedianPanel<TableRow>; 3] = [
    ("final |error| R_R (mm)", |r| 1e3 * r.err_r_right.median),
    ("final |error| R_L (mm)", |r| 1e3 * r.err_r_left.median),
    ("time per iteration (ms)", |r| r.mean_iteration_ms.median),
];

/// The `changing` experiment's note on run 0, drawn next to `png` as
/// `changing-run0.png`.
fn changing_note(s: &Setup, png: &Path) -> Result<String, PipelineError> {
    let fig = png.with_file_name("changing-run0.png");
    let mut md = format!(
        "\nRun 0 over time (radius estimates against the truth; the Adaptive-PF against the \
         same filter with N fixed at {FIG5_FIXED_PARTICLES}, as in Fariña et al.'s Fig. 5: radius \
         error, particle count, time per step): `changing-run0.png`.\n"
    );
    if let Some(Fig5 {
        adaptive: a,
        fixed: f,
    }) = changing_figure(&s.mc, &s.configs, &fig)?
    {
        md += &format!(
            "Adaptive-PF particles in run 0: {} before the step, up to {} after it, {} at the end \
             (one particle per 0.01 mm of the radius cloud's width, ±3σ of each radius summed, \
             clamped to [adaptive.n_min, adaptive.n_max]; a detected jump restarts from at least \
             the initial count).\n\n\
             | run 0 | radius error before the step (mm) | at the end (mm) | particles before / peak / end | ms per step (mean over the run) |\n\
             |---|---|---|---|---|\n\
             | adaptive N | {:.3} | {:.3} | {} / {} / {} | {:.3} |\n\
             | fixed N = {FIG5_FIXED_PARTICLES} | {:.3} | {:.3} | {} / {} / {} | {:.3} |\n\n\
             Radius error: the mean of |R_R − truth| and |R_L − truth|. Step times are wall \
             time of one run on whatever else the machine runs (the figure plots the median \
             step of each second, which a descheduled step does not move): their ratio is the \
             finding, not their value (`cargo bench --bench pf` has steady figures). Over all \
             runs the two are the table's rows `adaptive-pf` and `{}`.\n",
            a.before, a.peak, a.end,
            a.error_before_mm, a.error_end_mm, a.before, a.peak, a.end, a.ms_per_step,
            f.error_before_mm, f.error_end_mm, f.before, f.peak, f.end, f.ms_per_step,
            fixed_count_label(),
        );
    }
    Ok(md)
}

/// Runs Monte Carlo experiment `name` and draws its medians into `png`.
pub(in crate::experiments) fn monte_carlo(
    name: &str,
    inp: &ExperimentInputs<'_>,
    scans: &ScanMonteCarloParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let s = setup(name, inp);
    let table: MonteCarloTable = if name == "montecarlo-scans" {
        scan_montecarlo(inp.runs, inp.seed, scans, inp.robot, inp.icp, &s.configs)?
    } else {
        montecarlo(&s.mc, &s.configs)
    };
    let labels = table.rows.iter().map(|r| r.label.clone()).collect();
    let title = format!("{} ({} runs, medians)", s.title, inp.runs);
    draw_bars(png, &median_bars(title, labels, &table.rows, &PANELS))?;
    let mut md = table.to_markdown();
    md += &table.paired_markdown();
    if name == "changing" {
        md += &changing_note(&s, png)?;
    }
    Ok(ExperimentOutput::titled(s.title, md, &table))
}
