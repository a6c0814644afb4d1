//! What a model leaves in the residuals, by kind: each stream's residuals
//! regressed (weighted by their σ) on the regressor of each structure an
//! unmodelled effect leaves — a constant (bias), time (trend), the forward
//! speed (speed-dependent), the turn rate and its magnitude (turn-dependent),
//! the wheel rates times the sine and cosine of the wheel angles (periodic in
//! wheel angle: an out-of-round wheel) — with Newey–West standard errors.
//!
//! Scan matching errors are not white: consecutive pairs share a scan (their
//! errors are anti-correlated) and a place's geometry biases every pair
//! matched there (errors correlated over seconds). Newey–West standard errors
//! ([NeweyWest1987, eq. 2], Bartlett weights) make each test valid
//! under that serial correlation, and a structure is only reported when its
//! size also exceeds what scan matching leaves on recordings without any
//! effect ([`Floors`], measured on null runs through the simulator and ICP).

use super::data::{IcpRow, Part, GROUPS};
use super::diagnosis::{Remaining, ROBOT, SCAN_MATCHING};
use super::instrument::Instrument;
use super::stats::chi2_sf;
use crate::effects::Departures;
use crate::robot::RobotConfig;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The sizes below which a structure is not reported, whatever its
/// p-value: what scan matching itself leaves on null recordings, as a
/// fraction of the motion (see `relative`). Measured with `odocal
/// experiment diagnose` on null runs of every scenario (ICP scan to scan on
/// the LMS111 wheelchair): the largest seen there, with a margin of about
/// half as much again. ICP's forward velocity is the least trustworthy
/// stream: its scale varies by up to ±2 % between recordings with the
/// geometry seen; the turn rate (ICP and gyro) is an order of magnitude
/// cleaner.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Floors {
    /// Forward or lateral velocity streams (`icp_v`, `icp_lateral`).
    pub velocity: StreamFloors,
    /// Turn-rate streams (`icp_w`, `gyro`).
    pub turn: StreamFloors,
}

/// Floors of one kind of stream, each relative to the motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StreamFloors {
    /// Bias.
    pub bias: f64,
    /// Change over the run by a trend.
    pub trend: f64,
    /// Slope against the forward speed.
    pub speed: f64,
    /// Slope against the turn rate or its magnitude.
    pub turn: f64,
    /// Once-per-revolution radius wobble.
    pub periodic: f64,
}

impl Default for StreamFloors {
    fn default() -> Self {
        Self {
            bias: 0.007,
            trend: 0.009,
            speed: 0.03,
            turn: 0.006,
            periodic: 0.015,
        }
    }
}

impl Default for Floors {
    fn default() -> Self {
        Self {
            velocity: StreamFloors::default(),
            turn: StreamFloors {
                bias: 0.004,
                trend: 0.008,
                speed: 0.012,
                turn: 0.003,
                periodic: 0.003,
            },
        }
    }
}

/// One test of one structure in one stream.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RemainingTest {
    /// What it found (size, unit, p-value).
    pub found: Remaining,
    /// Whether it is significant (p below the Bonferroni level) and above
    /// its floor.
    pub significant: bool,
    /// The regression's coefficients (intercept first, then the regressors).
    pub coefficients: Vec<f64>,
}

/// The structure an out-of-round wheel leaves.
pub const PERIODIC: &str = "periodic in wheel angle";

/// The kinds of structure, with the regressors that expose each.
const KINDS: [&str; 6] = [
    "bias",
    "trend",
    "speed-dependent",
    "turn-dependent",
    "turn-magnitude-dependent",
    "periodic in wheel angle",
];

/// Per row of a stream: time, σ (physical) and the regressors.
struct Rows {
    t: Vec<f64>,
    e: Vec<f64>,
    sigma: Vec<f64>,
    speed: Vec<f64>,
    turn: Vec<f64>,
    /// ω_r cos φ_r, ω_r sin φ_r, ω_l cos φ_l, ω_l sin φ_l (rad/s).
    wheel: Vec<[f64; 4]>,
    /// The instrument's relative error and spread per row (scan matching).
    cell: Vec<[f64; 2]>,
}

