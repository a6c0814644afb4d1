//! Driving a scenario: the commanded body velocities (v, w) at the
//! integration rate, within the motion limits, and the body trajectory they
//! produce (exact arcs). Smooth routes use a path-following controller fed
//! back the true pose; stop-and-turn routes an open-loop trapezoidal timetable.

use super::config::ScenarioConfig;
use super::path::Path;
use super::scenario::{Route, Scenario};
use crate::geom::{self, wrap_angle};
use nalgebra::Point2;
use std::collections::VecDeque;

/// Commanded body velocities per integration step and the body trajectory
/// they produce (exact arcs), in the world frame.
#[derive(Debug, Clone)]
pub struct Drive {
    /// Step length (s).
    pub dt: f64,
    /// Forward speed (m/s) over step k, i.e. over `[k dt, (k+1) dt]`.
    pub v: Vec<f64>,
    /// Turn rate (rad/s) over step k.
    pub w: Vec<f64>,
    /// x (m) at `k dt`, k = 0..=steps.
    pub x: Vec<f64>,
    /// y (m) at `k dt`.
    pub y: Vec<f64>,
    /// Heading (rad) at `k dt`, unwrapped (continuous).
    pub theta: Vec<f64>,
}

impl Drive {
    /// Number of integration steps.
    pub fn steps(&self) -> usize {
        self.v.len()
    }

    /// Body pose `(x, y, θ unwrapped)` at time `t` (s), linear between steps
    /// (clamped to the run).
    pub fn pose_at(&self, t: f64) -> [f64; 3] {
        let (k, a) = step_at(t, self.dt, self.steps());
        let lerp = |v: &[f64]| v[k] + (v[k + 1] - v[k]) * a;
        [lerp(&self.x), lerp(&self.y), lerp(&self.theta)]
    }
}

/// The index of the step that holds time `t` (s) in a run of `steps` steps of
/// `dt` s, and how far into it `t` is (0–1); times outside the run are
/// clamped to it. Poses `k` and `k + 1` bound the step.
pub(crate) fn step_at(t: f64, dt: f64, steps: usize) -> (usize, f64) {
    let f = (t / dt).clamp(0.0, steps as f64);
    let k = (f.floor() as usize).min(steps.saturating_sub(1));
    (k, f - k as f64)
}

/// What commands the chair: a path follower, or a stop-and-turn timetable.
#[derive(Clone)]
enum Controller {
    Smooth(Follower),
    StopAndTurn { sched: Schedule, dt: f64 },
}

impl Controller {
    /// The command of step k given the pose at its start: `(v m/s, w rad/s)`.
    fn command(&mut self, k: usize, p: [f64; 3]) -> (f64, f64) {
        match self {
            Self::Smooth(f) => f.command(k, p),
            Self::StopAndTurn { sched, dt } => {
                let (t0, t1) = (k as f64 * *dt, (k + 1) as f64 * *dt);
                let (d0, a0) = sched.at(t0);
                let (d1, a1) = sched.at(t1);
                ((d1 - d0) / *dt, (a1 - a0) / *dt)
            }
        }
    }
}

/// One integration step: the command over it and the pose at its end.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// Forward speed (m/s) over the step.
    pub v: f64,
    /// Turn rate (rad/s) over the step.
    pub w: f64,
    /// Pose `(x, y, θ unwrapped)` at the end of the step.
    pub end: [f64; 3],
}

/// The drive of a run, integrated step by step on demand, so that a run of
/// any length needs only the controller's state: [`drive`] collects it, and
/// each sensor of a streamed run keeps a `Tape` of it.
#[derive(Clone)]
pub struct Driver {
    ctl: Controller,
    dt: f64,
    steps: usize,
    k: usize,
    p: [f64; 3],
}

impl Driver {
    /// The drive of `scn` for `duration` s in steps of `dt` s.
    pub fn new(scn: &Scenario, sc: &ScenarioConfig, duration: f64, dt: f64) -> Self {
        let steps = (duration / dt).round().max(1.0) as usize;
        let (start, ctl) = match &scn.route {
            Route::Smooth(path) => {
                let start = [path.points[0].x, path.points[0].y, path.heading[0]];
                (
                    start,
                    Controller::Smooth(Follower::new(path.clone(), sc, dt)),
                )
            }
            Route::StopAndTurn { waypoints, closed } => {
                let sched = Schedule::new(waypoints, *closed, sc, duration + 1.0);
                let d = waypoints[1] - waypoints[0];
                let start = [waypoints[0].x, waypoints[0].y, d.y.atan2(d.x)];
                (start, Controller::StopAndTurn { sched, dt })
            }
        };
        Self {
            ctl,
            dt,
            steps,
            k: 0,
            p: start,
        }
    }

