//! Resampling schemes with one contract: normalised weights in, ancestor
//! indices out. All four end in one shared inverse CDF over sorted uniforms,
//! so each is O(N) ([Farina, Sec. IV.B]; the layout of Chopin's `particles` \[Chopin2020\]).

use rand::{Rng, RngExt};
use rand_distr::{Distribution, Exp1};
use serde::{Deserialize, Serialize};

/// How ancestors are drawn from the weights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// N independent uniforms (eq. 7).
    Multinomial,
    /// One uniform in each of N strata.
    Stratified,
    /// One uniform, N evenly spaced points (eq. 8).
    #[default]
    Systematic,
    /// `floor(N ρ_i)` deterministic copies, the rest multinomial on the residuals (eq. 9).
    Residual,
}

impl Scheme {
    /// Every scheme, in the order of the paper's Table I.
    pub const ALL: [Scheme; 4] = [
        Scheme::Multinomial,
        Scheme::Stratified,
        Scheme::Systematic,
        Scheme::Residual,
    ];

    /// The name used on the command line and in tables.
    pub fn as_str(&self) -> &'static str {
        match self {
            Self::Multinomial => "multinomial",
            Self::Stratified => "stratified",
            Self::Systematic => "systematic",
            Self::Residual => "residual",
        }
    }
}

impl std::str::FromStr for Scheme {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|x| x.as_str() == s)
            .ok_or_else(|| {
                format!("unknown resampler {s:?} (multinomial|stratified|systematic|residual)")
            })
    }
}

/// Appends to `out` the ancestor of each sorted uniform `su[k] ∈ [0, 1)`: the
/// smallest index whose cumulative weight exceeds it. Never returns a
/// particle of weight 0. `w` must be non-empty with a positive sum ≈ 1.
pub fn inverse_cdf(su: &[f64], w: &[f64], out: &mut Vec<usize>) {
    let last = w.iter().rposition(|&x| x > 0.0).unwrap_or(w.len() - 1);
    let mut j = 0usize;
    let mut c = w[0];
    for &u in su {
        while c <= u && j < last {
            j += 1;
            c += w[j];
        }
        out.push(j);
    }
}

/// [`inverse_cdf`] of the evenly spaced points `(k + u)/n`, k < n, computed
/// on the fly (no buffer of uniforms).
fn systematic(u: f64, n: usize, w: &[f64], out: &mut Vec<usize>) {
    let last = w.iter().rposition(|&x| x > 0.0).unwrap_or(w.len() - 1);
    let inv = 1.0 / n as f64;
    let mut j = 0usize;
    let mut c = w[0];
    let from = out.len();
    out.resize(from + n, 0);
    for (k, slot) in out[from..].iter_mut().enumerate() {
        let u = (k as f64 + u) * inv;
        while c <= u && j < last {
            j += 1;
            c += w[j];
        }
        *slot = j;
    }
}

/// Draws ancestors with a reusable scratch buffer (no allocation once warm).
#[derive(Debug, Clone, Default)]
pub struct Resampler {
    su: Vec<f64>,
    resid: Vec<f64>,
}

impl Resampler {
    /// An empty resampler.
    pub fn new() -> Self {
        Self::default()
    }

    /// Replaces `out` by `n` ancestor indices drawn from the normalised
    /// weights `w` with `scheme`. `n` may differ from `w.len()` (adaptive
    /// particle counts). `w` must be non-empty, non-negative, summing to ≈ 1.
    pub fn resample<R: Rng + ?Sized>(
        &mut self,
        scheme: Scheme,
        w: &[f64],
        n: usize,
        rng: &mut R,
        out: &mut Vec<usize>,
    ) {
        out.clear();
        if n == 0 || w.is_empty() {
            return;
        }
        out.reserve(n);
        match scheme {
            Scheme::Multinomial => {
                sorted_uniforms(n, rng, &mut self.su);
                inverse_cdf(&self.su, w, out);
            }
            Scheme::Systematic => {
                let u: f64 = rng.random();
                systematic(u, n, w, out);
            }
            Scheme::Stratified => {
                self.su.clear();
                let inv = 1.0 / n as f64;
                self.su
                    .extend((0..n).map(|k| (k as f64 + rng.random::<f64>()) * inv));
                inverse_cdf(&self.su, w, out);
            }
            Scheme::Residual => {
                self.resid.clear();
                let nf = n as f64;
                let mut copies = 0usize;
                for (i, &wi) in w.iter().enumerate() {
                    let x = nf * wi;
                    let k = x.floor();
                    for _ in 0..k as usize {
                        out.push(i);
                    }
                    copies += k as usize;
                    self.resid.push(x - k);
                }
                let rest = n.saturating_sub(copies);
                if rest > 0 {
                    let s: f64 = self.resid.iter().sum();
                    if s > 0.0 {
                        let inv = 1.0 / s;
                        self.resid.iter_mut().for_each(|r| *r *= inv);
                        sorted_uniforms(rest, rng, &mut self.su);
                        inverse_cdf(&self.su, &self.resid, out);
                    } else {
                        sorted_uniforms(rest, rng, &mut self.su);
                        inverse_cdf(&self.su, w, out);
                    }
                }
                out.truncate(n);
            }
        }
    }
}

