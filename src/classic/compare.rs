//! Every classic method on the same simulated runs, side by side: final
//! parameter errors, RMSE of x,y and θ, end-position error as % of the path,
//! and compute time. The runs come from a caller's closure (the simulator's
//! `square` / `square-ccw` scenarios, or [`super::drive_segments`]).

use super::drive::{SimRun, Turn};
use super::error::ClassicError;
use super::ga::{ga_calibrate, GaBounds, GaParams, GaRun, TickParams};
use super::heading_gain::{fit_heading_gain, HeadingTrial};
use super::heading_pf::{heading_pf, simulate_heading, HeadingPfParams, HeadingSourceParams};
use super::tacho::{fit_tachometer, TachoReading};
use super::umbmark::{umbmark, UmbmarkRun};
use crate::geom::{self, Pose2};
use crate::recording::WheelSample;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::traj::Trajectory;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::time::Instant;

/// The methods compared side by side (kebab-case names, as in tables and JSON):
/// the classic ones and, for the literature comparison, seed 000's filters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClassicMethod {
    /// Nominal parameters.
    None,
    /// Seed 001: tachometer rpm correction and heading gain.
    TachoHeading,
    /// Borenstein & Feng's UMBmark correction.
    Umbmark,
    /// Seed 002's genetic algorithm.
    Ga,
    /// Seed 002's GA-calibrated odometry fused with a heading source in a PF.
    HeadingPf,
    /// Seed 000's Adaptive-PF on laser velocities and gyro (`calib`).
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

/// Differential-drive parameters (m), with design.md's JSON key names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FinalParams {
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
}

