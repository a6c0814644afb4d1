//! The extended model: the nominal differential drive plus any set of effects
//! (design.md's table, folded into [`Departures`]), replayed on the measured
//! wheel angles to predict what ICP and the gyro should have seen.

use crate::effects::Departures;
use crate::geom;
use crate::robot::{LaserMount, RobotConfig};

/// SE(2) composition of (x, y, θ) triples (scalar, allocation-free).
fn compose(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    [
        a[0] + c * b[0] - s * b[1],
        a[1] + s * b[0] + c * b[1],
        a[2] + b[2],
    ]
}

/// SE(2) inverse of an (x, y, θ) triple.
fn inverse(a: &[f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    [-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]]
}

/// Odd number of samples spanning about `seconds` at the mean spacing (not
/// the median: a stream logged in bursts, like the Intel log's odometry with
/// a 1 ms median and 0.1 s mean gap, would otherwise be averaged over tens
/// of seconds).
fn smoothing_samples(ts: &[f64], seconds: f64) -> usize {
    if ts.len() < 3 || seconds.is_nan() || seconds <= 0.0 {
        return 1;
    }
    let mean = (ts[ts.len() - 1] - ts[0]) / (ts.len() - 1) as f64;
    let k = (seconds / mean).round().max(1.0) as usize;
    (k | 1).min(ts.len() | 1)
}

/// Centred moving average of K samples of (stamp, angle), then the
/// second-order bias of the average (φ'' · var(stamps in window) / 2) removed
/// with divided second differences at stride K, so smooth motion passes
/// unchanged up to fourth-order terms while quantisation noise is averaged.
#[allow(clippy::type_complexity)]
fn smooth(ts: &[f64], r: &[f64], l: &[f64], k: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = ts.len() - k + 1;
    let mut t = vec![0.0; n];
    let mut a = vec![0.0; n];
    let mut b = vec![0.0; n];
    let mut var = vec![0.0; n];
    for i in 0..n {
        let w = &ts[i..i + k];
        let m = w.iter().sum::<f64>() / k as f64;
        t[i] = m;
        var[i] = w.iter().map(|x| (x - m).powi(2)).sum::<f64>() / k as f64;
        a[i] = r[i..i + k].iter().sum::<f64>() / k as f64;
        b[i] = l[i..i + k].iter().sum::<f64>() / k as f64;
    }
    let second = |v: &[f64], i: usize| -> f64 {
        let c = i.clamp(k, n - 1 - k);
        let (p, q) = (c - k, c + k);
        let d1 = (v[c] - v[p]) / (t[c] - t[p]);
        let d2 = (v[q] - v[c]) / (t[q] - t[c]);
        2.0 * (d2 - d1) / (t[q] - t[p])
    };
    let ca: Vec<f64> = (0..n)
        .map(|i| a[i] - 0.5 * var[i] * second(&a, i))
        .collect();
    let cb: Vec<f64> = (0..n)
        .map(|i| b[i] - 0.5 * var[i] * second(&b, i))
        .collect();
    (t, ca, cb)
}

/// Nominal robot plus wheel angle streams, ready for fast replay.
#[derive(Debug, Clone)]
pub struct Replay {
    r0: [f64; 2],
    base0: f64,
    mount: LaserMount,
    /// Time origin of step/drift (s).
    pub origin: f64,
    ts: Vec<f64>,
    right: Vec<f64>,
    left: Vec<f64>,
    /// One encoder tick period at the run's wheel rate (s; 0 when the
    /// angles are not quantised), [`super::resolution`].
    pub timing_resolution: f64,
}

/// Predicted body velocities over an interval: forward V, lateral L (m/s) and
/// turn rate W (rad/s), as ICP would report them in the base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Predicted {
    /// Forward velocity dx/dt (m/s).
    pub v: f64,
    /// Lateral velocity dy/dt (m/s).
    pub l: f64,
    /// Turn rate dθ/dt (rad/s).
    pub w: f64,
}

