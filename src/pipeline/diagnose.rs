//! `odocal diagnose`: replay the nominal model on a recording's wheel data,
//! compare with ICP and the gyro, name what differs, and show it.

use super::{icp, Common, PipelineError};
use crate::assumptions::Origin;
use crate::diagnose::{self, Cause, DiagnoseParams, Diagnosis, Measured, ResidualSeries};
use crate::recording::Recording;
use crate::robot::RobotConfig;
use crate::viz::plot::{self, LineChart, Series};
use crate::viz::report::{num, Report};
use std::path::{Path, PathBuf};

/// The scan matching the diagnosis compares the wheels with: `params`, but
/// scan to scan. Against a local map each keyframe registration starts from
/// the wheel-odometry prior over a longer baseline and can absorb what the
/// diagnosis looks for (on the LEGO log the 0.4 s scan lag vanishes from the
/// residuals with the local map and is found scan to scan).
pub fn icp_for_diagnosis(params: &crate::icp::IcpParams) -> crate::icp::IcpParams {
    crate::icp::IcpParams {
        local_map: false,
        ..params.clone()
    }
}

/// What `odocal diagnose` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct DiagnoseJob {
    /// A recording (any format [`crate::io::sniff`] knows) or Censi et al.'s
    /// calibration tuples.
    pub measured: PathBuf,
    /// The fraction at the end held out to measure the gain (else the
    /// configuration's).
    pub holdout: Option<f64>,
    /// Where to write `report.md` and the residual plots, if anywhere.
    pub report: Option<PathBuf>,
    /// Configuration and robot files.
    pub common: Common,
}

/// Runs `odocal diagnose`: reads the measurements by their format, diagnoses
/// them, and writes the report when asked.
pub fn run(job: &DiagnoseJob) -> Result<Diagnosis, PipelineError> {
    if let Some(dir) = &job.report {
        let outputs = ["report.md", "residuals.png", "regressors.png"].map(|f| dir.join(f));
        let outputs: Vec<&Path> = outputs.iter().map(PathBuf::as_path).collect();
        super::outputs::check_outputs(&[&job.measured], &outputs)?;
    }
    let report_dir: Vec<&Path> = job.report.iter().map(PathBuf::as_path).collect();
    let _lock = super::outputs::lock_outputs(&report_dir)?;
    let (mut cfg, nominal) = job.common.load_nominal()?;
    let robot = &nominal.robot;
    if let Some(h) = job.holdout {
        if !(h > 0.0 && h < 1.0) {
            return Err(PipelineError::BadArgument(format!(
                "--holdout must be a fraction in (0, 1), got {h}"
            )));
        }
        cfg.diagnose.holdout = h;
    }
    let d = if crate::io::sniff(&job.measured)? == crate::io::Format::CensiTuples {
        let tuples = crate::io::censi::read(&job.measured)?;
        run_tuples(&tuples, robot, &cfg.diagnose).map(|mut d| {
            d.assumptions = nominal.assumptions();
            if let Some(l) = robot.laser {
                let note = "the nominal mounting; laser_offset is the departure from it".into();
                d.assumptions.set("laser", l, Origin::RobotFile, Some(note));
            }
            d
        })
    } else {
        let read = super::read_options(&cfg, robot);
        let rec = crate::io::read_recording(&job.measured, &read)?;
        icp::mount(&rec, robot).and_then(|mount| {
            let (wheels, odom) = (rec.wheels.len(), rec.odom.len());
            let prior = crate::icp::Prior::choose(cfg.icp.prior, wheels, odom, robot.diff_drive())
                .map_err(|e| crate::error::InputError::new(&rec.source, e))?;
            let mut d = run_recording(&rec, robot, &cfg.icp, &cfg.diagnose)?;
            d.assumptions = nominal.assumptions_with(&mount);
            // Without wheels, the odometry's motion stands in for them.
            let values = if wheels >= 2 {
                rec.wheel_values
            } else {
                Some(crate::recording::WheelValues::Twist)
            };
            nominal.drop_unused_wheel_keys(&mut d.assumptions, values);
            nominal.state_prior(&mut d.assumptions, &prior, cfg.icp.prior, wheels);
            state_instrument(&mut d.assumptions, &cfg.diagnose.instrument);
            state_timing(&mut d.assumptions, &rec, &cfg.diagnose);
            d.wheel_source = (rec.wheels.len() >= 2).then(|| {
                super::wheels::describe(&read, &nominal, rec.wheels.len(), rec.wheel_values)
            });
            Ok(d)
        })
    };
    // "Not enough data" and the like are about the measured file: name it.
    let d = d.map_err(|e| match e {
        PipelineError::BadArgument(m) => {
            crate::error::InputError::new(job.measured.display().to_string(), m).into()
        }
        other => other,
    })?;
    if let Some(dir) = &job.report {
        write_report(dir, &job.measured.display().to_string(), &d)?;
    }
    Ok(d)
}

