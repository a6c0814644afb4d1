//! Tyres whose rolling radius follows their load: a fault outside the
//! effect table, told apart from the encoder gain it resembles.
//!
//! In a turn the lateral acceleration a = v ω moves load onto the outer
//! wheel (the centre of mass above the ground pushes it over), and a tyre
//! rolls on a radius shorter by its deflection: each radius changes by
//! ∓κ a relative to its own, r_R (1 − κ v ω) and r_L (1 + κ v ω) with a
//! linear tyre, κ = m h / (D k r) for mass m, centre of mass h above the
//! ground, wheel base D, tyre stiffness k and radius r. The wheels then
//! over-read the forward speed by κ v ω² D / 2 and the turn rate by
//! 2 κ v² / D of itself. At one speed that is what an encoder over-reading
//! with its own rate (`encoder_gain`, ω (1 + k |ω|)) does with the radii a
//! little larger (k = 2 κ v r / D): only the run's changes of speed, and
//! the forward speed in turns against that on the straights, tell them apart.
//!
//! The test, run when the selection named an encoder gain: from the
//! selected model with its gain taken out, the radii, the wheel base and
//! either the encoder gain or the load law are fitted again linearly to the
//! forward-speed and turn-rate streams (the same number of parameters each;
//! the regressors are the exact first-order change of the replayed motion,
//! the rows weighted by their σ times each stream's profiled σ scale). The
//! two non-nested fits are compared by Vuong's statistic \[Vuong1989\]
//! with a Newey–West variance (scan-matching errors are serially
//! correlated): a load law significant, of a size a tyre can have and not
//! rejected against the gain is the diagnosis's reading, either
//! [`Reading::Load`] (the gain rejected) or [`Reading::Either`] (the run's
//! speeds cannot tell them apart, said so).
//!
//! When the selection named radii and no gain, the same comparison is made
//! with the radii alone fitted again beside each law ([`Nuisance::Radii`]:
//! at one speed the load's turn over-read is a wheel base, and the
//! selection named none), on the rows with the scan matcher's own
//! forward-speed and turn-rate errors taken out: along a corridor ICP reads
//! the forward speed short by about what the load's turn over-read makes
//! the radii short, and read as it comes the two agree on the wrong radii.

use super::data::{GyroRow, IcpRow, Part};
use super::stats::chi2_sf;
use crate::effects::Departures;
use crate::robot::RobotConfig;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Settings of the load-transfer test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadSettings {
    /// Whether the test runs.
    pub enabled: bool,
    /// Vuong's z beyond which one law is preferred to the other (2.58: two
    /// sided 1 %).
    pub vuong_z: f64,
    /// Level of κ's Newey–West test (κ = 0 rejected below it).
    pub alpha: f64,
    /// Largest κ a tyre can have (s²/m): 0.05 is a radius 5 % shorter per
    /// m/s² of lateral acceleration, ten times a 100 kg chair on 50 kN/m
    /// tyres with its centre of mass 0.5 m up; beyond it the law is
    /// fitting something else.
    pub max_kappa: f64,
    /// Span of serial correlation allowed for in the Newey–West test (s).
    pub lag_seconds: f64,
}

impl Default for LoadSettings {
    fn default() -> Self {
        Self {
            enabled: true,
            vuong_z: 2.58,
            alpha: 1e-6,
            max_kappa: 0.05,
            lag_seconds: 3.0,
        }
    }
}

/// The load law's size as fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kappa {
    /// Relative radius change per m/s² of lateral acceleration (s²/m):
    /// the outer wheel's radius shrinks and the inner one's grows by κ v ω.
    pub kappa: f64,
    /// Its Newey–West standard error (s²/m).
    pub stderr: f64,
    /// p-value of κ = 0.
    pub p_value: f64,
}

