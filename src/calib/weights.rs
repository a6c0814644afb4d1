//! Particle weights kept as log-weights; normalised weights, the effective
//! sample size and the largest weight are derived once per step with a
//! log-sum-exp, so no product of likelihoods ever underflows to a silent 0/0.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Log-weights of a particle set and what is derived from them.
#[derive(Debug, Clone, Default)]
pub struct Weights {
    log: Vec<f64>,
    norm: Vec<f64>,
    ess: f64,
    max: f64,
    reset: bool,
}

impl Weights {
    /// `n` equal weights.
    pub fn uniform(n: usize) -> Self {
        let mut w = Self::default();
        w.reset_uniform(n);
        w
    }

    /// Weights from log-weights (normalised at once).
    pub fn from_log(log: &[f64]) -> Self {
        let mut w = Self {
            log: log.to_vec(),
            ..Self::default()
        };
        w.normalize();
        w
    }

    /// Sets `n` equal weights (keeps the allocations).
    pub fn reset_uniform(&mut self, n: usize) {
        self.log.clear();
        self.log.resize(n, 0.0);
        self.norm.clear();
        self.norm.resize(n, 1.0 / n.max(1) as f64);
        self.ess = n as f64;
        self.max = 1.0 / n.max(1) as f64;
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.log.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.log.is_empty()
    }

    /// Log-weights to add log-likelihoods into; call [`Weights::normalize`] after.
    pub fn log_mut(&mut self) -> &mut [f64] {
        &mut self.log
    }

    /// The log-weights.
    pub fn log(&self) -> &[f64] {
        &self.log
    }

    /// Normalises: NaN log-weights become −∞; if every log-weight is −∞ (all
    /// likelihoods underflowed, or all NaN) the weights are reset to uniform
    /// and [`Weights::was_reset`] reports it. Afterwards the log-weights are
    /// shifted so that the largest is 0 (keeps them in range forever).
    pub fn normalize(&mut self) {
        let n = self.log.len();
        self.norm.resize(n, 0.0);
        self.reset = false;
        if n == 0 {
            self.ess = 0.0;
            self.max = 0.0;
            return;
        }
        let mut m = f64::NEG_INFINITY;
        for l in self.log.iter_mut() {
            if l.is_nan() || *l == f64::INFINITY {
                // +∞ cannot come from a density with σ > 0: treat as invalid.
                *l = f64::NEG_INFINITY;
            }
            m = m.max(*l);
        }
        if m == f64::NEG_INFINITY {
            self.reset_uniform(n);
            self.reset = true;
            return;
        }
        let mut sum = 0.0;
        for (l, w) in self.log.iter_mut().zip(self.norm.iter_mut()) {
            *l -= m;
            *w = fast_exp(*l);
            sum += *w;
        }
        let inv = 1.0 / sum;
        let mut sq = 0.0;
        let mut mx = 0.0f64;
        for w in self.norm.iter_mut() {
            *w *= inv;
            sq += *w * *w;
            mx = mx.max(*w);
        }
        self.ess = 1.0 / sq;
        self.max = mx;
    }

    /// The log-weights and the weight buffer together, for fused passes that
    /// write the normalised `exp(log − max) / Σ` into the buffer and then
    /// call [`Weights::finish`].
    pub(crate) fn parts_mut(&mut self) -> (&mut [f64], &mut Vec<f64>) {
        (&mut self.log, &mut self.norm)
    }

    /// Completes a fused normalisation: the buffer already holds the
    /// normalised weights of unnormalised ones with sum `sum`, sum of squares
    /// `sq` and largest `max` (all finite, positive sum); records N_eff, the
    /// largest weight and whether the pass had to reset them.
    pub(crate) fn finish(&mut self, sum: f64, sq: f64, max: f64, reset: bool) {
        let inv = 1.0 / sum;
        self.ess = sum * sum / sq;
        self.max = max * inv;
        self.reset = reset;
    }

    /// Resets to uniform after a fused pass found no finite log-weight.
    pub(crate) fn reset_after_underflow(&mut self) {
        self.reset_uniform(self.log.len());
        self.reset = true;
    }

