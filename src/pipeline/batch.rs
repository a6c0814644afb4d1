//! `odocal calibrate --method batch`: the joint maximum-likelihood estimate
//! of the radii, the wheel base, the laser mounting and the time offset
//! ([`crate::calib::batch`]) from Censi et al.'s tuples or from a recording
//! (ICP motions moved into the laser frame and aggregated into intervals). The
//! mounting is estimated, never taken from the robot file or the recording
//! (those are only reported), so this path never needs a stated `[laser]`.

use super::calibrate_job::{CalibSource, CalibrateJob, CalibrateOutcome};
use super::Config;
use super::{PipelineError, RunObserver};
use crate::assumptions::{Assumptions, Origin};
use crate::calib::batch::{
    self, BatchEstimate, BatchParams, Interval, LaserMotion, Problem, WheelMotion, WheelTrack,
};
use crate::calib::{CalibSummary, Observability};
use crate::error::InputError;
use crate::io::censi::CensiTuple;
use crate::recording::{Recording, WheelSource};
use crate::robot::RobotConfig;
use crate::robot::{DiffDrive, LaserMount};
use std::path::Path;

/// The batch problem of Censi et al.'s tuples: one interval per tuple with
/// one wheel sub-step `(T·phi_l, T·phi_r)` and no covariance (the σ's are
/// estimated from the residuals, as the authors' solver does); no time.
pub fn tuples_problem(tuples: &[CensiTuple]) -> Problem {
    Problem {
        intervals: tuples
            .iter()
            .map(|t| Interval {
                s: t.sm,
                cov: None,
                duration: t.t,
                wheels: WheelMotion::Steps(vec![[t.t * t.phi_l, t.t * t.phi_r]]),
            })
            .collect(),
        track: None,
    }
}

/// Runs `odocal calibrate --method batch`: reads the input by its format,
/// estimates, writes `DIR/summary.json` atomically.
pub fn run(
    job: &CalibrateJob,
    _watch: &mut dyn RunObserver,
) -> Result<CalibrateOutcome, PipelineError> {
    let CalibSource::Recording(path) = &job.input else {
        return Err(PipelineError::BadArgument(
            "--method batch reads a recording or Censi tuples (--input), not --motions/--wheels CSV"
                .into(),
        ));
    };
    let mut outputs = vec![job.out.join("summary.json")];
    outputs.extend(super::paste::Paste::paths(&job.out, true));
    let outputs: Vec<&Path> = outputs.iter().map(|p| p.as_path()).collect();
    super::outputs::check_outputs(&[path], &outputs)?;
    let _lock = super::outputs::lock_outputs(&[job.out.as_path()])?;
    let (cfg, nominal) = job.common.load_nominal()?;
    let robot = &nominal.robot;
    let mut params = cfg.calib.clone();
    job.choice.apply(&mut params);
    let (problem, wheel_source, rec) = if crate::io::sniff(path)? == crate::io::Format::CensiTuples
    {
        (tuples_problem(&crate::io::censi::read(path)?), None, None)
    } else {
        let (rec, problem, wheels) = recording_problem(path, &cfg, &nominal, &params.batch)?;
        (problem, Some(wheels), Some(rec))
    };
    let est = solve(path, &problem, robot, &params, wheel_source.as_ref())?;
    let mut assumptions = nominal.assumptions();
    if let Some(rec) = &rec {
        nominal.drop_unused_wheel_keys(&mut assumptions, rec.wheel_values);
        state_prior(&mut assumptions, &cfg, &nominal, rec);
    }
    state_laser(&mut assumptions, &est, robot.laser);
    let mut summary = summary(
        est,
        robot.diff_drive(),
        problem.intervals.len(),
        assumptions,
    );
    if let Some(w) = wheel_source {
        super::wheels::state(&mut summary, w);
    }
    let paste = super::paste::Paste::of(&summary, robot, &path.display().to_string());
    write_summary(&job.out, &paste.with(&summary))?;
    paste.write(&job.out)?;
    Ok(CalibrateOutcome {
        summary,
        notes: Vec::new(),
        paste,
    })
}

/// The batch estimate of `problem` against the nominal `robot`; a refusal
/// names `path` (and, for a controller's twist, why a lag is likely).
pub(super) fn solve(
    path: &Path,
    problem: &Problem,
    robot: &RobotConfig,
    params: &crate::calib::CalibParams,
    wheel_source: Option<&WheelSource>,
) -> Result<BatchEstimate, PipelineError> {
    batch::estimate(problem, &robot.diff_drive(), &params.batch, &params.checks).map_err(|e| {
        let why = match wheel_source {
            Some(w) if w.kind == crate::robot::WheelSourceKind::Odometry => {
                " (the wheels come from a controller's twist, which lags its wheels by \
                 the controller's velocity filtering: a lag of more than a sample is \
                 refused like a clock offset)"
            }
            _ => "",
        };
        InputError::new(path.display().to_string(), format!("{e}{why}")).into()
    })
}