impl Kappa {
    /// Whether it is a tyre's: positive, at most `max_kappa`, significant
    /// (and the test enabled).
    pub fn is_tyre(&self, s: &LoadSettings) -> bool {
        s.enabled && self.kappa > 0.0 && self.kappa <= s.max_kappa && self.p_value < s.alpha
    }
}

/// What the comparison with the encoder gain found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadFit {
    /// The load law's fit.
    pub load: Kappa,
    /// The encoder gain fitted in its place (s/rad), for the comparison.
    pub gain: f64,
    /// The right and left radius scales that fit adds to the model's
    /// (relative).
    pub gain_radii: [f64; 2],
    /// Vuong's z of the load law against the gain (positive: the load law
    /// fits better).
    pub vuong_z: f64,
}

/// What the test makes of the speed-dependent over-reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// The encoder gain stands (the load law not significant, not a tyre's,
    /// or rejected against it).
    Gain,
    /// The load law, the gain rejected against it.
    Load,
    /// Either: the run's speeds cannot tell them apart.
    Either,
}

impl LoadFit {
    /// The reading at settings `s`.
    pub fn reading(&self, s: &LoadSettings) -> Reading {
        if !self.load.is_tyre(s) || self.vuong_z < -s.vuong_z {
            Reading::Gain
        } else if self.vuong_z > s.vuong_z {
            Reading::Load
        } else {
            Reading::Either
        }
    }
}

impl LoadSettings {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [
            ("vuong_z", self.vuong_z),
            ("max_kappa", self.max_kappa),
            ("lag_seconds", self.lag_seconds),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("load.{k} must be positive, got {v}"));
            }
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(format!("load.alpha must be in (0, 1), got {}", self.alpha));
        }
        Ok(())
    }
}

/// Columns of the linear fits: right and left radius scale, wheel-base
/// scale, encoder gain, load law.
const COLUMNS: usize = 5;
/// Index of the encoder gain's column.
const GAIN: usize = 3;
/// Index of the load law's column.
const LOAD: usize = 4;

/// One stream's first-order change of the motion per unit of each column's
/// parameter: `[v, w]` each with [`COLUMNS`] entries.
type Derivatives = [[f64; COLUMNS]; 2];

/// The first-order change of forward speed V and turn rate W (measured −
/// nominal replay) per unit of each parameter over [t0, t1], from the
/// nominal robot's wheel rates φ̇ (rad/s), radii r and wheel base D:
/// a radius scale s adds s r φ̇ / 2 to V and ± s r φ̇ / D to W; a wheel-base
/// scale −W to W; the encoder gain's true rate φ̇ (1 − k |φ̇|) takes
/// k r φ̇ |φ̇| from each wheel's rim speed; the load law's radii take
/// κ v ω r φ̇ from the right rim speed and give it to the left.
fn derivatives(all: &Part, x: &Departures, robot: &RobotConfig, t0: f64, t1: f64) -> Derivatives {
    let dt = t1 - t0;
    let (a0, b0) = all.replay.angles_at(x.encoder_stamp(t0));
    let (a1, b1) = all.replay.angles_at(x.encoder_stamp(t1));
    let (pr, pl) = ((a1 - a0) / dt, (b1 - b0) / dt);
    let (rr, rl, d) = (robot.r_right, robot.r_left, robot.wheel_base);
    let (sr, sl) = (rr * pr, rl * pl);
    let (v, w) = (0.5 * (sr + sl), (sr - sl) / d);
    let (gr, gl) = (-sr * pr.abs(), -sl * pl.abs());
    let (lr, ll) = (-v * w * sr, v * w * sl);
    [
        [0.5 * sr, 0.5 * sl, 0.0, 0.5 * (gr + gl), 0.5 * (lr + ll)],
        [sr / d, -sl / d, -w, (gr - gl) / d, (lr - ll) / d],
    ]
}