/// States the scan matcher's error model the leftover structures were
/// checked against (or that none was).
fn state_instrument(
    a: &mut crate::assumptions::Assumptions,
    inst: &diagnose::instrument::Instrument,
) {
    let source = if *inst == diagnose::instrument::Instrument::default() {
        Origin::Default
    } else {
        Origin::Config
    };
    let (value, note) = if inst.enabled {
        (
            "scan-to-scan ICP's error per pair, by geometry, step and rotation (turns in \
             place apart)",
            "measured on the simulated LMS111 wheelchair (docs/results/icp-instrument.md); for \
             another scanner an assumption. A leftover structure it accounts for is reported \
             with source scan_matching and does not count against the verdict; the gyro's scale \
             is checked against the scan-matched turns read on its scale, and without a gyro \
             the fit reads them so, naming a wheel base or turn slip only beyond the table's \
             spread; [diagnose.instrument] enabled = false calls every leftover structure the \
             robot's and takes the scan matching's turns as they come",
        )
    } else {
        (
            "none: every leftover structure is the robot's",
            "[diagnose.instrument] enabled = false",
        )
    };
    a.set("instrument", value, source, Some(note.into()));
}

/// States the wheel averaging window and the shortest latency the diagnosis
/// names, and why.
fn state_timing(
    a: &mut crate::assumptions::Assumptions,
    rec: &crate::recording::Recording,
    p: &diagnose::DiagnoseParams,
) {
    let encoder = diagnose::resolution::timing_resolution(&rec.wheels);
    let window = diagnose::resolution::smoothing_window(p.wheel_smoothing, encoder);
    a.set(
        "wheel_smoothing_s",
        window,
        if window > p.wheel_smoothing {
            Origin::Estimated
        } else if p.wheel_smoothing == diagnose::DiagnoseParams::default().wheel_smoothing {
            Origin::Default
        } else {
            Origin::Config
        },
        Some(format!(
            "the wheel angles are averaged over this centred window before the replay: \
             [diagnose] wheel_smoothing ({:.3} s), widened to {} tick periods of the encoder \
             at this run's wheel rate when longer (0: no averaging)",
            p.wheel_smoothing,
            diagnose::resolution::WINDOW_TICKS
        )),
    );
    let instrument = p.instrument.timing_floor();
    let note = format!(
        "a latency under it is not named: the wheel encoders time the wheels to one tick \
         period at this run's wheel rate ({:.1} ms; 0 when the angles are not quantised) \
         and scan-to-scan ICP reads the motion's timing to within [diagnose.instrument] \
         timing ({:.1} ms, from null runs)",
        1e3 * encoder,
        1e3 * instrument
    );
    let source = if instrument == diagnose::instrument::Instrument::default().timing {
        Origin::Default
    } else {
        Origin::Config
    };
    a.set(
        "latency_floor_s",
        encoder.max(instrument),
        source,
        Some(note),
    );
}