impl From<DiffDrive> for FinalParams {
    fn from(k: DiffDrive) -> Self {
        Self {
            r_right: k.r_right,
            r_left: k.r_left,
            wheel_base: k.wheel_base,
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
    pub final_params: FinalParams,
    /// |final − truth| per parameter (m), when the truth is known.
    pub param_errors: Option<FinalParams>,
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
    /// 6 m squares (seed 001), 5 runs each way, 3 evaluation runs, 8800 ticks/rev,
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

/// Cuts a run into consecutive pieces whose true path length is drawn in
/// [min, max] (m), each with its true start and end pose, as GA runs.
pub fn split_short_runs(
    run: &SimRun,
    ticks_per_rev: f64,
    min: f64,
    max: f64,
    seed: u64,
) -> Vec<GaRun> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    let w = &run.wheels;
    let pose = |s: &WheelSample| run.truth.pose_at(s.stamp);
    let mut i0 = 0;
    let mut target = rng.random_range(min..max.max(min + 1e-9));
    let mut len = 0.0;
    for i in 1..w.len() {
        let (Some(a), Some(b)) = (pose(&w[i - 1]), pose(&w[i])) else {
            continue;
        };
        len += (b.translation.vector - a.translation.vector).norm();
        if len >= target {
            if let Some(start) = pose(&w[i0]) {
                out.push(GaRun::from_wheels(&w[i0..=i], ticks_per_rev, start, b));
            }
            i0 = i;
            len = 0.0;
            target = rng.random_range(min..max.max(min + 1e-9));
        }
    }
    out
}

/// Cuts a run at every second segment end (a square's corners, after each
/// turn) into GA runs with the true poses there.
fn corner_pieces(run: &SimRun, ticks_per_rev: f64) -> Vec<GaRun> {
    let w = &run.wheels;
    let mut cuts = vec![0usize];
    for &t in run.segment_ends.iter().skip(1).step_by(2) {
        let i = w.partition_point(|s| s.stamp < t - 1e-9).min(w.len() - 1);
        if i > *cuts.last().unwrap_or(&0) {
            cuts.push(i);
        }
    }
    cuts.windows(2)
        .filter_map(|c| {
            let a = run.truth.pose_at(w[c[0]].stamp)?;
            let b = run.truth.pose_at(w[c[1]].stamp)?;
            Some(GaRun::from_wheels(&w[c[0]..=c[1]], ticks_per_rev, a, b))
        })
        .collect()
}

/// RMSE of position (m) and heading (rad) of `est` against the truth at the
/// estimate's stamps, and the end error as % of the true path length.
fn errors(est: &Trajectory, truth: &Trajectory) -> (f64, f64, f64, usize) {
    let (mut sxy, mut sth, mut n) = (0.0, 0.0, 0usize);
    let mut last = None;
    for (t, p) in est.stamps.iter().zip(&est.poses) {
        if let Some(q) = truth.pose_at(*t) {
            sxy += (p.translation.vector - q.translation.vector).norm_squared();
            sth += geom::wrap_angle(geom::heading(p) - geom::heading(&q)).powi(2);
            n += 1;
            last = Some((p.translation.vector - q.translation.vector).norm());
        }
    }
    let nn = n.max(1) as f64;
    let pct = 100.0 * last.unwrap_or(0.0) / truth.path_length().max(1e-9);
    ((sxy / nn).sqrt(), (sth / nn).sqrt(), pct, n)
}

/// Scores one method on the evaluation runs: `estimate` gives its trajectory
/// of each run, `k` the parameters it ends with (m), `ms` its compute time.
pub(crate) fn evaluate_method(
    method: ClassicMethod,
    k: DiffDrive,
    truth: Option<&DiffDrive>,
    ms: f64,
    details: serde_json::Value,
    evals: &[SimRun],
    estimate: &dyn Fn(&SimRun) -> Result<Trajectory, ClassicError>,
) -> Result<ClassicResult, ClassicError> {
    let (mut sxy, mut sth, mut pct, mut n) = (0.0, 0.0, 0.0, 0usize);
    for run in evals {
        let est = estimate(run)?;
        let (a, b, c, m) = errors(&est, &run.truth);
        sxy += a * a * m as f64;
        sth += b * b * m as f64;
        pct += c;
        n += m;
    }
    let nn = n.max(1) as f64;
    Ok(ClassicResult {
        method,
        final_params: k.into(),
        param_errors: truth.map(|t| FinalParams {
            r_right: (k.r_right - t.r_right).abs(),
            r_left: (k.r_left - t.r_left).abs(),
            wheel_base: (k.wheel_base - t.wheel_base).abs(),
        }),
        rmse_xy: (sxy / nn).sqrt(),
        rmse_theta: (sth / nn).sqrt(),
        path_error_percent: pct / evals.len().max(1) as f64,
        compute_ms: ms,
        details,
    })
}

/// The true start pose of a run (identity if unknown).
pub(crate) fn start_of(run: &SimRun) -> Pose2 {
    run.wheels
        .first()
        .and_then(|s| run.truth.pose_at(s.stamp))
        .unwrap_or_else(Pose2::identity)
}

/// Measurement noise of end poses: N(0, σ²) per coordinate, seeded.
struct PoseNoise {
    rng: StdRng,
    sigma: [f64; 2],
}

impl PoseNoise {
    fn new(sigma: [f64; 2], seed: u64) -> Self {
        Self {
            rng: StdRng::seed_from_u64(seed ^ 0x656e_6470_6f73),
            sigma,
        }
    }
    fn draw(&mut self, s: f64) -> f64 {
        if s > 0.0 {
            let z: f64 = self.rng.sample(rand_distr::StandardNormal);
            s * z
        } else {
            0.0
        }
    }
    fn xy(&mut self) -> (f64, f64) {
        (self.draw(self.sigma[0]), self.draw(self.sigma[0]))
    }
    fn angle(&mut self) -> f64 {
        self.draw(self.sigma[1])
    }
    fn pose(&mut self, p: &Pose2) -> Pose2 {
        let [x, y, t] = geom::xyt(p);
        let (dx, dy) = self.xy();
        geom::pose(x + dx, y + dy, t + self.angle())
    }
}

/// Total unwrapped heading change of a trajectory (rad).
fn total_turn(t: &Trajectory) -> f64 {
    t.poses
        .windows(2)
        .map(|w| geom::wrap_angle(geom::heading(&w[1]) - geom::heading(&w[0])))
        .sum()
}

/// Runs every classic method on the same data and evaluates each on held-out
/// runs. `simulate(scenario, seed)` must return the recorded wheels and the
/// true trajectory of one run; square runs are those a robot believing
/// `nominal` drives. `truth`, when known, gives the parameter errors.
pub fn compare_classic<F, E>(
    nominal: &DiffDrive,
    truth: Option<&DiffDrive>,
    p: &CompareParams,
    mut simulate: F,
) -> Result<Vec<ClassicResult>, ClassicError>
where
    F: FnMut(CompareScenario, u64) -> Result<SimRun, E>,
    E: std::fmt::Display,
{
    let mut simulate = |sc, seed| {
        simulate(sc, seed).map_err(|e| {
            ClassicError::invalid("comparison runs", format!("{sc:?} (seed {seed}): {e}"))
        })
    };
    let mut squares = Vec::new();
    for (k, (sc, dir)) in [
        (CompareScenario::Square, Turn::Cw),
        (CompareScenario::SquareCcw, Turn::Ccw),
    ]
    .into_iter()
    .enumerate()
    {
        for i in 0..p.runs_per_direction {
            let seed = p
                .seed
                .wrapping_mul(7919)
                .wrapping_add((k * p.runs_per_direction + i) as u64);
            squares.push((dir, simulate(sc, seed)?));
        }
    }
    let evals: Vec<SimRun> = (0..p.evaluation_runs)
        .map(|i| {
            simulate(
                CompareScenario::Evaluation,
                p.seed.wrapping_mul(104_729).wrapping_add(i as u64),
            )
        })
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    let mut push = |method,
                    k: DiffDrive,
                    ms: f64,
                    details,
                    estimate: &dyn Fn(&SimRun) -> Result<Trajectory, ClassicError>|
     -> Result<(), ClassicError> {
        out.push(evaluate_method(
            method, k, truth, ms, details, &evals, estimate,
        )?);
        Ok(())
    };
    let odo = |k: DiffDrive| move |run: &SimRun| Ok(wheel_odometry(&k, &run.wheels, start_of(run)));

    // No calibration.
    push(
        ClassicMethod::None,
        *nominal,
        0.0,
        serde_json::Value::Null,
        &odo(*nominal),
    )?;

    // Seed 001: tachometer correction (if a table is given) and heading gain
    // from the square runs' total turns (actual vs estimated).
    let t0 = Instant::now();
    let tacho = p.tachometer.as_deref().map(fit_tachometer).transpose()?;
    let correct = |w: &[WheelSample]| {
        tacho
            .as_ref()
            .map_or_else(|| w.to_vec(), |c| c.correct_wheels(w))
    };
    let mut noise = PoseNoise::new(p.end_pose_sigma, p.seed);
    let trials: Vec<HeadingTrial> = squares
        .iter()
        .map(|(_, run)| {
            let est = wheel_odometry(nominal, &correct(&run.wheels), Pose2::identity());
            HeadingTrial {
                actual_deg: (total_turn(&run.truth).abs() + noise.angle()).to_degrees(),
                estimated_deg: total_turn(&est).abs().to_degrees(),
            }
        })
        .collect();
    let gain = fit_heading_gain(&trials)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let scale = |s: Option<f64>| s.unwrap_or(1.0);
    let k_th = DiffDrive {
        r_right: nominal.r_right * scale(tacho.as_ref().map(|c| c.right.slope_through_origin)),
        r_left: nominal.r_left * scale(tacho.as_ref().map(|c| c.left.slope_through_origin)),
        wheel_base: gain.effective_wheel_base(nominal.wheel_base),
    };
    let k_gain = DiffDrive {
        wheel_base: gain.effective_wheel_base(nominal.wheel_base),
        ..*nominal
    };
    let details = serde_json::json!({ "tachometer": tacho, "heading_gain": gain });
    push(
        ClassicMethod::TachoHeading,
        k_th,
        ms,
        details,
        &|run: &SimRun| {
            Ok(wheel_odometry(
                &k_gain,
                &correct(&run.wheels),
                start_of(run),
            ))
        },
    )?;

    // UMBmark on the square runs.
    let t0 = Instant::now();
    let runs: Vec<UmbmarkRun> = squares
        .iter()
        .map(|(dir, run)| {
            let mut r = UmbmarkRun::from_sim(run, nominal, *dir);
            let (dx, dy) = noise.xy();
            r.eps_x += dx;
            r.eps_y += dy;
            r
        })
        .collect();
    let um = umbmark(&runs, p.square_side, nominal)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let k_um = um.corrected();
    push(
        ClassicMethod::Umbmark,
        k_um,
        ms,
        serde_json::to_value(&um).unwrap_or_default(),
        &odo(k_um),
    )?;

    // GA on 1.5–3 m pieces of the square runs (or the whole runs).
    let t0 = Instant::now();
    let pieces: Vec<GaRun> = squares
        .iter()
        .enumerate()
        .flat_map(|(i, (_, run))| {
            if p.ga_corners && !run.segment_ends.is_empty() {
                return corner_pieces(run, p.ticks_per_rev);
            }
            split_short_runs(
                run,
                p.ticks_per_rev,
                p.short_run_m.0,
                p.short_run_m.1,
                p.seed.wrapping_add(i as u64),
            )
        })
        .map(|g| GaRun {
            start: noise.pose(&g.start),
            end: noise.pose(&g.end),
            ..g
        })
        .collect();
    let nominal_ticks = TickParams::from_diff_drive(nominal, p.ticks_per_rev);
    let ga = ga_calibrate(
        &pieces,
        &GaParams {
            bounds: GaBounds::around(&nominal_ticks, p.ga_bounds_rel),
            ..p.ga
        },
    )?;
    let ms_ga = t0.elapsed().as_secs_f64() * 1e3;
    let k_ga = ga.params.to_diff_drive(p.ticks_per_rev);
    let details = serde_json::json!({ "params": ga.params, "cost": ga.cost, "pieces": pieces.len(), "evaluations": ga.evaluations });
    push(ClassicMethod::Ga, k_ga, ms_ga, details, &odo(k_ga))?;

    // GA-calibrated odometry fused with the heading source.
    let t0 = Instant::now();
    let mut pf_ms = 0.0;
    let pf_estimates: Vec<Trajectory> = evals
        .iter()
        .enumerate()
        .map(|(i, run)| {
            let h = simulate_heading(
                &run.truth,
                &p.heading,
                p.seed.wrapping_add(31 * i as u64 + 7),
            );
            heading_pf(
                &k_ga,
                &run.wheels,
                &h,
                &start_of(run),
                &HeadingPfParams {
                    seed: p.seed.wrapping_add(i as u64),
                    ..p.pf
                },
            )
        })
        .collect::<Result<_, _>>()?;
    pf_ms += t0.elapsed().as_secs_f64() * 1e3;
    let details = serde_json::json!({ "particles": p.pf.particles, "heading_sigma": p.heading.sigma, "filter_ms": pf_ms });
    let lookup = |run: &SimRun| {
        let i = evals.iter().position(|e| std::ptr::eq(e, run)).unwrap_or(0);
        Ok(pf_estimates[i].clone())
    };
    push(
        ClassicMethod::HeadingPf,
        k_ga,
        ms_ga + pf_ms,
        details,
        &lookup,
    )?;
    Ok(out)
}

/// The comparison as a markdown table (parameter errors in mm).
pub fn markdown_table(rows: &[ClassicResult]) -> String {
    let mut s = String::from("| method | R_R err (mm) | R_L err (mm) | D err (mm) | RMSE x,y (m) | RMSE θ (rad) | path error (%) | compute (ms) |\n|---|---|---|---|---|---|---|---|\n");
    let mm = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{:.2}", v * 1e3));
    for r in rows {
        let e = r.param_errors;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.4} | {:.4} | {:.3} | {:.1} |",
            r.method.name(),
            mm(e.map(|e| e.r_right)),
            mm(e.map(|e| e.r_left)),
            mm(e.map(|e| e.wheel_base)),
            r.rmse_xy,
            r.rmse_theta,
            r.path_error_percent,
            r.compute_ms
        );
    }
    s
}
