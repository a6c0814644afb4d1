//! Slip on part of the floor: a wheel scale that holds in one region of the
//! path and not elsewhere. No constant effect of the table describes it, so
//! it is looked for on the residuals of the nominal model before any effect
//! is selected (a selection would otherwise spread it over table effects).
//!
//! Model. Wheels that spin by a factor (1 + s) over the ground make the
//! replay predict (1 + s) times the true forward speed V and turn rate W
//! there. With ê = measured − predicted on ICP's forward velocity and turn
//! rate, and p̂ the predicted V or W:
//!
//!   constant:  ê = M · p̂                 (p̂ = (p̂_V, p̂_W), M 2 × 2)
//!   region R:  ê = (M + Δ·1_R · I) · p̂
//!
//! (M is the linear part of every constant wheel effect: both radii and the
//! wheel base change V and W linearly in the two wheel rates, so a radius
//! difference, which turns the robot while it drives straight, is not taken
//! for a place; Δ is the same on both streams because slip scales both
//! wheels alike). Weighted least squares with each row's ICP σ and one
//! robust scale per stream; the likelihood-ratio statistic of the region model against the constant one
//! is maximised over bands {p : lo ≤ p·u < hi} of the scan-matched path
//! (directions u every 180°/`directions`, bounds on a grid of the rows'
//! quantiles: a change-point search in two dimensions that includes every
//! half-plane). The best band's Δ gets a Newey–West (sandwich) standard
//! error over `lag_seconds`, since scan-matching errors stay correlated
//! while the robot sees the same geometry; it is reported only beyond a
//! z-score and a size calibrated on null runs, where ICP's own
//! place-dependent forward scale error (±2 % between recordings) is the
//! structure a search finds by chance.

use super::data::{GyroRow, IcpRow, Part};
use super::stats::robust;
use crate::effects::Departures;
use nalgebra::{Matrix2, Matrix5, Vector5};

/// Systematic standard error of a slip (relative): the root mean square of
/// the slip the search finds on null runs (the blind suite's null group,
/// seeds 1000–1023: 0.1–1.5 %, RMS 0.64 %, |z| at most 7), the scan
/// matching's own place-dependent scale error, which no number of rows
/// averages away.
pub const SYSTEMATIC_SLIP: f64 = 0.0065;

/// Settings of the region search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorSettings {
    /// Directions of the bands over 180°.
    pub directions: usize,
    /// Quantile steps of the band bounds along each direction.
    pub quantiles: usize,
    /// Least and most share of the rows inside a band.
    pub share: (f64, f64),
    /// Least |z| of the region's Δ (Newey–West) reported.
    pub z: f64,
    /// Least relative slip reported: above the largest the search finds on
    /// null runs (1.5 %, [`SYSTEMATIC_SLIP`]) and about three times their
    /// RMS, so that a 3 % slip, whose estimate scatters by ±0.3 %, is not
    /// cut in half at its own size.
    pub floor: f64,
    /// Newey–West span (s).
    pub lag_seconds: f64,
    /// Rows this close to the region's bounds (m) are not used to fit the
    /// table effects.
    pub margin: f64,
}

impl Default for FloorSettings {
    fn default() -> Self {
        Self {
            directions: 18,
            quantiles: 20,
            share: (0.15, 0.85),
            z: 10.0,
            floor: 0.02,
            lag_seconds: 3.0,
            margin: 1.0,
        }
    }
}

/// A band of the scan-matched path (origin and axes at its start pose):
/// the points p with `lo` ≤ p·(cos `angle`, sin `angle`) < `hi` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// Direction of the band's axis (rad).
    pub angle: f64,
    /// Lower bound along it (m; −∞ when open).
    pub lo: f64,
    /// Upper bound along it (m; +∞ when open).
    pub hi: f64,
}

impl Region {
    /// Whether point `p` lies in the band.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let s = p[0] * self.angle.cos() + p[1] * self.angle.sin();
        s >= self.lo && s < self.hi
    }
}

/// The region model fitted on one region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipFit {
    /// The region.
    pub region: Region,
    /// Relative over-reading of the wheels inside against outside:
    /// (1 + g) / (1 + g + Δ) − 1, g the fitted forward scale outside.
    pub slip: f64,
    /// Its Newey–West standard error.
    pub stderr: f64,
    /// Δ / stderr(Δ).
    pub z: f64,
    /// Likelihood-ratio statistic against the constant model (σ² units).
    pub lr: f64,
    /// Rows inside and in all.
    pub rows: (usize, usize),
    /// Bounding box of the path inside: x0, x1, y0, y1 (m).
    pub bbox: [f64; 4],
}

