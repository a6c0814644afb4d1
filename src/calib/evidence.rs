//! What the steps of a run show before any parameter is believed: how far
//! the robot drove, how much it turned each way and drove straight — the
//! excitation each parameter needs — and whether the wheel rates turn and
//! move the robot the way the scan matching (or the gyro) sees it.
//!
//! The wiring test regresses the measured W on the wheel rates,
//! W ≈ a·ω_R + b·ω_L, and the measured V likewise, V ≈ c·ω_R + d·ω_L. The
//! model W = (R_R ω_R − R_L ω_L)/D, V = (R_R ω_R + R_L ω_L)/2 ([Farina,
//! eq. 3]) wants a > 0 > b and c, d > 0; swapped joints flip a and b, an
//! encoder counting backwards flips its own wheel's pair.

use super::steps::{CalibStep, Kind};
use serde::Serialize;

/// Weighted normal equations of y ≈ p·ω_R + q·ω_L.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Normal2 {
    sxx: [[f64; 2]; 2],
    sxy: [f64; 2],
    syy: f64,
    n: usize,
}

impl Normal2 {
    fn add(&mut self, x: [f64; 2], y: f64, w: f64) {
        for i in 0..2 {
            for j in 0..2 {
                self.sxx[i][j] += w * x[i] * x[j];
            }
            self.sxy[i] += w * x[i] * y;
        }
        self.syy += w * y * y;
        self.n += 1;
    }

    /// The reduced χ² of the least-squares fit: ≈ 1 when the measurements
    /// scatter about a fixed linear law as their σ say; `None` without a fit.
    pub fn reduced_chi2(&self) -> Option<f64> {
        let ([p, q], _) = self.solve()?;
        let chi2 = (self.syy - p * self.sxy[0] - q * self.sxy[1]).max(0.0);
        Some(chi2 / (self.n - 2) as f64)
    }

    /// The least-squares (p, q) and their standard deviations, scaled by the
    /// residual's reduced χ² (so a wrong σ does not fake significance);
    /// `None` when the wheel rates never differ enough to separate them.
    pub fn solve(&self) -> Option<([f64; 2], [f64; 2])> {
        let [[a, b], [_, d]] = self.sxx;
        let det = a * d - b * b;
        if self.n < 4 || !(det > 1e-12 * (a * d).max(f64::MIN_POSITIVE)) {
            return None;
        }
        let inv = [[d / det, -b / det], [-b / det, a / det]];
        let p = [
            inv[0][0] * self.sxy[0] + inv[0][1] * self.sxy[1],
            inv[1][0] * self.sxy[0] + inv[1][1] * self.sxy[1],
        ];
        let chi2 = (self.syy - p[0] * self.sxy[0] - p[1] * self.sxy[1]).max(0.0);
        let scale = (chi2 / (self.n - 2) as f64).max(1.0);
        Some((p, [(inv[0][0] * scale).sqrt(), (inv[1][1] * scale).sqrt()]))
    }
}

/// The excitation and wiring evidence of a run's steps.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Evidence {
    /// Steps with at least one usable measurement.
    pub steps: usize,
    /// Distance driven, Σ|V|·dt over V measurements (m).
    pub distance_m: f64,
    /// Rotation to the left (counter-clockwise), Σ W·dt over significant
    /// positive W (rad).
    pub turn_left_rad: f64,
    /// Rotation to the right, Σ −W·dt over significant negative W (rad).
    pub turn_right_rad: f64,
    /// Distance driven straight: wheel speeds within 10 % of each other (m).
    pub straight_m: f64,
    /// Largest |V| measured (m/s).
    pub speed_max: f64,
    #[serde(skip)]
    w: Normal2,
    #[serde(skip)]
    v: Normal2,
}

/// A W below this many of its σ is not counted as turning.
const SIGNIFICANT_W: f64 = 3.0;
/// Wheel speeds within this fraction of their mean count as straight.
const STRAIGHT: f64 = 0.1;

