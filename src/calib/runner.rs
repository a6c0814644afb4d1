//! The one calibration driver: a calibrator fed one aligned step at a time,
//! giving its estimate and the calibrated odometry as it goes. Batch runs
//! ([`run`]) and streamed bags are this runner fed a list or a stream.

use std::time::Instant;

use super::run::{CalibSummary, CalibrationRun};
use super::steps::CalibStep;
use super::{Calibrator, CloudView, Estimate};
use crate::geom::Pose2;
use crate::robot::DiffDrive;
use crate::traj::Trajectory;

/// Drives a calibrator step by step, integrating the calibrated odometry
/// with the estimate after each step (what an online system knows then).
/// It keeps the run's bookkeeping; the calibrator is lent to each step, so
/// that a driver may build it once it knows where the filter starts.
pub struct Runner {
    name: &'static str,
    nominal: DiffDrive,
    pose: Pose2,
    /// End (s) of the time already integrated; `None` before the first step.
    covered: Option<f64>,
    total_s: f64,
    steps: usize,
    resets: usize,
    firings: usize,
    /// Times (s) of the steps at which the detector fired as a re-spread.
    respreads: Vec<f64>,
    last: Option<Estimate>,
}

impl Runner {
    /// A runner of the calibrator called `name`; `nominal` is what the
    /// summary reports before any step.
    pub fn new(name: &'static str, nominal: DiffDrive) -> Self {
        Self {
            name,
            nominal,
            pose: Pose2::identity(),
            covered: None,
            total_s: 0.0,
            steps: 0,
            resets: 0,
            firings: 0,
            respreads: Vec::new(),
            last: None,
        }
    }

    /// Runs one step and returns its estimate; `pose` gets the calibrated
    /// odometry's new poses (identity at the first step's `t0`, then the pose
    /// at `t1` of every step that adds time). Only the part of the step not
    /// already integrated moves the pose, so overlapping steps count once.
    pub fn step(
        &mut self,
        cal: &mut dyn Calibrator,
        s: &CalibStep,
        pose: &mut dyn FnMut(f64, &Pose2),
    ) -> Estimate {
        let covered = *self.covered.get_or_insert_with(|| {
            pose(s.t0, &Pose2::identity());
            s.t0
        });
        let t = Instant::now();
        let e = cal.step(s);
        self.total_s += t.elapsed().as_secs_f64();
        self.resets += e.weights_reset as usize;
        self.firings += (e.changed || e.respread) as usize;
        if e.respread {
            self.respreads.push(e.t);
        }
        let dt = s.t1 - s.t0.max(covered);
        if dt > 0.0 {
            self.pose *= e.drive().increment(s.omega_right * dt, s.omega_left * dt);
            pose(s.t1, &self.pose);
            self.covered = Some(s.t1);
        }
        self.steps += 1;
        self.last = Some(e);
        e
    }

    /// The estimate after the last step, if any.
    pub fn last(&self) -> Option<Estimate> {
        self.last
    }

    /// Steps run so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Steps whose weights all underflowed and were reset.
    pub fn weight_resets(&self) -> usize {
        self.resets
    }

    /// Steps at which the change detector fired (on a change or as a
    /// re-spread).
    pub fn firings(&self) -> usize {
        self.firings
    }

    /// The summary after the steps so far (the nominal parameters before any).
    pub fn summary(&self) -> CalibSummary {
        let mut s = CalibSummary::after(
            self.name,
            self.last.as_ref(),
            self.nominal,
            self.steps,
            self.total_s,
        );
        s.respreads_s = self.respreads.clone();
        s
    }
}

/// Runs `cal` over `steps` (a [`Runner`] fed the whole list). Each step's
/// wheel increment (rate × the part of its interval not already integrated,
/// so overlapping intervals are not counted twice) is integrated with
/// `DiffDrive::increment` using the estimate after that step — what an online
/// system knows at the step's end. With no steps the summary holds the
/// nominal parameters and 0 iterations.
pub fn run(cal: &mut dyn Calibrator, steps: &[CalibStep], nominal: DiffDrive) -> CalibrationRun {
    run_observed(cal, steps, nominal, &mut |_, _| {})
}

/// Like [`run`], calling `on_step` after every step with the estimate and the
/// calibrator's particle cloud (if it has one), e.g. to show it in a viewer.
pub fn run_observed(
    cal: &mut dyn Calibrator,
    steps: &[CalibStep],
    nominal: DiffDrive,
    on_step: &mut dyn FnMut(&Estimate, Option<CloudView<'_>>),
) -> CalibrationRun {
    let mut history = Vec::with_capacity(steps.len());
    let mut trajectory = Trajectory::with_capacity(steps.len() + 1);
    let mut runner = Runner::new(cal.name(), nominal);
    for s in steps {
        let e = runner.step(cal, s, &mut |t, p| {
            trajectory.push(t, *p);
        });
        on_step(&e, cal.cloud());
        history.push(e);
    }
    CalibrationRun {
        summary: runner.summary(),
        history,
        trajectory,
        weight_resets: runner.weight_resets(),
    }
}
