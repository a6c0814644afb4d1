//! `odocal experiment NAME`: the seed papers' tables and figures regenerated
//! on our own data, each written as `NAME.md`, `NAME.json` and `NAME.png`.
//! Seed 000: Monte Carlo over synthetic wheelchair runs (`resampling`,
//! `montecarlo`, `changing`) and over simulated scans matched by ICP
//! (`montecarlo-scans`); the literature comparison (`literature`); seed
//! 001/002 and UMBmark (`square`, `umbmark`, `heading-pf`, `tachometer`).

use super::changing_figure::changing_figure;
use super::scan_montecarlo::{scan_montecarlo, ScanMonteCarloParams};
use super::PipelineError;
use crate::calib::experiments::{
    montecarlo, table1_configs, table2_configs, MonteCarloParams, MonteCarloTable,
};
use crate::calib::synth::RadiusStep;
use crate::calib::CalibParams;
use crate::classic::{
    heading_pf_experiment, literature, path_error_markdown, square_experiment,
    tachometer_experiment, umbmark_cycles, LiteratureParams, LiteratureTable, PfExperimentParams,
    SquareExperimentParams, UmbmarkParams,
};
use crate::error::InputError;
use crate::io::seed_tables::{self, read_seed_table};
use crate::robot::RobotConfig;
use crate::viz::plot::{self, BarChart, LineChart, PathSeries, Series, TrajectoryPlot};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Experiment names `odocal experiment` knows.
pub const EXPERIMENTS: [&str; 9] = [
    "resampling",
    "montecarlo",
    "montecarlo-scans",
    "changing",
    "literature",
    "square",
    "umbmark",
    "heading-pf",
    "tachometer",
];

/// Settings of the experiments (`--settings FILE.toml`), one table each.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentSettings {
    /// `literature`.
    pub literature: LiteratureParams,
    /// `square`.
    pub square: SquareExperimentParams,
    /// `umbmark`.
    pub umbmark: UmbmarkParams,
    /// `heading-pf` (its `trials` is replaced by `--runs`, its `seed` by `--seed`).
    pub heading_pf: PfExperimentParams,
    /// `montecarlo-scans`.
    pub scans: ScanMonteCarloParams,
}

impl ExperimentSettings {
    /// Loads `path`, or the defaults when `None`. Unknown keys are refused.
    pub fn load(path: Option<&Path>) -> Result<Self, PipelineError> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| InputError::new(&name, format!("cannot read: {e}")))?;
        toml::from_str(&text).map_err(|e| InputError::new(&name, e.message().to_string()).into())
    }
}

/// What an experiment runs on besides its name and output directory.
#[derive(Debug, Clone, Copy)]
pub struct ExperimentInputs<'a> {
    /// Monte Carlo runs, repetitions or trials (`--runs`).
    pub runs: usize,
    /// Seed of run 0 (`--seed`).
    pub seed: u64,
    /// Calibrator settings (`--config`'s `[calib]`).
    pub calib: &'a CalibParams,
    /// Nominal robot (`--robot`).
    pub robot: &'a RobotConfig,
    /// Experiment settings (`--settings`).
    pub settings: &'a ExperimentSettings,
    /// Folder with the seed tables (`--tables`), for square, heading-pf, tachometer.
    pub tables: Option<&'a Path>,
    /// Scan matching settings (`--config`'s `[icp]`), for montecarlo-scans.
    pub icp: &'a crate::icp::IcpParams,
}

/// An experiment's outputs: the markdown written to `NAME.md`, the text the
/// command prints, and the JSON written to `NAME.json` (and printed with `--json`).
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentOutput {
    /// Content of `NAME.md`.
    pub markdown: String,
    /// Human-readable summary for stdout.
    pub summary: String,
    /// Content of `NAME.json` (pretty-printed, fields in declaration order).
    pub json: String,
}

fn bad(e: impl std::fmt::Display) -> PipelineError {
    PipelineError::BadArgument(e.to_string())
}

fn write_text(out: &Path, file: String, text: &str) -> Result<(), PipelineError> {
    let p = out.join(file);
    crate::io::atomic::write_bytes_atomic(&p, text.as_bytes())
        .map_err(|e| PipelineError::write(&p, e))
}