impl SlipFit {
    /// Whether it is beyond the settings' z-score and size.
    pub fn reported(&self, s: &FloorSettings) -> bool {
        self.z <= -s.z && self.slip >= s.floor
    }
}

/// Positions (m) of the rows' midpoints on the path chained from the ICP
/// rows themselves (origin and axes at the first row's start).
pub fn path(icp: &[IcpRow]) -> Vec<[f64; 2]> {
    let (mut x, mut y, mut th) = (0.0f64, 0.0f64, 0.0f64);
    let mut out = Vec::with_capacity(icp.len());
    for r in icp {
        let h = 0.5 * (r.t1 - r.t0);
        let step = |x: &mut f64, y: &mut f64, th: &mut f64| {
            *x += (th.cos() * r.z[0] - th.sin() * r.z[1]) * h;
            *y += (th.sin() * r.z[0] + th.cos() * r.z[1]) * h;
            *th += r.z[2] * h;
        };
        step(&mut x, &mut y, &mut th);
        out.push([x, y]);
        step(&mut x, &mut y, &mut th);
    }
    out
}

/// Position of time `t` on the path (`icp`'s rows with positions `pos`):
/// that of the row whose midpoint is nearest.
pub fn position_at(icp: &[IcpRow], pos: &[[f64; 2]], t: f64) -> [f64; 2] {
    let k = icp.partition_point(|r| 0.5 * (r.t0 + r.t1) < t);
    let mid = |i: usize| 0.5 * (icp[i].t0 + icp[i].t1);
    let i = match k {
        0 => 0,
        k if k >= icp.len() => icp.len() - 1,
        k if (mid(k) - t).abs() < (t - mid(k - 1)).abs() => k,
        k => k - 1,
    };
    pos[i]
}

/// The rows with the slip taken out: what ICP and the gyro measured inside
/// `region` scaled by (1 + `slip`), the speeds the wheels would have shown
/// on the rest of the floor, so that the table effects are fitted on every
/// row as if the floor were uniform. ICP rows are placed by their midpoint
/// on the path chained from `icp`, gyro rows by the position at their
/// midpoint; rows within `margin` m of the band's bounds, on either side,
/// are left out (the bounds are known to a row or two of a drifting path).
pub fn corrected(
    icp: &[IcpRow],
    gyro: &[GyroRow],
    region: &Region,
    slip: f64,
    margin: f64,
) -> (Vec<IcpRow>, Vec<GyroRow>) {
    let pos = path(icp);
    let wide = Region {
        lo: region.lo - margin,
        hi: region.hi + margin,
        ..*region
    };
    let narrow = Region {
        lo: region.lo + margin,
        hi: region.hi - margin,
        ..*region
    };
    // None: near a bound; Some(k): the factor on the measurements.
    let place = |p: [f64; 2]| match (narrow.contains(p), wide.contains(p)) {
        (true, _) => Some(1.0 + slip),
        (false, false) => Some(1.0),
        (false, true) => None,
    };
    let i: Vec<IcpRow> = icp
        .iter()
        .zip(&pos)
        .filter_map(|(r, p)| {
            let k = place(*p)?;
            Some(IcpRow {
                z: r.z.map(|v| v * k),
                sigma: r.sigma.map(|v| v * k),
                ..*r
            })
        })
        .collect();
    let g: Vec<GyroRow> = gyro
        .iter()
        .filter_map(|g| {
            let k = place(position_at(icp, &pos, 0.5 * (g.t0 + g.t1)))?;
            Some(GyroRow { w: g.w * k, ..*g })
        })
        .collect();
    (i, g)
}

/// Per ICP row: weighted regressor and residual of both streams, its
/// position and time.
struct Rows {
    /// Per row: w_V (p̂_V², p̂_V p̂_W, p̂_W²), w_W (p̂_V², p̂_V p̂_W, p̂_W²),
    /// w_V (p̂_V ê_V, p̂_W ê_V), w_W (p̂_V ê_W, p̂_W ê_W).
    q: Vec<[f64; Q]>,
    /// (p̂_V, ê_V, w_V, p̂_W, ê_W, w_W) per row.
    raw: Vec<[f64; 6]>,
    pos: Vec<[f64; 2]>,
    /// Rows per second.
    rate: f64,
}

