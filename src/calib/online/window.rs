//! The sliding window of the stream that the joint model is fitted over:
//! the last `window_s` seconds of intervals and the wheel samples they are
//! read against (widened by the largest time offset accepted), so that its
//! memory does not grow with the stream.

use std::collections::VecDeque;

use crate::calib::batch::{
    self, BatchError, BatchEstimate, BatchParams, Interval, Problem, WheelMotion, WheelTrack, P3,
};
use crate::calib::CheckParams;
use crate::recording::WheelSample;
use crate::robot::DiffDrive;

/// Intervals and wheel samples of the last `window_s` seconds.
#[derive(Debug, Clone)]
pub struct GeometryWindow {
    window_s: f64,
    max_intervals: usize,
    /// Whether the window slides (after the first successful fit).
    sliding: bool,
    /// Wheel samples are kept this much (s) before the oldest interval.
    margin_s: f64,
    /// Each interval with its laser-clock `[t0, t1]`.
    intervals: VecDeque<(Interval, f64, f64)>,
    wheels: VecDeque<WheelSample>,
    /// End of the time the intervals without stamps (Censi's tuples) cover.
    untimed_end: f64,
}

impl GeometryWindow {
    /// A window of `window_s` (s) once sliding, of at most `max_intervals`;
    /// wheel samples up to `max_offset_s` before its oldest interval are kept
    /// for reading it at a time offset.
    pub fn new(window_s: f64, max_intervals: usize, max_offset_s: f64) -> Self {
        Self {
            window_s,
            max_intervals: max_intervals.max(1),
            sliding: false,
            margin_s: max_offset_s.abs() + 1.0,
            intervals: VecDeque::new(),
            wheels: VecDeque::new(),
            untimed_end: 0.0,
        }
    }

    /// A wheel sample (stamp order).
    pub fn push_wheel(&mut self, w: &WheelSample) {
        self.wheels.push_back(*w);
    }

    /// An interval (time order); with [`WheelMotion::Steps`] its time is the
    /// sum of the durations so far. Returns its laser-clock `[t0, t1]`.
    pub fn push(&mut self, iv: Interval) -> (f64, f64) {
        let span = match iv.wheels {
            WheelMotion::Span { t0, t1 } => (t0, t1),
            WheelMotion::Steps(_) => {
                let t0 = self.untimed_end;
                self.untimed_end += iv.duration;
                (t0, self.untimed_end)
            }
        };
        self.intervals.push_back((iv, span.0, span.1));
        self.forget(span.1);
        span
    }

    /// From now on the window slides (keeps the last `window_s` seconds).
    pub fn slide(&mut self) {
        self.sliding = true;
        if let Some(&(_, _, t1)) = self.intervals.back() {
            self.forget(t1);
        }
    }

    /// Forgets every interval that starts before `t` (s, laser clock):
    /// after a change of the robot, one fit over both sides of it would
    /// describe neither, and the time offset would absorb the difference.
    pub fn forget_before(&mut self, t: f64) {
        while self.intervals.front().is_some_and(|&(_, t0, _)| t0 < t) {
            self.intervals.pop_front();
        }
        self.trim_wheels();
    }

    /// Intervals in the window.
    pub fn len(&self) -> usize {
        self.intervals.len()
    }

    /// Whether the window holds no interval.
    pub fn is_empty(&self) -> bool {
        self.intervals.is_empty()
    }

    /// Drops what ended more than `window_s` before `now` (s), and the
    /// wheel samples no kept interval can read.
    fn forget(&mut self, now: f64) {
        let old = |(_, _, t1): &(Interval, f64, f64)| *t1 < now - self.window_s;
        while self.intervals.len() > self.max_intervals
            || (self.sliding && self.intervals.front().is_some_and(old))
        {
            self.intervals.pop_front();
        }
        self.trim_wheels();
    }

    /// Drops the wheel samples no kept interval can read (those more than
    /// the margin before the oldest, two always kept).
    fn trim_wheels(&mut self) {
        let Some(&(_, oldest, _)) = self.intervals.front() else {
            return;
        };
        while self.wheels.len() > 2 && self.wheels[1].stamp < oldest - self.margin_s {
            self.wheels.pop_front();
        }
    }

    /// The window as a batch problem.
    pub fn problem(&self) -> Problem {
        let timed = self
            .intervals
            .iter()
            .any(|(iv, _, _)| matches!(iv.wheels, WheelMotion::Span { .. }));
        let track = (timed && self.wheels.len() >= 2).then(|| WheelTrack {
            t: self.wheels.iter().map(|w| w.stamp).collect(),
            left: self.wheels.iter().map(|w| w.left).collect(),
            right: self.wheels.iter().map(|w| w.right).collect(),
        });
        Problem {
            intervals: self.intervals.iter().map(|(iv, _, _)| iv.clone()).collect(),
            track,
        }
    }

    /// The joint estimate over the window ([`batch::estimate_with_laser`]):
    /// `nominal` sets the scale and the plausibility bounds; the mounting is
    /// held at `laser` when given.
    pub fn solve(
        &self,
        nominal: &DiffDrive,
        params: &BatchParams,
        checks: &CheckParams,
        laser: Option<P3>,
    ) -> Result<BatchEstimate, BatchError> {
        batch::estimate_with_laser(&self.problem(), nominal, params, checks, laser)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(t0: f64) -> Interval {
        Interval {
            s: [0.1, 0.0, 0.0],
            cov: None,
            duration: 1.0,
            wheels: WheelMotion::Span { t0, t1: t0 + 1.0 },
        }
    }

    #[test]
    fn keeps_the_last_window_and_the_wheels_it_reads() {
        let mut w = GeometryWindow::new(10.0, 1000, 1.0);
        w.slide();
        for i in 0..1000 {
            w.push_wheel(&WheelSample {
                stamp: i as f64 * 0.1,
                left: 0.0,
                right: 0.0,
            });
        }
        for i in 0..100 {
            w.push(span(i as f64));
        }
        // Intervals ending within 10 s of the last end (100 s): 89..=99.
        assert_eq!(w.len(), 11);
        // Wheels from 2 s before the oldest interval's start (89 s) on.
        assert!(w.wheels[1].stamp >= 87.0 - 1e-9 && w.wheels[0].stamp < 87.0);
        // Untimed intervals are counted by their durations.
        let mut u = GeometryWindow::new(10.0, 30, 1.0);
        for _ in 0..50 {
            u.push(Interval {
                wheels: WheelMotion::Steps(vec![[0.1, 0.1]]),
                ..span(0.0)
            });
        }
        // Not sliding yet: it grows, up to its cap.
        assert_eq!(u.len(), 30);
        u.slide();
        assert_eq!(u.len(), 11);
    }
}
