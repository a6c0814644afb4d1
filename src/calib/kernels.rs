//! The particle filter's per-step passes over its particle columns, kept
//! apart so they can be compiled twice: for the baseline CPU and, picked at
//! run time, with AVX2 (same instructions' results, wider registers: no fused
//! multiply-add is enabled, so both versions give bit-identical numbers).
//! Each pass keeps `LANES` independent partial sums in a fixed order, which
//! lets the compiler vectorise the reductions without changing the result.

use super::weights::fast_exp;

/// Independent accumulators per pass.
const LANES: usize = 4;

/// Smallest value a radius or wheel base may take (m).
pub(crate) const MIN_LENGTH: f64 = 1e-6;

/// Inputs of the fused predict-and-weigh pass [Farina, eqs. 2–4].
pub(crate) struct Predict<'a> {
    pub rr: &'a mut [f64],
    pub rl: &'a mut [f64],
    pub d: &'a mut [f64],
    pub v: &'a mut [f64],
    pub w: &'a mut [f64],
    /// Log-weights, updated in place.
    pub lw: &'a mut [f64],
    /// Prior normalised weights (for V_O, W_O).
    pub rho: &'a [f64],
    /// Standard normals for the random walks of R_R, R_L, D.
    pub e: [&'a [f64]; 3],
    /// Wheel rates (rad/s).
    pub wr: f64,
    pub wl: f64,
    /// Random-walk σ of the radii and of D (m).
    pub sr: f64,
    pub sd: f64,
    /// D's observability in [0, 1] and the belief's ratio D̄ / (R̄_R + R̄_L):
    /// W is predicted with the wheel base `obs·D + (1 − obs)·ratio·(R_R + R_L)`,
    /// so an unobservable D is not selected on, while a common scale of the
    /// radii and D stays invisible to W (only V sees it).
    pub obs: f64,
    pub ratio: f64,
    /// Likelihood `−kv (V − zv)² − kw (W − zw)²`.
    pub kv: f64,
    pub zv: f64,
    pub kw: f64,
    pub zw: f64,
}

impl Predict<'_> {
    /// The same inputs with every column cut to the particle count (a
    /// shorter one panics): known lengths spare the chunks their bounds
    /// checks.
    #[inline(always)]
    fn cut(self) -> Self {
        let n = self.rr.len();
        Self {
            rl: &mut self.rl[..n],
            d: &mut self.d[..n],
            v: &mut self.v[..n],
            w: &mut self.w[..n],
            lw: &mut self.lw[..n],
            rho: &self.rho[..n],
            e: self.e.map(|e| &e[..n]),
            ..self
        }
    }
}

/// Output of [`predict`]: prior weighted-mean velocities and the largest
/// log-weight.
pub(crate) struct Predicted {
    pub vo: f64,
    pub wo: f64,
    pub max: f64,
}

/// `max(x, MIN_LENGTH)` as a plain compare-select (NaN becomes MIN_LENGTH).
#[inline(always)]
fn clamp_len(x: f64) -> f64 {
    if x > MIN_LENGTH {
        x
    } else {
        MIN_LENGTH
    }
}

/// Running sums of the fused pass, one per lane: `[Σ ρ·V, Σ ρ·W, max
/// log-weight]`.
type PredictSums<const N: usize> = [[f64; N]; 3];

/// The fused pass over all particles: whole chunks of `LANES` particles, one
/// accumulator lane each, then the leftover particles on lane 0.
#[inline(always)]
fn predict_impl(a: Predict<'_>) -> Predicted {
    let mut a = a.cut();
    let n = a.rr.len();
    let rfix = (1.0 - a.obs) * a.ratio;
    let mut acc: PredictSums<LANES> = [[0.0; LANES], [0.0; LANES], [f64::NEG_INFINITY; LANES]];
    let full = n / LANES * LANES;
    for c in (0..full).step_by(LANES) {
        acc = predict_lanes(&mut a, rfix, c, acc);
    }
    for i in full..n {
        let lane0 = predict_lanes(&mut a, rfix, i, acc.map(|x| [x[0]]));
        for (x, l) in acc.iter_mut().zip(lane0) {
            x[0] = l[0];
        }
    }
    let [vo, wo, mx] = acc;
    Predicted {
        vo: vo.iter().sum(),
        wo: wo.iter().sum(),
        max: mx.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)),
    }
}

