//! Every method on the same simulated runs, side by side: final parameter
//! errors, RMSE of x,y and θ, end-position error as % of the path, and
//! compute time. The runs come from a caller's closure (the simulator's
//! `square` / `square-ccw` scenarios, or [`crate::classic::drive_segments`]);
//! the classic methods calibrate on the squares, every method is scored on
//! the held-out evaluation runs. The literature comparison adds the
//! filters of \[Farina\] to the same runs.

mod methods;
mod runs;
mod score;
mod simulator;

pub(crate) use methods::classic_methods;
pub use runs::{split_short_runs, ComparisonRuns};
pub use score::{Calibrated, Evaluation};
pub use simulator::{compare_on_simulator, sim_run};

use crate::classic::{
    ClassicError, GaParams, HeadingPfParams, HeadingSourceParams, SimRun, TachoReading,
};
use crate::robot::DiffDrive;
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// The methods compared side by side (kebab-case names, as in tables and JSON):
/// the classic ones and, for the literature comparison, the filters of \[Farina\].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClassicMethod {
    /// Nominal parameters.
    None,
    /// \[Paryanto\]: tachometer rpm correction and heading gain.
    TachoHeading,
    /// The UMBmark correction \[Borenstein1996\].
    Umbmark,
    /// The genetic algorithm of \[GAHeading\].
    Ga,
    /// The GA-calibrated odometry of \[GAHeading\] fused with a heading source in a PF.
    HeadingPf,
    /// The Adaptive-PF of \[Farina\] on laser velocities and gyro (`calib`).
    AdaptivePf,
    /// The dual Kalman filter baseline on the same measurements (`calib`).
    Dkf,
}

impl ClassicMethod {
    /// The kebab-case name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::TachoHeading => "tacho-heading",
            Self::Umbmark => "umbmark",
            Self::Ga => "ga",
            Self::HeadingPf => "heading-pf",
            Self::AdaptivePf => "adaptive-pf",
            Self::Dkf => "dkf",
        }
    }
}

/// One method's outcome on the evaluation runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassicResult {
    /// The method.
    pub method: ClassicMethod,
    /// Parameters it ends with (for methods that correct rates or headings
    /// rather than radii, the equivalent radii and wheel base).
    #[serde(rename = "final")]
    pub final_params: DiffDrive,
    /// |final − truth| per parameter (m), when the truth is known.
    pub param_errors: Option<DiffDrive>,
    /// RMSE of position over the evaluation runs (m).
    pub rmse_xy: f64,
    /// RMSE of heading (rad).
    pub rmse_theta: f64,
    /// Mean end-position error as % of path length.
    pub path_error_percent: f64,
    /// Wall time of the calibration (and, for the PF, of filtering) (ms).
    pub compute_ms: f64,
    /// Method-specific figures (fits, gains, UMBmark table, GA cost).
    pub details: serde_json::Value,
}

/// What the runs closure is asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CompareScenario {
    /// The simulator's `square` (clockwise) run, driven by the nominal model.
    Square,
    /// `square-ccw`.
    SquareCcw,
    /// A run held out for evaluation.
    Evaluation,
}

/// Settings of the comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CompareParams {
    /// Side of the square scenarios (m).
    pub square_side: f64,
    /// Square runs per direction.
    pub runs_per_direction: usize,
    /// Evaluation runs.
    pub evaluation_runs: usize,
    /// Encoder ticks per wheel revolution (the GA works in pulses).
    pub ticks_per_rev: f64,
    /// GA settings; its bounds are replaced by ± `ga_bounds_rel` around nominal.
    pub ga: GaParams,
    /// Relative half-width of the GA's search box.
    pub ga_bounds_rel: f64,
    /// Shortest and longest piece the square runs are cut into for the GA (m).
    pub short_run_m: (f64, f64),
    /// Cut the square runs at their corners (after each turn) instead of into
    /// random pieces: the GA then sees the poses a tape measurement at the
    /// marked corners gives (runs without segment ends fall back to pieces).
    pub ga_corners: bool,
    /// Pulse counts are read at most this often for the GA (Hz); fewer, longer
    /// increments make each replay cheaper at no visible cost in accuracy.
    pub ga_rate_hz: f64,
    /// Heading-fusion filter.
    pub pf: HeadingPfParams,
    /// Simulated heading source for the filter.
    pub heading: HeadingSourceParams,
    /// A tachometer table, if one was measured; otherwise rates are not corrected.
    #[serde(skip)]
    pub tachometer: Option<Vec<TachoReading>>,
    /// σ of the measured end poses the classic methods rely on, [m, rad]:
    /// added to UMBmark's end positions, the GA pieces' start and end poses
    /// and the heading trials' actual turns (a tape or marker measurement).
    pub end_pose_sigma: [f64; 2],
    /// Seed for every random choice.
    pub seed: u64,
}

