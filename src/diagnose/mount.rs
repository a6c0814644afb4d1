//! Whether the laser moved on the robot during a run (a knock), from the
//! scan matching alone. A differential drive does not slide sideways: at
//! the base origin its motion between two scans is an arc, whose chord
//! leans by half the heading change, so the lateral displacement left over,
//! ℓ = dy − dx tan(dθ/2), is zero when the laser sits where the mounting
//! says. A laser turned by δ on its bracket leans every forward step by δ:
//! ℓ ≈ a dx with a ≈ −δ. The filters' change detector never sees this (it
//! tests the forward speed and the turn rate against the radii and the
//! wheel base), so the watch tests the lean a itself: the run is cut into
//! blocks of `block_s`; each block's least-squares a is compared with that
//! of every earlier block since the last firing (the reference) by the Wald
//! statistic T = (a_block − a_ref)² / (s² (1/Σ_block dx² + 1/Σ_ref dx²)), s²
//! the pooled residual variance, χ² with one degree of freedom without a
//! change, and must also move by more than `min_turn_rad` (scan matching
//! leans by a few 10⁻³ rad from one stretch of wall to the next, which the
//! white-noise statistic does not know). A block beyond both is held as a
//! suspect; the next block beyond both too confirms the firing, dated at
//! the suspect block's end (one block's excursion is added back to the
//! reference). A mounting that was off from the start does not fire: only a
//! change does. The lean in turns (a laser moved forward or sideways) is
//! not watched: on straight stretches the matcher's heading noise, at the
//! lever arm of the walls, leans the motions far more.

use crate::motion::Motion;

/// Settings of the laser-mounting watch (defined with the change vocabulary).
pub use crate::effects::change::MountParams;

/// Sums of the least-squares lean ℓ = a dx over some rows.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Lean {
    xx: f64,
    xy: f64,
    yy: f64,
    n: usize,
    span_s: f64,
}

impl Lean {
    fn add(&mut self, x: f64, y: f64) {
        self.xx += x * x;
        self.xy += x * y;
        self.yy += y * y;
        self.n += 1;
    }

    fn merge(&mut self, o: &Self) {
        self.xx += o.xx;
        self.xy += o.xy;
        self.yy += o.yy;
        self.n += o.n;
        self.span_s += o.span_s;
    }

    /// The lean a (rad), 1 / Σ dx² and the residual sum of squares; `None`
    /// when the robot did not drive.
    fn solve(&self) -> Option<(f64, f64, f64)> {
        (self.xx > 0.0).then(|| {
            let a = self.xy / self.xx;
            (a, 1.0 / self.xx, (self.yy - a * self.xy).max(0.0))
        })
    }
}

/// The change of lean from `reference` to `block` (rad) and its Wald
/// statistic.
fn statistic(block: &Lean, reference: &Lean) -> Option<(f64, f64)> {
    let (ab, cb, rb) = block.solve()?;
    let (ar, cr, rr) = reference.solve()?;
    let dof = (block.n + reference.n).checked_sub(2).filter(|d| *d > 0)?;
    let s2 = (rb + rr) / dof as f64;
    let d = ab - ar;
    let var = s2 * (cb + cr);
    (var > 0.0).then(|| (d, d * d / var))
}

/// The watch over one run's scan-matching motions, in time order.
#[derive(Debug, Clone)]
pub struct MountWatch {
    p: MountParams,
    reference: Lean,
    block: Lean,
    block_start: Option<f64>,
    /// A block beyond the threshold awaiting the next: its end (s) and rows.
    suspect: Option<(f64, Lean)>,
}

impl MountWatch {
    /// A watch by `p`.
    pub fn new(p: &MountParams) -> Self {
        Self {
            p: p.clone(),
            reference: Lean::default(),
            block: Lean::default(),
            block_start: None,
            suspect: None,
        }
    }

    /// How far back (s) a firing can be dated when it is confirmed.
    pub fn lag_s(&self) -> f64 {
        2.0 * self.p.block_s
    }

    /// The earliest time (s) a firing confirmed later can be dated at: the
    /// held suspect block's end, else the current block's start (a block
    /// that turns suspect ends after it); `None` before the first motion.
    pub fn earliest_next_s(&self) -> Option<f64> {
        self.suspect.map(|s| s.0).or(self.block_start)
    }