/// Predicts and weighs the `N` particles from index `c` on (eq. 2–4), one
/// per lane, and returns the running sums `acc` updated with them. Written
/// as whole-chunk operations so that the compiler vectorises them; `rfix` is
/// `(1 − obs)·ratio`.
#[inline(always)]
fn predict_lanes<const N: usize>(
    a: &mut Predict<'_>,
    rfix: f64,
    c: usize,
    acc: PredictSums<N>,
) -> PredictSums<N> {
    let (sr, sd, wr, wl, obs) = (a.sr, a.sd, a.wr, a.wl, a.obs);
    let (kv, zv, kw, zw) = (a.kv, a.zv, a.kw, a.zw);
    // Fixed-size views: no bounds check per lane.
    let rr: &mut [f64; N] = (&mut a.rr[c..c + N]).try_into().unwrap();
    let rl: &mut [f64; N] = (&mut a.rl[c..c + N]).try_into().unwrap();
    let d: &mut [f64; N] = (&mut a.d[c..c + N]).try_into().unwrap();
    let v: &mut [f64; N] = (&mut a.v[c..c + N]).try_into().unwrap();
    let w: &mut [f64; N] = (&mut a.w[c..c + N]).try_into().unwrap();
    let lw: &mut [f64; N] = (&mut a.lw[c..c + N]).try_into().unwrap();
    let rho: &[f64; N] = a.rho[c..c + N].try_into().unwrap();
    let e1: &[f64; N] = a.e[0][c..c + N].try_into().unwrap();
    let e2: &[f64; N] = a.e[1][c..c + N].try_into().unwrap();
    let e3: &[f64; N] = a.e[2][c..c + N].try_into().unwrap();
    let [vo, wo, mx] = acc;
    let aa: [f64; N] = std::array::from_fn(|l| clamp_len(rr[l] + sr * e1[l]));
    let b: [f64; N] = std::array::from_fn(|l| clamp_len(rl[l] + sr * e2[l]));
    let cc: [f64; N] = std::array::from_fn(|l| clamp_len(d[l] + sd * e3[l]));
    let x: [f64; N] = std::array::from_fn(|l| wr * aa[l]);
    let y: [f64; N] = std::array::from_fn(|l| wl * b[l]);
    let vi: [f64; N] = std::array::from_fn(|l| 0.5 * (x[l] + y[l]));
    let wi: [f64; N] =
        std::array::from_fn(|l| (x[l] - y[l]) / (rfix * (aa[l] + b[l]) + obs * cc[l]));
    let ev: [f64; N] = std::array::from_fn(|l| vi[l] - zv);
    let ew: [f64; N] = std::array::from_fn(|l| wi[l] - zw);
    let q: [f64; N] = std::array::from_fn(|l| lw[l] - kv * ev[l] * ev[l] - kw * ew[l] * ew[l]);
    *rr = aa;
    *rl = b;
    *d = cc;
    *v = vi;
    *w = wi;
    *lw = q;
    [
        std::array::from_fn(|l| vo[l] + rho[l] * vi[l]),
        std::array::from_fn(|l| wo[l] + rho[l] * wi[l]),
        std::array::from_fn(|l| if q[l] > mx[l] { q[l] } else { mx[l] }),
    ]
}

/// Inputs of the normalise-and-summarise passes.
pub(crate) struct Summarize<'a> {
    pub rr: &'a [f64],
    pub rl: &'a [f64],
    pub d: &'a [f64],
    pub v: &'a [f64],
    pub w: &'a [f64],
    /// Log-weights: shifted by `shift` in place (−∞ where the weight is 0).
    pub lw: &'a mut [f64],
    /// Receives the normalised weights `exp(lw − shift) / Σ`.
    pub buf: &'a mut [f64],
    pub shift: f64,
    /// All weights 1 (after an underflow reset).
    pub uniform: bool,
    /// Reference point subtracted from (R_R, R_L, D) before the moments.
    pub r: [f64; 3],
}

/// Output of [`summarize`]: sum, sum of squares and maximum of the
/// unnormalised weights; normalised-weight means of (R_R, R_L, D) − r, V, W;
/// normalised-weight products of the shifted parameters (rr·rr, rr·rl,
/// rr·d, rl·rl, rl·d, d·d).
pub(crate) struct Sums {
    pub sum: f64,
    pub sq: f64,
    pub max: f64,
    pub s1: [f64; 5],
    pub s2: [f64; 6],
}

