//! The "no calibration" baseline: the nominal parameters, unchanged.

use super::steps::CalibStep;
use super::{Calibrator, Estimate};
use crate::robot::DiffDrive;

/// Returns the nominal parameters at every step (V, W from them).
#[derive(Debug, Clone)]
pub struct Nominal {
    drive: DiffDrive,
}

impl Nominal {
    /// The baseline for these nominal parameters.
    pub fn new(drive: DiffDrive) -> Self {
        Self { drive }
    }
}

impl Calibrator for Nominal {
    fn step(&mut self, s: &CalibStep) -> Estimate {
        let (v, w) = self.drive.body_velocity(s.omega_right, s.omega_left);
        Estimate {
            t: s.t1,
            r_right: self.drive.r_right,
            r_left: self.drive.r_left,
            wheel_base: self.drive.wheel_base,
            std_r_right: 0.0,
            std_r_left: 0.0,
            std_wheel_base: 0.0,
            v,
            w,
            particles: 0,
            process_sigma: 0.0,
            resampled: false,
            weights_reset: false,
            changed: false,
            respread: false,
        }
    }

    fn name(&self) -> &'static str {
        "none"
    }
}
