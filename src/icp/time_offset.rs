//! A check of the prior's clock: how well the odometry's heading increments
//! fit the matched ones when the odometry is read at offsets around the one
//! in use.
//!
//! The prior of a pair of scans stamped `t0`, `t1` is the odometry's motion
//! over `[t0 + δ, t1 + δ]`, δ = odometry stamp minus laser stamp of one
//! instant (`IcpParams::time_offset`, 0 unless set). Drivers and loggers
//! often stamp a scan when it arrives, a sweep and a transfer after the
//! instant it shows; then δ is negative and a prior read at δ = 0 lags the
//! turns. The heading increment of a pair is what the scans measure best,
//! and what a shift of the odometry in time changes most where the robot
//! turns: over the matched pairs, the RMS difference between the two as a
//! function of the offset has its minimum at the clocks' actual offset.
//! The check reports that minimum beside the offset used; it never changes
//! the matching.

use serde::Serialize;

/// Spacing of the offsets tried (s); a parabola through the best and its
/// neighbours refines the best between them.
pub const OFFSET_STEP_S: f64 = 0.04;
/// Number of offsets tried, centred on the one used.
const OFFSETS: usize = 25;
/// Offsets are tried up to this far on either side of the one used (s).
pub const OFFSET_SPAN_S: f64 = (OFFSETS / 2) as f64 * OFFSET_STEP_S;
/// A best offset at least this far (s) from the one used, and fitting 10 %
/// better, contradicts it.
const CONTRADICTION_S: f64 = 0.04;
/// Fewest matched pairs for a result.
const MIN_PAIRS: usize = 50;

/// The offsets (s) tried around `used`, increasing: `used + (k − 12) ·
/// OFFSET_STEP_S` for k = 0 ..= 24.
pub fn offsets(used: f64) -> impl Iterator<Item = f64> + Clone {
    let half = (OFFSETS / 2) as f64;
    (0..OFFSETS).map(move |k| used + (k as f64 - half) * OFFSET_STEP_S)
}

/// Sums of squared heading-increment differences per offset tried.
#[derive(Debug, Clone)]
pub struct OffsetCheck {
    used: f64,
    sums: [f64; OFFSETS],
    pairs: usize,
}

impl OffsetCheck {
    /// An empty check around the offset `used` (s).
    pub fn new(used: f64) -> Self {
        Self {
            used,
            sums: [0.0; OFFSETS],
            pairs: 0,
        }
    }

    /// Adds one matched pair: `prior` holds the odometry's heading increment
    /// (rad) over the pair read at each of [`offsets`] in turn, `matched` the
    /// matched one (rad). A pair without all of them, or with one that is
    /// not finite or half a turn off, is not added.
    pub fn add(&mut self, prior: &[f64], matched: f64) {
        let near = |p: &f64| (p - matched).abs() < std::f64::consts::PI;
        if prior.len() != OFFSETS || !prior.iter().all(near) {
            return;
        }
        // Increments of one pair: well within ±π of each other, no wrap.
        for (s, p) in self.sums.iter_mut().zip(prior) {
            let d = p - matched;
            *s += d * d;
        }
        self.pairs += 1;
    }

    /// The offset with the smallest RMS difference (refined by a parabola
    /// through it and its neighbours), beside the RMS at the offset used;
    /// `None` below [`MIN_PAIRS`] pairs.
    pub fn result(&self) -> Option<TimeOffsetFit> {
        if self.pairs < MIN_PAIRS {
            return None;
        }
        let n = self.pairs as f64;
        let (k, &best) = self
            .sums
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))?;
        let at = |k: usize| offsets(self.used).nth(k).unwrap_or(self.used);
        let (mut best_s, mut best_sum) = (at(k), best);
        let at_edge = k == 0 || k + 1 == OFFSETS;
        if !at_edge {
            // Vertex of the parabola through the three sums around k: where
            // the sum is smallest, and its value there.
            let (a, b, c) = (self.sums[k - 1], best, self.sums[k + 1]);
            let den = a - 2.0 * b + c;
            if den > 0.0 {
                best_s += 0.5 * OFFSET_STEP_S * (a - c) / den;
                best_sum = (b - (a - c).powi(2) / (8.0 * den)).max(0.0);
            }
        }
        Some(TimeOffsetFit {
            used_s: self.used,
            best_s,
            at_edge,
            rms_used_rad: (self.sums[OFFSETS / 2] / n).sqrt(),
            rms_best_rad: (best_sum / n).sqrt(),
            pairs: self.pairs,
        })
    }
}

/// What the check found (JSON `prior_time_offset` of `odocal icp`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimeOffsetFit {
    /// Offset in use (s): odometry stamp minus laser stamp of one instant.
    pub used_s: f64,
    /// Offset (s) at which the odometry's heading increments fit the matched
    /// ones best.
    pub best_s: f64,
    /// Whether that is the edge of the offsets tried (±`OFFSET_SPAN_S`
    /// around the one used): the actual offset may lie beyond.
    pub at_edge: bool,
    /// RMS difference of the heading increments (rad per pair) at the offset
    /// used.
    pub rms_used_rad: f64,
    /// The same at the best offset (the parabola's value there).
    pub rms_best_rad: f64,
    /// Matched pairs counted.
    pub pairs: usize,
}

impl TimeOffsetFit {
    /// Whether the data contradict the offset in use: the best lies at least
    /// `CONTRADICTION_S` away and fits at least 10 % better.
    pub fn contradicts_used(&self) -> bool {
        (self.best_s - self.used_s).abs() >= CONTRADICTION_S
            && self.rms_best_rad <= 0.9 * self.rms_used_rad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A robot turning at `ω(t) = 0.8 sin(0.7 t) + 0.3 sin(2.3 t)` rad/s,
    /// its heading in closed form; odometry stamped `delta` s off the
    /// scans' clock: the check finds `delta` from 10 Hz pairs.
    #[test]
    fn finds_the_offset_of_a_shifted_heading() {
        let heading = |t: f64| -0.8 / 0.7 * (0.7 * t).cos() - 0.3 / 2.3 * (2.3 * t).cos();
        for delta in [-0.14, 0.0, 0.07, 0.31] {
            // The odometry's clock reads t + delta at the instant t.
            let odom_heading = |stamp: f64| heading(stamp - delta);
            let mut check = OffsetCheck::new(0.0);
            for i in 0..600 {
                let (t0, t1) = (0.1 * i as f64, 0.1 * (i + 1) as f64);
                let matched = heading(t1) - heading(t0);
                let prior: Vec<f64> = offsets(0.0)
                    .map(|d| odom_heading(t1 + d) - odom_heading(t0 + d))
                    .collect();
                check.add(&prior, matched);
            }
            let fit = check.result().unwrap();
            assert!((fit.best_s - delta).abs() < 0.005, "{delta}: {fit:?}");
            assert!(fit.rms_best_rad < 1e-3, "{fit:?}");
            assert_eq!(fit.contradicts_used(), delta.abs() >= 0.04, "{fit:?}");
        }
    }

    #[test]
    fn too_few_pairs_or_incomplete_ones_give_nothing() {
        let mut check = OffsetCheck::new(0.0);
        for _ in 0..MIN_PAIRS - 1 {
            check.add(&[0.0; OFFSETS], 0.0);
        }
        check.add(&[0.0; 3], 0.0);
        check.add(&[f64::NAN; OFFSETS], 0.0);
        assert!(check.result().is_none());
        check.add(&[0.0; OFFSETS], 0.0);
        assert_eq!(check.result().unwrap().pairs, MIN_PAIRS);
    }
}
