//! A sliding window over a run's drive: the poses (and, for the encoders,
//! the measured wheel angles) of the integration steps between two times,
//! integrated on demand and forgotten once behind. Every sensor of a streamed
//! run reads the motion through its own tape, asking for non-decreasing
//! times, so the memory of a run does not grow with its length: a tape holds
//! the steps of the span its reader asks at once (a block of scans, a gyro
//! interval), never the run.

use super::drive::{step_at, Driver};
use super::effects::TrueRobot;
use std::collections::VecDeque;

/// The measured wheel angle increments (rad, right and left) over step `k`
/// of `dt` s commanding `v` (m/s), `w` (rad/s) with the body at `x` (m) in
/// mid-step: the true wheel rates that realise the command, altered by the
/// robot's faults (which may depend on the true wheel angles `truth`, rad,
/// advanced here, and on where the robot is), as the encoders read them.
pub(crate) fn wheel_step(
    robot: &TrueRobot,
    k: usize,
    dt: f64,
    (v, w): (f64, f64),
    truth: &mut (f64, f64),
    x: f64,
) -> (f64, f64) {
    let t = (k as f64 + 0.5) * dt;
    let rates = robot.wheel_rates(t, v, w);
    let (wr, wl) = robot.faulty_rates(rates, *truth, x);
    truth.0 += wr * dt;
    truth.1 += wl * dt;
    (robot.measured_rate(wr) * dt, robot.measured_rate(wl) * dt)
}

/// The measured wheel angles of a tape: the encoder's reading of the true
/// wheel rates that realise each step's command (see [`super::WheelTrack`]).
#[derive(Clone)]
struct Wheels {
    robot: TrueRobot,
    /// Angles (rad, right and left) at the end of the last step integrated.
    now: (f64, f64),
    /// True wheel angles (rad, right and left) there, for the faults.
    truth: (f64, f64),
    /// Angles at the poses kept, `first..first + len`.
    right: VecDeque<f64>,
    left: VecDeque<f64>,
}

/// A window of the drive: poses at `k dt` for `k` in `first..first + len`.
#[derive(Clone)]
pub struct Tape {
    driver: Driver,
    /// Step index of the first pose kept.
    first: usize,
    x: VecDeque<f64>,
    y: VecDeque<f64>,
    theta: VecDeque<f64>,
    /// Index of the next step the driver gives.
    next: usize,
    wheels: Option<Wheels>,
}

impl Tape {
    /// A tape of the drive of `driver` (not yet started), poses only.
    pub fn new(driver: Driver) -> Self {
        let p = driver.pose();
        Self {
            driver,
            first: 0,
            x: VecDeque::from([p[0]]),
            y: VecDeque::from([p[1]]),
            theta: VecDeque::from([p[2]]),
            next: 0,
            wheels: None,
        }
    }

    /// A tape that also integrates the wheel angles the encoders of `robot` measure.
    pub fn with_wheels(driver: Driver, robot: TrueRobot) -> Self {
        let mut t = Self::new(driver);
        t.wheels = Some(Wheels {
            robot,
            now: (0.0, 0.0),
            truth: (0.0, 0.0),
            right: VecDeque::from([0.0]),
            left: VecDeque::from([0.0]),
        });
        t
    }

    /// Poses held (at most the steps between the times of the last [`cover`](Self::cover), plus two).
    pub fn held(&self) -> usize {
        self.x.len()
    }

    /// Makes the window hold every time in `[from, to]` (s) and forgets the
    /// steps before `from`: later questions must not go back before `from`.
    pub fn cover(&mut self, from: f64, to: f64) {
        let (dt, steps) = (self.driver.dt(), self.driver.steps());
        let (keep, _) = step_at(from, dt, steps);
        let (last, _) = step_at(to, dt, steps);
        self.forget_before(keep);
        while self.next <= last {
            self.advance();
            self.forget_before(keep);
        }
    }

    /// Forgets the poses before step `keep` (the last pose always stays).
    fn forget_before(&mut self, keep: usize) {
        let drop = keep.saturating_sub(self.first).min(self.x.len() - 1);
        if drop == 0 {
            return;
        }
        self.x.drain(..drop);
        self.y.drain(..drop);
        self.theta.drain(..drop);
        if let Some(w) = &mut self.wheels {
            w.right.drain(..drop);
            w.left.drain(..drop);
        }
        self.first += drop;
    }

    /// Integrates one more step into the window.
    fn advance(&mut self) {
        let Some(s) = self.driver.next() else {
            return;
        };
        let k = self.next;
        self.next += 1;
        let mid_x = 0.5 * (self.x[self.x.len() - 1] + s.end[0]);
        self.x.push_back(s.end[0]);
        self.y.push_back(s.end[1]);
        self.theta.push_back(s.end[2]);
        if let Some(w) = &mut self.wheels {
            let dt = self.driver.dt();
            let (dr, dl) = wheel_step(&w.robot, k, dt, (s.v, s.w), &mut w.truth, mid_x);
            w.now.0 += dr;
            w.now.1 += dl;
            w.right.push_back(w.now.0);
            w.left.push_back(w.now.1);
        }
    }

    /// Position of the step holding `t` in the window, and how far into it
    /// `t` is. A time before the window is a reader going back in time, a
    /// logic error of the simulator, not of its input.
    fn locate(&self, t: f64) -> (usize, f64) {
        let (k, a) = step_at(t, self.driver.dt(), self.driver.steps());
        assert!(
            k >= self.first && k + 1 < self.first + self.x.len(),
            "tape asked for t = {t} s outside its window (steps {}..{})",
            self.first,
            self.first + self.x.len()
        );
        (k - self.first, a)
    }

    /// Body pose `(x, y, θ unwrapped)` at `t` (s), linear between steps:
    /// the value of [`super::Drive::pose_at`]. `t` must be covered.
    pub fn pose_at(&self, t: f64) -> [f64; 3] {
        let (i, a) = self.locate(t);
        let lerp = |v: &VecDeque<f64>| v[i] + (v[i + 1] - v[i]) * a;
        [lerp(&self.x), lerp(&self.y), lerp(&self.theta)]
    }

    /// Measured wheel angles (right, left) (rad) at `t` (s), exact between
    /// steps: the value of [`super::WheelTrack::at`]. `t` must be covered,
    /// and the tape made [`with_wheels`](Self::with_wheels).
    pub fn wheels_at(&self, t: f64) -> (f64, f64) {
        let (i, a) = self.locate(t);
        let w = self.wheels.as_ref().expect("a tape made with wheels");
        (
            w.right[i] + (w.right[i + 1] - w.right[i]) * a,
            w.left[i] + (w.left[i + 1] - w.left[i]) * a,
        )
    }
}