/// First pass: unnormalised weights, their sum, sum of squares and maximum,
/// and the weighted sums of V and W (5 accumulators: no register spills).
#[inline(always)]
fn weigh_impl(
    lw: &mut [f64],
    buf: &mut [f64],
    v: &[f64],
    w: &[f64],
    shift: f64,
    uniform: bool,
) -> [f64; 5] {
    let n = lw.len();
    let (buf, v, w) = (&mut buf[..n], &v[..n], &w[..n]);
    let mut sum = [0.0f64; LANES];
    let mut sq = [0.0f64; LANES];
    let mut max = [0.0f64; LANES];
    let mut sv = [0.0f64; LANES];
    let mut sw = [0.0f64; LANES];
    // Element-wise exponentials first (a plain loop the compiler vectorises,
    // exp included), then the reductions over the buffer.
    if uniform {
        lw.iter_mut().for_each(|x| *x -= shift);
        buf.fill(1.0);
    } else {
        for i in 0..n {
            let x = lw[i] - shift;
            let e = fast_exp(x);
            lw[i] = if e > 0.0 { x } else { f64::NEG_INFINITY };
            buf[i] = e;
        }
    }
    let full = n / LANES * LANES;
    for c in (0..full).step_by(LANES) {
        let e: &[f64; LANES] = buf[c..c + LANES].try_into().unwrap();
        let v: &[f64; LANES] = v[c..c + LANES].try_into().unwrap();
        let w: &[f64; LANES] = w[c..c + LANES].try_into().unwrap();
        sum = std::array::from_fn(|l| sum[l] + e[l]);
        sq = std::array::from_fn(|l| sq[l] + e[l] * e[l]);
        max = std::array::from_fn(|l| if e[l] > max[l] { e[l] } else { max[l] });
        sv = std::array::from_fn(|l| sv[l] + e[l] * v[l]);
        sw = std::array::from_fn(|l| sw[l] + e[l] * w[l]);
    }
    for i in full..n {
        let e = buf[i];
        sum[0] += e;
        sq[0] += e * e;
        max[0] = if e > max[0] { e } else { max[0] };
        sv[0] += e * v[i];
        sw[0] += e * w[i];
    }
    let fold = |x: &[f64; LANES]| x.iter().sum::<f64>();
    [
        fold(&sum),
        fold(&sq),
        max.iter().fold(0.0f64, |a, &b| a.max(b)),
        fold(&sv),
        fold(&sw),
    ]
}

/// Second pass: scales the weights by `inv` (normalises them) and takes the
/// weighted first and second moments of the shifted parameters (9
/// accumulators).
#[inline(always)]
fn moments_impl(
    buf: &mut [f64],
    rr: &[f64],
    rl: &[f64],
    d: &[f64],
    r: [f64; 3],
    inv: f64,
) -> ([f64; 3], [f64; 6]) {
    let n = buf.len();
    let (rr, rl, d) = (&rr[..n], &rl[..n], &d[..n]);
    let mut s1 = [[0.0f64; LANES]; 3];
    let mut s2 = [[0.0f64; LANES]; 6];
    let full = n / LANES * LANES;
    for c in (0..full).step_by(LANES) {
        let buf: &mut [f64; LANES] = (&mut buf[c..c + LANES]).try_into().unwrap();
        let rr: &[f64; LANES] = rr[c..c + LANES].try_into().unwrap();
        let rl: &[f64; LANES] = rl[c..c + LANES].try_into().unwrap();
        let d: &[f64; LANES] = d[c..c + LANES].try_into().unwrap();
        let e: [f64; LANES] = std::array::from_fn(|l| buf[l] * inv);
        *buf = e;
        let a: [f64; LANES] = std::array::from_fn(|l| rr[l] - r[0]);
        let b: [f64; LANES] = std::array::from_fn(|l| rl[l] - r[1]);
        let cc: [f64; LANES] = std::array::from_fn(|l| d[l] - r[2]);
        let ea: [f64; LANES] = std::array::from_fn(|l| e[l] * a[l]);
        let eb: [f64; LANES] = std::array::from_fn(|l| e[l] * b[l]);
        let ec: [f64; LANES] = std::array::from_fn(|l| e[l] * cc[l]);
        s1[0] = std::array::from_fn(|l| s1[0][l] + ea[l]);
        s1[1] = std::array::from_fn(|l| s1[1][l] + eb[l]);
        s1[2] = std::array::from_fn(|l| s1[2][l] + ec[l]);
        s2[0] = std::array::from_fn(|l| s2[0][l] + ea[l] * a[l]);
        s2[1] = std::array::from_fn(|l| s2[1][l] + ea[l] * b[l]);
        s2[2] = std::array::from_fn(|l| s2[2][l] + ea[l] * cc[l]);
        s2[3] = std::array::from_fn(|l| s2[3][l] + eb[l] * b[l]);
        s2[4] = std::array::from_fn(|l| s2[4][l] + eb[l] * cc[l]);
        s2[5] = std::array::from_fn(|l| s2[5][l] + ec[l] * cc[l]);
    }
    for i in full..n {
        let e = buf[i] * inv;
        buf[i] = e;
        let (a, b, c) = (rr[i] - r[0], rl[i] - r[1], d[i] - r[2]);
        let (ea, eb, ec) = (e * a, e * b, e * c);
        s1[0][0] += ea;
        s1[1][0] += eb;
        s1[2][0] += ec;
        s2[0][0] += ea * a;
        s2[1][0] += ea * b;
        s2[2][0] += ea * c;
        s2[3][0] += eb * b;
        s2[4][0] += eb * c;
        s2[5][0] += ec * c;
    }
    let fold = |x: &[f64; LANES]| x.iter().sum::<f64>();
    (
        std::array::from_fn(|k| fold(&s1[k])),
        std::array::from_fn(|k| fold(&s2[k])),
    )
}

