//! [Paryanto, Table III] as an experiment: the measured square's corner and
//! closure errors, the radius and wheel-base errors that reproduce them, and
//! the same 6 m square simulated with those errors (noise-free, then with
//! wheel slip over several runs) to show how much of the table they explain.

use super::inputs::{bad, ExperimentInputs};
use super::output::{comma_list, draw_paths, ExperimentOutput};
use super::stats::{finite_stat, sample_std, Stat};
use crate::classic::{
    drive_segments, fit_square_effects, measured_square, square_odometry_corners, square_report,
    square_segments, ClassicError, DriveParams, SquareCorner, SquareEffectFit, SquareReport,
};
use crate::error::InputError;
use crate::geom::Pose2;
use crate::io::seed_tables::SeedTable;
use crate::pipeline::PipelineError;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::viz::plot::{PathSeries, TrajectoryPlot};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// Settings of the square experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SquareExperimentParams {
    /// The model the odometry of \[Paryanto\] used: 30 cm wheels (r = 0.15 m); its
    /// wheel base is not stated, 0.55 m is assumed.
    pub nominal: DiffDrive,
    /// Driving of the noisy repetitions (slip is the non-systematic error).
    pub drive: DriveParams,
}

impl Default for SquareExperimentParams {
    /// r = 0.15 m, D = 0.55 m; 0.4 m/s, 20 Hz, 1 % wheel slip per step.
    fn default() -> Self {
        Self {
            nominal: DiffDrive {
                r_right: 0.15,
                r_left: 0.15,
                wheel_base: 0.55,
            },
            drive: DriveParams {
                slip_sigma: 0.01,
                ..DriveParams::default()
            },
        }
    }
}

/// What the experiment found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SquareExperiment {
    /// The measured table ([Paryanto, Table III]).
    pub measured: SquareReport,
    /// Radius and wheel-base errors fitted to the measured odometry corners.
    pub fit: SquareEffectFit,
    /// The simulated square with the fitted errors, noise-free.
    pub simulated: SquareReport,
    /// Closure error in x (m) over the noisy simulated repetitions.
    pub noisy_closure_dx: Stat,
    /// Closure error in y (m) over the noisy repetitions.
    pub noisy_closure_dy: Stat,
    /// Standard deviation of the noisy closure errors (x, y) (m).
    pub noisy_closure_std: [f64; 2],
    /// Repetitions with slip.
    pub runs: usize,
}

/// Fits the measured corners, simulates the fitted square, and repeats it
/// `runs` times with slip (run i seeded `seed + i`).
pub fn square_experiment(
    measured: &[SquareCorner],
    p: &SquareExperimentParams,
    runs: usize,
    seed: u64,
) -> Result<SquareExperiment, ClassicError> {
    let report = square_report(measured)?;
    let nominal = p.nominal;
    let fit = fit_square_effects(measured, &nominal)?;
    let (side, dir) = measured_square(measured)?;
    let mut truth = nominal;
    for e in &fit.effects {
        match *e {
            crate::effects::Effect::RadiusScale { right, left } => {
                truth.r_right *= 1.0 + right;
                truth.r_left *= 1.0 + left;
            }
            crate::effects::Effect::WheelBaseScale { scale } => truth.wheel_base *= 1.0 + scale,
            _ => {}
        }
    }
    let simulated = square_report(&square_odometry_corners(&nominal, &truth, side, dir))?;
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for i in 0..runs {
        let run = drive_segments(
            &truth,
            &truth,
            &square_segments(side, dir),
            &p.drive,
            seed.wrapping_add(i as u64),
        );
        let odo = wheel_odometry(&nominal, &run.wheels, Pose2::identity());
        let t = run.segment_ends.get(6).copied().unwrap_or(0.0);
        if let (Some(o), Some(a)) = (odo.pose_at(t), run.truth.pose_at(t)) {
            xs.push(o.translation.x - a.translation.x);
            ys.push(o.translation.y - a.translation.y);
        }
    }
    Ok(SquareExperiment {
        measured: report,
        fit,
        simulated,
        noisy_closure_std: [sample_std(&xs), sample_std(&ys)],
        noisy_closure_dx: finite_stat(xs),
        noisy_closure_dy: finite_stat(ys),
        runs,
    })
}