impl Replay {
    /// Prepares a replay; wheel samples with non-increasing stamps are dropped.
    /// The (stamp, angle) pairs are averaged over a centred window of about
    /// `smoothing` s, widened to span [`super::resolution::WINDOW_TICKS`]
    /// ticks of a coarse encoder (an odd number of samples; exact for constant rates even
    /// with irregular stamps): encoder quantisation then no longer depends on
    /// where an interval falls between two samples, which would otherwise bias
    /// the latency estimate (shifting by a fraction of a sample averages
    /// neighbouring quantisation errors and lowers the residual for any shift).
    pub fn new(
        robot: &RobotConfig,
        wheels: &[crate::recording::WheelSample],
        origin: f64,
        smoothing: f64,
    ) -> Self {
        let mut ts = Vec::with_capacity(wheels.len());
        let mut right = Vec::with_capacity(wheels.len());
        let mut left = Vec::with_capacity(wheels.len());
        for s in wheels {
            if ts.last().is_some_and(|&l| s.stamp <= l) || !s.stamp.is_finite() {
                continue;
            }
            if !(s.left.is_finite() && s.right.is_finite()) {
                continue;
            }
            ts.push(s.stamp);
            right.push(s.right);
            left.push(s.left);
        }
        let timing_resolution = super::resolution::timing_resolution(wheels);
        let smoothing = super::resolution::smoothing_window(smoothing, timing_resolution);
        let k = smoothing_samples(&ts, smoothing);
        if k > 1 && ts.len() >= 3 * k {
            (ts, right, left) = smooth(&ts, &right, &left, k);
        }
        Self {
            r0: [robot.r_right, robot.r_left],
            base0: robot.wheel_base,
            mount: robot.laser.unwrap_or_default(),
            origin,
            ts,
            right,
            left,
            timing_resolution,
        }
    }