fn rows(all: Part, x: &Departures, g: usize, inst: &Instrument) -> Rows {
    let phys = all.physical(x);
    let nominal = Departures::default();
    let mut r = Rows {
        t: Vec::new(),
        e: phys[g].clone(),
        sigma: Vec::new(),
        speed: Vec::new(),
        turn: Vec::new(),
        wheel: Vec::new(),
        cell: Vec::new(),
    };
    let mut push = |t0: f64, t1: f64, s: f64, icp: Option<&IcpRow>| {
        let tm = 0.5 * (t0 + t1);
        let (v, w) = all.replay.body(&nominal, t0, t1);
        r.t.push(tm);
        r.sigma.push(s);
        r.speed.push(v);
        r.turn.push(w);
        r.wheel.push(wheel_regressors(all.replay, t0, t1));
        r.cell
            .push(icp.map_or([0.0, 0.0], |row| inst.cell(g, row, v, w)));
    };
    if g < 3 {
        for row in all.icp {
            push(row.t0, row.t1, row.sigma[g], Some(row));
        }
    } else {
        for row in all.gyro {
            push(row.t0, row.t1, row.sigma, None);
        }
    }
    r
}

/// The periodic structure's regressors over `[t0, t1]`: each wheel's mean
/// rate times the cosine and sine of its mid-interval angle, `[ω_R cos φ_R,
/// ω_R sin φ_R, ω_L cos φ_L, ω_L sin φ_L]` (rad/s).
pub fn wheel_regressors(replay: &super::model::Replay, t0: f64, t1: f64) -> [f64; 4] {
    let (a0, b0) = replay.angles_at(t0);
    let (a1, b1) = replay.angles_at(t1);
    let (pr, pl) = (0.5 * (a0 + a1), 0.5 * (b0 + b1));
    let (wr, wl) = ((a1 - a0) / (t1 - t0), (b1 - b0) / (t1 - t0));
    [wr * pr.cos(), wr * pr.sin(), wl * pl.cos(), wl * pl.sin()]
}

/// Weighted least squares of `y` on the columns of `x` (rows weighted by
/// 1/σ²) with the Newey–West covariance over `lags` rows; the Wald statistic
/// of the coefficients `test` and the coefficients.
fn hac_wald(
    y: &[f64],
    x: &[Vec<f64>],
    sigma: &[f64],
    lags: usize,
    test: &[usize],
) -> Option<(f64, Vec<f64>)> {
    let (n, k) = (y.len(), x.len());
    if n < 8 * k.max(1) {
        return None;
    }
    let xm = DMatrix::from_fn(n, k, |i, j| x[j][i] / sigma[i]);
    let yv = DVector::from_iterator(n, y.iter().zip(sigma).map(|(v, s)| v / s));
    let xtx = xm.transpose() * &xm;
    let inv = xtx.clone().try_inverse()?;
    let beta = &inv * xm.transpose() * &yv;
    let u = &yv - &xm * &beta;
    // Newey–West: S = Γ0 + Σ_l (1 − l/(L+1)) (Γl + Γlᵀ), Γl = Σ_i g_i g_{i−l}ᵀ.
    let gm = DMatrix::from_fn(n, k, |i, j| xm[(i, j)] * u[i]);
    let mut s = gm.transpose() * &gm;
    for l in 1..=lags.min(n - 1) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        let a = gm.rows(l, n - l);
        let b = gm.rows(0, n - l);
        let gl = a.transpose() * b;
        s += (&gl + gl.transpose()) * w;
    }
    let cov = &inv * s * &inv;
    let m = test.len();
    let sub = DMatrix::from_fn(m, m, |i, j| cov[(test[i], test[j])]);
    let b = DVector::from_iterator(m, test.iter().map(|&i| beta[i]));
    let w = (b.transpose() * sub.try_inverse()? * &b)[(0, 0)];
    w.is_finite().then(|| (w, beta.iter().copied().collect()))
}

/// Units of a stream's residual.
fn unit(g: usize) -> &'static str {
    if g < 2 {
        "m/s"
    } else {
        "rad/s"
    }
}