/// Runs experiment `name` into `out` (`NAME.md`, `NAME.json`, `NAME.png`).
pub fn run(
    name: &str,
    inp: &ExperimentInputs<'_>,
    out: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    if inp.runs == 0 {
        return Err(bad("--runs must be at least 1"));
    }
    if !EXPERIMENTS.contains(&name) {
        return Err(bad(format!(
            "unknown experiment '{name}' (known: {})",
            EXPERIMENTS.join(", ")
        )));
    }
    std::fs::create_dir_all(out).map_err(|e| PipelineError::write(out, e))?;
    let png = out.join(format!("{name}.png"));
    let res = match name {
        "literature" => literature_experiment(inp, &png)?,
        "square" => square(inp, &png)?,
        "umbmark" => umbmark(inp, &png)?,
        "heading-pf" => heading_pf(inp, &png)?,
        "tachometer" => tachometer(inp, &png)?,
        _ => monte_carlo(name, inp, &png)?,
    };
    write_text(out, format!("{name}.md"), &res.markdown)?;
    write_text(out, format!("{name}.json"), &res.json)?;
    Ok(res)
}

fn to_json<T: Serialize>(v: &T) -> String {
    serde_json::to_string_pretty(v).expect("experiment results serialise")
}

fn monte_carlo(
    name: &str,
    inp: &ExperimentInputs<'_>,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let base = inp.calib;
    let mut mc = MonteCarloParams {
        runs: inp.runs,
        seed: inp.seed,
        ..Default::default()
    };
    let (configs, title) = match name {
        "resampling" => (
            table1_configs(base),
            "Seed 000 Table I: resampling scheme × trigger",
        ),
        "montecarlo" => (
            table2_configs(base),
            "Seed 000 Table II: Adaptive-PF against the baselines",
        ),
        "montecarlo-scans" => (
            table2_configs(base),
            "Seed 000 Table II end to end: simulated LMS111 scans, ICP, calibrators",
        ),
        _ => {
            // A new user boards at 55 s (seed 000, Fig. 6b); runs long enough to re-converge.
            mc.synth.duration = mc.synth.duration.max(110.0);
            mc.synth.radius_step = Some(RadiusStep {
                time: 55.0,
                right: 0.004,
                left: 0.002,
            });
            (
                table2_configs(base),
                "Radii step at 55 s: convergence measured from the step",
            )
        }
    };
    let table: MonteCarloTable = if name == "montecarlo-scans" {
        let scans = &inp.settings.scans;
        scan_montecarlo(inp.runs, inp.seed, scans, inp.robot, inp.icp, &configs)?
    } else {
        montecarlo(&mc, &configs)
    };
    let cats: Vec<String> = table.rows.iter().map(|r| r.label.clone()).collect();
    let one = |f: &dyn Fn(&crate::calib::experiments::TableRow) -> f64| {
        vec![table.rows.iter().map(f).collect::<Vec<_>>()]
    };
    let chart = BarChart::new(
        format!("{title} ({} runs, medians)", inp.runs),
        cats,
        vec!["median".into()],
    )
    .panel(
        "final |error| R_R (mm)",
        one(&|r| 1e3 * r.err_r_right.median),
        None,
    )
    .panel(
        "final |error| R_L (mm)",
        one(&|r| 1e3 * r.err_r_left.median),
        None,
    )
    .panel(
        "time per iteration (ms)",
        one(&|r| r.mean_iteration_ms.median),
        None,
    );
    plot::bar_chart(png, &chart).map_err(|e| PipelineError::write(png, e))?;
    let mut md = table.to_markdown();
    if name == "changing" {
        let fig = png.with_file_name("changing-run0.png");
        md += "\nRun 0 over time (radius estimates against the truth, the Adaptive-PF's particle count): `changing-run0.png`.\n";
        if let Some(c) = changing_figure(&mc, &configs, &fig)? {
            md += &format!(
                "Adaptive-PF particles in run 0: {} before the step, up to {} after it, {} at the end (one particle per 0.01 mm of radius standard deviation, clamped to [adaptive.n_min, adaptive.n_max]; a detected jump restarts from the initial count).\n",
                c.before, c.peak, c.end
            );
        }
    }
    Ok(ExperimentOutput {
        markdown: format!("# {title}\n\n{md}"),
        summary: md,
        json: to_json(&table),
    })
}

