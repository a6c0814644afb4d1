//! UMBmark \[Borenstein1996\]: five clockwise and five counter-clockwise
//! square runs of side L, driven by odometry; the end-position errors separate
//! a wheel-base error (type A, same in both directions) from unequal wheel
//! diameters (type B, opposite), and give correction factors for both.
//!
//! Conventions (checked by derivation and by simulation, `tests/classic_umbmark.rs`):
//! REP 103 frame, start at the origin heading +x, CW = right turns. The error of
//! a run is ε = absolute − calculated end position (the paper's eq. 1). To
//! first order a run ends at x_cw = −2Lα − 2Lβ, x_ccw = −2Lα + 2Lβ, where
//! α > 0 is an under-turn at each corner (wheel base larger than nominal) and
//! β > 0 a leftward curvature on each leg (right wheel larger): the paper's
//! equations hold unchanged in this frame.

use super::drive::{drive_segments, square_segments, DriveParams, SimRun, Turn};
use super::error::{check_finite, ClassicError};
use crate::geom::Pose2;
use crate::robot::{wheel_odometry, DiffDrive};
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// The end-position error of one square run: absolute − calculated (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct UmbmarkRun {
    /// Direction of the run.
    pub dir: Turn,
    /// ε_x = x_abs − x_calc (m).
    pub eps_x: f64,
    /// ε_y = y_abs − y_calc (m).
    pub eps_y: f64,
}

impl UmbmarkRun {
    /// The error of a simulated run: true end minus the end the `model`'s
    /// odometry computes from the recorded wheels.
    pub fn from_sim(run: &SimRun, model: &DiffDrive, dir: Turn) -> Self {
        let odo = wheel_odometry(model, &run.wheels, Pose2::identity());
        let calc = odo.poses.last().copied().unwrap_or_else(Pose2::identity);
        let abs = run
            .truth
            .poses
            .last()
            .copied()
            .unwrap_or_else(Pose2::identity);
        Self {
            dir,
            eps_x: abs.translation.x - calc.translation.x,
            eps_y: abs.translation.y - calc.translation.y,
        }
    }
}

/// UMBmark figures and the corrected kinematics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UmbmarkResult {
    /// Side of the square (m).
    pub side_m: f64,
    /// Runs per direction (cw, ccw).
    pub runs: (usize, usize),
    /// Centre of gravity of the clockwise errors (x, y) (m).
    pub cg_cw: [f64; 2],
    /// Centre of gravity of the counter-clockwise errors (x, y) (m).
    pub cg_ccw: [f64; 2],
    /// Distance of the cw centre of gravity from the origin (m).
    pub r_cw: f64,
    /// Distance of the ccw centre of gravity from the origin (m).
    pub r_ccw: f64,
    /// E_max,syst = max(r_cw, r_ccw) (m).
    pub e_max_syst: f64,
    /// α = (x_cw + x_ccw)/(−4L): turn error per corner (rad).
    pub alpha_rad: f64,
    /// β = (x_cw − x_ccw)/(−4L): curvature error per leg (rad).
    pub beta_rad: f64,
    /// R = (L/2)/sin(β/2), radius of the curved legs (m); None when β = 0.
    pub radius_m: Option<f64>,
    /// E_d = D_R/D_L = (R + b/2)/(R − b/2); 1 when β = 0.
    pub e_d: f64,
    /// E_b = 90°/(90° − α): actual over nominal wheel base.
    pub e_b: f64,
    /// c_L = 2/(E_d + 1): left radius multiplier.
    pub c_left: f64,
    /// c_R = 2/(1/E_d + 1): right radius multiplier.
    pub c_right: f64,
    /// The model after correction: r_R·c_R, r_L·c_L, b·E_b.
    pub corrected_r_right: f64,
    /// Corrected left radius (m).
    pub corrected_r_left: f64,
    /// Corrected wheel base (m).
    pub corrected_wheel_base: f64,
}

impl UmbmarkResult {
    /// The corrected kinematics.
    pub fn corrected(&self) -> DiffDrive {
        DiffDrive {
            r_right: self.corrected_r_right,
            r_left: self.corrected_r_left,
            wheel_base: self.corrected_wheel_base,
        }
    }
}

