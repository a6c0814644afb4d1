//! The calibration steps built sample by sample: wheel angles, gyro rates and
//! velocity observations arrive in stamp order, and each filter step leaves as
//! soon as the samples around it are known. Only the samples still needed are
//! kept, so a recording of any length streams through in flat memory;
//! [`calib::steps`](crate::calib::steps) is the same builder fed whole streams.
//!
//! Steps are on the laser's clock (the observations' and the gyro's); the
//! wheels are read `wheel_offset` s later on their own stamps (wheel stamp
//! minus laser stamp of one instant), as the online time-offset estimate
//! ([`crate::calib::online`]) sets it.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::VecDeque;

use super::steps::{CalibStep, Kind, Measurement, MAX_GAP_STEP};
use crate::motion::VelocityObs;
use crate::recording::{GyroSample, WheelSample};

/// The tail of a time-sorted sample stream, with what is known of its whole.
#[derive(Debug)]
struct Tail<T> {
    items: VecDeque<T>,
    first: Option<f64>,
    count: usize,
    ended: bool,
}

impl<T> Default for Tail<T> {
    fn default() -> Self {
        Self {
            items: VecDeque::new(),
            first: None,
            count: 0,
            ended: false,
        }
    }
}

impl<T> Tail<T> {
    fn push(&mut self, t: f64, item: T) {
        self.first.get_or_insert(t);
        self.count += 1;
        self.items.push_back(item);
    }

    /// Drops the samples before the last one at or before `t`.
    fn forget_before(&mut self, t: f64, stamp: impl Fn(&T) -> f64) {
        let keep = self
            .items
            .partition_point(|s| stamp(s) <= t)
            .saturating_sub(1);
        if keep > 1024 {
            self.items.drain(..keep);
        }
    }

    /// Whether a query at `t` is final: a later sample exists or the stream ended.
    fn covers(&self, t: f64, stamp: impl Fn(&T) -> f64) -> bool {
        self.ended || self.items.back().is_some_and(|s| stamp(s) > t)
    }
}

/// Builds calibration steps incrementally.
#[derive(Debug)]
pub struct StepBuilder {
    wheels: Tail<WheelSample>,
    gyro: Tail<GyroSample>,
    obs: VecDeque<VelocityObs>,
    gyro_sigma: f64,
    covered: Option<f64>,
    finished: bool,
    /// Wheel stamp minus laser stamp of one instant (s).
    offset: f64,
}

impl StepBuilder {
    /// A builder; `use_gyro` false ignores gyro samples; `gyro_sigma` is the
    /// per-sample σ (rad/s).
    pub fn new(use_gyro: bool, gyro_sigma: f64) -> Self {
        Self {
            wheels: Tail::default(),
            gyro: Tail {
                ended: !use_gyro,
                ..Tail::default()
            },
            obs: VecDeque::new(),
            gyro_sigma,
            covered: None,
            finished: false,
            offset: 0.0,
        }
    }

    /// Reads the wheels `offset` s after the laser time of each step from
    /// now on (wheel stamp minus laser stamp of one instant).
    pub fn set_wheel_offset(&mut self, offset: f64) {
        if offset.is_finite() {
            self.offset = offset;
        }
    }

    /// The wheel offset in use (s).
    pub fn wheel_offset(&self) -> f64 {
        self.offset
    }

    /// A wheel sample (stamp order).
    pub fn push_wheel(&mut self, s: WheelSample) {
        self.wheels.push(s.stamp, s);
    }

    /// A gyro sample (stamp order); ignored when the gyro is unused.
    pub fn push_gyro(&mut self, g: GyroSample) {
        if !self.gyro.ended {
            self.gyro.push(g.stamp, g);
        }
    }

    /// A velocity observation (sorted by `t0`).
    pub fn push_obs(&mut self, o: VelocityObs) {
        self.obs.push_back(o);
    }

    /// No more wheel samples.
    pub fn end_wheels(&mut self) {
        self.wheels.ended = true;
    }

    /// No more gyro samples.
    pub fn end_gyro(&mut self) {
        self.gyro.ended = true;
    }

    /// Observations waiting for samples.
    pub fn pending(&self) -> usize {
        self.obs.len()
    }