/// The estimated mounting under `laser`, with the stated one (if any) in
/// the note.
fn state_laser(a: &mut Assumptions, est: &BatchEstimate, stated: Option<LaserMount>) {
    let l = &est.laser;
    let note = match stated {
        Some(s) => format!(
            "batch estimate; the robot file states x {:.4} m, y {:.4} m, yaw {:.4} rad (not used)",
            s.x, s.y, s.yaw
        ),
        None => "batch estimate".to_string(),
    };
    let mount = LaserMount {
        x: l.x.value,
        y: l.y.value,
        yaw: l.yaw.value,
    };
    a.set("laser", mount, Origin::Estimated, Some(note));
}

/// design.md's calibrate summary with the batch keys added.
fn summary(
    est: BatchEstimate,
    nominal: DiffDrive,
    n: usize,
    assumptions: Assumptions,
) -> CalibSummary {
    let mut s = CalibSummary::after("batch", None, nominal, n, 0.0);
    s.final_params = est.drive();
    s.std = est.drive_std();
    let ratio = |a: f64, b: f64| a / b;
    s.multipliers.right_wheel_radius = ratio(est.r_right.value, nominal.r_right);
    s.multipliers.left_wheel_radius = ratio(est.r_left.value, nominal.r_left);
    s.multipliers.wheel_separation = ratio(est.wheel_base.value, nominal.wheel_base);
    s.assumptions = assumptions;
    s.observability = Some(Observability {
        parameters: est.observability.clone(),
        excitation: est.excitation.clone(),
    });
    s.batch = Some(est);
    s
}

fn write_summary(dir: &Path, s: &impl serde::Serialize) -> Result<(), PipelineError> {
    std::fs::create_dir_all(dir).map_err(|e| PipelineError::write(dir, e))?;
    let js = dir.join("summary.json");
    let text = serde_json::to_string_pretty(s).expect("summary serialises");
    crate::io::atomic::write_bytes_atomic(&js, text.as_bytes())
        .map_err(|e| PipelineError::write(&js, e))
}

/// States in `a` the prior the batch's scan matching took for `rec`.
fn state_prior(a: &mut Assumptions, cfg: &Config, nominal: &super::Nominal, rec: &Recording) {
    let choice = nominal.prior_choice(cfg.icp.prior, &crate::io::StreamInfo::of(rec));
    let (w, o) = (rec.wheels.len(), rec.odom.len());
    // The matching ran, so the choice was possible.
    if let Ok(prior) = crate::icp::Prior::choose(choice, w, o, nominal.robot.diff_drive()) {
        nominal.state_prior(a, &prior, cfg.icp.prior, w);
    }
}

/// The batch problem of a recording: ICP as the online filters match (the
/// same `[icp]` settings, so both calibrate from the same evidence) with the
/// mounting the recording or robot file states (else the identity, so the
/// motions are the laser's own), each motion's scan-measured part moved into
/// the laser frame ([`LaserMotion::from_motion`]), composed into intervals, and the wheel angles as the
/// track the time offset shifts; with the recording and the wheel source it
/// was read from.
pub(super) fn recording_problem(
    path: &Path,
    cfg: &Config,
    nominal: &super::Nominal,
    p: &BatchParams,
) -> Result<(crate::recording::Recording, Problem, WheelSource), PipelineError> {
    let robot = &nominal.robot;
    let mut read = super::read_options(cfg, robot);
    let mut rec = crate::io::read_recording(path, &read)?;
    let mut found = super::wheels::Found {
        wheels: rec.wheels.len(),
        odom: rec.odom.len(),
        bag: crate::io::sniff(path)? != crate::io::Format::Text,
    };
    if let Some(only) = super::wheels::only_source(&read, nominal, found) {
        read = only;
        rec = crate::io::read_recording(path, &read)?;
        found.wheels = rec.wheels.len();
    }
    super::wheels::require(&read, nominal, &rec.source, found)?;
    let wheels = super::wheels::describe(&read, nominal, found.wheels, rec.wheel_values);
    let robot_icp = match super::icp::mount(&rec, robot) {
        Ok(_) => robot.clone(),
        Err(_) => RobotConfig {
            laser: Some(LaserMount {
                x: 0.0,
                y: 0.0,
                yaw: 0.0,
            }),
            ..robot.clone()
        },
    };
    let mount = super::icp::mount(&rec, &robot_icp)?.pose;
    let icp_params = nominal.icp_params(&cfg.icp, &crate::io::StreamInfo::of(&rec));
    let icp = super::icp::match_recording(&rec, &robot_icp, &icp_params)?;
    let motions: Vec<LaserMotion> = icp
        .motions
        .iter()
        .map(|m| LaserMotion::from_motion(m, &mount))
        .collect();
    let intervals = batch::aggregate(&motions, p.interval_s, p.interval_rad, 1e-3);
    let track = WheelTrack {
        t: rec.wheels.iter().map(|w| w.stamp).collect(),
        left: rec.wheels.iter().map(|w| w.left).collect(),
        right: rec.wheels.iter().map(|w| w.right).collect(),
    };
    let problem = Problem {
        intervals,
        track: Some(track),
    };
    Ok((rec, problem, wheels))
}
