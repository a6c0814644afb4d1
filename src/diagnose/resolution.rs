//! How finely the wheel encoders time the wheels' motion: one tick's angle
//! over the run's mean wheel rate while moving.
//!
//! A quantised angle stream changes only when a tick is crossed, so the
//! wheels' motion is known in time only to about one tick period. Shifting
//! a coarse stream by a fraction of that period averages neighbouring
//! quantisation errors and lowers the residuals whatever the true timing,
//! so a latency fitted below it is what the encoder cannot tell, not a
//! delay of the robot (measured: the same clean run re-quantised to 512
//! and 256 ticks per revolution reads 2.5 and 4.8 ms late, to 2048 not at
//! all). The tick is read from the data: the smallest step between
//! consecutive angles, kept only when nearly every step is a whole number of
//! it (a lattice); an angle stream that is not on one (floating odometry,
//! interpolated joints) has no such floor.

use crate::recording::WheelSample;

/// Least encoder ticks (at the run's mean wheel rate) the replay's moving
/// average spans: half a tick of quantisation at each end of the window is
/// then at most 1/32 of the motion averaged. With coarse encoders the
/// configured window alone leaves the per-pair speed noisy enough that the
/// fit's regressors carry the noise (measured: 512 ticks per revolution on
/// the figure eight, 0.1 s averaging 21 ticks, read as a 2.2 % slip on a
/// fifth of the floor; 0.15 s or more, nothing).
pub const WINDOW_TICKS: f64 = 32.0;

/// The replay's averaging window (s): the configured `seconds`, or
/// [`WINDOW_TICKS`] tick periods (`timing_resolution`, s) when longer; 0
/// (no averaging, as configured) stays 0.
pub fn smoothing_window(seconds: f64, timing_resolution: f64) -> f64 {
    if seconds > 0.0 {
        seconds.max(WINDOW_TICKS * timing_resolution)
    } else {
        seconds
    }
}

/// Share of moving steps that must lie on the lattice.
const ON_LATTICE: f64 = 0.95;
/// Distance from a whole number of ticks still counted as on it (ticks).
const LATTICE_TOLERANCE: f64 = 0.05;
/// Most ticks the smallest step may span.
const MAX_DIVISOR: usize = 64;
/// Steps smaller than this (rad) are rounding, not motion.
const SMALLEST_STEP: f64 = 1e-7;

/// The moving steps |Δφ| (rad) of both wheels and the time they span (s,
/// counted once per wheel).
fn steps(wheels: &[WheelSample]) -> (Vec<f64>, f64) {
    let (mut step, mut time) = (Vec::new(), 0.0);
    for w in wheels.windows(2) {
        let dt = w[1].stamp - w[0].stamp;
        if !(dt > 0.0 && dt.is_finite()) {
            continue;
        }
        for d in [w[1].right - w[0].right, w[1].left - w[0].left] {
            let d = d.abs();
            if d.is_finite() && d > SMALLEST_STEP {
                step.push(d);
                time += dt;
            }
        }
    }
    (step, time)
}

/// Whether nearly every step is a whole number of `tick`s.
fn on_lattice(step: &[f64], tick: f64) -> bool {
    let on = step
        .iter()
        .filter(|d| {
            let k = *d / tick;
            (k - k.round()).abs() <= LATTICE_TOLERANCE
        })
        .count();
    on as f64 >= ON_LATTICE * step.len() as f64
}

/// The encoder's tick (rad) when the angles lie on a lattice, else `None`:
/// the largest of the smallest step over 1, 2, … `MAX_DIVISOR` that every
/// step is nearly a whole number of (a fast wheel on a fine encoder may
/// never move a single tick between samples).
pub fn tick(wheels: &[WheelSample]) -> Option<f64> {
    let (step, _) = steps(wheels);
    let smallest = step.iter().copied().fold(f64::INFINITY, f64::min);
    if step.len() < 20 || !smallest.is_finite() {
        return None;
    }
    (1..=MAX_DIVISOR)
        .map(|k| smallest / k as f64)
        .find(|&t| on_lattice(&step, t))
}

