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

    #[test]
    fn forgets_before_a_change_and_reads_the_wheels_it_keeps() {
        // Offsets up to 0.5 s: wheels kept from 1.5 s before the oldest
        // interval (the sample before that bound too, for interpolation).
        let mut w = GeometryWindow::new(100.0, 1000, -0.5);
        for i in 0..200 {
            let t = i as f64 * 0.1;
            w.push_wheel(&WheelSample {
                stamp: t,
                left: t,
                right: 2.0 * t,
            });
        }
        // Untimed intervals are laid end to end by their durations.
        let mut u = GeometryWindow::new(100.0, 1000, 0.0);
        let tuple = |d: f64| Interval {
            wheels: WheelMotion::Steps(vec![[0.1, 0.1]]),
            duration: d,
            ..span(0.0)
        };
        assert_eq!(u.push(tuple(0.5)), (0.0, 0.5));
        assert_eq!(u.push(tuple(0.25)), (0.5, 0.75));
        // Tuples carry their wheels: no track, whatever wheels there are.
        u.push_wheel(&WheelSample {
            stamp: 0.0,
            left: 0.0,
            right: 0.0,
        });
        u.push_wheel(&WheelSample {
            stamp: 1.0,
            left: 0.0,
            right: 0.0,
        });
        assert!(u.problem().track.is_none());
        for k in 0..10 {
            assert_eq!(w.push(span(k as f64)), (k as f64, k as f64 + 1.0));
        }
        // Not sliding: nothing is forgotten for age, and every wheel sample
        // from the start is kept.
        assert_eq!(w.len(), 10);
        assert_eq!(w.wheels.len(), 200);
        // A change at 4.5 s: the intervals starting before it go (0..=4),
        // the one starting at 5 s stays; wheels before 5 − 1.5 s go but
        // the last sample before that bound.
        assert!(!w.is_empty());
        w.forget_before(4.5);
        assert_eq!(w.len(), 5);
        // A change at an interval's very start keeps that interval.
        w.forget_before(5.0);
        assert_eq!(w.len(), 5);
        assert_eq!(w.intervals[0].1, 5.0);
        assert!(
            (w.wheels[0].stamp - 3.4).abs() < 1e-9,
            "{}",
            w.wheels[0].stamp
        );
        let p = w.problem();
        assert_eq!(p.intervals.len(), 5);
        let track = p.track.unwrap();
        assert_eq!(track.t.len(), w.wheels.len());
        assert!((track.right[3] - 2.0 * track.t[3]).abs() < 1e-12);
        assert!((track.left[3] - track.t[3]).abs() < 1e-12);
        // A change after every interval's start leaves none, and the wheels
        // as they were; an empty window reads nothing.
        w.forget_before(100.0);
        assert!(w.is_empty());
        assert_eq!(w.problem().intervals.len(), 0);
        // Two wheel samples are always kept, however old.
        let mut old = GeometryWindow::new(10.0, 10, 0.0);
        for i in 0..3 {
            old.push_wheel(&WheelSample {
                stamp: 0.1 * i as f64,
                left: 0.0,
                right: 0.0,
            });
        }
        old.push(span(100.0));
        assert_eq!(old.wheels.len(), 2);
        // One wheel sample is no track.
        let mut one = GeometryWindow::new(10.0, 10, 0.0);
        one.push_wheel(&WheelSample {
            stamp: 0.0,
            left: 0.0,
            right: 0.0,
        });
        one.push(span(0.0));
        assert!(one.problem().track.is_none());
        // Over the cap, the oldest go first even before sliding.
        let mut cap = GeometryWindow::new(1000.0, 12, 0.0);
        for k in 0..20 {
            cap.push(span(k as f64));
        }
        assert_eq!((cap.len(), cap.intervals[0].1), (12, 8.0));
    }
}