/// Runs ICP on the recording and diagnoses the nominal model against it.
/// A recording without wheel encoders but with the robot's own integrated
/// odometry (classic CARMEN logs) is diagnosed through virtual wheel angles
/// ([`diagnose::odometry::wheels_from_odometry`]): the causes then describe
/// what that odometry gets wrong against scan matching.
pub fn run_recording(
    rec: &Recording,
    robot: &RobotConfig,
    icp_params: &crate::icp::IcpParams,
    params: &DiagnoseParams,
) -> Result<Diagnosis, PipelineError> {
    let virtual_wheels;
    let wheels = if rec.wheels.len() >= 2 {
        &rec.wheels
    } else if rec.odom.len() >= 2 {
        virtual_wheels = diagnose::odometry::wheels_from_odometry(&rec.odom, robot);
        &virtual_wheels
    } else {
        return Err(crate::error::InputError::new(
            &rec.source,
            "no wheel data (the stream the robot file's [wheels] source and topic name; JointState \
             with left_joint and right_joint by default) and no odometry: nothing to replay",
        )
        .into());
    };
    let icp_params = icp_for_diagnosis(icp_params);
    let mut icp_out = icp::match_recording(rec, robot, &icp_params)?;
    // Wheels wired the wrong way give ICP a prior (and a deskew) turning the
    // wrong way: rewire them and match again before diagnosing.
    let wiring = diagnose::faults::wiring(wheels, &icp_out.motions);
    let rewired = diagnose::faults::rewire(wheels, wiring);
    let fixed;
    let wheels = match &rewired {
        Some((w, _)) => {
            fixed = Recording {
                wheels: w.clone(),
                ..rec.clone()
            };
            icp_out = icp::match_recording(&fixed, robot, &icp_params)?;
            &fixed.wheels
        }
        None => wheels,
    };
    let mut measured = Measured::new(rec, &icp_out.motions);
    measured.wheels = wheels;
    // The nominal mount is the one ICP used (the recording's /tf_static
    // when present), so `laser_offset` is relative to it.
    let robot = RobotConfig {
        laser: Some(icp::mount(rec, robot)?.laser()),
        ..robot.clone()
    };
    let mut d = diagnose::diagnose(&robot, &measured, params)
        .map_err(|e| PipelineError::BadArgument(e.to_string()))?;
    if let Some((_, fault)) = rewired {
        d.faults.insert(0, fault);
        d.verdict = diagnose::run::verdict(&d.causes, &d.remaining, &d.faults);
    }
    Ok(d)
}

/// Diagnoses Censi et al.'s calibration tuples (`.tuple`: wheel rates and
/// the laser's scan-matching displacement per interval). The laser motions
/// enter with the robot file's laser mount as the nominal one, so
/// `laser_offset` estimates the mount relative to it; σ per tuple is
/// `sigma_xy` (m) and `sigma_theta` (rad), relative weights only (the
/// diagnosis profiles each stream's scale). Latency is no candidate: the
/// tuples carry no common clock.
pub fn run_tuples(
    tuples: &[crate::io::censi::CensiTuple],
    robot: &RobotConfig,
    params: &DiagnoseParams,
) -> Result<Diagnosis, PipelineError> {
    let Some(laser) = robot.laser else {
        return Err(PipelineError::BadArgument(
            "the tuples' laser mounting is unknown: set [laser] x, y, yaw (the nominal \
             base_from_laser, m, m, rad) in the robot file (--robot ROBOT.toml); the diagnosis \
             estimates the mounting relative to it (laser_offset)"
                .into(),
        ));
    };
    let (wheels, motions) = crate::io::censi::to_streams(tuples, &laser.pose(), 1e-3, 1e-3);
    // The tuples are laid end to end on a made-up clock: a delay between
    // the wheel and the laser stream means nothing there.
    let mut params = params.clone();
    params.candidates.retain(|c| c != "latency");
    // Nor does the scan-to-scan error table of 20–40 ms pairs describe the
    // authors' matching over whole intervals.
    params.instrument.enabled = false;
    let params = &params;
    let measured = Measured {
        wheels: &wheels,
        motions: &motions,
        gyro: &[],
        reference: &[],
    };
    diagnose::diagnose(robot, &measured, params)
        .map_err(|e| PipelineError::BadArgument(e.to_string()))
}

fn pairs(t: &[f64], y: &[f64]) -> Vec<[f64; 2]> {
    t.iter().zip(y).map(|(&a, &b)| [a, b]).collect()
}

/// Mean of `y` in `n` equal-width bins of `x` (empty bins skipped): the
/// shape of a residual against a regressor without the noise.
fn binned(x: &[f64], y: &[f64], n: usize) -> Vec<[f64; 2]> {
    let (lo, hi) = x
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi <= lo {
        return Vec::new();
    }
    let mut sum = vec![(0.0, 0usize); n];
    for (&a, &b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() {
            let k = (((a - lo) / (hi - lo)) * n as f64).min(n as f64 - 1.0) as usize;
            sum[k].0 += b;
            sum[k].1 += 1;
        }
    }
    sum.iter()
        .enumerate()
        .filter(|(_, s)| s.1 > 0)
        .map(|(k, s)| {
            [
                lo + (k as f64 + 0.5) * (hi - lo) / n as f64,
                s.0 / s.1 as f64,
            ]
        })
        .collect()
}

fn viz_err(e: crate::viz::VizError) -> PipelineError {
    PipelineError::Write {
        path: "report".into(),
        message: e.to_string(),
    }
}