/// Computes UMBmark from run errors on a square of side `side` (m) driven with
/// the `model` being corrected. Needs at least one run in each direction
/// (the benchmark prescribes five).
pub fn umbmark(
    runs: &[UmbmarkRun],
    side: f64,
    model: &DiffDrive,
) -> Result<UmbmarkResult, ClassicError> {
    const M: &str = "umbmark";
    check_finite(M, "error", runs.iter().flat_map(|r| [r.eps_x, r.eps_y]))?;
    if !(side.is_finite() && side > 0.0) {
        return Err(ClassicError::invalid(
            M,
            format!("side must be > 0 m, got {side}"),
        ));
    }
    let cg = |dir| {
        let sel: Vec<_> = runs.iter().filter(|r| r.dir == dir).collect();
        let n = sel.len();
        let x = sel.iter().map(|r| r.eps_x).sum::<f64>() / n.max(1) as f64;
        let y = sel.iter().map(|r| r.eps_y).sum::<f64>() / n.max(1) as f64;
        (n, [x, y])
    };
    let (n_cw, cg_cw) = cg(Turn::Cw);
    let (n_ccw, cg_ccw) = cg(Turn::Ccw);
    if n_cw == 0 || n_ccw == 0 {
        return Err(ClassicError::TooFew {
            method: M,
            what: "runs in each direction",
            needed: 1,
            got: n_cw.min(n_ccw),
        });
    }
    let r_cw = cg_cw[0].hypot(cg_cw[1]);
    let r_ccw = cg_ccw[0].hypot(cg_ccw[1]);
    let l = side;
    let b = model.wheel_base;
    // [Borenstein1996, eqs. 6.1, 6.2] (radians here).
    let alpha = (cg_cw[0] + cg_ccw[0]) / (-4.0 * l);
    let beta = (cg_cw[0] - cg_ccw[0]) / (-4.0 * l);
    let (radius, e_d) = if beta.abs() < 1e-12 {
        (None, 1.0)
    } else {
        let r = (l / 2.0) / (beta / 2.0).sin();
        (Some(r), (r + b / 2.0) / (r - b / 2.0))
    };
    if !(e_d.is_finite() && e_d > 0.0) || alpha.abs() >= FRAC_PI_2 {
        return Err(ClassicError::invalid(
            M,
            format!("errors too large for the square of {l} m (E_d = {e_d}, α = {alpha} rad)"),
        ));
    }
    let e_b = FRAC_PI_2 / (FRAC_PI_2 - alpha);
    let c_left = 2.0 / (e_d + 1.0);
    let c_right = 2.0 / (1.0 / e_d + 1.0);
    Ok(UmbmarkResult {
        side_m: l,
        runs: (n_cw, n_ccw),
        cg_cw,
        cg_ccw,
        r_cw,
        r_ccw,
        e_max_syst: r_cw.max(r_ccw),
        alpha_rad: alpha,
        beta_rad: beta,
        radius_m: radius,
        e_d,
        e_b,
        c_left,
        c_right,
        corrected_r_right: model.r_right * c_right,
        corrected_r_left: model.r_left * c_left,
        corrected_wheel_base: b * e_b,
    })
}

/// `n` runs each way on a square of `side` (m) with a robot that is really
/// `truth` but believes `model`; run i uses seed `seed + i`.
pub fn umbmark_runs(
    model: &DiffDrive,
    truth: &DiffDrive,
    side: f64,
    n: usize,
    drive: &DriveParams,
    seed: u64,
) -> Vec<UmbmarkRun> {
    let mut out = Vec::with_capacity(2 * n);
    for (k, dir) in [Turn::Cw, Turn::Ccw].into_iter().enumerate() {
        let segs = square_segments(side, dir);
        for i in 0..n {
            let s = seed.wrapping_add((k * n + i) as u64);
            let run = drive_segments(model, truth, &segs, drive, s);
            out.push(UmbmarkRun::from_sim(&run, model, dir));
        }
    }
    out
}