/// Runs one kind's test on one stream: (size, unit of size, p, floor).
fn test_kind(
    r: &Rows,
    e: &[f64],
    g: usize,
    kind: &str,
    lags: usize,
    floors: &Floors,
) -> Option<(f64, String, f64, f64, Vec<f64>)> {
    let n = e.len();
    let one = vec![1.0; n];
    let tm = r.t.iter().sum::<f64>() / n.max(1) as f64;
    let f = if g < 2 {
        &floors.velocity
    } else {
        &floors.turn
    };
    let (cols, test, size_unit, floor): (Vec<Vec<f64>>, Vec<usize>, String, f64) = match kind {
        "bias" => (vec![one], vec![0], unit(g).into(), f.bias),
        "trend" => (
            vec![one, r.t.iter().map(|t| t - tm).collect()],
            vec![1],
            format!("{}/s", unit(g)),
            f.trend,
        ),
        "speed-dependent" => (
            vec![one, r.speed.clone()],
            vec![1],
            format!("{} per m/s", unit(g)),
            f.speed,
        ),
        "turn-dependent" => (
            vec![one, r.turn.clone()],
            vec![1],
            format!("{} per rad/s", unit(g)),
            f.turn,
        ),
        "turn-magnitude-dependent" => (
            vec![one, r.turn.iter().map(|w| w.abs()).collect()],
            vec![1],
            format!("{} per rad/s", unit(g)),
            f.turn,
        ),
        _ => {
            let mut c = vec![one];
            for j in 0..4 {
                c.push(r.wheel.iter().map(|w| w[j]).collect());
            }
            (
                c,
                vec![1, 2, 3, 4],
                format!("{} per rad/s of wheel rate", unit(g)),
                f.periodic,
            )
        }
    };
    let (w, beta) = hac_wald(e, &cols, &r.sigma, lags, &test)?;
    let size = if test.len() == 1 {
        beta[test[0]]
    } else {
        // Amplitude of the larger wheel's periodic term.
        beta[1].hypot(beta[2]).max(beta[3].hypot(beta[4]))
    };
    // A velocity residual per wheel rate is relative once divided by the radius.
    Some((size, size_unit, chi2_sf(w, test.len()), floor, beta))
}

/// Root mean square of a series (0 when empty).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// A structure's size as a fraction of the motion it rides on, so one set
/// of floors serves robots of any size and speed: a bias or the change a
/// trend makes over the run against the stream's typical magnitude (the
/// forward speed for both velocity streams, the turn rate for the turn
/// streams), a slope times its regressor's typical magnitude likewise, a
/// periodic term as the radius wobble behind it.
fn relative(size: f64, kind: &str, g: usize, r: &Rows, robot: &RobotConfig) -> f64 {
    let scale = if g < 2 { rms(&r.speed) } else { rms(&r.turn) };
    let span = r.t.last().unwrap_or(&0.0) - r.t.first().unwrap_or(&0.0);
    let reg = match kind {
        "bias" => 1.0,
        "trend" => span,
        "speed-dependent" => rms(&r.speed),
        "turn-dependent" | "turn-magnitude-dependent" => rms(&r.turn),
        _ => return wobble(size, g, robot),
    };
    size * reg / scale.max(1e-9)
}

/// The relative radius wobble behind a periodic term of `size` per rad/s of
/// wheel rate in stream `g`: δV = ω δr / 2, δW = ω δr / D.
pub fn wobble(size: f64, g: usize, robot: &RobotConfig) -> f64 {
    let radius = 0.5 * (robot.r_right + robot.r_left);
    if g < 2 {
        2.0 * size / radius
    } else {
        size * robot.wheel_base / radius
    }
}

/// What the instrument's table makes of one stream's rows: the residuals
/// with its error taken out, the weighted mean of its relative error and of
/// its spread (weights: each row's information on the motion it rides on).
struct Corrected {
    e: Vec<f64>,
    error: f64,
    spread: f64,
}