fn rows(all: Part, x: &Departures) -> Option<Rows> {
    let n = all.icp.len();
    if n < 100 {
        return None;
    }
    let pred: Vec<_> = all
        .icp
        .iter()
        .map(|r| all.replay.icp(x, r.t0, r.t1))
        .collect();
    let norm = |g: usize, p: &dyn Fn(usize) -> f64| {
        let v: Vec<f64> = (0..n)
            .map(|i| (all.icp[i].z[g] - p(i)) / all.icp[i].sigma[g])
            .collect();
        robust(&v).1
    };
    let (sv, sw) = (norm(0, &|i| pred[i].v), norm(2, &|i| pred[i].w));
    if !(sv > 0.0 && sw > 0.0) {
        return None;
    }
    let raw: Vec<[f64; 6]> = all
        .icp
        .iter()
        .zip(&pred)
        .map(|(r, p)| {
            let wv = (r.sigma[0] * sv).powi(-2);
            let ww = (r.sigma[2] * sw).powi(-2);
            [p.v, r.z[0] - p.v, wv, p.w, r.z[2] - p.w, ww]
        })
        .collect();
    let q = raw
        .iter()
        .map(|&[pv, ev, wv, pw, ew, ww]| {
            [
                wv * pv * pv,
                wv * pv * pw,
                wv * pw * pw,
                ww * pv * pv,
                ww * pv * pw,
                ww * pw * pw,
                wv * pv * ev,
                wv * pw * ev,
                ww * pv * ew,
                ww * pw * ew,
            ]
        })
        .collect();
    let span = all.icp[n - 1].t1 - all.icp[0].t0;
    Some(Rows {
        q,
        raw,
        pos: path(all.icp),
        rate: n as f64 / span.max(1e-9),
    })
}

/// Sums per row kept for the search.
const Q: usize = 10;

/// Normal equations of the region model from the totals `t` and the sums
/// `s` inside: (A, r) with A β = r, β = (M_VV, M_VW, M_WV, M_WW, Δ).
fn normal(t: &[f64; Q], s: &[f64; Q]) -> (Matrix5<f64>, Vector5<f64>) {
    let mut a = Matrix5::zeros();
    a.fixed_view_mut::<2, 2>(0, 0)
        .copy_from(&Matrix2::new(t[0], t[1], t[1], t[2]));
    a.fixed_view_mut::<2, 2>(2, 2)
        .copy_from(&Matrix2::new(t[3], t[4], t[4], t[5]));
    for (k, v) in [s[0], s[1], s[4], s[5]].into_iter().enumerate() {
        a[(k, 4)] = v;
        a[(4, k)] = v;
    }
    a[(4, 4)] = s[0] + s[5];
    (a, Vector5::new(t[6], t[7], t[8], t[9], s[6] + s[9]))
}

/// β and the likelihood-ratio statistic against the constant model.
fn solve(t: &[f64; Q], s: &[f64; Q]) -> Option<(Vector5<f64>, f64)> {
    let (a, r) = normal(t, s);
    let b = a.try_inverse()? * r;
    let a0 = a.fixed_view::<4, 4>(0, 0).into_owned();
    let r0 = r.fixed_rows::<4>(0).into_owned();
    let b0 = a0.try_inverse()? * r0;
    Some((b, b.dot(&r) - b0.dot(&r0)))
}

/// Column sums of the rows' search sums.
fn totals<'a>(q: impl Iterator<Item = &'a [f64; Q]>) -> [f64; Q] {
    q.fold([0.0; Q], |a, r| std::array::from_fn(|j| a[j] + r[j]))
}