/// Every row of `all` (ICP forward and turn rate, gyro) as a residual under
/// `x` and its derivatives, both divided by the row's σ times its stream's
/// σ `scale`; with the row's time, in time order per stream.
fn stacked(
    all: &Part,
    x: &Departures,
    robot: &RobotConfig,
    scale: &[f64; 4],
) -> (Vec<f64>, Vec<[f64; COLUMNS]>, Vec<f64>) {
    let e = all.physical(x);
    let (mut y, mut cols, mut t) = (Vec::new(), Vec::new(), Vec::new());
    let mut push = |e: f64, s: f64, d: &[f64; COLUMNS], tm: f64| {
        if e.is_finite() && s.is_finite() && s > 0.0 && d.iter().all(|v| v.is_finite()) {
            y.push(e / s);
            cols.push(d.map(|v| v / s));
            t.push(tm);
        }
    };
    for (i, r) in all.icp.iter().enumerate() {
        let d = derivatives(all, x, robot, r.t0, r.t1);
        let tm = 0.5 * (r.t0 + r.t1);
        push(e[0][i], r.sigma[0] * scale[0], &d[0], tm);
        push(e[2][i], r.sigma[2] * scale[2], &d[1], tm);
    }
    for (i, r) in all.gyro.iter().enumerate() {
        let d = derivatives(all, x, robot, r.t0, r.t1);
        push(e[3][i], r.sigma * scale[3], &d[1], 0.5 * (r.t0 + r.t1));
    }
    (y, cols, t)
}

/// Least squares of `y` on the columns `which` of `cols`: coefficients and
/// residuals; `None` when singular.
fn lsq(y: &[f64], cols: &[[f64; COLUMNS]], which: &[usize]) -> Option<(Vec<f64>, Vec<f64>)> {
    let (n, k) = (y.len(), which.len());
    let a = DMatrix::from_fn(n, k, |i, j| cols[i][which[j]]);
    let b = DVector::from_column_slice(y);
    let ata = a.transpose() * &a;
    let beta = ata.try_inverse()? * a.transpose() * &b;
    let u = &b - &a * &beta;
    Some((beta.iter().copied().collect(), u.iter().copied().collect()))
}

/// Newey–West standard error of coefficient `j` of the fit of the columns
/// `which` with residuals `u` (rows in time order, `lags` rows of serial
/// correlation, Bartlett weights [NeweyWest1987, eq. 2]).
fn hac_stderr(
    cols: &[[f64; COLUMNS]],
    which: &[usize],
    u: &[f64],
    lags: usize,
    j: usize,
) -> Option<f64> {
    let (n, k) = (u.len(), which.len());
    let a = DMatrix::from_fn(n, k, |i, c| cols[i][which[c]]);
    let inv = (a.transpose() * &a).try_inverse()?;
    let g = DMatrix::from_fn(n, k, |i, c| a[(i, c)] * u[i]);
    let mut s = g.transpose() * &g;
    for l in 1..=lags.min(n.saturating_sub(1)) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        let gl = g.rows(l, n - l).transpose() * g.rows(0, n - l);
        s += (&gl + gl.transpose()) * w;
    }
    let cov = &inv * s * &inv;
    let v = cov[(j, j)];
    (v.is_finite() && v > 0.0).then(|| v.sqrt())
}

/// Which parameters are fitted again beside the gain or the load law.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nuisance {
    /// Both radii and the wheel base: the selection named a gain, which a
    /// wheel base may have stood in for.
    RadiiAndBase,
    /// Both radii: the selection named radii and no wheel base (at one
    /// speed the load's turn over-read is a wheel base).
    Radii,
}