/// Writes `DIR/report.md` with the verdict, causes, gain and the residual
/// plots before and after the extension (`residuals.png`, `regressors.png`).
pub fn write_report(dir: &Path, name: &str, d: &Diagnosis) -> Result<(), PipelineError> {
    std::fs::create_dir_all(dir).map_err(|e| PipelineError::write(dir, e))?;
    plot_residuals(&dir.join("residuals.png"), &d.series)?;
    plot_regressors(&dir.join("regressors.png"), &d.series)?;
    let mut r = Report::new();
    r.heading(1, "odocal diagnose");
    r.kv(&[
        ("recording", name.to_string()),
        ("verdict", verdict_word(d)),
        (
            "held out from",
            format!(
                "t = {:.1} s (fitted before, gain measured after; dashed line in residuals.png)",
                d.series.split
            ),
        ),
    ]);
    r.heading(2, "Causes");
    write_causes(&mut r, &d.causes)?;
    write_faults_and_remaining(&mut r, d)?;
    super::nominal::report_assumptions(&mut r, &d.assumptions)?;
    r.heading(2, "Gain on held-out data");
    write_gain(&mut r, d);
    r.image("residuals.png", "Residuals before and after the extension.");
    r.image(
        "regressors.png",
        "Nominal-model residuals against the regressors that expose effects.",
    );
    r.write(&dir.join("report.md")).map_err(viz_err)
}

/// Grey: the nominal model's residuals.
const BEFORE: [u8; 3] = [161, 161, 161];
/// Blue: the extended model's residuals.
const AFTER: [u8; 3] = [31, 119, 180];

/// Residuals over time before and after the extension, one panel per stream.
fn plot_residuals(path: &Path, s: &ResidualSeries) -> Result<(), PipelineError> {
    let panel = |b: &[f64], a: &[f64], t: &[f64]| {
        let (lo, hi) = b
            .iter()
            .chain(a)
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        let mut v = vec![
            Series::new("before (nominal model)", pairs(t, b)).color(BEFORE),
            Series::new("after (extended model)", pairs(t, a)).color(AFTER),
        ];
        if lo < hi {
            v.push(
                Series::new("held-out part starts", vec![[s.split, lo], [s.split, hi]])
                    .color([0, 0, 0])
                    .dashed(),
            );
        }
        v
    };
    let mut chart = LineChart::new(
        format!(
            "Residuals, measured − predicted (held out after t = {:.1} s)",
            s.split
        ),
        "time (s)",
    )
    .panel("ICP V residual (m/s)", panel(&s.v_before, &s.v_after, &s.t))
    .panel(
        "ICP W residual (rad/s)",
        panel(&s.w_before, &s.w_after, &s.t),
    );
    if !s.gyro_t.is_empty() {
        chart = chart.panel(
            "gyro residual (rad/s)",
            panel(&s.gyro_before, &s.gyro_after, &s.gyro_t),
        );
    }
    plot::line_chart(path, &chart).map_err(viz_err)
}

/// The nominal model's residuals against the regressors that expose effects
/// (mean per bin), each panel on its own regressor axis with its unit.
fn plot_regressors(path: &Path, s: &ResidualSeries) -> Result<(), PipelineError> {
    let name = "nominal-model residual, mean per bin";
    let chart = LineChart::new(
        "Nominal-model residuals against the regressors that expose effects",
        "",
    )
    .panel_x(
        "predicted speed V (m/s)",
        "ICP V residual (m/s)",
        vec![Series::new(name, binned(&s.speed, &s.v_before, 24)).color(AFTER)],
    )
    .panel_x(
        "predicted turn rate W (rad/s)",
        "ICP W residual (rad/s)",
        vec![Series::new(name, binned(&s.turn_rate, &s.w_before, 24)).color(AFTER)],
    )
    .panel_x(
        "|V|·|W| (m·rad/s²)",
        "ICP W residual (rad/s)",
        vec![Series::new(name, binned(&s.speed_turn, &s.w_before, 24)).color(AFTER)],
    );
    plot::line_chart(path, &chart).map_err(viz_err)
}

/// The unit of an effect's parameter (`1` for relative ones).
fn unit(effect: &str, key: &str) -> &'static str {
    crate::effects::EffectKind::from_name(effect)
        .and_then(|k| k.params().iter().find(|p| p.key == key))
        .map_or("", |p| p.unit)
}

/// A value with its unit: relative ones in per cent.
fn with_unit(v: f64, unit: &str) -> String {
    match unit {
        "1" => format!("{:+.3} %", 100.0 * v),
        "" => format!("{v:.6}"),
        u => format!("{v:.6} {u}"),
    }
}