    /// Normalised weights (sum 1), valid after [`Weights::normalize`].
    pub fn normalized(&self) -> &[f64] {
        &self.norm
    }

    /// Effective sample size `N_eff = 1 / Σ ρ_i²` [Farina, eq. 10].
    pub fn ess(&self) -> f64 {
        self.ess
    }

    /// Largest normalised weight.
    pub fn max_weight(&self) -> f64 {
        self.max
    }

    /// Whether the last normalisation found no finite log-weight and reset.
    pub fn was_reset(&self) -> bool {
        self.reset
    }
}

/// `exp(x)` for `x ≤ 0` (log-weights shifted by their maximum), relative error
/// below 2e-13, branch-light so the normalisation loop vectorises; underflows
/// to exactly 0 below −708.
#[inline(always)]
pub fn fast_exp(x: f64) -> f64 {
    // exp(x) = 2^k · exp(r), r = x − k ln2 ∈ [−ln2/2, ln2/2]; k is rounded
    // with the 1.5·2^52 trick (no libm call, so the loops vectorise).
    const LOG2E: f64 = std::f64::consts::LOG2_E;
    #[allow(clippy::excessive_precision)]
    const LN2_HI: f64 = 6.931_471_803_691_238_2e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let ok = x > -708.0;
    let xc = if ok { x } else { -708.0 };
    let t = xc * LOG2E + SHIFT;
    let k = t - SHIFT;
    let r = (xc - k * LN2_HI) - k * LN2_LO;
    // Taylor to degree 11 on |r| ≤ 0.347: truncation < 1e-15.
    let mut p = 1.0 / 39_916_800.0;
    p = p * r + 1.0 / 3_628_800.0;
    p = p * r + 1.0 / 362_880.0;
    p = p * r + 1.0 / 40_320.0;
    p = p * r + 1.0 / 5_040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    // The low bits of t hold k (two's complement, |k| ≤ 1022 here).
    let ki = t.to_bits().wrapping_sub(SHIFT.to_bits());
    let bits = ki.wrapping_add(1023) << 52;
    let y = p * f64::from_bits(bits);
    if ok {
        y
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_exp_matches_std() {
        let mut x = -707.9;
        while x <= 0.0 {
            let (a, b) = (fast_exp(x), x.exp());
            assert!(((a - b) / b).abs() < 2e-13, "{x}: {a} vs {b}");
            x += 0.0137;
        }
        assert_eq!(fast_exp(-1000.0), 0.0);
        assert_eq!(fast_exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(fast_exp(0.0), 1.0);
    }

    #[test]
    fn normalises_with_log_sum_exp_and_reports_ess() {
        let w = Weights::from_log(&[-1000.0, -1000.0 + 2f64.ln(), f64::NAN, -1000.0]);
        let n = w.normalized();
        assert!((n[0] - 0.25).abs() < 1e-12 && (n[1] - 0.5).abs() < 1e-12);
        assert_eq!(n[2], 0.0);
        assert!((w.ess() - 1.0 / (0.0625 * 2.0 + 0.25)).abs() < 1e-9);
        assert!((w.max_weight() - 0.5).abs() < 1e-12);
        assert!(!w.was_reset());
    }

    #[test]
    fn all_underflowed_weights_reset_to_uniform() {
        let mut w = Weights::from_log(&[f64::NEG_INFINITY, f64::NAN, f64::NEG_INFINITY]);
        assert!(w.was_reset());
        assert!(w
            .normalized()
            .iter()
            .all(|&x| (x - 1.0 / 3.0).abs() < 1e-15));
        assert_eq!(w.ess(), 3.0);
        w.log_mut()
            .copy_from_slice(&[f64::NEG_INFINITY, -5.0, f64::NEG_INFINITY]);
        w.normalize();
        assert!(!w.was_reset());
        assert_eq!(w.normalized()[1], 1.0);
        assert!(w.log().iter().all(|l| !l.is_nan()));
    }
}