fn literature_experiment(
    inp: &ExperimentInputs<'_>,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let nominal = inp.robot.diff_drive();
    let t: LiteratureTable = literature(
        &nominal,
        inp.calib,
        &inp.settings.literature,
        inp.runs,
        inp.seed,
    )
    .map_err(bad)?;
    let cats: Vec<String> = t.rows.iter().map(|r| r.method.name().to_string()).collect();
    let col = |f: &dyn Fn(&crate::classic::LiteratureRow) -> f64| {
        vec![t.rows.iter().map(f).collect::<Vec<_>>()]
    };
    let chart = BarChart::new(
        format!(
            "Literature methods on the same runs ({} repetitions, medians)",
            t.runs
        ),
        cats,
        vec!["median".into()],
    )
    .panel(
        "|error| R_R (mm)",
        col(&|r| 1e3 * r.err_r_right.median),
        None,
    )
    .panel(
        "|error| R_L (mm)",
        col(&|r| 1e3 * r.err_r_left.median),
        None,
    )
    .panel(
        "|error| D (mm)",
        col(&|r| 1e3 * r.err_wheel_base.median),
        None,
    )
    .panel("RMSE x,y (m)", col(&|r| r.rmse_xy.median), None)
    .panel("RMSE θ (rad)", col(&|r| r.rmse_theta.median), None)
    .panel(
        "path error (%)",
        col(&|r| r.path_error_percent.median),
        None,
    );
    plot::bar_chart(png, &chart).map_err(|e| PipelineError::write(png, e))?;
    let md = t.markdown();
    Ok(ExperimentOutput {
        markdown: format!("# Literature methods side by side\n\n{md}"),
        summary: md,
        json: to_json(&t),
    })
}

/// A seed table from the `--tables` folder.
fn table(inp: &ExperimentInputs<'_>, file: &str) -> Result<seed_tables::SeedTable, PipelineError> {
    let dir = inp.tables.ok_or_else(|| {
        bad(format!(
            "this experiment reads the seed tables: give --tables DIR (the folder with {file})"
        ))
    })?;
    Ok(read_seed_table(&dir.join(file))?)
}

fn square(inp: &ExperimentInputs<'_>, png: &Path) -> Result<ExperimentOutput, PipelineError> {
    let corners = seed_tables::square_corners(&table(inp, "square_path.csv")?)?;
    let e = square_experiment(&corners, &inp.settings.square, inp.runs, inp.seed).map_err(bad)?;
    let path = |name: &str,
                f: &dyn Fn(&crate::classic::SquareCorner) -> [f64; 2],
                rep: &crate::classic::SquareReport| {
        PathSeries::new(name, rep.corners.iter().map(|c| f(&c.corner)).collect())
    };
    let fig = TrajectoryPlot::new(
        "Seed 001's 6 m square: actual, measured odometry, simulated with fitted errors",
        vec![
            path("actual", &|c| [c.actual_x, c.actual_y], &e.measured),
            path("measured odometry", &|c| [c.odom_x, c.odom_y], &e.measured),
            path(
                "simulated odometry (fitted effects)",
                &|c| [c.odom_x, c.odom_y],
                &e.simulated,
            )
            .dashed(),
        ],
    );
    plot::trajectory_plot(png, &fig).map_err(|er| PipelineError::write(png, er))?;
    let md = e.markdown();
    Ok(ExperimentOutput {
        markdown: format!("# Seed 001 Table III: the 6 m square\n\n{md}"),
        summary: md,
        json: to_json(&e),
    })
}

fn umbmark(inp: &ExperimentInputs<'_>, png: &Path) -> Result<ExperimentOutput, PipelineError> {
    let c = umbmark_cycles(
        &inp.robot.diff_drive(),
        &inp.settings.umbmark,
        inp.runs,
        inp.seed,
    )
    .map_err(bad)?;
    let cats: Vec<String> = c
        .cycles
        .iter()
        .map(|k| format!("robot {}", k.seed))
        .collect();
    let chart = BarChart::new(
        format!(
            "UMBmark: E_max,syst before and after correction ({} robots)",
            c.cycles.len()
        ),
        cats,
        vec!["before".into(), "after (fresh runs)".into()],
    )
    .panel(
        "E_max,syst (m)",
        vec![
            c.cycles
                .iter()
                .map(|k| k.result.before.e_max_syst)
                .collect(),
            c.cycles.iter().map(|k| k.result.after.e_max_syst).collect(),
        ],
        None,
    );
    plot::bar_chart(png, &chart).map_err(|e| PipelineError::write(png, e))?;
    let md = c.markdown();
    Ok(ExperimentOutput {
        markdown: format!("# UMBmark (Borenstein & Feng 1996)\n\n{md}"),
        summary: md,
        json: to_json(&c),
    })
}