    /// Time span covered by the wheel samples (s).
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((*self.ts.first()?, *self.ts.last()?))
    }

    /// Number of usable wheel samples.
    pub fn len(&self) -> usize {
        self.ts.len()
    }

    /// Whether no wheel sample is usable.
    pub fn is_empty(&self) -> bool {
        self.ts.is_empty()
    }

    /// Measured wheel angles (right, left) at time t, linear between samples,
    /// held at the ends.
    pub fn angles_at(&self, t: f64) -> (f64, f64) {
        let n = self.ts.len();
        if t <= self.ts[0] {
            return (self.right[0], self.left[0]);
        }
        if t >= self.ts[n - 1] {
            return (self.right[n - 1], self.left[n - 1]);
        }
        let i = self.ts.partition_point(|&s| s <= t);
        let (a, b) = (i - 1, i);
        let s = (t - self.ts[a]) / (self.ts[b] - self.ts[a]);
        (
            self.right[a] + s * (self.right[b] - self.right[a]),
            self.left[a] + s * (self.left[b] - self.left[a]),
        )
    }

    /// True body (V, W) over [t0, t1] under the departures, from the measured
    /// wheel angles (latency shifts the encoder stream, encoder gain is
    /// inverted on the mean rate, radii at the interval midpoint).
    pub fn body(&self, x: &Departures, t0: f64, t1: f64) -> (f64, f64) {
        let dt = t1 - t0;
        let (r0, l0) = self.angles_at(x.encoder_stamp(t0));
        let (r1, l1) = self.angles_at(x.encoder_stamp(t1));
        let wr = x.wheel_rate((r1 - r0) / dt);
        let wl = x.wheel_rate((l1 - l0) / dt);
        let [rr, rl] = x.radii_at(self.r0, 0.5 * (t0 + t1) - self.origin);
        let (vr, vl) = (wr * rr, wl * rl);
        let v = 0.5 * (vr + vl);
        let w = x.turn_rate(vr - vl, x.wheel_base(self.base0));
        (v, w)
    }

    /// What ICP (converted to the base frame with the NOMINAL mount) should
    /// report over [t0, t1]: the true arc, seen through the laser offset.
    pub fn icp(&self, x: &Departures, t0: f64, t1: f64) -> Predicted {
        let dt = t1 - t0;
        let (v, w) = self.body(x, t0, t1);
        let arc = geom::arc_increment(v, w, dt);
        let mut m = [arc.translation.x, arc.translation.y, w * dt];
        if !x.laser_nominal() {
            // measured = l0 · (l⁻¹ o l) · l0⁻¹ = E⁻¹ o E with E = l · l0⁻¹.
            let triple = |l: &LaserMount| [l.x, l.y, l.yaw];
            let l0 = triple(&self.mount);
            let l = triple(&x.laser_mount(&self.mount));
            let e = compose(&l, &inverse(&l0));
            m = compose(&compose(&inverse(&e), &m), &e);
        }
        Predicted {
            v: m[0] / dt,
            l: m[1] / dt,
            w: m[2] / dt,
        }
    }

    /// Mean gyro rate the model predicts over [t0, t1] (rad/s), bias included.
    pub fn gyro(&self, x: &Departures, t0: f64, t1: f64) -> f64 {
        x.gyro_rate(self.body(x, t0, t1).1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::WheelSample;

    #[test]
    fn nominal_replay_reproduces_constant_motion() {
        let robot = RobotConfig::default();
        let k = robot.diff_drive();
        let (wr, wl) = k.wheel_rates(0.8, 0.3);
        let wheels: Vec<_> = (0..100)
            .map(|i| {
                let t = i as f64 * 0.02;
                WheelSample {
                    stamp: t,
                    left: wl * t,
                    right: wr * t,
                }
            })
            .collect();
        let r = Replay::new(&robot, &wheels, 0.0, 0.0);
        let p = r.icp(&Departures::default(), 0.5, 0.54);
        let arc = geom::arc_increment(0.8, 0.3, 0.04);
        assert!((p.v - arc.translation.x / 0.04).abs() < 1e-9);
        assert!((p.w - 0.3).abs() < 1e-9);
        // A pure mount offset with no rotation changes nothing on a straight line.
        let x = Departures {
            laser_offset: [0.1, 0.0, 0.0],
            ..Default::default()
        };
        let straight = Replay::new(
            &robot,
            &[
                WheelSample {
                    stamp: 0.0,
                    left: 0.0,
                    right: 0.0,
                },
                WheelSample {
                    stamp: 1.0,
                    left: 1.0,
                    right: 1.0,
                },
            ],
            0.0,
            0.0,
        );
        let q = straight.icp(&x, 0.2, 0.3);
        assert!(q.l.abs() < 1e-12 && (q.v - 0.32).abs() < 1e-12);
    }

    #[test]
    fn scalar_conjugation_matches_the_pose_algebra() {
        let robot = RobotConfig::default();
        let wheels: Vec<_> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.02;
                WheelSample {
                    stamp: t,
                    left: 2.0 * t,
                    right: 2.6 * t,
                }
            })
            .collect();
        let r = Replay::new(&robot, &wheels, 0.0, 0.0);
        let x = Departures {
            laser_offset: [0.05, -0.03, 0.04],
            ..Default::default()
        };
        let (t0, t1) = (0.3, 0.34);
        let (v, w) = r.body(&Departures::default(), t0, t1);
        let o = geom::arc_increment(v, w, t1 - t0);
        let m = robot.laser.unwrap();
        let l0 = geom::pose(m.x, m.y, m.yaw);
        let l = geom::pose(m.x + 0.05, m.y - 0.03, m.yaw + 0.04);
        let want = geom::xyt(&(l0 * (l.inverse() * o * l) * l0.inverse()));
        let p = r.icp(&x, t0, t1);
        let got = [p.v * 0.04, p.l * 0.04, p.w * 0.04];
        for k in 0..3 {
            assert!((want[k] - got[k]).abs() < 1e-12, "{want:?} {got:?}");
        }
    }
}
