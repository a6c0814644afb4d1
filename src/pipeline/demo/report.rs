//! The demo's markdown report.

use super::{viz_err, DemoInput, DemoSummary};
use crate::eval::TrajectoryMetrics;
use crate::pipeline::PipelineError;
use crate::viz::report::{num, Report};
use std::path::Path;

fn opt(v: Option<f64>, decimals: usize) -> String {
    v.map(|x| num(x, decimals)).unwrap_or_else(|| "–".into())
}

/// Writes `OUT/report.md`: settings, calibration and accuracy tables, plots.
pub(super) fn report(
    input: &DemoInput<'_>,
    s: &DemoSummary,
    out: &Path,
) -> Result<(), PipelineError> {
    let mut r = Report::new();
    r.heading(1, "odocal demo");
    settings(input, s, &mut r);
    calibration(s, &mut r)?;
    odometry(s, &mut r)?;
    timing(s, &mut r);
    r.write(&out.join("report.md")).map_err(viz_err)
}

/// The recording, the nominal robot, the seed, and a simulation's truth.
fn settings(input: &DemoInput<'_>, s: &DemoSummary, r: &mut Report) {
    let mut settings = vec![
        ("recording".to_string(), s.input.clone()),
        ("scans".into(), s.scans.to_string()),
        ("duration".into(), format!("{:.1} s", s.duration_s)),
        (
            "nominal robot".into(),
            format!(
                "{}: R_R {} m, R_L {} m, D {} m, {} ticks/rev",
                input.robot.name,
                input.robot.r_right,
                input.robot.r_left,
                input.robot.wheel_base,
                input.robot.ticks_per_rev
            ),
        ),
        (
            "calibrator seed".into(),
            input.config.calib.seed.to_string(),
        ),
    ];
    if let Some(t) = input.truth {
        settings.push((
            "scenario".into(),
            format!("{} (seed {})", t.scenario, t.seed),
        ));
        settings.push(("injected effects".into(), t.effect_specs.join("; ")));
    }
    r.kv(&settings);
}

/// Each method's final parameters, errors, convergence and cost.
fn calibration(s: &DemoSummary, r: &mut Report) -> Result<(), PipelineError> {
    r.heading(2, "Calibration");
    let rows: Vec<Vec<String>> = s
        .methods
        .iter()
        .map(|m| {
            let e = m.final_errors;
            vec![
                m.method.clone(),
                num(m.final_params[0], 5),
                num(m.final_params[1], 5),
                num(m.final_params[2], 4),
                opt(e.map(|e| e[0] * 1000.0), 2),
                opt(e.map(|e| e[1] * 1000.0), 2),
                opt(e.map(|e| e[2] * 1000.0), 2),
                opt(m.convergence_s, 1),
                num(m.mean_iteration_ms, 3),
            ]
        })
        .collect();
    r.table(
        &[
            "method",
            "R_R (m)",
            "R_L (m)",
            "D (m)",
            "err R_R (mm)",
            "err R_L (mm)",
            "err D (mm)",
            "settled within 0.5 % (s)",
            "ms / step",
        ],
        &rows,
    )
    .map_err(viz_err)?;
    r.image(
        "radii.png",
        "Radii and wheel base of each method against the truth (seed 000, Fig. 6/8).",
    );
    r.image(
        "particles.png",
        "Adaptive-PF particle count and process noise (seed 000, Fig. 5).",
    );
    Ok(())
}

/// Every trajectory against the reference; without a reference (or without
/// any figure) no table and no error plot, only why and the trajectories.
fn odometry(s: &DemoSummary, r: &mut Report) -> Result<(), PipelineError> {
    let named: Vec<(String, &TrajectoryMetrics)> = [
        ("raw odometry (nominal)".to_string(), &s.raw_odometry_eval),
        ("ICP".to_string(), &s.icp_eval),
    ]
    .into_iter()
    .chain(
        s.methods
            .iter()
            .map(|m| (format!("odometry calibrated by {}", m.method), &m.eval)),
    )
    .filter_map(|(n, m)| m.as_ref().map(|m| (n, m)))
    .collect();
    let Some(&(_, first)) = named.first() else {
        r.heading(2, "Odometry");
        for note in &s.eval_notes {
            r.paragraph(&format!("Note — {note}."));
        }
        r.image(
            "trajectories.png",
            "Trajectories from the recording's start (no reference to compare with).",
        );
        return Ok(());
    };
    r.heading(2, "Odometry against the reference");
    for note in &s.eval_notes {
        r.paragraph(&format!("Note — {note}."));
    }
    let rot = first.rotation_omitted.is_none();
    let rows: Vec<Vec<String>> = named
        .iter()
        .map(|(name, m)| {
            let mut row = vec![name.clone(), num(m.ape.rmse, 3)];
            if rot {
                row.push(opt(m.rmse_theta, 4));
            }
            row.extend([
                opt(m.drift_percent, 2),
                num(m.final_error, 3),
                num(m.rpe.rmse, 4),
            ]);
            row
        })
        .collect();
    let mut header = vec!["trajectory", "APE RMSE (m)"];
    if rot {
        header.push("RMSE θ (rad)");
    }
    header.extend(["drift (%)", "final error (m)", "RPE RMSE (m, 1 frame)"]);
    r.table(&header, &rows).map_err(viz_err)?;
    r.paragraph(&format!(
        "Every trajectory starts on the reference at its first stamp, as a robot's dead \
         reckoning would: alignment `{}` ({}). Pairs: {} of {} ({}).{}",
        first.alignment.kind,
        first.alignment.reason,
        first.paired,
        first.of,
        first.pairing.reason,
        first
            .rotation_omitted
            .as_ref()
            .map(|w| format!(" No θ error: {w}."))
            .unwrap_or_default()
    ));
    r.image(
        "trajectories.png",
        "Trajectories against the reference (seed 000, Fig. 7).",
    );
    r.image("errors.png", "Position error over time.");
    Ok(())
}

/// ICP's counts and the run's timing.
fn timing(s: &DemoSummary, r: &mut Report) {
    r.heading(2, "Scan matching and timing");
    r.kv(&[
        ("pairs", s.icp.pairs.to_string()),
        ("failed pairs", s.icp.failed_pairs.to_string()),
        (
            "mean ICP iterations",
            format!("{:.1}", s.icp.mean_iterations),
        ),
        ("ICP pairs per second", format!("{:.0}", s.icp.pairs_per_s)),
        ("whole demo", format!("{:.1} s", s.wall_s)),
    ]);
}