fn heading_pf(inp: &ExperimentInputs<'_>, png: &Path) -> Result<ExperimentOutput, PipelineError> {
    let seed_rows = match inp.tables {
        Some(_) => seed_tables::ga_path_errors(&table(inp, "ga_path_errors.csv")?)?,
        None => Vec::new(),
    };
    let p = PfExperimentParams {
        trials: inp.runs,
        seed: inp.seed,
        ..inp.settings.heading_pf.clone()
    };
    let (rows, ga) = heading_pf_experiment(&p, &seed_rows).map_err(bad)?;
    let names = [
        "uncalibrated",
        "calibrated_odometry",
        "calibrated_odometry_vo_pf",
    ];
    let cats: Vec<String> = p.lengths.iter().map(|l| format!("{l} m")).collect();
    let cell = |n: &str, l: f64, f: &dyn Fn(&crate::classic::PathErrorRow) -> f64| {
        rows.iter()
            .find(|r| r.scenario == n && r.length_m == l)
            .map_or(0.0, f)
    };
    let grid = |f: &dyn Fn(&crate::classic::PathErrorRow) -> f64| -> Vec<Vec<f64>> {
        names
            .iter()
            .map(|n| p.lengths.iter().map(|&l| cell(n, l, f)).collect())
            .collect()
    };
    let mut chart = BarChart::new(
        format!("Seed 002 Table 2: end-position error ({} trials)", p.trials),
        cats,
        names.iter().map(|s| s.to_string()).collect(),
    )
    .panel(
        "odocal: error (% of length)",
        grid(&|r| r.error_percent),
        Some(grid(&|r| r.error_std)),
    );
    if !seed_rows.is_empty() {
        chart = chart.panel(
            "seed 002 (0 = not completed)",
            grid(&|r| r.seed_error_percent.unwrap_or(0.0)),
            None,
        );
    }
    plot::bar_chart(png, &chart).map_err(|e| PipelineError::write(png, e))?;
    let md = format!(
        "{} trials per length; GA-calibrated k_left {:.6e}, k_right {:.6e} m/pulse, b {:.5} m \
         (truth {:.6e}, {:.6e}, {:.5}).\n\n{}",
        p.trials,
        ga.k_left,
        ga.k_right,
        ga.wheel_base,
        p.truth.k_left,
        p.truth.k_right,
        p.truth.wheel_base,
        path_error_markdown(&rows)
    );
    Ok(ExperimentOutput {
        markdown: format!("# Seed 002 Table 2: GA calibration and heading fusion\n\n{md}"),
        summary: md,
        json: to_json(&serde_json::json!({ "rows": rows, "ga": ga, "params": p })),
    })
}

fn tachometer(inp: &ExperimentInputs<'_>, png: &Path) -> Result<ExperimentOutput, PipelineError> {
    let rows = seed_tables::tachometer_table(&table(inp, "encoder_vs_tachometer.csv")?)?;
    let trials = seed_tables::heading_trials(&table(inp, "heading_trials.csv")?)?;
    let pairs = match inp.tables.map(|d| d.join("wheel_speed_pairs.csv")) {
        Some(p) if p.is_file() => {
            let t = read_seed_table(&p)?;
            let (r, l) = (t.numbers("right_rad_s")?, t.numbers("left_rad_s")?);
            r.into_iter().zip(l).collect()
        }
        _ => Vec::new(),
    };
    let e = tachometer_experiment(
        &rows,
        &trials,
        &pairs,
        Some(inp.settings.square.nominal.wheel_base),
    )
    .map_err(bad)?;
    let xs: Vec<f64> = rows.iter().map(|r| r.tachometer_rpm).collect();
    let err = |f: &dyn Fn(&crate::classic::TachoReading) -> f64| -> Vec<f64> {
        rows.iter().map(|r| f(r) - r.tachometer_rpm).collect()
    };
    let (fr, fl) = (&e.tachometer.right, &e.tachometer.left);
    let chart = LineChart::new(
        "Seed 001 Table I: encoder − tachometer before and after the rpm correction",
        "tachometer (rpm)",
    )
    .panel(
        "encoder − tachometer (rpm)",
        vec![
            Series::from_xy("right, as read", &xs, &err(&|r| r.right_encoder_rpm)),
            Series::from_xy("left, as read", &xs, &err(&|r| r.left_encoder_rpm)),
            Series::from_xy(
                "right, corrected",
                &xs,
                &err(&|r| fr.apply(r.right_encoder_rpm)),
            )
            .dashed(),
            Series::from_xy(
                "left, corrected",
                &xs,
                &err(&|r| fl.apply(r.left_encoder_rpm)),
            )
            .dashed(),
        ],
    );
    plot::line_chart(png, &chart).map_err(|er| PipelineError::write(png, er))?;
    let md = e.markdown(&rows);
    Ok(ExperimentOutput {
        markdown: format!("# Seed 001: tachometer rpm correction and heading gain\n\n{md}"),
        summary: md,
        json: to_json(&e),
    })
}