/// The region model on the rows flagged `inside`, with its Newey–West
/// sandwich standard error.
fn fit(rows: &Rows, inside: &[bool], region: Region, lag_seconds: f64) -> Option<SlipFit> {
    let t = totals(rows.q.iter());
    let s = totals(
        rows.q
            .iter()
            .zip(inside)
            .filter(|(_, k)| **k)
            .map(|(q, _)| q),
    );
    let (b, lr) = solve(&t, &s)?;
    let (a, _) = normal(&t, &s);
    let ainv = a.try_inverse()?;
    let scores: Vec<Vector5<f64>> = rows
        .raw
        .iter()
        .zip(inside)
        .map(|(&[pv, ev, wv, pw, ew, ww], &k)| {
            let d = if k { b[4] } else { 0.0 };
            let uv = wv * (ev - (b[0] + d) * pv - b[1] * pw);
            let uw = ww * (ew - b[2] * pv - (b[3] + d) * pw);
            let inner = if k { pv * uv + pw * uw } else { 0.0 };
            Vector5::new(pv * uv, pw * uv, pv * uw, pw * uw, inner)
        })
        .collect();
    let lags = (lag_seconds * rows.rate).ceil() as usize;
    let mut meat: Matrix5<f64> = scores.iter().map(|g| g * g.transpose()).sum();
    for l in 1..=lags.min(scores.len().saturating_sub(1)) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        let gamma: Matrix5<f64> = (l..scores.len())
            .map(|i| scores[i] * scores[i - l].transpose())
            .sum();
        meat += (gamma + gamma.transpose()) * w;
    }
    let cov = ainv * meat * ainv;
    let se = cov[(4, 4)].max(0.0).sqrt();
    let inner: Vec<[f64; 2]> = rows
        .pos
        .iter()
        .zip(inside)
        .filter(|(_, k)| **k)
        .map(|(p, _)| *p)
        .collect();
    if inner.is_empty() || !(se > 0.0) {
        return None;
    }
    let ext =
        |k: usize, f: fn(f64, f64) -> f64, init: f64| inner.iter().map(|p| p[k]).fold(init, f);
    // The forward scale outside: the fitted M p̂ over p̂ on the rows outside
    // (M itself is not identified when V and W stay proportional).
    let (num, den) = rows.raw.iter().zip(inside).filter(|(_, k)| !**k).fold(
        (0.0, 0.0),
        |(n, d), (&[pv, _, wv, pw, _, _], _)| {
            (n + wv * pv * (b[0] * pv + b[1] * pw), d + wv * pv * pv)
        },
    );
    let (g, d) = (if den > 0.0 { num / den } else { 0.0 }, b[4]);
    let slip = (1.0 + g) / (1.0 + g + d) - 1.0;
    Some(SlipFit {
        region,
        slip,
        stderr: se * (1.0 + g) / (1.0 + g + d).powi(2),
        z: d / se,
        lr,
        rows: (inner.len(), rows.q.len()),
        bbox: [
            ext(0, f64::min, f64::INFINITY),
            ext(0, f64::max, f64::NEG_INFINITY),
            ext(1, f64::min, f64::INFINITY),
            ext(1, f64::max, f64::NEG_INFINITY),
        ],
    })
}

/// The band of the path where the wheels over-read most against the rest
/// (largest likelihood ratio with Δ < 0), fitted on the residuals of model
/// `x`; `None` when there are too few rows. A coarse search over
/// `directions` and `quantiles` is refined around its best band (directions
/// a fifth of a step apart, bounds on five times finer quantiles).
pub fn search(all: Part, x: &Departures, s: &FloorSettings) -> Option<SlipFit> {
    let rows = rows(all, x)?;
    let t = totals(rows.q.iter());
    let d = s.directions.max(1);
    let step = std::f64::consts::PI / d as f64;
    let coarse: Vec<f64> = (0..d).map(|k| step * k as f64).collect();
    let (_, first) = best_band(&rows, &t, &coarse, s.quantiles, s.share)?;
    let fine: Vec<f64> = (-5..=5)
        .map(|k| first.angle + 0.2 * step * k as f64)
        .collect();
    let (_, region) = best_band(&rows, &t, &fine, 5 * s.quantiles, s.share)?;
    let inside: Vec<bool> = rows.pos.iter().map(|p| region.contains(*p)).collect();
    fit(&rows, &inside, region, s.lag_seconds)
}

/// The band with the largest likelihood ratio and Δ < 0 over the given
/// directions (rad) and bounds at `quantiles` steps of the rows, with a
/// share of the rows inside `share`: (likelihood ratio, band).
fn best_band(
    rows: &Rows,
    t: &[f64; Q],
    angles: &[f64],
    quantiles: usize,
    share: (f64, f64),
) -> Option<(f64, Region)> {
    let n = rows.q.len();
    let mut best: Option<(f64, Region)> = None;
    for &angle in angles {
        let (c, sn) = (angle.cos(), angle.sin());
        let proj: Vec<f64> = rows.pos.iter().map(|p| p[0] * c + p[1] * sn).collect();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|a, b| proj[*a].total_cmp(&proj[*b]));
        let mut prefix = vec![[0.0; Q]; n + 1];
        for (i, &o) in order.iter().enumerate() {
            prefix[i + 1] = std::array::from_fn(|j| prefix[i][j] + rows.q[o][j]);
        }
        let bound = |b: usize| match b {
            0 => f64::NEG_INFINITY,
            b if b >= n => f64::INFINITY,
            b => 0.5 * (proj[order[b - 1]] + proj[order[b]]),
        };
        let cuts: Vec<usize> = (0..=quantiles).map(|j| j * n / quantiles).collect();
        for (i0, &b0) in cuts.iter().enumerate() {
            for &b1 in &cuts[i0 + 1..] {
                let part = (b1 - b0) as f64 / n as f64;
                if part < share.0 || part > share.1 {
                    continue;
                }
                let inside: [f64; Q] = std::array::from_fn(|j| prefix[b1][j] - prefix[b0][j]);
                let Some((b, lr)) = solve(t, &inside) else {
                    continue;
                };
                if b[4] < 0.0 && best.is_none_or(|(l, _)| lr > l) {
                    let region = Region {
                        angle,
                        lo: bound(b0),
                        hi: bound(b1),
                    };
                    best = Some((lr, region));
                }
            }
        }
    }
    best
}

