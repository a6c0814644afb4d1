//! Measured streams turned into observation rows: ICP motions as base-frame
//! velocities with σ, gyro samples averaged over short windows.

use super::model::Replay;
use super::stats::robust;
use crate::effects::Departures;
use crate::motion::Motion;
use crate::recording::GyroSample;

/// One ICP motion as velocities over [t0, t1] (base frame, nominal mount).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpRow {
    /// Interval start (s).
    pub t0: f64,
    /// Interval end (s).
    pub t1: f64,
    /// Measured forward, lateral (m/s) and turn rate (rad/s).
    pub z: [f64; 3],
    /// Their σ from the ICP covariance (m/s, m/s, rad/s).
    pub sigma: [f64; 3],
}

/// Mean gyro rate over a window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroRow {
    /// Window start (s).
    pub t0: f64,
    /// Window end (s).
    pub t1: f64,
    /// Mean measured rate (rad/s).
    pub w: f64,
    /// Relative σ of the mean: 1/√(samples); the absolute scale is estimated.
    pub sigma: f64,
}

/// Chains runs of consecutive valid motions (each starting where the last
/// ended) into motions spanning at least `min_dt` s: the SE(2) composition
/// of the increments, covariances added (their rotation between the parts
/// ignored: they only weight the rows), each increment the scan's own
/// ([`Motion::scan_measured`]). Streams stamped in bursts (odometry
/// logged in packets) then compare over intervals the bursts cannot split.
/// `min_dt` ≤ 0 returns the motions unchanged; a run shorter than `min_dt`
/// at a gap or at the end is dropped.
pub fn merge_motions(motions: &[Motion], min_dt: f64) -> Vec<Motion> {
    if min_dt.is_nan() || min_dt <= 0.0 {
        return motions.to_vec();
    }
    let mut out = Vec::new();
    let mut acc: Option<(Motion, crate::geom::Pose2)> = None;
    for m in motions {
        if !m.is_valid() || m.t1 <= m.t0 {
            acc = None;
            continue;
        }
        // The scan's own increment: never the part the matcher's odometry
        // prior supplied (see `InfoSplit`).
        let [sx, sy, st] = m.scan_measured().0;
        let inc = crate::geom::pose(sx, sy, st);
        acc = match acc.take() {
            Some((mut a, p)) if (a.t1 - m.t0).abs() < 1e-9 => {
                a.t1 = m.t1;
                a.cov += m.cov;
                Some((a, p * inc))
            }
            _ => Some((m.clone(), inc)),
        };
        if acc
            .as_ref()
            .is_some_and(|(a, _)| a.t1 - a.t0 >= min_dt - 1e-9)
        {
            let (a, p) = acc.take().expect("checked above");
            let [dx, dy, dtheta] = crate::geom::xyt(&p);
            out.push(Motion {
                dx,
                dy,
                dtheta,
                split: None,
                ..a
            });
        }
    }
    out
}

/// Rows of every stream inside the wheel time span (with `margin` s kept free
/// at both ends for latency shifts).
pub fn icp_rows(motions: &[Motion], span: (f64, f64), margin: f64) -> Vec<IcpRow> {
    motions
        .iter()
        .filter(|m| m.is_valid() && m.t1 > m.t0)
        .filter(|m| m.t0 >= span.0 + margin && m.t1 <= span.1 - margin)
        .filter_map(|m| {
            let dt = m.t1 - m.t0;
            let z = [m.dx / dt, m.dy / dt, m.dtheta / dt];
            let sigma = [
                m.cov[(0, 0)].max(0.0).sqrt() / dt,
                m.cov[(1, 1)].max(0.0).sqrt() / dt,
                m.cov[(2, 2)].max(0.0).sqrt() / dt,
            ];
            let ok =
                z.iter().all(|v| v.is_finite()) && sigma.iter().all(|s| s.is_finite() && *s > 0.0);
            ok.then_some(IcpRow {
                t0: m.t0,
                t1: m.t1,
                z,
                sigma,
            })
        })
        .collect()
}