/// A cause's parameters with their standard errors and units (relative
/// ones in per cent).
pub fn cause_parameters(c: &Cause) -> String {
    c.parameters
        .iter()
        .map(|(k, v)| {
            let u = unit(&c.effect, k);
            match c.stderr.get(k) {
                Some(e) => format!("{k} = {} ± {}", with_unit(*v, u), with_unit(*e, u)),
                None => format!("{k} = {}", with_unit(*v, u)),
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The causes as a table (effect, parameters ± standard error with units, ΔBIC).
fn write_causes(r: &mut Report, causes: &[Cause]) -> Result<(), PipelineError> {
    if causes.is_empty() {
        r.paragraph("No effect of the table improves the evidence by the required margin.");
        return Ok(());
    }
    let rows: Vec<Vec<String>> = causes
        .iter()
        .map(|c| vec![c.effect.clone(), cause_parameters(c), num(c.delta_bic, 1)])
        .collect();
    r.table(&["effect", "parameters (± standard error)", "ΔBIC"], &rows)
        .map_err(viz_err)?;
    Ok(())
}

/// Faults outside the table and the structure the model leaves.
fn write_faults_and_remaining(r: &mut Report, d: &Diagnosis) -> Result<(), PipelineError> {
    if !d.faults.is_empty() {
        r.heading(2, "Faults outside the effect table");
        let rows: Vec<Vec<String>> = d
            .faults
            .iter()
            .map(|f| {
                let p = f
                    .parameters
                    .iter()
                    .map(|(k, v)| format!("{k} = {:.3} % of the radius", 100.0 * v))
                    .collect::<Vec<_>>()
                    .join(", ");
                vec![f.name.clone(), p, f.evidence.clone(), f.fix.clone()]
            })
            .collect();
        r.table(&["fault", "size", "evidence", "fix"], &rows)
            .map_err(viz_err)?;
    }
    r.heading(2, "What the model leaves");
    if d.remaining.is_empty() {
        r.paragraph(
            "No structure left above the floors of what scan matching alone leaves \
             (bias, trend, speed-, turn- or wheel-angle-dependent; Newey–West tests).",
        );
        return Ok(());
    }
    let rows: Vec<Vec<String>> = d
        .remaining
        .iter()
        .map(|x| {
            vec![
                x.stream.clone(),
                x.structure.clone(),
                format!("{:.5} {}", x.size, x.unit),
                format!("{:.1e}", x.p_value),
                x.reason
                    .as_ref()
                    .map_or_else(|| x.source.clone(), |why| format!("{}: {why}", x.source)),
            ]
        })
        .collect();
    r.table(&["stream", "structure", "size", "p", "whose"], &rows)
        .map_err(viz_err)?;
    Ok(())
}

/// The held-out gain: normalised RMSE, trajectory error against a
/// reference, and the effects the held-out part did not confirm.
fn write_gain(r: &mut Report, d: &Diagnosis) {
    r.kv(&[
        ("residual RMSE before", num(d.gain.heldout_rmse_before, 5)),
        ("residual RMSE after", num(d.gain.heldout_rmse_after, 5)),
        ("relative gain", format!("{:.1} %", d.gain.relative * 100.0)),
    ]);
    if let Some(t) = &d.gain.trajectory {
        let mut kv = vec![(
            "relative-pose error vs reference (m)",
            format!(
                "{} → {} ({} windows of {} s)",
                num(t.rpe_before, 4),
                num(t.rpe_after, 4),
                t.windows,
                t.window_s
            ),
        )];
        if let (Some(b), Some(a)) = (t.ate_before, t.ate_after) {
            kv.push((
                "held-out ATE vs reference, 2D-aligned (m)",
                format!("{} → {}", num(b, 4), num(a, 4)),
            ));
        }
        r.kv(&kv);
    }
    if !d.heldout_rejected.is_empty() {
        let names: Vec<&str> = d
            .heldout_rejected
            .iter()
            .map(|c| c.effect.as_str())
            .collect();
        r.paragraph(&format!(
            "Selected on the training part but not confirmed on the held-out part: {}.",
            names.join(", ")
        ));
    }
}

/// The verdict as design.md spells it (`explained`, `partly-explained`,
/// `no-discrepancy`, `unexplained`).
pub fn verdict_word(d: &Diagnosis) -> String {
    serde_json::to_value(d.verdict)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}