/// The load law against the encoder gain on the rows of `all`, from the
/// selected model `x` (its encoder gain taken out) with the streams'
/// profiled σ `scale`, the `nuisance` parameters fitted again beside each.
/// `None` when there are too few rows or a fit is singular (a run without
/// turns says nothing of either).
pub fn compare(
    all: Part,
    x: &Departures,
    robot: &RobotConfig,
    scale: &[f64; 4],
    s: &LoadSettings,
    nuisance: Nuisance,
) -> Option<LoadFit> {
    let base = Departures {
        encoder_gain: 0.0,
        ..x.clone()
    };
    let (y, cols, t) = stacked(&all, &base, robot, scale);
    if y.len() < 8 * COLUMNS {
        return None;
    }
    let fixed: &[usize] = match nuisance {
        Nuisance::RadiiAndBase => &[0, 1, 2],
        Nuisance::Radii => &[0, 1],
    };
    let with_gain = [fixed, &[GAIN]].concat();
    let with_load = [fixed, &[LOAD]].concat();
    let (bg, ug) = lsq(&y, &cols, &with_gain)?;
    let (bl, u) = lsq(&y, &cols, &with_load)?;
    let lags = lags_for(&t, s.lag_seconds);
    let load = kappa(&cols, &with_load, &bl, &u, lags)?;
    let d: Vec<f64> = ug.iter().zip(&u).map(|(a, b)| a * a - b * b).collect();
    // Fits that span the same columns (one speed) leave the same residuals
    // but for rounding, whose ratio means nothing: no preference.
    let rss: f64 = u.iter().map(|v| v * v).sum();
    let same = d.iter().sum::<f64>().abs() <= 1e-9 * rss;
    Some(LoadFit {
        load,
        gain: bg[fixed.len()],
        gain_radii: [bg[0], bg[1]],
        vuong_z: if same { 0.0 } else { vuong(&d, lags) },
    })
}

/// κ, the last of the columns `which` fitted with coefficients `beta` and
/// residuals `u`, with its Newey–West standard error and p-value.
fn kappa(
    cols: &[[f64; COLUMNS]],
    which: &[usize],
    beta: &[f64],
    u: &[f64],
    lags: usize,
) -> Option<Kappa> {
    let j = which.len() - 1;
    let stderr = hac_stderr(cols, which, u, lags, j)?;
    let z = beta[j] / stderr;
    Some(Kappa {
        kappa: beta[j],
        stderr,
        p_value: chi2_sf(z * z, 1),
    })
}

/// Newey–West lags (rows) covering `seconds` of the stacked rows at times
/// `t`: the rows of all streams per second, which over-covers the sparser
/// streams.
fn lags_for(t: &[f64], seconds: f64) -> usize {
    let span = t.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - t.iter().copied().fold(f64::INFINITY, f64::min);
    ((seconds / span.max(1e-9)) * t.len() as f64)
        .ceil()
        .max(1.0) as usize
}

/// Vuong's statistic \[Vuong1989\] of per-row log-likelihood
/// differences `d` (the gain's squared normalised residual minus the load
/// law's; twice the Gaussian log-likelihood ratio): their sum over its
/// standard deviation, the variance Newey–West over `lags` rows.
fn vuong(d: &[f64], lags: usize) -> f64 {
    let n = d.len();
    let m = d.iter().sum::<f64>() / n as f64;
    let c: Vec<f64> = d.iter().map(|v| v - m).collect();
    let mut s = c.iter().map(|v| v * v).sum::<f64>();
    for l in 1..=lags.min(n.saturating_sub(1)) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        s += 2.0 * w * (l..n).map(|i| c[i] * c[i - l]).sum::<f64>();
    }
    m * n as f64 / s.max(1e-300).sqrt()
}