impl Default for CompareParams {
    /// 6 m squares (\[Paryanto\]), 5 runs each way, 3 evaluation runs, 8800 ticks/rev,
    /// GA box ± 10 %, pieces of 1.5–3 m.
    fn default() -> Self {
        Self {
            square_side: 6.0,
            runs_per_direction: 5,
            evaluation_runs: 3,
            ticks_per_rev: 8800.0,
            ga: GaParams::default(),
            ga_bounds_rel: 0.1,
            short_run_m: (1.5, 3.0),
            ga_corners: false,
            ga_rate_hz: 10.0,
            pf: HeadingPfParams::default(),
            heading: HeadingSourceParams::default(),
            tachometer: None,
            end_pose_sigma: [0.0, 0.0],
            seed: 1,
        }
    }
}

/// Runs every classic method on the same data and evaluates each on held-out
/// runs. `simulate(scenario, seed)` must return the recorded wheels and the
/// true trajectory of one run; square runs are those a robot believing
/// `nominal` drives. `truth`, when known, gives the parameter errors.
pub fn compare_classic<F, E>(
    nominal: &DiffDrive,
    truth: Option<&DiffDrive>,
    p: &CompareParams,
    simulate: F,
) -> Result<Vec<ClassicResult>, ClassicError>
where
    F: FnMut(CompareScenario, u64) -> Result<SimRun, E>,
    E: std::fmt::Display,
{
    let runs = ComparisonRuns::simulate(p, simulate)?;
    let eval = Evaluation {
        truth,
        runs: &runs.evals,
    };
    classic_methods(nominal, p, &runs, &eval)
}

/// The comparison as a markdown table (parameter errors in mm).
pub fn markdown_table(rows: &[ClassicResult]) -> String {
    side_by_side_table(rows.iter().map(|r| {
        let errors = r.param_errors.map(|e| [e.r_right, e.r_left, e.wheel_base]);
        let figures = [r.rmse_xy, r.rmse_theta, r.path_error_percent, r.compute_ms];
        (r.method, errors, figures)
    }))
}

/// One method's line of a side-by-side table: the method, its parameter
/// errors R_R, R_L, D (m; `None` when the truth is unknown) and its RMSE x,y
/// (m), RMSE θ (rad), path error (%) and compute time (ms).
pub(crate) type TableLine = (ClassicMethod, Option<[f64; 3]>, [f64; 4]);

/// A markdown table with one line per method (parameter errors in mm).
pub(crate) fn side_by_side_table(lines: impl IntoIterator<Item = TableLine>) -> String {
    let mut s = String::from("| method | R_R err (mm) | R_L err (mm) | D err (mm) | RMSE x,y (m) | RMSE θ (rad) | path error (%) | compute (ms) |\n|---|---|---|---|---|---|---|---|\n");
    let mm = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{:.2}", v * 1e3));
    for (method, e, [xy, theta, path, ms]) in lines {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.4} | {:.4} | {:.3} | {:.1} |",
            method.name(),
            mm(e.map(|e| e[0])),
            mm(e.map(|e| e[1])),
            mm(e.map(|e| e[2])),
            xy,
            theta,
            path,
            ms
        );
    }
    s
}
