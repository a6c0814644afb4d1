//! Driving a scenario: the commanded body velocities (v, w) at the
//! integration rate, within the motion limits, and the body trajectory they
//! produce (exact arcs). Smooth routes use a path-following controller fed
//! back the true pose; stop-and-turn routes an open-loop trapezoidal timetable.

use super::config::ScenarioConfig;
use super::path::Path;
use super::scenario::{Route, Scenario};
use crate::geom::{self, wrap_angle};
use nalgebra::Point2;

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
        let f = (t / self.dt).clamp(0.0, self.steps() as f64);
        let k = (f.floor() as usize).min(self.steps().saturating_sub(1));
        let a = f - k as f64;
        let lerp = |v: &[f64]| v[k] + (v[k + 1] - v[k]) * a;
        [lerp(&self.x), lerp(&self.y), lerp(&self.theta)]
    }
}

/// The command of step k given the pose at its start: `(v m/s, w rad/s)`.
type Command<'a> = Box<dyn FnMut(usize, [f64; 3]) -> (f64, f64) + 'a>;

/// Drives the scenario for `duration` s in steps of `dt` s.
pub fn drive(scn: &Scenario, sc: &ScenarioConfig, duration: f64, dt: f64) -> Drive {
    let steps = (duration / dt).round().max(1.0) as usize;
    let (start, mut cmd): ([f64; 3], Command) = match &scn.route {
        Route::Smooth(path) => {
            let mut f = Follower::new(path, sc, dt);
            let start = [path.points[0].x, path.points[0].y, path.heading[0]];
            (start, Box::new(move |k, p| f.command(k, p)))
        }
        Route::StopAndTurn { waypoints, closed } => {
            let sched = Schedule::new(waypoints, *closed, sc, duration + 1.0);
            let d = waypoints[1] - waypoints[0];
            let start = [waypoints[0].x, waypoints[0].y, d.y.atan2(d.x)];
            (
                start,
                Box::new(move |k, _| {
                    let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
                    let (d0, a0) = sched.at(t0);
                    let (d1, a1) = sched.at(t1);
                    ((d1 - d0) / dt, (a1 - a0) / dt)
                }),
            )
        }
    };
    let mut d = Drive {
        dt,
        v: Vec::with_capacity(steps),
        w: Vec::with_capacity(steps),
        x: Vec::with_capacity(steps + 1),
        y: Vec::with_capacity(steps + 1),
        theta: Vec::with_capacity(steps + 1),
    };
    let mut p = start;
    d.x.push(p[0]);
    d.y.push(p[1]);
    d.theta.push(p[2]);
    for k in 0..steps {
        let (v, w) = cmd(k, p);
        let inc = geom::arc_increment(v, w, dt);
        let (s, c) = p[2].sin_cos();
        let (dx, dy) = (inc.translation.x, inc.translation.y);
        p = [
            p[0] + c * dx - s * dy,
            p[1] + s * dx + c * dy,
            p[2] + w * dt,
        ];
        d.v.push(v);
        d.w.push(w);
        d.x.push(p[0]);
        d.y.push(p[1]);
        d.theta.push(p[2]);
    }
    d
}

/// Path-following controller: curvature feed-forward with preview plus
/// lateral and heading feedback, then rate and magnitude limits.
struct Follower<'a> {
    path: &'a Path,
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

impl<'a> Follower<'a> {
    fn new(path: &'a Path, sc: &ScenarioConfig, dt: f64) -> Self {
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
        let path = self.path;
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
/// turned as functions of time, with trapezoidal speed profiles.
struct Schedule {
    /// (start time, duration, distance or angle, is_turn, peak rate, accel).
    phases: Vec<(f64, f64, f64, bool, f64, f64)>,
    /// Cumulative (distance, angle) at each phase start.
    base: Vec<(f64, f64)>,
    end: (f64, f64, f64),
}

impl Schedule {
    fn new(wp: &[Point2<f64>], closed: bool, sc: &ScenarioConfig, until: f64) -> Self {
        let mut s = Self {
            phases: Vec::new(),
            base: Vec::new(),
            end: (sc.start_hold_s, 0.0, 0.0),
        };
        let n = wp.len();
        let dir = |i: usize| {
            let d = wp[(i + 1) % n] - wp[i % n];
            d.y.atan2(d.x)
        };
        let legs = if closed { usize::MAX } else { n - 1 };
        let mut i = 0;
        while s.end.0 < until && i < legs {
            let len = (wp[(i + 1) % n] - wp[i % n]).norm();
            s.push(len, false, sc.cruise_speed, sc.max_accel);
            s.end.0 += sc.corner_pause_s;
            let last = !closed && i + 2 == n;
            if !last {
                let turn = wrap_angle(dir(i + 1) - dir(i));
                s.push(turn, true, sc.turn_rate, sc.max_angular_accel);
                s.end.0 += sc.corner_pause_s;
            }
            i += 1;
        }
        s
    }

    fn push(&mut self, amount: f64, turn: bool, peak: f64, acc: f64) {
        let d = amount.abs();
        let vp = peak.min((d * acc).sqrt());
        let dur = if vp > 0.0 { d / vp + vp / acc } else { 0.0 };
        self.phases.push((self.end.0, dur, amount, turn, vp, acc));
        self.base.push((self.end.1, self.end.2));
        self.end.0 += dur;
        if turn {
            self.end.2 += amount;
        } else {
            self.end.1 += amount;
        }
    }

    /// Cumulative (distance m, angle rad) at time `t` (s).
    fn at(&self, t: f64) -> (f64, f64) {
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