    /// Step length (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of steps of the whole run.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The pose at the end of the steps taken so far (the start pose at first).
    pub fn pose(&self) -> [f64; 3] {
        self.p
    }
}

impl Iterator for Driver {
    type Item = Step;

    /// The next step, exact arcs; `None` after the last one.
    fn next(&mut self) -> Option<Step> {
        if self.k >= self.steps {
            return None;
        }
        let (p, dt) = (self.p, self.dt);
        let (v, w) = self.ctl.command(self.k, p);
        let inc = geom::arc_increment(v, w, dt);
        let (s, c) = p[2].sin_cos();
        let (dx, dy) = (inc.translation.x, inc.translation.y);
        self.p = [
            p[0] + c * dx - s * dy,
            p[1] + s * dx + c * dy,
            p[2] + w * dt,
        ];
        self.k += 1;
        Some(Step { v, w, end: self.p })
    }
}

/// Drives the scenario for `duration` s in steps of `dt` s, every step kept.
pub fn drive(scn: &Scenario, sc: &ScenarioConfig, duration: f64, dt: f64) -> Drive {
    let driver = Driver::new(scn, sc, duration, dt);
    let steps = driver.steps();
    let mut d = Drive {
        dt,
        v: Vec::with_capacity(steps),
        w: Vec::with_capacity(steps),
        x: Vec::with_capacity(steps + 1),
        y: Vec::with_capacity(steps + 1),
        theta: Vec::with_capacity(steps + 1),
    };
    let p = driver.pose();
    d.x.push(p[0]);
    d.y.push(p[1]);
    d.theta.push(p[2]);
    for s in driver {
        d.v.push(s.v);
        d.w.push(s.w);
        d.x.push(s.end[0]);
        d.y.push(s.end[1]);
        d.theta.push(s.end[2]);
    }
    d
}

/// Path-following controller: curvature feed-forward with preview plus
/// lateral and heading feedback, then rate and magnitude limits.
#[derive(Clone)]
struct Follower {
    path: Path,
    idx: usize,
    v: f64,
    w: f64,
    dt: f64,
    hold_steps: usize,
    lim: [f64; 4],
}

/// Lateral (1/m²) and heading (1/m) feedback gains: critically damped in distance.
const K_LAT: f64 = 1.5;
const K_HEAD: f64 = 2.45;
/// Curvature preview (s), half the time the turn rate needs to ramp up.
const PREVIEW: f64 = 0.3;

impl Follower {
    fn new(path: Path, sc: &ScenarioConfig, dt: f64) -> Self {
        Self {
            path,
            idx: 0,
            v: 0.0,
            w: 0.0,
            dt,
            hold_steps: (sc.start_hold_s / dt).round() as usize,
            lim: [
                sc.max_speed,
                sc.max_turn_rate,
                sc.max_accel,
                sc.max_angular_accel,
            ],
        }
    }

    fn next(&self, i: usize) -> Option<usize> {
        let n = self.path.points.len();
        if i + 1 < n {
            Some(i + 1)
        } else if self.path.closed {
            Some(0)
        } else {
            None
        }
    }

    fn command(&mut self, k: usize, p: [f64; 3]) -> (f64, f64) {
        if k < self.hold_steps {
            return (0.0, 0.0);
        }
        let path = &self.path;
        let pos = Point2::new(p[0], p[1]);
        // Progress: hill-climb to the nearest sample ahead.
        while let Some(j) = self.next(self.idx) {
            if (path.points[j] - pos).norm() < (path.points[self.idx] - pos).norm() {
                self.idx = j;
            } else {
                break;
            }
        }
        let i = self.idx;
        let h = path.heading[i];
        let e_y = (pos - path.points[i]).dot(&nalgebra::Vector2::new(-h.sin(), h.cos()));
        let e_th = wrap_angle(p[2] - h);
        // Curvature a little ahead, so the turn rate ramps up in time.
        let mut j = i;
        let mut ahead = 0.0;
        while ahead < self.v * PREVIEW {
            match self.next(j) {
                Some(n) => {
                    ahead += (path.points[n] - path.points[j]).norm();
                    j = n;
                }
                None => break,
            }
        }
        let at_end = !path.closed && i + 1 == path.points.len();
        let v_des = if at_end { 0.0 } else { path.speed[i] };
        let w_des = self.v * (path.curvature[j] - K_LAT * e_y - K_HEAD * e_th.sin());
        let [vmax, wmax, a, alpha] = self.lim;
        let dt = self.dt;
        self.v = v_des
            .clamp(self.v - a * dt, self.v + a * dt)
            .clamp(-vmax, vmax);
        self.w = w_des
            .clamp(self.w - alpha * dt, self.w + alpha * dt)
            .clamp(-wmax, wmax);
        (self.v, self.w)
    }
}