/// Gyro samples averaged over consecutive windows of about `window` s. Each
/// sample is taken as the mean rate over the sampling period that ends at its
/// stamp (median spacing δ; what an integrating MEMS gyro read at the end of
/// each period reports, and what the simulator writes), so a row of samples
/// s_1..s_n covers [s_1 − δ, s_n].
pub fn gyro_rows(gyro: &[GyroSample], span: (f64, f64), margin: f64, window: f64) -> Vec<GyroRow> {
    let (a, b) = (span.0 + margin, span.1 - margin);
    let mut rows = Vec::new();
    let g: Vec<&GyroSample> = gyro
        .iter()
        .filter(|g| g.stamp.is_finite() && g.wz.is_finite())
        .collect();
    if window.is_nan() || window <= 0.0 || b <= a || g.len() < 2 {
        return rows;
    }
    let mut gaps: Vec<f64> = g
        .windows(2)
        .map(|w| w[1].stamp - w[0].stamp)
        .filter(|d| *d > 0.0)
        .collect();
    if gaps.is_empty() {
        return rows;
    }
    gaps.sort_by(|x, y| x.total_cmp(y));
    let half = 0.5 * gaps[gaps.len() / 2];
    let mut i = 0;
    while i < g.len() {
        let t0 = g[i].stamp - 2.0 * half;
        if t0 < a {
            i += 1;
            continue;
        }
        let (mut j, mut sum) = (i, 0.0);
        while j < g.len() && g[j].stamp <= t0 + window + 1e-9 {
            sum += g[j].wz;
            j += 1;
        }
        if j == i {
            i += 1;
            continue;
        }
        let t1 = g[j - 1].stamp;
        if t1 > b {
            break;
        }
        let n = (j - i) as f64;
        // Windows with a gap (missing samples) are skipped.
        if t1 - t0 <= window + 1e-9 && n * 2.0 * half >= 0.9 * (t1 - t0) {
            rows.push(GyroRow {
                t0,
                t1,
                w: sum / n,
                sigma: 1.0 / n.sqrt(),
            });
        }
        i = j;
    }
    rows
}

/// Drops the rows far from model `x`: a row is an outlier when one of its
/// normalised residuals lies more than `sigma` robust σ (1.4826·MAD) from
/// its group's median. Returns how many rows were dropped.
pub fn drop_outliers(
    replay: &Replay,
    icp: &mut Vec<IcpRow>,
    gyro: &mut Vec<GyroRow>,
    sigma: f64,
    x: &Departures,
) -> usize {
    let before = icp.len() + gyro.len();
    let all = Part {
        replay,
        icp: icp.as_slice(),
        gyro: gyro.as_slice(),
    };
    let mut e: [Vec<f64>; 4] = Default::default();
    all.normalised(x, &mut e);
    let rb: Vec<(f64, f64)> = e.iter().map(|v| robust(v)).collect();
    let bad = |g: usize, v: f64| {
        let (c, s) = rb[g];
        s > 0.0 && ((v - c) / s).abs() > sigma
    };
    let keep_icp: Vec<bool> = (0..icp.len())
        .map(|i| !(0..3).any(|g| bad(g, e[g][i])))
        .collect();
    let keep_gyro: Vec<bool> = (0..gyro.len()).map(|i| !bad(3, e[3][i])).collect();
    let mut it = keep_icp.iter();
    icp.retain(|_| *it.next().unwrap());
    let mut it = keep_gyro.iter();
    gyro.retain(|_| *it.next().unwrap());
    before - icp.len() - gyro.len()
}

/// Residual groups: ICP forward, ICP lateral, ICP turn rate, gyro.
pub const GROUPS: [&str; 4] = ["icp_v", "icp_lateral", "icp_w", "gyro"];