/// The rows with the load law's part (κ times its regressor, under the
/// model `x`) taken out of the forward speed, the turn rate and the gyro:
/// what the table effects are selected on again once the load is named.
pub fn without_load(
    all: Part,
    x: &Departures,
    robot: &RobotConfig,
    kappa: f64,
) -> (Vec<IcpRow>, Vec<GyroRow>) {
    let icp = all
        .icp
        .iter()
        .map(|r| {
            let d = derivatives(&all, x, robot, r.t0, r.t1);
            let mut z = r.z;
            z[0] -= kappa * d[0][LOAD];
            z[2] -= kappa * d[1][LOAD];
            IcpRow { z, ..*r }
        })
        .collect();
    let gyro = all
        .gyro
        .iter()
        .map(|r| GyroRow {
            w: r.w - kappa * derivatives(&all, x, robot, r.t0, r.t1)[1][LOAD],
            ..*r
        })
        .collect();
    (icp, gyro)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::model::Replay;
    use crate::recording::WheelSample;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// How the wheels of the test drive depart from the nominal chair.
    #[derive(Clone, Copy)]
    enum Truth {
        /// Tyres: r_R (1 − κ v ω), r_L (1 + κ v ω).
        Load(f64),
        /// Encoders reading φ̇ (1 + k |φ̇|).
        Gain(f64),
    }

    /// A drive of 1 s segments at the `speeds` in turn, each straight, then
    /// turning left, straight, turning right at 0.5 rad/s (wheels at 100 Hz
    /// integrated exactly, ICP rows every 0.1 s with seeded noise of 2 mm/s
    /// and 2 mrad/s): the wheels as `truth` makes them read, the rows what
    /// the robot did.
    fn drive(speeds: &[f64], truth: Truth, seed: u64) -> (Replay, Vec<IcpRow>) {
        let robot = RobotConfig::default();
        let (r, d) = (robot.r_right, robot.wheel_base);
        let mut segs = Vec::new();
        for _ in 0..20 {
            for &v in speeds {
                for w in [0.0, 0.5, 0.0, -0.5] {
                    segs.push((v, w));
                }
            }
        }
        let (mut wheels, mut icp) = (Vec::new(), Vec::new());
        let (mut pr, mut pl, mut t) = (0.0, 0.0, 0.0);
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.002).unwrap();
        wheels.push(WheelSample {
            stamp: 0.0,
            right: 0.0,
            left: 0.0,
        });
        for &(v, w) in &segs {
            let (vr, vl) = (v + 0.5 * w * d, v - 0.5 * w * d);
            let (rr, rl, k) = match truth {
                Truth::Load(kappa) => (r * (1.0 - kappa * v * w), r * (1.0 + kappa * v * w), 0.0),
                Truth::Gain(k) => (r, r, k),
            };
            let read = |rate: f64| rate * (1.0 + k * rate.abs());
            let (fr, fl) = (read(vr / rr), read(vl / rl));
            for i in 1..=100 {
                let s = t + 0.01 * i as f64;
                wheels.push(WheelSample {
                    stamp: s,
                    right: pr + fr * 0.01 * i as f64,
                    left: pl + fl * 0.01 * i as f64,
                });
            }
            for i in 0..10 {
                let arc = crate::geom::xyt(&crate::geom::arc_increment(v, w, 0.1));
                let t0 = t + 0.1 * i as f64;
                icp.push(IcpRow {
                    t0,
                    t1: t0 + 0.1,
                    z: [
                        arc[0] / 0.1 + noise.sample(&mut rng),
                        arc[1] / 0.1 + noise.sample(&mut rng),
                        w + noise.sample(&mut rng),
                    ],
                    sigma: [0.002; 3],
                });
            }
            (pr, pl, t) = (pr + fr, pl + fl, t + 1.0);
        }
        // Rows clear of the ends.
        icp.retain(|row| row.t0 > 0.5 && row.t1 < t - 0.5);
        (Replay::new(&robot, &wheels, 0.0, 0.0), icp)
    }

    fn compared(speeds: &[f64], truth: Truth) -> LoadFit {
        compared_from(speeds, truth, &Departures::default())
    }

    /// [`compared`] from the selected model `x`.
    fn compared_from(speeds: &[f64], truth: Truth, x: &Departures) -> LoadFit {
        let (replay, icp) = drive(speeds, truth, 7);
        let all = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        let robot = RobotConfig::default();
        compare(
            all,
            x,
            &robot,
            &[1.0; 4],
            &LoadSettings::default(),
            Nuisance::RadiiAndBase,
        )
        .unwrap()
    }

    /// One second of the nominal chair's wheels turning steadily at 3 and
    /// 2 rad/s (100 Hz).
    fn steady(robot: &RobotConfig) -> Replay {
        let wheels: Vec<WheelSample> = (0..=100)
            .map(|i| {
                let t = 0.01 * i as f64;
                WheelSample {
                    stamp: t,
                    right: 3.0 * t,
                    left: 2.0 * t,
                }
            })
            .collect();
        Replay::new(robot, &wheels, 0.0, 0.0)
    }

    #[test]
    fn the_first_order_changes_are_the_laws_by_hand() {
        // Wheels at 3 and 2 rad/s on the nominal chair (r 0.32 m, D 0.65 m):
        // rims 0.96 and 0.64 m/s, V 0.8 m/s, W 0.32/0.65 rad/s.
        let robot = RobotConfig::default();
        let replay = steady(&robot);
        let all = Part {
            replay: &replay,
            icp: &[],
            gyro: &[],
        };
        let [dv, dw] = derivatives(&all, &Departures::default(), &robot, 0.2, 0.6);
        let (v, w) = (0.8, 0.32 / 0.65);
        let want_v = [
            0.48,
            0.32,
            0.0,
            -(0.96 * 3.0 + 0.64 * 2.0) / 2.0,
            -v * w * w * 0.65 / 2.0,
        ];
        let want_w = [
            0.96 / 0.65,
            -0.64 / 0.65,
            -w,
            -(0.96 * 3.0 - 0.64 * 2.0) / 0.65,
            -2.0 * v * v * w / 0.65,
        ];
        for j in 0..COLUMNS {
            assert!((dv[j] - want_v[j]).abs() < 1e-12, "V column {j}: {dv:?}");
            assert!((dw[j] - want_w[j]).abs() < 1e-12, "W column {j}: {dw:?}");
        }
    }

    /// Rows stacked by hand: each residual and its regressors divided by
    /// the row's σ times its stream's scale, ICP forward and turn rate then
    /// the gyro, at the rows' mid-times; rows with a residual or σ that is
    /// not finite, or σ 0, left out.
    #[test]
    fn rows_are_stacked_with_their_weights_by_hand() {
        let robot = RobotConfig::default();
        let replay = steady(&robot);
        let x = Departures::default();
        let row = |t0: f64, off: [f64; 3], sigma: [f64; 3]| {
            let p = replay.icp(&x, t0, t0 + 0.2);
            IcpRow {
                t0,
                t1: t0 + 0.2,
                z: [p.v + off[0], p.l + off[1], p.w + off[2]],
                sigma,
            }
        };
        let icp = [
            row(0.2, [0.01, 0.0, 0.02], [0.5, 1.0, 0.25]),
            row(0.4, [f64::NAN, 0.0, 0.04], [0.5, 1.0, 0.0]),
            row(0.6, [0.03, 0.0, 0.0], [f64::INFINITY, 1.0, 0.25]),
        ];
        let gyro = [GyroRow {
            t0: 0.3,
            t1: 0.5,
            w: replay.gyro(&x, 0.3, 0.5) + 0.002,
            sigma: 0.1,
        }];
        let all = Part {
            replay: &replay,
            icp: &icp,
            gyro: &gyro,
        };
        let scale = [2.0, 7.0, 4.0, 0.5];
        let (y, cols, t) = stacked(&all, &x, &robot, &scale);
        // Kept: row 1's forward (σ 0.5 · 2) and turn (0.25 · 4), the gyro
        // (0.1 · 0.5); row 2's forward is NaN and its turn's σ 0, row 3's
        // forward σ infinite and its turn's residual 0 (kept).
        let want_y = [0.01 / 1.0, 0.02 / 1.0, 0.0, 0.002 / 0.05];
        let want_t = [0.3, 0.3, 0.7, 0.4];
        assert_eq!(y.len(), 4, "{y:?}");
        for k in 0..4 {
            assert!((y[k] - want_y[k]).abs() < 1e-9, "{k}: {y:?}");
            assert!((t[k] - want_t[k]).abs() < 1e-12, "{k}: {t:?}");
        }
        // Regressors: the motion's at 3 and 2 rad/s (V 0.8 m/s, W 0.32/0.65
        // rad/s), over each row's own weight.
        let w = 0.32 / 0.65;
        let (load_v, load_w) = (-0.8 * w * w * 0.65 / 2.0, -2.0 * 0.64 * w / 0.65);
        for (k, (want, weight)) in [(load_v, 1.0), (load_w, 1.0), (load_w, 1.0), (load_w, 0.05)]
            .iter()
            .enumerate()
        {
            assert!(
                (cols[k][LOAD] - want / weight).abs() < 1e-9,
                "{k}: {cols:?}"
            );
        }
    }

    #[test]
    fn turns_at_two_speeds_tell_tyres_under_load_from_an_encoder_gain() {
        let tyres = compared(&[0.4, 1.0], Truth::Load(0.01));
        assert_eq!(
            tyres.reading(&LoadSettings::default()),
            Reading::Load,
            "{tyres:?}"
        );
        assert!((tyres.load.kappa - 0.01).abs() < 5e-4, "{tyres:?}");
        let gain = compared(&[0.4, 1.0], Truth::Gain(0.004));
        assert_eq!(
            gain.reading(&LoadSettings::default()),
            Reading::Gain,
            "{gain:?}"
        );
        assert!((gain.gain - 0.004).abs() < 4e-4, "{gain:?}");
        // From a selection that named that gain: it is taken out first, so
        // the comparison reads the same.
        let selected = Departures {
            encoder_gain: 0.004,
            ..Default::default()
        };
        let again = compared_from(&[0.4, 1.0], Truth::Gain(0.004), &selected);
        assert!((again.gain - gain.gain).abs() < 1e-12, "{again:?}");
        // The control: nothing departs, nothing significant.
        let none = compared(&[0.4, 1.0], Truth::Gain(0.0));
        assert_eq!(
            none.reading(&LoadSettings::default()),
            Reading::Gain,
            "{none:?}"
        );
    }

    #[test]
    fn at_one_speed_the_two_laws_are_one_and_either_is_the_reading() {
        for truth in [Truth::Load(0.01), Truth::Gain(0.008)] {
            let f = compared(&[0.8], truth);
            assert_eq!(
                f.reading(&LoadSettings::default()),
                Reading::Either,
                "{f:?}"
            );
            assert!(f.vuong_z.abs() < 1e-6, "{f:?}");
        }
    }

    /// The radii alone fitted again beside each law (no wheel base to take
    /// the turn over-read), at one speed: the tyres' κ recovered, and the
    /// gain the same law there (Vuong's z near 0, either); nothing on the same
    /// drive without load (the control).
    #[test]
    fn at_one_speed_with_the_radii_alone_the_load_is_found_and_either_law_fits() {
        let robot = RobotConfig::default();
        let s = LoadSettings::default();
        let fit = |truth| {
            let (replay, icp) = drive(&[0.8], truth, 9);
            let all = Part {
                replay: &replay,
                icp: &icp,
                gyro: &[],
            };
            let x = Departures::default();
            compare(all, &x, &robot, &[1.0; 4], &s, Nuisance::Radii).unwrap()
        };
        let tyres = fit(Truth::Load(0.01));
        assert_eq!(tyres.reading(&s), Reading::Either, "{tyres:?}");
        assert!((tyres.load.kappa - 0.01).abs() < 1e-3, "{tyres:?}");
        // The same span but for second-order terms: no preference.
        assert!(tyres.vuong_z.abs() < 1.0, "{tyres:?}");
        let none = fit(Truth::Load(0.0));
        assert!(!none.load.is_tyre(&s), "{none:?}");
        assert_eq!(none.reading(&s), Reading::Gain, "{none:?}");
    }

    #[test]
    fn the_reading_follows_its_thresholds() {
        let s = LoadSettings::default();
        let f = LoadFit {
            load: Kappa {
                kappa: 0.01,
                stderr: 0.001,
                p_value: 1e-9,
            },
            gain: 0.003,
            gain_radii: [0.0; 2],
            vuong_z: 3.0,
        };
        assert_eq!(f.reading(&s), Reading::Load);
        let at = |vuong_z, kappa, p_value| {
            LoadFit {
                vuong_z,
                load: Kappa {
                    kappa,
                    p_value,
                    ..f.load
                },
                ..f
            }
            .reading(&s)
        };
        assert_eq!(at(2.58, 0.01, 1e-9), Reading::Either);
        assert_eq!(at(-2.58, 0.01, 1e-9), Reading::Either);
        assert_eq!(at(-2.59, 0.01, 1e-9), Reading::Gain);
        // κ must be a tyre's: positive, at most max_kappa, significant.
        assert_eq!(at(3.0, -0.01, 1e-9), Reading::Gain);
        assert_eq!(at(3.0, 0.0, 1e-9), Reading::Gain);
        assert_eq!(at(3.0, 0.05, 1e-9), Reading::Load);
        assert_eq!(at(3.0, 0.0501, 1e-9), Reading::Gain);
        assert_eq!(at(3.0, 0.01, 1e-6), Reading::Gain);
        let off = LoadSettings {
            enabled: false,
            ..s.clone()
        };
        assert_eq!(f.reading(&off), Reading::Gain);
        assert!(s.validate().is_ok());
        for bad in [
            LoadSettings {
                vuong_z: 0.0,
                ..s.clone()
            },
            LoadSettings {
                max_kappa: f64::NAN,
                ..s.clone()
            },
            LoadSettings {
                lag_seconds: -1.0,
                ..s.clone()
            },
            LoadSettings {
                alpha: 1.0,
                ..s.clone()
            },
            LoadSettings {
                alpha: 0.0,
                ..s.clone()
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn newey_west_standard_error_by_hand() {
        // One column of ones (a mean), residuals (1, −1, 1, −1): lag 0 sums
        // u² = 4, (AᵀA)⁻¹ = 1/4, variance 4/16, σ 0.5; with one lag
        // (Bartlett weight 1/2) the products of neighbours, −3, add
        // 2 · 1/2 · (−3): variance 1/16, σ 0.25.
        let mut cols = vec![[0.0; COLUMNS]; 4];
        for c in &mut cols {
            c[2] = 1.0;
        }
        let u = [1.0, -1.0, 1.0, -1.0];
        let se0 = hac_stderr(&cols, &[2], &u, 0, 0).unwrap();
        assert!((se0 - 0.5).abs() < 1e-12, "{se0}");
        let se1 = hac_stderr(&cols, &[2], &u, 1, 0).unwrap();
        assert!((se1 - 0.25).abs() < 1e-12, "{se1}");
        // Two lags: weights 2/3 and 1/3, products −3 and +2: variance
        // (4 − 4 + 4/3)/16, σ √(1/12).
        let se2 = hac_stderr(&cols, &[2], &u, 2, 0).unwrap();
        assert!((se2 - (1.0f64 / 12.0).sqrt()).abs() < 1e-12, "{se2}");
        // No residual, no standard error.
        assert!(hac_stderr(&cols, &[2], &[0.0; 4], 1, 0).is_none());
    }

    #[test]
    fn vuong_by_hand() {
        // d = (1, 3) mean 2, centred (−1, 1): variance sum 2 at lag 0, the
        // lag-1 term 2·(1/2)·(−1) = −1: z = 2·2/√1 = 4.
        assert!((vuong(&[1.0, 3.0], 1) - 4.0).abs() < 1e-12);
        assert!((vuong(&[1.0, 3.0], 0) - 4.0 / 2f64.sqrt()).abs() < 1e-12);
    }
}