/// Open-loop stop-and-turn timetable: cumulative distance driven and angle
/// turned as functions of time, with trapezoidal speed profiles. Its phases
/// are laid out leg by leg as time advances and forgotten once past, so a
/// looping route needs no more than its current leg (times asked must not
/// decrease).
#[derive(Clone)]
struct Schedule {
    /// (start time, duration, distance or angle, is_turn, peak rate, accel).
    phases: VecDeque<(f64, f64, f64, bool, f64, f64)>,
    /// Cumulative (distance, angle) at each phase start.
    base: VecDeque<(f64, f64)>,
    end: (f64, f64, f64),
    /// The route, its number of legs (unbounded when closed), the next leg to lay out.
    wp: Vec<Point2<f64>>,
    closed: bool,
    legs: usize,
    leg: usize,
    /// No leg starts after this time (s).
    until: f64,
    limits: ScenarioConfig,
}

impl Schedule {
    fn new(wp: &[Point2<f64>], closed: bool, sc: &ScenarioConfig, until: f64) -> Self {
        Self {
            phases: VecDeque::new(),
            base: VecDeque::new(),
            end: (sc.start_hold_s, 0.0, 0.0),
            wp: wp.to_vec(),
            closed,
            legs: if closed { usize::MAX } else { wp.len() - 1 },
            leg: 0,
            until,
            limits: sc.clone(),
        }
    }

    /// Lays out the phases of every leg that starts by `t` (s).
    fn lay_out(&mut self, t: f64) {
        let n = self.wp.len();
        let dir = |wp: &[Point2<f64>], i: usize| {
            let d = wp[(i + 1) % n] - wp[i % n];
            d.y.atan2(d.x)
        };
        while self.end.0 <= t && self.end.0 < self.until && self.leg < self.legs {
            let i = self.leg;
            let sc = &self.limits;
            let (drive, turn, pause) = (
                (sc.cruise_speed, sc.max_accel),
                (sc.turn_rate, sc.max_angular_accel),
                sc.corner_pause_s,
            );
            let len = (self.wp[(i + 1) % n] - self.wp[i % n]).norm();
            self.push(len, false, drive.0, drive.1);
            self.end.0 += pause;
            let last = !self.closed && i + 2 == n;
            if !last {
                let angle = wrap_angle(dir(&self.wp, i + 1) - dir(&self.wp, i));
                self.push(angle, true, turn.0, turn.1);
                self.end.0 += pause;
            }
            self.leg += 1;
        }
    }

    fn push(&mut self, amount: f64, turn: bool, peak: f64, acc: f64) {
        let d = amount.abs();
        let vp = peak.min((d * acc).sqrt());
        let dur = if vp > 0.0 { d / vp + vp / acc } else { 0.0 };
        self.phases
            .push_back((self.end.0, dur, amount, turn, vp, acc));
        self.base.push_back((self.end.1, self.end.2));
        self.end.0 += dur;
        if turn {
            self.end.2 += amount;
        } else {
            self.end.1 += amount;
        }
    }

    /// Cumulative (distance m, angle rad) at time `t` (s), not before the
    /// time last asked.
    fn at(&mut self, t: f64) -> (f64, f64) {
        self.lay_out(t);
        while self.phases.len() > 1 && self.phases[1].0 <= t {
            self.phases.pop_front();
            self.base.pop_front();
        }
        let k = self.phases.partition_point(|p| p.0 <= t);
        if k == 0 {
            return (0.0, 0.0);
        }
        let (t0, dur, amount, turn, vp, acc) = self.phases[k - 1];
        let (b_d, b_a) = self.base[k - 1];
        let tau = (t - t0).clamp(0.0, dur);
        let ta = vp / acc;
        // Trapezoid: accelerate for ta, cruise, decelerate for ta.
        let x = if tau < ta {
            0.5 * acc * tau * tau
        } else if tau < dur - ta {
            0.5 * acc * ta * ta + vp * (tau - ta)
        } else {
            let r = dur - tau;
            amount.abs() - 0.5 * acc * r * r
        };
        let x = x * amount.signum();
        if turn {
            (b_d, b_a + x)
        } else {
            (b_d + x, b_a)
        }
    }
}