/// The rows of stream `g` corrected by the instrument's table; `None` for
/// the streams it has no table of (lateral, gyro) or when it is off.
fn corrected(r: &Rows, g: usize, inst: &Instrument) -> Option<Corrected> {
    let x = match g {
        0 if inst.enabled => &r.speed,
        2 if inst.enabled => &r.turn,
        _ => return None,
    };
    let e =
        r.e.iter()
            .zip(&r.cell)
            .zip(x)
            .map(|((e, c), x)| e - c[0] * x);
    let (mut se, mut ss, mut sw) = (0.0, 0.0, 0.0);
    for ((c, x), s) in r.cell.iter().zip(x).zip(&r.sigma) {
        let w = (x / s).powi(2);
        se += w * c[0];
        ss += w * c[1];
        sw += w;
    }
    (sw > 0.0).then(|| Corrected {
        e: e.collect(),
        error: se / sw,
        spread: ss / sw,
    })
}

/// Why a structure is the instrument's, in words.
fn instrument_reason(g: usize, c: &Corrected, rel: f64, rel_c: f64) -> String {
    let what = if g == 0 {
        "forward speed (more where the geometry leaves the motion's axis loose and where \
         the scans are close together)"
    } else {
        "turn rate"
    };
    format!(
        "scan-to-scan ICP reads the {what} {:+.2} % ± {:.2} % on these rows: {:+.2} % of the \
         motion found, {:+.2} % once that is taken out",
        100.0 * c.error,
        100.0 * c.spread,
        100.0 * rel,
        100.0 * rel_c
    )
}

/// Every structure test of every stream of `all` under the model `x`.
/// `alpha` is family-wise (Bonferroni over all tests); `lag_seconds` the
/// span of serial correlation allowed for. A significant structure that the
/// scan matcher's own error (`inst`) accounts for is reported with source
/// `scan_matching` and the reason: once the table's error is out of the
/// rows, it is no longer significant or no larger than its floor widened by
/// `inst.spreads` times the table's spread.
pub fn remaining_tests(
    all: Part,
    x: &Departures,
    alpha: f64,
    lag_seconds: f64,
    floors: &Floors,
    inst: &Instrument,
    robot: &RobotConfig,
) -> Vec<RemainingTest> {
    let mut found = Vec::new();
    let counts = all.counts();
    for g in 0..4 {
        if counts[g] < 50 {
            continue;
        }
        let r = rows(all, x, g, inst);
        let corr = corrected(&r, g, inst);
        let span = r.t.last().unwrap_or(&0.0) - r.t.first().unwrap_or(&0.0);
        let lags = (((lag_seconds / span.max(1e-9)) * r.t.len() as f64).ceil() as usize).max(1);
        for kind in KINDS {
            // The gyro has no lateral counterpart of speed; test all the same.
            let Some((size, u, p, floor, beta)) = test_kind(&r, &r.e, g, kind, lags, floors) else {
                continue;
            };
            let rel = relative(size, kind, g, &r, robot);
            // The same test once the instrument's error is out of the rows,
            // for a structure that can be significant (α/m ≤ α).
            let candidate = rel.abs() > floor && p < alpha;
            let after = corr.as_ref().filter(|_| candidate).and_then(|c| {
                let (size_c, _, p_c, _, _) = test_kind(&r, &c.e, g, kind, lags, floors)?;
                let rel_c = relative(size_c, kind, g, &r, robot);
                let big_c = rel_c.abs() > floor + inst.spreads * c.spread;
                Some((big_c, p_c, instrument_reason(g, c, rel, rel_c)))
            });
            found.push((
                Remaining {
                    stream: GROUPS[g].to_string(),
                    structure: kind.to_string(),
                    size,
                    unit: u,
                    p_value: p,
                    source: ROBOT.to_string(),
                    reason: None,
                },
                rel.abs() > floor,
                beta,
                after,
            ));
        }
    }
    let m = found.len().max(1) as f64;
    found
        .into_iter()
        .map(|(mut f, big, beta, after)| {
            let significant = big && f.p_value < alpha / m;
            if let Some((big_c, p_c, reason)) = after {
                if significant && !(big_c && p_c < alpha / m) {
                    f.source = SCAN_MATCHING.to_string();
                    f.reason = Some(reason);
                }
            }
            RemainingTest {
                significant,
                found: f,
                coefficients: beta,
            }
        })
        .collect()
}
