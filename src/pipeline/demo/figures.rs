//! The demo's figures ([Farina, Figs. 5–8]) as PNG.

use super::{plot_anchor, viz_err, xy, DemoInput, DemoReference};
use crate::calib::{self, CalibrationRun, Method};
use crate::geom::Pose2;
use crate::pipeline::recorder::in_world;
use crate::pipeline::PipelineError;
use crate::traj::Trajectory;
use crate::viz::plot::{self, LineChart, PathSeries, Series, TrajectoryPlot};
use crate::viz::TrajectoryKind;
use std::path::Path;

fn series_over_time(
    name: &str,
    run: &CalibrationRun,
    t_start: f64,
    f: impl Fn(&calib::Estimate) -> f64,
) -> Series {
    let pts = run.history.iter().map(|h| [h.t - t_start, f(h)]).collect();
    Series::new(name, pts)
}

const METHOD_COLORS: [[u8; 3]; 5] = [
    [44, 160, 44],
    [31, 119, 180],
    [148, 103, 189],
    [255, 127, 14],
    [214, 39, 40],
];

/// The paper's figures as PNG: radii over time, the Adaptive-PF's particle
/// count, the trajectories and their errors.
pub(super) fn plots(
    input: &DemoInput<'_>,
    icp_traj: &Trajectory,
    raw: &Trajectory,
    runs: &[(Method, CalibrationRun)],
    reference: Option<&DemoReference>,
    t_start: f64,
    out: &Path,
) -> Result<(), PipelineError> {
    radii_chart(input, runs, t_start, out)?;
    particles_chart(&runs[0].1, t_start, out)?;
    trajectory_charts(icp_traj, raw, &runs[0].1, reference, t_start, out)
}

/// Fig. 6/8: radius evolution against the truth.
fn radii_chart(
    input: &DemoInput<'_>,
    runs: &[(Method, CalibrationRun)],
    t_start: f64,
    out: &Path,
) -> Result<(), PipelineError> {
    let mut panels: Vec<(String, Vec<Series>)> = vec![
        ("R_R (m)".into(), Vec::new()),
        ("R_L (m)".into(), Vec::new()),
        ("wheel base D (m)".into(), Vec::new()),
    ];
    for ((m, run), color) in runs.iter().zip(METHOD_COLORS) {
        panels[0]
            .1
            .push(series_over_time(m.as_str(), run, t_start, |h| h.r_right).color(color));
        panels[1]
            .1
            .push(series_over_time(m.as_str(), run, t_start, |h| h.r_left).color(color));
        panels[2]
            .1
            .push(series_over_time(m.as_str(), run, t_start, |h| h.wheel_base).color(color));
    }
    if let Some(t) = input.truth {
        let get = |f: fn(&crate::sim::TrueParameters) -> f64| {
            t.parameters.iter().map(|p| [p.t, f(p)]).collect::<Vec<_>>()
        };
        panels[0].1.push(
            Series::new("truth", get(|p| p.r_right))
                .color([0, 0, 0])
                .dashed(),
        );
        panels[1].1.push(
            Series::new("truth", get(|p| p.r_left))
                .color([0, 0, 0])
                .dashed(),
        );
        panels[2].1.push(
            Series::new("truth", get(|p| p.wheel_base))
                .color([0, 0, 0])
                .dashed(),
        );
    }
    let mut chart = LineChart::new("Wheel radii and wheel base over time", "time (s)");
    for (label, s) in panels {
        chart = chart.panel(label, s);
    }
    plot::line_chart(&out.join("radii.png"), &chart).map_err(viz_err)
}

/// Fig. 5: particle count and process noise of the Adaptive-PF.
fn particles_chart(
    adaptive: &CalibrationRun,
    t_start: f64,
    out: &Path,
) -> Result<(), PipelineError> {
    let chart = LineChart::new("Adaptive-PF: particle count and process noise", "time (s)")
        .panel(
            "particles",
            vec![series_over_time("particles", adaptive, t_start, |h| {
                h.particles as f64
            })],
        )
        .panel(
            "process σ (m)",
            vec![series_over_time("process sigma", adaptive, t_start, |h| {
                h.process_sigma
            })],
        );
    plot::line_chart(&out.join("particles.png"), &chart).map_err(viz_err)
}

/// Fig. 7: trajectories against the reference, and position error over time.
fn trajectory_charts(
    icp_traj: &Trajectory,
    raw: &Trajectory,
    adaptive: &CalibrationRun,
    reference: Option<&DemoReference>,
    t_start: f64,
    out: &Path,
) -> Result<(), PipelineError> {
    let mut paths = Vec::new();
    let mut errors = Vec::new();
    let mut add = |name: &str, t: &Trajectory, kind: TrajectoryKind| {
        let w = reference.map_or_else(Pose2::identity, |r| plot_anchor(t, r));
        let poses = in_world(t, &w);
        if let Some(r) = reference.map(|r| &r.traj) {
            let e: Vec<[f64; 2]> = t
                .stamps
                .iter()
                .zip(&poses)
                .filter_map(|(&s, p)| {
                    r.pose_at(s).map(|q| {
                        [
                            s - t_start,
                            (p.translation.vector - q.translation.vector).norm(),
                        ]
                    })
                })
                .collect();
            errors.push(Series::new(name, e).color(kind.color()));
        }
        paths.push(PathSeries::new(name, xy(&poses)).color(kind.color()));
    };
    add("raw odometry", raw, TrajectoryKind::RawOdometry);
    add("ICP", icp_traj, TrajectoryKind::Icp);
    add(
        "calibrated (adaptive-pf)",
        &adaptive.trajectory,
        TrajectoryKind::Calibrated,
    );
    if let Some(r) = reference.map(|r| &r.traj) {
        paths.insert(
            0,
            PathSeries::new("reference", xy(&r.poses))
                .color(TrajectoryKind::Reference.color())
                .dashed(),
        );
    }
    plot::trajectory_plot(
        &out.join("trajectories.png"),
        &TrajectoryPlot::new("Trajectories (start anchored on the reference)", paths),
    )
    .map_err(viz_err)?;
    if !errors.is_empty() {
        let chart = LineChart::new("Position error against the reference", "time (s)")
            .panel("position error (m)", errors);
        plot::line_chart(&out.join("errors.png"), &chart).map_err(viz_err)?;
    }
    Ok(())
}
