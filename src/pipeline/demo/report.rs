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
    crate::pipeline::nominal::report_assumptions(&mut r, &s.assumptions)?;
    calibration(s, &mut r)?;
    changes(s, &mut r);
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
                input.nominal.robot.name,
                input.nominal.robot.r_right,
                input.nominal.robot.r_left,
                input.nominal.robot.wheel_base,
                input.nominal.robot.ticks_per_rev
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
                match (m.estimates, m.convergence_s) {
                    (false, _) => "– (fixed prior)".into(),
                    (true, c) => opt(c, 1),
                },
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
    r.paragraph(
        "Settled: the time after which both radii stay within 0.5 % of the truth to the end \
         (with a radii step mid-run, within 0.5 % of the radii in effect); `none` estimates \
         nothing and is never reported as settled.",
    );
    r.image(
        "radii.png",
        "Radii and wheel base of each method against the truth (Fariña et al., Figs. 6 and 8).",
    );
    r.image(
        "particles.png",
        "Adaptive-PF particle count and process noise (Fariña et al., Fig. 5).",
    );
    Ok(())
}

/// The odometry table's rows: each trajectory's figures, the heading's
/// when `rot`, and each method's 10 s windows.
fn odometry_rows(
    s: &DemoSummary,
    named: &[(String, &TrajectoryMetrics, Option<&TrajectoryMetrics>)],
    rot: bool,
) -> Vec<Vec<String>> {
    let windowed: std::collections::HashMap<String, Option<f64>> = s
        .methods
        .iter()
        .map(|m| {
            let name = format!("odometry calibrated by {}", m.method);
            (name, m.windowed.map(|w| w.rmse_m))
        })
        .collect();
    named
        .iter()
        .map(|(name, m, f)| {
            let mut row = vec![name.clone(), num(m.ape.rmse, 3)];
            if rot {
                row.push(opt(m.rmse_theta, 4));
            }
            row.extend([
                opt(m.drift_percent, 2),
                num(m.final_error, 3),
                num(m.rpe.rmse, 4),
                opt(f.map(|f| f.ape.rmse), 3),
                opt(windowed.get(name.as_str()).copied().flatten(), 3),
            ]);
            row
        })
        .collect()
}

/// Every trajectory against the reference; without a reference (or without
/// any figure) no table and no error plot, only why and the trajectories.
fn odometry(s: &DemoSummary, r: &mut Report) -> Result<(), PipelineError> {
    let named: Vec<(String, &TrajectoryMetrics, Option<&TrajectoryMetrics>)> = [
        (
            "raw odometry (nominal)".to_string(),
            &s.raw_odometry_eval,
            None,
        ),
        ("ICP".to_string(), &s.icp_eval, None),
    ]
    .into_iter()
    .chain(s.methods.iter().map(|m| {
        (
            format!("odometry calibrated by {}", m.method),
            &m.eval,
            m.eval_final.as_ref(),
        )
    }))
    .filter_map(|(n, m, f)| m.as_ref().map(|m| (n, m, f)))
    .collect();
    let Some(&(_, first, _)) = named.first() else {
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
    let rows = odometry_rows(s, &named, rot);
    let mut header = vec!["trajectory", "APE RMSE (m)"];
    if rot {
        header.push("RMSE θ (rad)");
    }
    header.extend([
        "drift (%)",
        "final error (m)",
        "RPE RMSE (m, 1 frame)",
        "APE RMSE, final parameters (m)",
        "RMSE, 10 s windows from the estimate at each start (m)",
    ]);
    r.table(&header, &rows).map_err(viz_err)?;
    r.paragraph(
        "Calibrated odometry integrates each step's wheel rotation with the estimate after \
         that step, as a robot would online. A filter whose estimate moves with every step \
         re-fits each step's measured turn rate (the gyro's), so its online odometry follows \
         the gyro even while its parameters are wrong: the fixed PF's random walk of 0.5 mm \
         per step does this. The last column dead-reckons the whole recording with each \
         method's final parameters instead: what the calibration is worth afterwards (left \
         out when the true parameters change during the recording). The window column is \
         what a robot runs on while it calibrates: the wheels dead-reckoned over 10 s \
         windows, each with the estimate in effect at its start, against the reference's \
         motion over the window (RMSE of the position relative to the window's start; \
         none against a reference without headings).",
    );
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
        "Trajectories against the reference (Fariña et al., Fig. 7).",
    );
    r.image("errors.png", "Position error over time.");
    Ok(())
}

/// What changed at each firing of the proposed filter's change detector.
fn changes(s: &DemoSummary, r: &mut Report) {
    r.heading(2, "What changed");
    let Some(first) = s.methods.first() else {
        return;
    };
    if s.changes.is_empty() {
        r.paragraph(&format!(
            "The {} filter's change detector did not fire: nothing was named.",
            first.method
        ));
        return;
    }
    let lines: Vec<String> = s
        .changes
        .iter()
        .map(|c| format!("- {}", crate::pipeline::changes::describe(c)))
        .collect();
    r.paragraph(&format!(
        "Where the {} filter's change detector fired, the effect that changed, named from \
         the diagnosis's candidate models on a window around the firing (as `odocal \
         calibrate` does; `changes` in summary.json):",
        first.method
    ));
    r.paragraph(&lines.join("\n"));
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