/// One tick period at the run's mean wheel rate while moving (s), or 0
/// when the angles are on no lattice.
pub fn timing_resolution(wheels: &[WheelSample]) -> f64 {
    let Some(tick) = tick(wheels) else {
        return 0.0;
    };
    let (step, time) = steps(wheels);
    let rate = step.iter().sum::<f64>() / time;
    if rate > 0.0 {
        tick / rate
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 100 Hz samples of both wheels turning at `rate` rad/s (the left at
    /// 0.8 of it), rounded to `ticks` per revolution when given.
    fn stream(rate: f64, ticks: Option<f64>, seconds: f64) -> Vec<WheelSample> {
        let q = |p: f64| match ticks {
            Some(n) => {
                let t = std::f64::consts::TAU / n;
                (p / t).round() * t
            }
            None => p,
        };
        (0..(seconds * 100.0) as usize)
            .map(|i| {
                let t = i as f64 * 0.01;
                WheelSample {
                    stamp: t,
                    right: q(rate * t),
                    left: q(0.8 * rate * t),
                }
            })
            .collect()
    }

    #[test]
    fn a_512_tick_encoder_at_one_and_a_third_rad_per_second_times_to_9_ms() {
        // One tick 2π/512 = 12.27 mrad over the mean of the wheels' 1.5 and
        // 1.2 rad/s: 9.09 ms (the left wheel's 10 ms steps without a tick
        // left out of its moving time, so a little more).
        let w = stream(1.5, Some(512.0), 20.0);
        let tick = tick(&w).unwrap();
        assert!((tick - std::f64::consts::TAU / 512.0).abs() < 1e-12);
        let t = timing_resolution(&w);
        assert!(t > 0.0085 && t < 0.0095, "{t}");
        // 8800 ticks: 0.71 mrad, under half a millisecond, although no
        // step is shorter than 16 ticks.
        let w = stream(1.5, Some(8800.0), 20.0);
        assert!((super::tick(&w).unwrap() - std::f64::consts::TAU / 8800.0).abs() < 1e-12);
        let fine = timing_resolution(&w);
        assert!(fine > 0.0004 && fine < 0.0006, "{fine}");
    }

    #[test]
    fn angles_on_no_lattice_have_no_floor() {
        // Unquantised at constant rates: steps of 15 and 12 mrad, whose
        // ratio 1.25 makes a lattice of 3 mrad after all (a constant-rate
        // stream is one).
        let w = stream(1.5, None, 20.0);
        assert!((super::tick(&w).unwrap() - 0.003).abs() < 1e-9);
        // Unquantised at a varying rate: on no lattice.
        let w: Vec<WheelSample> = (0..2000)
            .map(|i| {
                let t = i as f64 * 0.01;
                let p = 1.5 * t - 0.3 * t.cos();
                WheelSample {
                    stamp: t,
                    right: p,
                    left: 0.8 * p,
                }
            })
            .collect();
        assert_eq!(tick(&w), None);
        assert_eq!(timing_resolution(&w), 0.0);
        // Standing still: no step at all.
        assert_eq!(timing_resolution(&stream(0.0, Some(512.0), 20.0)), 0.0);
    }

    /// `n` samples 10 ms apart, the right wheel one tick of 2π/512 further
    /// at each, the left standing.
    fn ticking(n: usize) -> Vec<WheelSample> {
        let tick = std::f64::consts::TAU / 512.0;
        (0..n)
            .map(|i| WheelSample {
                stamp: i as f64 * 0.01,
                right: i as f64 * tick,
                left: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_lattice_needs_twenty_moving_steps() {
        assert!(tick(&ticking(21)).is_some());
        assert_eq!(tick(&ticking(20)), None);
        assert_eq!(timing_resolution(&ticking(20)), 0.0);
    }

    #[test]
    fn a_step_without_time_between_its_stamps_is_no_motion() {
        // The right wheel moves one tick only between two samples of the
        // same stamp (or one stamped earlier), and stands between the
        // others: no step that took time, so no lattice to read.
        let one = std::f64::consts::TAU / 512.0;
        let mut w = Vec::new();
        for i in 0..40 {
            let t = i as f64 * 0.01;
            let back = if i % 2 == 0 { 0.0 } else { 0.001 };
            w.push(WheelSample {
                stamp: t,
                right: i as f64 * one,
                left: 0.0,
            });
            w.push(WheelSample {
                stamp: t - back,
                right: (i + 1) as f64 * one,
                left: 0.0,
            });
        }
        assert_eq!(tick(&w), None);
    }

    #[test]
    fn coarse_encoders_widen_the_averaging_window() {
        // 8800 ticks at 2.6 rad/s: a tick period of 0.27 ms, 32 of them 8.8
        // ms, under the configured 0.1 s.
        let fine = std::f64::consts::TAU / 8800.0 / 2.6;
        assert_eq!(smoothing_window(0.1, fine), 0.1);
        // 512 ticks: 4.7 ms, 32 of them 0.151 s.
        let coarse = std::f64::consts::TAU / 512.0 / 2.6;
        assert!((smoothing_window(0.1, coarse) - 32.0 * coarse).abs() < 1e-15);
        assert!((smoothing_window(0.1, coarse) - 0.151).abs() < 1e-3);
        // Angles on no lattice (0): the configured window; averaging
        // switched off stays off.
        assert_eq!(smoothing_window(0.1, 0.0), 0.1);
        assert_eq!(smoothing_window(0.0, coarse), 0.0);
    }
}