impl SquareExperiment {
    /// Markdown: measured table, fitted effects, simulated corners, noise.
    pub fn markdown(&self) -> String {
        let mut s = String::from("## Measured (Paryanto et al., Table III)\n\n");
        s.push_str(&self.measured.markdown());
        let _ = writeln!(
            s,
            "\n## Effects that reproduce it\n\nLeast-squares fit of the odometry corners \
             (the chair driven exactly along the actual square, odometry with the nominal \
             model): {}. Corner RMS {:.3} m with no effect, {:.3} m with these.\n",
            comma_list(&self.fit.effects, |e| format!("`{e}`")),
            self.fit.rms_before,
            self.fit.rms_after
        );
        s.push_str("| corner | measured odometry (m) | simulated odometry (m) | difference (m) |\n|---|---|---|---|\n");
        for (i, (m, f)) in self
            .measured
            .corners
            .iter()
            .zip(&self.simulated.corners)
            .enumerate()
        {
            let (a, b) = (m.corner, f.corner);
            let _ = writeln!(
                s,
                "| {i} | ({:.2}, {:.2}) | ({:.2}, {:.2}) | {:.2} |",
                a.odom_x,
                a.odom_y,
                b.odom_x,
                b.odom_y,
                (a.odom_x - b.odom_x).hypot(a.odom_y - b.odom_y)
            );
        }
        let _ = writeln!(
            s,
            "\nSimulated closure error: x {:+.2} m, y {:+.2} m (measured {:+.2}, {:+.2}). \
             With wheel slip over {} runs: x {:+.2} ± {:.2} m, y {:+.2} ± {:.2} m (mean ± std).\n\n\
             Constant radius and wheel-base errors reproduce the shape of the table but not \
             necessarily all of it: the measured sides ({} m) may differ by more than \
             constant radii allow; {:.2} m RMS per corner stays with other causes \
             (slip in the turns, a guided rather than driven path, reading errors).",
            self.simulated.closure_dx,
            self.simulated.closure_dy,
            self.measured.closure_dx,
            self.measured.closure_dy,
            self.runs,
            self.noisy_closure_dx.mean,
            self.noisy_closure_std[0],
            self.noisy_closure_dy.mean,
            self.noisy_closure_std[1],
            comma_list(&self.measured.odom_sides, |v| format!("{v:.2}")),
            self.fit.rms_after
        );
        s
    }
}

/// `square_path.csv`: odom_x,odom_y,actual_x,actual_y.
pub fn square_corners(t: &SeedTable) -> Result<Vec<SquareCorner>, InputError> {
    let c = ["odom_x", "odom_y", "actual_x", "actual_y"].map(|n| t.numbers(n));
    let [ox, oy, ax, ay] = c;
    let (ox, oy, ax, ay) = (ox?, oy?, ax?, ay?);
    let odom = ox.into_iter().zip(oy);
    let actual = ax.into_iter().zip(ay);
    Ok(odom
        .zip(actual)
        .map(|((odom_x, odom_y), (actual_x, actual_y))| SquareCorner {
            odom_x,
            odom_y,
            actual_x,
            actual_y,
        })
        .collect())
}

/// `odocal experiment square`: the experiment on `square_path.csv`, the
/// actual, measured and simulated squares drawn into `png`.
pub(super) fn square_output(
    inp: &ExperimentInputs<'_>,
    params: &SquareExperimentParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let corners = square_corners(&inp.seed_table("square_path.csv")?)?;
    let e = square_experiment(&corners, params, inp.runs, inp.seed).map_err(bad)?;
    let path = |name: &str, f: &dyn Fn(&SquareCorner) -> [f64; 2], rep: &SquareReport| {
        PathSeries::new(name, rep.corners.iter().map(|c| f(&c.corner)).collect())
    };
    let fig = TrajectoryPlot::new(
        "Paryanto et al.'s 6 m square: actual, measured odometry, simulated with fitted errors",
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
    draw_paths(png, &fig)?;
    let title = "Paryanto et al. Table III: the 6 m square";
    Ok(ExperimentOutput::titled(title, e.markdown(), &e))
}