    /// Hands out every step that is now final. With `all_done` (no more
    /// observations, every stream ended) also the final gap up to the last
    /// wheel sample.
    pub fn poll(&mut self, all_done: bool, out: &mut dyn FnMut(CalibStep)) {
        if self.finished || self.wheels.count == 0 {
            return;
        }
        let off = self.offset;
        let start = self.wheels.first.expect("a wheel sample exists") - off;
        self.covered.get_or_insert(start);
        while let Some(o) = self.obs.front().copied() {
            let finite = [o.t0, o.t1, o.v, o.w].iter().all(|x| x.is_finite());
            if !(finite && o.t1 > o.t0 && o.t0 >= start) {
                self.obs.pop_front();
                continue;
            }
            // `o.t1 <= end` of the whole wheel stream, once known.
            if !self.wheels.covers(o.t1 + off, |s| s.stamp) {
                break;
            }
            if !self.gyro.covers(o.t1, |s| s.stamp) {
                break;
            }
            self.obs.pop_front();
            let last = self.wheels.items.back().map(|s| s.stamp - off);
            if self.wheels.count < 2 || last.is_none_or(|l| o.t1 > l) {
                continue;
            }
            let covered = self.covered.expect("set above");
            if o.t0 > covered {
                self.fill(covered, o.t0, out);
            }
            if let Some(mut s) = self.make(o.t0, o.t1) {
                // An infinite σ_V: the scan did not measure the forward
                // motion (the matcher's odometry prior did), so the step
                // carries no V rather than the odometry fed back to itself.
                if o.sigma_v.is_finite() {
                    s.push(Measurement {
                        kind: Kind::V,
                        value: o.v,
                        sigma: o.sigma_v,
                    });
                }
                s.push(Measurement {
                    kind: Kind::W,
                    value: o.w,
                    sigma: o.sigma_w,
                });
                out(s);
                self.covered = Some(covered.max(o.t1));
            }
            let floor = self
                .covered
                .unwrap_or(o.t0)
                .min(o.t0)
                .min(self.obs.front().map_or(f64::INFINITY, |n| n.t0));
            self.wheels.forget_before(floor + off, |s| s.stamp);
            self.gyro.forget_before(floor, |s| s.stamp);
        }
        if all_done && self.obs.is_empty() && self.wheels.ended && self.gyro.ended {
            self.finished = true;
            if self.wheels.count >= 2 {
                let end = self.wheels.items.back().expect("samples").stamp - off;
                let covered = self.covered.expect("set above");
                self.fill(covered, end, out);
            }
        }
    }

    fn fill(&mut self, from: f64, to: f64, out: &mut dyn FnMut(CalibStep)) {
        if !(to > from) {
            return;
        }
        let pieces = ((to - from) / MAX_GAP_STEP).ceil().max(1.0) as usize;
        for k in 0..pieces {
            let a = from + (to - from) * k as f64 / pieces as f64;
            let b = from + (to - from) * (k + 1) as f64 / pieces as f64;
            if let Some(s) = self.make(a, b) {
                out(s);
            }
        }
    }

    fn make(&self, t0: f64, t1: f64) -> Option<CalibStep> {
        let (r0, l0) = self.angles_at(t0 + self.offset)?;
        let (r1, l1) = self.angles_at(t1 + self.offset)?;
        let dt = t1 - t0;
        let mut s = CalibStep::new(t0, t1, (r1 - r0) / dt, (l1 - l0) / dt);
        if let Some((wz, k)) = self.gyro_mean(t0, t1) {
            s.push(Measurement {
                kind: Kind::W,
                value: wz,
                sigma: self.gyro_sigma / (k.max(1) as f64).sqrt(),
            });
        }
        (s.omega_right.is_finite() && s.omega_left.is_finite()).then_some(s)
    }

    /// Wheel angles at wheel time `t` by linear interpolation between the last sample
    /// at or before `t` and the next (capped one before the stream's last).
    fn angles_at(&self, t: f64) -> Option<(f64, f64)> {
        let w = &self.wheels.items;
        let n = w.len();
        let first = self.wheels.first?;
        if self.wheels.count < 2 || n == 0 || !(t >= first) || !(t <= w[n - 1].stamp) {
            return None;
        }
        if n < 2 {
            return Some((w[0].right, w[0].left));
        }
        let h = w
            .partition_point(|s| s.stamp <= t)
            .saturating_sub(1)
            .min(n - 2);
        let (a, b) = (w[h], w[h + 1]);
        let dt = b.stamp - a.stamp;
        if !(dt > 0.0) {
            return Some((a.right, a.left));
        }
        let s = (t - a.stamp) / dt;
        Some((
            a.right + (b.right - a.right) * s,
            a.left + (b.left - a.left) * s,
        ))
    }

    /// Mean gyro rate over `[t0, t1]` (trapezoid integral of the linearly
    /// interpolated samples) and the number of samples inside; `None` when
    /// the gyro stream does not cover the interval.
    fn gyro_mean(&self, t0: f64, t1: f64) -> Option<(f64, usize)> {
        let g = &self.gyro.items;
        let n = g.len();
        let first = self.gyro.first?;
        if self.gyro.count < 2 || n < 2 || t0 < first || t1 > g[n - 1].stamp || !(t1 > t0) {
            return None;
        }
        let at = |t: f64| {
            let i = g.partition_point(|s| s.stamp <= t).clamp(1, n - 1);
            let (a, b) = (g[i - 1], g[i]);
            let dt = b.stamp - a.stamp;
            if dt > 0.0 {
                a.wz + (b.wz - a.wz) * (t - a.stamp) / dt
            } else {
                b.wz
            }
        };
        let lo = g.partition_point(|s| s.stamp <= t0);
        let hi = g.partition_point(|s| s.stamp < t1);
        let mut integral = 0.0;
        let (mut pt, mut pv) = (t0, at(t0));
        for s in g.range(lo..hi) {
            integral += 0.5 * (pv + s.wz) * (s.stamp - pt);
            pt = s.stamp;
            pv = s.wz;
        }
        integral += 0.5 * (pv + at(t1)) * (t1 - pt);
        let mean = integral / (t1 - t0);
        mean.is_finite().then_some((mean, hi - lo))
    }
}
