//! Keeps what a calibration run needs to name its changes after the run:
//! the wheel, gyro and ICP streams and the estimate at every step, then,
//! at every firing of the change detector, the effect that changed
//! ([`crate::diagnose::onset`]) against the filter's estimate at the start of
//! the firing's window.

use super::observe::RunObserver;
use crate::calib::{CloudView, Estimate};
use crate::diagnose::onset::{name_change, NamedChange, OnsetParams};
use crate::diagnose::Measured;
use crate::io::Item;
use crate::motion::Motion;
use crate::recording::{GyroSample, WheelSample};
use crate::robot::RobotConfig;

/// The streams and estimates of a run (an observer).
#[derive(Debug, Default)]
pub struct ChangeWatch {
    wheels: Vec<WheelSample>,
    gyro: Vec<GyroSample>,
    motions: Vec<Motion>,
    /// (end of step (s), estimated radii and wheel base (m), detector fired).
    steps: Vec<(f64, [f64; 3], bool)>,
}

impl ChangeWatch {
    /// Whether the detector fired at all.
    pub fn fired(&self) -> bool {
        self.steps.iter().any(|s| s.2)
    }

    /// What changed at each firing, in order; `robot` is the model the
    /// filter started from (the baseline of a firing before any estimate).
    pub fn name(&self, robot: &RobotConfig, p: &OnsetParams) -> Vec<NamedChange> {
        let measured = Measured {
            wheels: &self.wheels,
            motions: &self.motions,
            gyro: &self.gyro,
            reference: &[],
        };
        self.steps
            .iter()
            .filter(|s| s.2)
            .map(|&(t, _, _)| {
                let start = t - p.before_s;
                let mut base = robot.clone();
                if let Some((_, [rr, rl, d], _)) =
                    self.steps.iter().take_while(|s| s.0 <= start).last()
                {
                    (base.r_right, base.r_left, base.wheel_base) = (*rr, *rl, *d);
                }
                name_change(&base, &measured, t, p).unwrap_or_else(|| NamedChange::undetermined(t))
            })
            .collect()
    }
}

impl RunObserver for ChangeWatch {
    fn item(&mut self, item: &Item) {
        match item {
            Item::Wheel(w) => self.wheels.push(*w),
            Item::Gyro(g) => self.gyro.push(*g),
            _ => {}
        }
    }

    fn motion(&mut self, motion: &Motion) {
        self.motions.push(motion.clone());
    }

    fn step(&mut self, e: &Estimate, _cloud: Option<CloudView<'_>>) {
        self.steps
            .push((e.t, [e.r_right, e.r_left, e.wheel_base], e.changed));
    }
}

/// One line per named change for the terminal.
pub fn describe(c: &NamedChange) -> String {
    if c.effect == crate::diagnose::onset::UNDETERMINED {
        let why = if c.candidates.is_empty() {
            "too few scan-matching rows on a side of the window"
        } else {
            "no candidate lowers BIC by the margin"
        };
        return format!("change at {:.2} s: undetermined ({why})", c.time_s);
    }
    format!(
        "change at {:.2} s (onset {:.2} s): {} {} = {:.6} ± {:.6}, ΔBIC {:.1}",
        c.time_s, c.onset_s, c.effect, c.parameter, c.estimate, c.stderr, c.delta_bic
    )
}