impl Evidence {
    /// Adds one step.
    pub fn add(&mut self, s: &CalibStep) {
        let dt = s.t1 - s.t0;
        let x = [s.omega_right, s.omega_left];
        if !(dt > 0.0 && x.iter().all(|v| v.is_finite())) {
            return;
        }
        let usable = s
            .measurements()
            .iter()
            .filter(|m| m.value.is_finite() && m.sigma.is_finite() && m.sigma > 0.0);
        let mut any = false;
        for m in usable {
            any = true;
            let w = 1.0 / (m.sigma * m.sigma);
            match m.kind {
                Kind::V => {
                    self.v.add(x, m.value, w);
                    self.distance_m += m.value.abs() * dt;
                    self.speed_max = self.speed_max.max(m.value.abs());
                    let (r, l) = (s.omega_right.abs(), s.omega_left.abs());
                    if s.omega_right * s.omega_left > 0.0
                        && (r - l).abs() < STRAIGHT * 0.5 * (r + l)
                    {
                        self.straight_m += m.value.abs() * dt;
                    }
                }
                Kind::W => {
                    self.w.add(x, m.value, w);
                    if m.value.abs() > SIGNIFICANT_W * m.sigma {
                        if m.value > 0.0 {
                            self.turn_left_rad += m.value * dt;
                        } else {
                            self.turn_right_rad -= m.value * dt;
                        }
                    }
                }
            }
        }
        self.steps += usize::from(any);
    }

    /// Reduced χ² of V and of W against the best fixed linear law of the
    /// wheel rates (see `Normal2::reduced_chi2`).
    pub fn fit_chi2(&self) -> [Option<f64>; 2] {
        [self.v.reduced_chi2(), self.w.reduced_chi2()]
    }

    /// The wiring the rates show (see the module's note).
    pub fn wiring(&self) -> Wiring {
        let sign = |v: f64, s: f64| -> i8 {
            if v.abs() > 5.0 * s {
                v.signum() as i8
            } else {
                0
            }
        };
        let Some(([a, b], [sa, sb])) = self.w.solve() else {
            return Wiring::Inconclusive;
        };
        let (sa, sb) = (sign(a, sa), sign(b, sb));
        let v = self
            .v
            .solve()
            .map(|([c, d], [sc, sd])| (sign(c, sc), sign(d, sd)));
        match (sa, sb, v) {
            (1, -1, _) => Wiring::Consistent,
            (-1, 1, Some((-1, -1))) => Wiring::BothReversed,
            (-1, 1, _) => Wiring::Swapped,
            (1, 1, _) => Wiring::LeftReversed,
            (-1, -1, _) => Wiring::RightReversed,
            _ => Wiring::Inconclusive,
        }
    }
}

/// What the wheel rates show of how the encoders are wired.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Wiring {
    /// The rates turn and move the robot as measured.
    Consistent,
    /// The joint named left carries the right encoder (and vice versa).
    Swapped,
    /// The left encoder counts backwards.
    LeftReversed,
    /// The right encoder counts backwards.
    RightReversed,
    /// Both count backwards (or the laser faces the other way).
    BothReversed,
    /// Too little turning, or too much noise, to tell.
    Inconclusive,
}

impl Wiring {
    /// What is wrong and how to fix it; `None` when nothing is.
    pub fn fault(self) -> Option<&'static str> {
        match self {
            Wiring::Consistent | Wiring::Inconclusive => None,
            Wiring::Swapped => Some(
                "the wheels turn the robot the opposite way to what the scan matching \
                 (or gyro) sees, while both move it forward: the joint named left carries the \
                 right encoder. Swap left_joint and right_joint in the robot file",
            ),
            Wiring::LeftReversed => Some(
                "the left wheel's rate has the wrong sign: the left encoder counts backwards. \
                 Negate it (or fix the joint's axis direction)",
            ),
            Wiring::RightReversed => Some(
                "the right wheel's rate has the wrong sign: the right encoder counts backwards. \
                 Negate it (or fix the joint's axis direction)",
            ),
            Wiring::BothReversed => Some(
                "both wheels' rates have the wrong sign: both encoders count backwards, or the \
                 laser faces the other way from its stated mounting (check [laser] yaw)",
            ),
        }
    }
}