/// `n` sorted independent uniforms in O(n): normalised cumulative sums of
/// n + 1 exponential spacings.
pub fn sorted_uniforms<R: Rng + ?Sized>(n: usize, rng: &mut R, su: &mut Vec<f64>) {
    su.clear();
    let mut acc = 0.0;
    for _ in 0..n {
        let e: f64 = Exp1.sample(rng);
        acc += e;
        su.push(acc);
    }
    let e: f64 = Exp1.sample(rng);
    let inv = 1.0 / (acc + e);
    su.iter_mut().for_each(|x| *x *= inv);
}

/// Convenience form of [`Resampler::resample`] that allocates its result.
pub fn resample<R: Rng + ?Sized>(scheme: Scheme, w: &[f64], n: usize, rng: &mut R) -> Vec<usize> {
    let mut out = Vec::with_capacity(n);
    Resampler::new().resample(scheme, w, n, rng, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn inverse_cdf_skips_zero_weights() {
        let mut out = vec![];
        inverse_cdf(&[0.0, 0.3, 0.5, 0.99], &[0.0, 0.5, 0.0, 0.5, 0.0], &mut out);
        assert_eq!(out, vec![1, 1, 3, 3]);
    }

    #[test]
    fn no_weights_or_no_draws_give_no_ancestors() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(5);
        for scheme in Scheme::ALL {
            assert!(resample(scheme, &[], 3, &mut rng).is_empty(), "{scheme:?}");
            assert!(
                resample(scheme, &[0.5, 0.5], 0, &mut rng).is_empty(),
                "{scheme:?}"
            );
        }
    }

    #[test]
    fn words_read_back() {
        for scheme in Scheme::ALL {
            assert_eq!(scheme.as_str().parse::<Scheme>().unwrap(), scheme);
        }
        assert!("uniform".parse::<Scheme>().is_err());
    }

    #[test]
    fn rounding_never_reaches_past_the_last_weighted_particle() {
        // Ten weights of 0.1 sum to 0.9999999999999999 in floating point, as
        // does the largest uniform below 1: the search stops at the last
        // particle with weight (9), not at the trailing zero (10), and never
        // past the end when nothing trails.
        let u = [1.0 - f64::EPSILON / 2.0];
        let mut w = vec![0.1; 10];
        assert!(w.iter().sum::<f64>() <= u[0]);
        let both = |w: &[f64]| {
            let (mut a, mut b) = (vec![], vec![]);
            inverse_cdf(&u, w, &mut a);
            systematic(u[0], 1, w, &mut b);
            (a, b)
        };
        assert_eq!(both(&w), (vec![9], vec![9]));
        w.push(0.0);
        assert_eq!(both(&w), (vec![9], vec![9]));
        // No weight at all (outside the contract): the last index, no panic.
        let mut out = vec![];
        inverse_cdf(&[0.5], &[0.0, 0.0], &mut out);
        assert_eq!(out, vec![1]);
        let mut out = vec![];
        systematic(0.5, 1, &[0.0, 0.0], &mut out);
        assert_eq!(out, vec![1]);
    }

    #[test]
    fn a_uniform_on_a_cumulative_boundary_goes_to_the_next_particle() {
        // Cumulative weights 0.25, 1.0: u = 0.25 is not below the first.
        let mut out = vec![];
        inverse_cdf(&[0.0, 0.25, 0.9], &[0.25, 0.75], &mut out);
        assert_eq!(out, vec![0, 1, 1]);
    }

    #[test]
    fn systematic_points_by_hand() {
        // u = 0.5, n = 4: points 0.125, 0.375, 0.625, 0.875 against the
        // cumulative weights 0.1, 0.3, 0.6, 1.0.
        let mut out = vec![7];
        systematic(0.5, 4, &[0.1, 0.2, 0.3, 0.4], &mut out);
        assert_eq!(out, vec![7, 1, 2, 3, 3], "appends after what is there");
        // n = 2 from four weights: 0.25, 0.75.
        let mut out = vec![];
        systematic(0.5, 2, &[0.1, 0.2, 0.3, 0.4], &mut out);
        assert_eq!(out, vec![1, 3]);
    }

    #[test]
    fn sorted_uniforms_are_sorted_in_the_unit_interval_with_mean_one_half() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut su = vec![9.0];
        sorted_uniforms(20_000, &mut rng, &mut su);
        assert_eq!(su.len(), 20_000);
        assert!(su.windows(2).all(|p| p[0] <= p[1]));
        assert!(su[0] > 0.0 && su[su.len() - 1] < 1.0);
        // Mean 1/2 with std 1/√(12·20000) = 0.002; the k-th of n sorted
        // uniforms has mean k/(n+1): the median sits at 1/2.
        let mean = su.iter().sum::<f64>() / su.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert!((su[9_999] - 0.5).abs() < 0.01, "{}", su[9_999]);
    }

    #[test]
    fn every_scheme_draws_each_particle_in_proportion_to_its_weight() {
        // 200 draws of n = 50 from weights 0.1…0.4: each count's mean is
        // n·w within 3 standard errors of the multinomial spread (at most
        // √(50·0.4·0.6)/√200 = 0.25); the low-variance schemes keep every
        // single count within one of n·w, and residual above its floor.
        let w = [0.1, 0.2, 0.3, 0.4];
        let n = 50;
        for scheme in Scheme::ALL {
            let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(11);
            let mut r = Resampler::new();
            let mut out = vec![];
            let mut total = [0usize; 4];
            for _ in 0..200 {
                r.resample(scheme, &w, n, &mut rng, &mut out);
                assert_eq!(out.len(), n, "{scheme:?}");
                let mut c = [0usize; 4];
                out.iter().for_each(|&i| c[i] += 1);
                for i in 0..4 {
                    total[i] += c[i];
                    let expect = n as f64 * w[i];
                    match scheme {
                        Scheme::Systematic | Scheme::Stratified => {
                            assert!(
                                (c[i] as f64 - expect).abs() <= 1.0 + 1e-9,
                                "{scheme:?} {c:?}"
                            )
                        }
                        Scheme::Residual => {
                            assert!(c[i] as f64 >= expect.floor() - 1e-9, "{scheme:?} {c:?}")
                        }
                        Scheme::Multinomial => {}
                    }
                }
            }
            for i in 0..4 {
                let mean = total[i] as f64 / 200.0;
                assert!(
                    (mean - n as f64 * w[i]).abs() < 0.75,
                    "{scheme:?} {i}: {mean}"
                );
            }
        }
    }

    #[test]
    fn systematic_is_deterministic_for_equal_weights() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(1);
        let w = vec![0.25; 4];
        assert_eq!(
            resample(Scheme::Systematic, &w, 4, &mut rng),
            vec![0, 1, 2, 3]
        );
        assert_eq!(
            resample(Scheme::Residual, &w, 8, &mut rng),
            vec![0, 0, 1, 1, 2, 2, 3, 3]
        );
    }

    #[test]
    fn residual_draws_the_fractions_in_proportion_after_the_whole_copies() {
        // n = 3 from 0.5, 0.3, 0.2: n·w = 1.5, 0.9, 0.6, so one whole copy of
        // particle 0, then two draws from the fractions 0.5, 0.9, 0.6
        // (normalised 0.25, 0.45, 0.30). Every draw holds particle 0 at least
        // once; the counts' means are n·w (the scheme is unbiased), within
        // 0.05 of them over 4000 draws (five standard errors: each count's
        // standard deviation is at most √(2·0.45·0.55) = 0.70).
        let w = [0.5, 0.3, 0.2];
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(17);
        let mut r = Resampler::new();
        let mut out = vec![];
        let mut total = [0usize; 3];
        for _ in 0..4000 {
            r.resample(Scheme::Residual, &w, 3, &mut rng, &mut out);
            assert_eq!(out.len(), 3);
            assert!(out.contains(&0), "{out:?}");
            out.iter().for_each(|&i| total[i] += 1);
        }
        for (i, want) in [1.5, 0.9, 0.6].into_iter().enumerate() {
            let mean = total[i] as f64 / 4000.0;
            assert!((mean - want).abs() < 0.05, "{i}: {mean} vs {want}");
        }
    }

    #[test]
    fn residual_with_only_whole_copies_draws_no_random_numbers() {
        // n·w = 2 for each of four equal weights: the copies are the whole
        // answer and the generator is left as it was.
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(23);
        let mut untouched = rng.clone();
        let out = resample(Scheme::Residual, &[0.25; 4], 8, &mut rng);
        assert_eq!(out, vec![0, 0, 1, 1, 2, 2, 3, 3]);
        assert_eq!(rng.next_u64(), untouched.next_u64());
    }

    #[test]
    fn residual_without_fractions_draws_the_rest_from_the_weights() {
        // Weights summing to one half (outside the contract) with n·w whole:
        // two copies of particle 1 leave two to draw and no fraction to draw
        // them from; they come from the weights, so never a particle of
        // weight 0.
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(29);
        let out = resample(Scheme::Residual, &[0.0, 0.5, 0.0], 4, &mut rng);
        assert_eq!(out, vec![1, 1, 1, 1]);
    }
}