/// The region model on a given `region` with the residuals of model `x`.
pub fn refit(all: Part, x: &Departures, region: &Region, lag_seconds: f64) -> Option<SlipFit> {
    let rows = rows(all, x)?;
    let inside: Vec<bool> = rows.pos.iter().map(|p| region.contains(*p)).collect();
    fit(&rows, &inside, *region, lag_seconds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::model::Replay;
    use crate::recording::WheelSample;
    use crate::robot::RobotConfig;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Three laps of a circle of radius 3 m (start at the origin heading +x,
    /// turning left: x = 3 sin θ, y = 3 (1 − cos θ)) at a varying speed, with
    /// both wheels spinning `slip` faster wherever x > 1 m; ICP rows are the
    /// true motion plus noise.
    fn circle(slip: f64, seed: u64) -> (Replay, Vec<IcpRow>) {
        let robot = RobotConfig::default();
        let (r, d) = (robot.r_right, robot.wheel_base);
        let radius = 3.0;
        let speed = |t: f64| 0.5 + 0.2 * (0.3 * t).sin();
        let dt = 0.001;
        let (mut s, mut t) = (0.0f64, 0.0f64);
        let (mut right, mut left) = (0.0f64, 0.0f64);
        let mut wheels = vec![WheelSample {
            stamp: 0.0,
            right: 0.0,
            left: 0.0,
        }];
        let mut arc = vec![0.0];
        while s < 3.0 * std::f64::consts::TAU * radius {
            let v = speed(t);
            let k = if radius * (s / radius).sin() > 1.0 {
                1.0 + slip
            } else {
                1.0
            };
            right += k * (v + 0.5 * d * v / radius) / r * dt;
            left += k * (v - 0.5 * d * v / radius) / r * dt;
            s += v * dt;
            t += dt;
            let n = (t / dt).round() as usize;
            if n.is_multiple_of(10) {
                wheels.push(WheelSample {
                    stamp: t,
                    right,
                    left,
                });
            }
            if n.is_multiple_of(100) {
                arc.push(s);
            }
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let nv = Normal::new(0.0, 0.01).unwrap();
        let nw = Normal::new(0.0, 0.004).unwrap();
        let icp = arc
            .windows(2)
            .enumerate()
            .map(|(i, a)| {
                let v = (a[1] - a[0]) / 0.1;
                IcpRow {
                    t0: i as f64 * 0.1,
                    t1: (i + 1) as f64 * 0.1,
                    z: [
                        v + nv.sample(&mut rng),
                        nv.sample(&mut rng),
                        v / radius + nw.sample(&mut rng),
                    ],
                    sigma: [0.01, 0.01, 0.004],
                }
            })
            .collect();
        (Replay::new(&robot, &wheels, 0.0, 0.0), icp)
    }

    #[test]
    fn the_search_finds_the_slippery_part_of_a_circle() {
        let (replay, icp) = circle(0.1, 5);
        let all = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        let s = FloorSettings::default();
        let f = search(all, &Departures::default(), &s).unwrap();
        assert!(f.reported(&s), "{f:?}");
        assert!((f.slip - 0.1).abs() < 0.01, "{f:?}");
        // The arc with x > 1 m: sin θ > 1/3, (π − 2 asin(1/3)) / 2π of the
        // path, travelled at the same mean speed as the rest.
        let share = (std::f64::consts::PI - 2.0 * (1.0f64 / 3.0).asin()) / std::f64::consts::TAU;
        let got = f.rows.0 as f64 / f.rows.1 as f64;
        assert!((got - share).abs() < 0.04, "{got} vs {share}: {f:?}");
        for (p, inside) in [
            ([2.9, 3.0], true),
            ([1.5, 0.4], true),
            ([1.5, 5.6], true),
            ([0.3, 0.0], false),
            ([-2.9, 3.0], false),
            ([0.3, 6.0], false),
        ] {
            assert_eq!(f.region.contains(p), inside, "{p:?}: {f:?}");
        }
        // The same drive on a uniform floor.
        let (replay, icp) = circle(0.0, 5);
        let all = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        let f = search(all, &Departures::default(), &s);
        assert!(f.is_none_or(|f| !f.reported(&s)), "{f:?}");
    }
}