#[inline(always)]
fn summarize_impl(a: Summarize<'_>) -> Sums {
    let n = a.rr.len();
    let (lw, buf) = (&mut a.lw[..n], &mut a.buf[..n]);
    let [sum, sq, max, sv, sw] = weigh_impl(lw, buf, a.v, a.w, a.shift, a.uniform);
    let inv = 1.0 / sum;
    let (m, s2) = moments_impl(buf, a.rr, a.rl, a.d, a.r, inv);
    Sums {
        sum,
        sq,
        max,
        s1: [m[0], m[1], m[2], sv * inv, sw * inv],
        s2,
    }
}

/// Inputs of the resampling move: particle k takes ancestor `anc[k]`'s
/// parameters θ and becomes `max(a·θ + c + L·ε_k, MIN_LENGTH)` (\[LiuWest2001\];
/// `l` = the lower triangle of L row by row, `ε_k` from `e`).
pub(crate) struct GatherMove<'a> {
    pub anc: &'a [usize],
    pub src: [&'a [f64]; 3],
    pub dst: [&'a mut [f64]; 3],
    pub e: [&'a [f64]; 3],
    pub a: f64,
    pub c: [f64; 3],
    pub l: [f64; 6],
}

#[inline(always)]
fn gather_move_impl(g: GatherMove<'_>) {
    let GatherMove {
        anc,
        src: [srr, srl, sd],
        dst: [rr, rl, d],
        e: [e1, e2, e3],
        a,
        c,
        l,
    } = g;
    let n = anc.len();
    let (rr, rl, d) = (&mut rr[..n], &mut rl[..n], &mut d[..n]);
    let (e1, e2, e3) = (&e1[..n], &e2[..n], &e3[..n]);
    // Gather (scalar loads), then move in place (a vectorised loop).
    for k in 0..n {
        let i = anc[k];
        rr[k] = srr[i];
        rl[k] = srl[i];
        d[k] = sd[i];
    }
    for k in 0..n {
        let j0 = l[0] * e1[k];
        let j1 = l[1] * e1[k] + l[2] * e2[k];
        let j2 = l[3] * e1[k] + l[4] * e2[k] + l[5] * e3[k];
        rr[k] = (a * rr[k] + c[0] + j0).max(MIN_LENGTH);
        rl[k] = (a * rl[k] + c[1] + j1).max(MIN_LENGTH);
        d[k] = (a * d[k] + c[2] + j2).max(MIN_LENGTH);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gather_move_avx2(g: GatherMove<'_>) {
    gather_move_impl(g)
}

/// Gathers the ancestors' parameters and applies the resampling move.
pub(crate) fn gather_move(g: GatherMove<'_>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        return unsafe { gather_move_avx2(g) };
    }
    gather_move_impl(g)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn predict_avx2(a: Predict<'_>) -> Predicted {
    predict_impl(a)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn summarize_avx2(a: Summarize<'_>) -> Sums {
    summarize_impl(a)
}

/// Random walk, V and W from the wheel rates, log-likelihood, in one pass.
pub(crate) fn predict(a: Predict<'_>) -> Predicted {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        return unsafe { predict_avx2(a) };
    }
    predict_impl(a)
}

/// Normalised weights from log-weights and the weighted moments, in two
/// passes (split so that neither runs out of vector registers).
pub(crate) fn summarize(a: Summarize<'_>) -> Sums {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        return unsafe { summarize_avx2(a) };
    }
    summarize_impl(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One noise-free predict pass over particles (R_R, R_L, D) with wheel
    /// rates 3 and 2.5 rad/s and a W measurement `zw`: (W, log-weights),
    /// through the scalar pass or the dispatched (AVX2) one.
    fn pass(
        p: &[[f64; 3]],
        obs: f64,
        ratio: f64,
        zw: f64,
        dispatched: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = p.len();
        let (mut rr, mut rl, mut d): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            p.iter().map(|x| x[0]).collect(),
            p.iter().map(|x| x[1]).collect(),
            p.iter().map(|x| x[2]).collect(),
        );
        let (mut v, mut w, mut lw) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let rho = vec![1.0 / n as f64; n];
        let zero = vec![0.0; n];
        let a = Predict {
            rr: &mut rr,
            rl: &mut rl,
            d: &mut d,
            v: &mut v,
            w: &mut w,
            lw: &mut lw,
            rho: &rho,
            e: [&zero, &zero, &zero],
            wr: 3.0,
            wl: 2.5,
            sr: 0.0,
            sd: 0.0,
            obs,
            ratio,
            kv: 0.0,
            zv: 0.0,
            kw: 1.0,
            zw,
        };
        if dispatched {
            predict(a);
        } else {
            predict_impl(a);
        }
        (w, lw)
    }

    #[test]
    fn a_common_scale_of_radii_and_wheel_base_never_changes_w() {
        // Particles on the ray k·(R_R, R_L, D) through the belief: the full
        // model (obs = 1), the straight-run model (obs = 0) and anything
        // between predict the same W all along it, in both passes bit for
        // bit: W cannot see the scale, whatever D's observability.
        let (r, l, dd) = (0.32, 0.33, 0.65);
        let ray: Vec<[f64; 3]> = [0.97, 0.98, 0.99, 1.0, 1.01, 1.02, 1.03, 1.04, 1.05]
            .iter()
            .map(|k| [k * r, k * l, k * dd])
            .collect();
        let expected = (3.0 * r - 2.5 * l) / dd;
        for obs in [0.0, 0.3, 1.0] {
            let (scalar, _) = pass(&ray, obs, dd / (r + l), 0.1, false);
            let (wide, _) = pass(&ray, obs, dd / (r + l), 0.1, true);
            assert_eq!(scalar, wide, "scalar and dispatched passes differ");
            for w in scalar {
                assert!(
                    (w - expected).abs() < 1e-12,
                    "obs {obs}: W {w} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn an_unobservable_wheel_base_is_not_selected_on() {
        // Same radii, different D: at obs = 0 every particle predicts the
        // same W (no weight difference from D); at obs = 1 W follows 1/D.
        let ds = [0.6, 0.65, 0.7, 0.75];
        let p: Vec<[f64; 3]> = ds.iter().map(|&d| [0.32, 0.33, d]).collect();
        let (w0, lw0) = pass(&p, 0.0, 1.0, 0.0, true);
        assert!(w0.iter().all(|&x| x == w0[0]) && lw0.iter().all(|&x| x == lw0[0]));
        let (w1, _) = pass(&p, 1.0, 1.0, 0.0, true);
        for (x, d) in w1.iter().zip(ds) {
            assert!((x - (3.0 * 0.32 - 2.5 * 0.33) / d).abs() < 1e-12);
        }
    }

    /// |a − b| within 1e-12 of b's scale (the weights' fast_exp is within
    /// 2e-13 of exp).
    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + b.abs())
    }

    /// Seven particles (one chunk of four lanes and three on lane 0) through
    /// one predict pass with noise, a likelihood on both V and W and D
    /// half observable: the columns after it and the pass's output.
    fn predict_seven(dispatched: bool) -> ([Vec<f64>; 6], Predicted) {
        let mut rr = vec![0.30, 0.25, 0.30, 0.20, 0.30, 0.25, 0.35];
        let mut rl = vec![0.25, 0.30, 0.30, 0.25, 0.01, 0.25, 0.30];
        let mut d = vec![0.50, 0.60, 0.50, 0.40, 0.50, 0.50, 0.60];
        let e1 = [1.0, 0.0, -2.0, 0.5, 0.0, 4.0, -1.0];
        let e2 = [0.0, 2.0, 1.0, -0.5, -3.0, 0.0, -1.0];
        let e3 = [0.0, -1.0, 3.0, 2.0, 0.0, -4.0, 1.0];
        let mut lw = vec![0.0, -1.0, -0.5, 1.0, 0.0, -2.0, 0.5];
        let rho = [0.125, 0.125, 0.25, 0.0625, 0.0625, 0.25, 0.125];
        let (mut v, mut w) = (vec![9.0; 7], vec![9.0; 7]);
        let a = Predict {
            rr: &mut rr,
            rl: &mut rl,
            d: &mut d,
            v: &mut v,
            w: &mut w,
            lw: &mut lw,
            rho: &rho,
            e: [&e1, &e2, &e3],
            wr: 4.0,
            wl: 2.0,
            sr: 0.01,
            sd: 0.02,
            obs: 0.5,
            ratio: 2.0,
            kv: 2.0,
            zv: 0.5,
            kw: 3.0,
            zw: 1.0,
        };
        let out = if dispatched {
            predict(a)
        } else {
            predict_impl(a)
        };
        ([rr, rl, d, v, w, lw], out)
    }

    #[test]
    fn predict_walks_the_parameters_and_weighs_v_and_w_of_every_particle() {
        // By hand, particle by particle: R_R + 0.01 e1, R_L + 0.01 e2,
        // D + 0.02 e3 (particle 4's R_L, 0.01 − 0.03, stops at 1e-6 m);
        // V = (4 R_R + 2 R_L) / 2; W = (4 R_R − 2 R_L) / B with the wheel
        // base B = 0.5 D + (1 − 0.5)·2·(R_R + R_L); the log-weight loses
        // 2 (V − 0.5)² + 3 (W − 1)².
        let want: [[f64; 6]; 7] = [
            [0.31, 0.25, 0.50, 0.87, 74.0 / 81.0, -3239003.0 / 10935000.0],
            [0.25, 0.32, 0.58, 0.82, 18.0 / 43.0, -2564172.0 / 1155625.0],
            [
                0.28,
                0.31,
                0.56,
                0.87,
                50.0 / 87.0,
                -16606487.0 / 12615000.0,
            ],
            [
                0.205,
                0.245,
                0.44,
                0.655,
                33.0 / 67.0,
                16106071.0 / 89780000.0,
            ],
            [
                0.30,
                1e-6,
                0.50,
                0.600001,
                1199998.0 / 550001.0,
                -4.210029130551442,
            ],
            [0.29, 0.25, 0.42, 0.83, 0.88, -2.261],
            [0.34, 0.29, 0.62, 0.97, 39.0 / 47.0, -317181.0 / 11045000.0],
        ];
        for dispatched in [false, true] {
            let (cols, out) = predict_seven(dispatched);
            for (i, row) in want.iter().enumerate() {
                for (k, &x) in row.iter().enumerate() {
                    assert!(
                        close(cols[k][i], x),
                        "dispatched {dispatched}, particle {i}, column {k}: {} vs {x}",
                        cols[k][i]
                    );
                }
            }
            // Σ ρ V = 0.8359375625 and Σ ρ W by hand from the rows above;
            // the largest log-weight is particle 3's.
            assert!(close(out.vo, 0.8359375625), "{}", out.vo);
            assert!(close(out.wo, 0.8010714206818468), "{}", out.wo);
            assert!(close(out.max, 16106071.0 / 89780000.0), "{}", out.max);
        }
        let (a, b) = (predict_seven(false), predict_seven(true));
        assert_eq!(a.0, b.0, "scalar and dispatched passes differ");
        assert_eq!((a.1.vo, a.1.wo, a.1.max), (b.1.vo, b.1.wo, b.1.max));
    }

    /// Seven particles' columns for the summarising passes: V, W and
    /// (R_R, R_L, D) around the reference (0.3, 0.3, 0.6).
    const V7: [f64; 7] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
    const W7: [f64; 7] = [0.5, -1.0, 2.0, 0.0, 1.0, 3.0, 10.0];
    const RR7: [f64; 7] = [0.31, 0.29, 0.27, 0.32, 0.34, 0.28, 0.90];
    const RL7: [f64; 7] = [0.33, 0.26, 0.31, 0.29, 0.27, 0.35, 0.90];
    const D7: [f64; 7] = [0.62, 0.57, 0.58, 0.61, 0.65, 0.59, 0.90];

    /// `summarize` on the seven particles with unnormalised weights
    /// `weights` (0 as a log-weight 800 below the shift, which underflows):
    /// the sums and the log-weights and weights left in place.
    fn summarize_seven(
        weights: [f64; 7],
        uniform: bool,
        dispatched: bool,
    ) -> (Sums, Vec<f64>, Vec<f64>) {
        let shift = 3.0;
        let mut lw: Vec<f64> = weights
            .iter()
            .map(|&e| {
                if e > 0.0 {
                    shift + e.ln()
                } else {
                    shift - 800.0
                }
            })
            .collect();
        let mut buf = vec![f64::NAN; 7];
        let a = Summarize {
            rr: &RR7,
            rl: &RL7,
            d: &D7,
            v: &V7,
            w: &W7,
            lw: &mut lw,
            buf: &mut buf,
            shift,
            uniform,
            r: [0.3, 0.3, 0.6],
        };
        let s = if dispatched {
            summarize(a)
        } else {
            summarize_impl(a)
        };
        (s, lw, buf)
    }

    #[test]
    fn summarize_normalises_the_weights_and_takes_their_moments() {
        // Weights 1, 1/2, 4, 2 | 1/4, 1/8, 0: Σ = 63/8, Σ² = 1365/64, the
        // largest 4 (in the chunk of four lanes). Normalised: 8, 4, 32, 16,
        // 2, 1, 0 (/63). Means of V and W: 192/63 = 64/21 and 69/63 = 23/21;
        // of R_R − 0.3 = (8·1 − 4·1 − 32·3 + 16·2 + 2·4 − 1·2)/6300 = −3/350,
        // and so on for R_L and D; the products likewise, all by hand over 63.
        let weights = [1.0, 0.5, 4.0, 2.0, 0.25, 0.125, 0.0];
        for dispatched in [false, true] {
            let (s, lw, buf) = summarize_seven(weights, false, dispatched);
            assert!(
                close(s.sum, 7.875) && close(s.sq, 1365.0 / 64.0),
                "{} {}",
                s.sum,
                s.sq
            );
            assert!(close(s.max, 4.0), "{}", s.max);
            let s1 = [
                -3.0 / 350.0,
                23.0 / 6300.0,
                -1.0 / 180.0,
                64.0 / 21.0,
                23.0 / 21.0,
            ];
            for k in 0..5 {
                assert!(close(s.s1[k], s1[k]), "s1[{k}] {} vs {}", s.s1[k], s1[k]);
            }
            let s2 = [
                1.0 / 1575.0,
                -61.0 / 315000.0,
                7.0 / 15000.0,
                227.0 / 630000.0,
                -19.0 / 630000.0,
                263.0 / 630000.0,
            ];
            for k in 0..6 {
                assert!(
                    (s.s2[k] - s2[k]).abs() < 1e-15,
                    "s2[{k}] {} vs {}",
                    s.s2[k],
                    s2[k]
                );
            }
            // In place: the normalised weights, the log-weights less the
            // shift, and −∞ where the weight underflowed to 0.
            let norm = [8.0, 4.0, 32.0, 16.0, 2.0, 1.0, 0.0];
            for i in 0..7 {
                assert!(close(buf[i], norm[i] / 63.0), "buf[{i}] {}", buf[i]);
            }
            for i in 0..6 {
                assert!(close(lw[i], weights[i].ln()), "lw[{i}] {}", lw[i]);
            }
            assert_eq!(lw[6], f64::NEG_INFINITY);
        }
    }

    #[test]
    fn the_largest_weight_is_found_on_the_leftover_lane_too() {
        // The same weights with 4 moved to particle 4, after the chunk.
        let weights = [1.0, 0.5, 0.25, 2.0, 4.0, 0.125, 0.0];
        for dispatched in [false, true] {
            let (s, _, _) = summarize_seven(weights, false, dispatched);
            assert!(
                close(s.max, 4.0) && close(s.sum, 7.875),
                "{} {}",
                s.max,
                s.sum
            );
        }
    }

    #[test]
    fn uniform_weights_are_all_one_and_still_shift_the_log_weights() {
        // After an underflow reset every weight is 1 (Σ = Σ² = 7, largest 1):
        // the means are the plain means, V's 4 and W's 15.5/7.
        for dispatched in [false, true] {
            let (s, lw, buf) = summarize_seven([1.0; 7], true, dispatched);
            assert!(close(s.sum, 7.0) && close(s.sq, 7.0) && close(s.max, 1.0));
            assert!(
                close(s.s1[3], 4.0) && close(s.s1[4], 15.5 / 7.0),
                "{:?}",
                s.s1
            );
            // R_R − 0.3: (1 − 1 − 3 + 2 + 4 − 2 + 60)/700 = 61/700.
            assert!(close(s.s1[0], 61.0 / 700.0), "{}", s.s1[0]);
            assert!(buf.iter().all(|&x| close(x, 1.0 / 7.0)), "{buf:?}");
            // Log-weights 3 (= shift + ln 1) less the shift 3.
            assert!(lw.iter().all(|&x| x.abs() < 1e-15), "{lw:?}");
        }
    }

    /// The resampling move on six particles drawn from four (ancestors
    /// 0, 1, 1, 3, 3, 3), through the scalar or the dispatched pass.
    fn gather_six(dispatched: bool) -> [Vec<f64>; 3] {
        let src = [
            [0.30, 0.32, 0.28, 0.31],
            [0.33, 0.29, 0.30, 0.34],
            [0.60, 0.62, 0.58, 0.64],
        ];
        let anc = [0, 1, 1, 3, 3, 3];
        let e1 = [1.0, -2.0, 0.5, 3.0, -1.0, 2.0];
        let e2 = [2.0, 1.0, -3.0, 0.5, 4.0, -1.0];
        let e3 = [-1.0, 3.0, 2.0, -2.0, 0.5, -40.0];
        let (mut rr, mut rl, mut d) = (vec![0.0; 6], vec![0.0; 6], vec![0.0; 6]);
        let g = GatherMove {
            anc: &anc,
            src: [&src[0], &src[1], &src[2]],
            dst: [&mut rr, &mut rl, &mut d],
            e: [&e1, &e2, &e3],
            a: 0.5,
            c: [0.15, 0.15, 0.3],
            l: [0.01, 0.002, 0.02, 0.003, 0.004, 0.05],
        };
        if dispatched {
            gather_move(g);
        } else {
            gather_move_impl(g);
        }
        [rr, rl, d]
    }

    #[test]
    fn gather_move_shrinks_the_ancestors_and_adds_the_correlated_jitter() {
        // θ = 0.5 θ_ancestor + c + L ε with L = [[0.01], [0.002, 0.02],
        // [0.003, 0.004, 0.05]]: particle 0 (ancestor 0, ε = (1, 2, −1)):
        // R_R = 0.15 + 0.15 + 0.01 = 0.31, R_L = 0.165 + 0.15 + 0.002 + 0.04
        // = 0.357, D = 0.3 + 0.3 + 0.003 + 0.008 − 0.05 = 0.561; particle 5's
        // D (ε₃ = −40) would be −1.378 and stops at 1e-6 m.
        let want = [
            [0.31, 0.29, 0.315, 0.335, 0.295, 0.325],
            [0.357, 0.311, 0.236, 0.336, 0.398, 0.304],
            [0.561, 0.758, 0.6995, 0.531, 0.658, 1e-6],
        ];
        for dispatched in [false, true] {
            let got = gather_six(dispatched);
            for k in 0..3 {
                for i in 0..6 {
                    assert!(
                        close(got[k][i], want[k][i]),
                        "dispatched {dispatched}, column {k}, particle {i}: {} vs {}",
                        got[k][i],
                        want[k][i]
                    );
                }
            }
        }
    }
}