/// Rows of one part (training or held-out) with the replay that predicts them.
#[derive(Debug, Clone, Copy)]
pub struct Part<'a> {
    /// The replayed wheel streams.
    pub replay: &'a Replay,
    /// ICP rows.
    pub icp: &'a [IcpRow],
    /// Gyro rows.
    pub gyro: &'a [GyroRow],
}

impl Part<'_> {
    /// Rows per group.
    pub fn counts(&self) -> [usize; 4] {
        let n = self.icp.len();
        [n, n, n, self.gyro.len()]
    }

    /// Residuals (measured − predicted) divided by the measurement σ, per group.
    pub fn normalised(&self, x: &Departures, out: &mut [Vec<f64>; 4]) {
        for o in out.iter_mut() {
            o.clear();
        }
        for r in self.icp {
            let p = self.replay.icp(x, r.t0, r.t1);
            out[0].push((r.z[0] - p.v) / r.sigma[0]);
            out[1].push((r.z[1] - p.l) / r.sigma[1]);
            out[2].push((r.z[2] - p.w) / r.sigma[2]);
        }
        for g in self.gyro {
            out[3].push((g.w - self.replay.gyro(x, g.t0, g.t1)) / g.sigma);
        }
    }

    /// Residuals (measured − predicted) in physical units (m/s, rad/s), per group.
    pub fn physical(&self, x: &Departures) -> [Vec<f64>; 4] {
        let mut out: [Vec<f64>; 4] = Default::default();
        for r in self.icp {
            let p = self.replay.icp(x, r.t0, r.t1);
            out[0].push(r.z[0] - p.v);
            out[1].push(r.z[1] - p.l);
            out[2].push(r.z[2] - p.w);
        }
        for g in self.gyro {
            out[3].push(g.w - self.replay.gyro(x, g.t0, g.t1));
        }
        out
    }

    /// Σ of squared normalised residuals per group.
    pub fn rss(&self, x: &Departures) -> [f64; 4] {
        let mut out: [Vec<f64>; 4] = Default::default();
        self.normalised(x, &mut out);
        let mut s = [0.0; 4];
        for (g, v) in out.iter().enumerate() {
            s[g] = v.iter().map(|e| e * e).sum();
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom;
    use nalgebra::Matrix3;

    fn motion(t0: f64, t1: f64, inc: &geom::Pose2, valid: bool) -> Motion {
        Motion {
            iterations: 1,
            inliers: 100,
            failure: (!valid).then_some(crate::motion::PairFailure::NotConverged),
            split: None,
            ..Motion::from_increment(t0, t1, inc, Matrix3::identity() * 1e-6)
        }
    }

    #[test]
    fn merged_motions_compose_contiguous_runs_and_stop_at_gaps() {
        let inc = geom::arc_increment(0.5, 0.3, 0.1);
        let mut ms: Vec<Motion> = (0..25)
            .map(|k| motion(k as f64 * 0.1, (k + 1) as f64 * 0.1, &inc, k != 12))
            .collect();
        ms.push(motion(10.0, 10.1, &inc, true));
        let m = merge_motions(&ms, 0.5);
        // 0–1.2 s gives two 0.5 s runs (the 0.2 s rest dies at the failed
        // pair), 1.3–2.3 s two more; the lone motion at 10 s is too short.
        assert_eq!(m.len(), 4, "{m:?}");
        let want = geom::xyt(&geom::arc_increment(0.5, 0.3, 0.5));
        for x in &m {
            assert!((x.t1 - x.t0 - 0.5).abs() < 1e-9);
            let got = [x.dx, x.dy, x.dtheta];
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-12, "{got:?} {want:?}");
            }
            assert!((x.cov[(0, 0)] - 5e-6).abs() < 1e-15);
        }
        assert!((m[2].t0 - 1.3).abs() < 1e-9);
        assert_eq!(merge_motions(&ms, 0.0).len(), ms.len());
    }
}