    /// Takes a motion; returns the time (s) of a confirmed firing.
    pub fn motion(&mut self, m: &Motion) -> Option<f64> {
        let start = *self.block_start.get_or_insert(m.t1);
        let mut fired = None;
        if m.t1 >= start + self.p.block_s {
            self.block.span_s = m.t1 - start;
            fired = self.close(m.t1);
            self.block = Lean::default();
            self.block_start = Some(m.t1);
        }
        if m.is_valid() {
            let ([dx, dy, dth], _) = m.scan_measured();
            let lean = dy - dx * (0.5 * dth).tan();
            if dx.is_finite() && lean.is_finite() {
                self.block.add(dx, lean);
            }
        }
        fired
    }

    /// Tests the block ending at `end` (s) against the reference.
    fn close(&mut self, end: f64) -> Option<f64> {
        let tested =
            self.reference.span_s >= self.p.min_reference_s && self.block.n >= self.p.min_rows;
        let beyond = tested
            && statistic(&self.block, &self.reference).is_some_and(|(d, t)| {
                super::stats::chi2_sf(t, 1) < self.p.false_alarm && d.abs() > self.p.min_turn_rad
            });
        match (beyond, self.suspect.take()) {
            (true, Some((t, s))) => {
                // The mounting moved: the reference starts again after it.
                self.reference = s;
                self.reference.merge(&self.block);
                return Some(t);
            }
            (true, None) => self.suspect = Some((end, self.block)),
            (false, Some((_, s))) => {
                self.reference.merge(&s);
                self.reference.merge(&self.block);
            }
            (false, None) => self.reference.merge(&self.block),
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    /// Straight and turning steps at 20 Hz with a laser turned by `yaw(t)`
    /// (rad): the lateral lean of each step, with a small deterministic
    /// noise.
    fn motions(yaw: impl Fn(f64) -> f64, seconds: f64) -> Vec<Motion> {
        let dt = 0.05;
        (0..(seconds / dt) as usize)
            .map(|k| {
                let t0 = k as f64 * dt;
                let (v, w) = (0.8, 0.6 * (0.3 * t0).sin());
                let (dx, dth) = (v * dt, w * dt);
                let noise = 2e-4 * ((k * 7919 % 101) as f64 / 50.0 - 1.0);
                Motion {
                    t0,
                    t1: t0 + dt,
                    dx,
                    dy: dx * (0.5 * dth).tan() + dx * yaw(t0) + noise,
                    dtheta: dth,
                    cov: Matrix3::identity() * 1e-6,
                    iterations: 5,
                    inliers: 300,
                    failure: None,
                    split: None,
                }
            })
            .collect()
    }

    fn firings(ms: &[Motion]) -> Vec<f64> {
        let mut w = MountWatch::new(&MountParams::default());
        ms.iter().filter_map(|m| w.motion(m)).collect()
    }

    #[test]
    fn a_turned_laser_fires_once_after_the_knock_and_a_constant_one_never() {
        let knocked = firings(&motions(|t| if t >= 30.0 { 0.035 } else { 0.0 }, 60.0));
        assert_eq!(knocked.len(), 1, "{knocked:?}");
        assert!((30.0..=40.0).contains(&knocked[0]), "{knocked:?}");
        assert!(firings(&motions(|_| 0.035, 60.0)).is_empty());
        assert!(firings(&motions(|_| 0.0, 60.0)).is_empty());
        // Half a degree, below the floor, does not fire.
        assert!(firings(&motions(|t| if t >= 30.0 { 0.008 } else { 0.0 }, 60.0)).is_empty());
    }

    /// What a caller holding rows for the watch relies on: no firing is
    /// dated before the earliest time announced beforehand, and that time
    /// trails the motions by at most two blocks (knocks every 40 s).
    #[test]
    fn no_firing_is_dated_before_the_time_announced() {
        let ms = motions(|t| 0.035 * ((t / 40.0).floor() % 2.0), 600.0);
        let mut w = MountWatch::new(&MountParams::default());
        assert_eq!(w.earliest_next_s(), None);
        let mut fired = 0;
        for m in &ms {
            let before = w.earliest_next_s().unwrap_or(f64::NEG_INFINITY);
            if let Some(t) = w.motion(m) {
                assert!(t >= before, "fired at {t} s, announced {before} s");
                fired += 1;
            }
            let next = w.earliest_next_s().unwrap();
            assert!(
                next >= m.t1 - w.lag_s() && next <= m.t1,
                "{next} at {} s",
                m.t1
            );
        }
        assert!(fired >= 10, "{fired} firings");
    }
}
