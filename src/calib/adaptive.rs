//! The Adaptive-PF rules [Farina, Sec. V]: the particle count follows the
//! dispersion of the radius particles, and the process noise follows the
//! disagreement between measured and predicted velocities. KLD-sampling
//! (Fox 2001) is offered as a second count rule.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::steps::{usable, CalibStep, Kind};
use super::units::{PAPER_RADIUS_M, SQRT_PAPER_STEP};
use crate::stats::chi2_quantile;
use serde::{Deserialize, Serialize};

/// How the particle count is chosen at each resampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CountRule {
    /// Fixed count.
    Fixed,
    /// \[Farina\]: N = dispersion / `per_particle`, the dispersion being the
    /// width of the radius cloud (`dispersion_sigmas` weighted standard
    /// deviations of R_R plus as many of R_L).
    #[default]
    Dispersion,
    /// KLD-sampling: enough particles that the KL divergence between the
    /// sample-based and the true posterior stays below ε with probability 1−δ.
    Kld,
}

/// Parameters of the adaptive rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdaptiveParams {
    /// Count rule used by the `adaptive-pf` method.
    pub rule: CountRule,
    /// Radius dispersion per particle, in wheel radii: \[Farina\]'s "one
    /// particle per 0.01 mm" on its 0.32 m wheels (3.125·10⁻⁵).
    pub per_particle: f64,
    /// How many standard deviations of a radius make its dispersion (the
    /// width of the interval its particles fill: 6 = ±3σ, 99.7 % of a
    /// Gaussian cloud). \[Farina\] does not say which spread it means; the
    /// standard deviation alone (1) gives fewer particles than any sensible
    /// floor from the first resampling on, so the count would never move.
    pub dispersion_sigmas: f64,
    /// Lower clamp of the particle count.
    pub n_min: usize,
    /// Upper clamp of the particle count.
    pub n_max: usize,
    /// α of [Farina, eq. 11] (√s: σ_ε per √s, the paper's 10⁻⁴ per 0.02 s
    /// iteration): σ_ε = α·sqrt((V_m−V_O)² + (ℓ·(W_m−W_O))²),
    /// the turn rate's residual weighed by the lever ℓ that turns it into a
    /// wheel speed (half the wheel base: each wheel runs ±W·D/2 from V). The
    /// paper prints ℓ = 1 (m/s and rad/s added as they are), which only
    /// suits a robot of its size; `preset = "published"` keeps that form.
    /// σ_ε comes out in the unit the parameters are configured in (the
    /// wheel radius, see [`super::NoiseParams`]).
    pub alpha: f64,
    /// ℓ of eq. 11 (m), set when the filter is built (not configured).
    #[serde(skip, default = "unit_lever")]
    pub turn_lever: f64,
    /// Time constant (s) of the exponential average of the residuals
    /// V_m − V_O, W_m − W_O that enter eq. 11: white measurement noise
    /// averages out, a persistent disagreement (the parameters changed) stays.
    /// 0 = the paper's instantaneous residuals.
    pub residual_tau: f64,
    /// Lower clamp of σ_ε, in wheel radii per √s.
    pub sigma_min: f64,
    /// Upper clamp of σ_ε, in wheel radii per √s.
    pub sigma_max: f64,
    /// KLD error bound ε.
    pub kld_epsilon: f64,
    /// KLD confidence 1−δ (the quantile z_{1−δ} is taken of it).
    pub kld_confidence: f64,
    /// KLD bin sizes over (R_R, R_L, D), in wheel radii.
    pub kld_bin: [f64; 3],
}

impl Default for AdaptiveParams {
    fn default() -> Self {
        Self {
            rule: CountRule::Dispersion,
            per_particle: 1e-5 / PAPER_RADIUS_M,
            dispersion_sigmas: 6.0,
            n_min: 300,
            n_max: 20_000,
            alpha: 1e-4 / SQRT_PAPER_STEP,
            turn_lever: 1.0,
            residual_tau: 1.0,
            sigma_min: 1e-7 / PAPER_RADIUS_M / SQRT_PAPER_STEP,
            sigma_max: 5e-3 / PAPER_RADIUS_M / SQRT_PAPER_STEP,
            kld_epsilon: 0.05,
            kld_confidence: 0.99,
            kld_bin: [
                1e-4 / PAPER_RADIUS_M,
                1e-4 / PAPER_RADIUS_M,
                1e-3 / PAPER_RADIUS_M,
            ],
        }
    }
}

fn unit_lever() -> f64 {
    1.0
}

impl AdaptiveParams {
    /// The rules in metres for a robot whose lengths are `unit` (m) wheel
    /// radii, with eq. 11's turn lever `lever` (m), σ_ε's per-√s values
    /// multiplied by `sqrt_s` (see [`super::NoiseParams::in_metres`]).
    pub fn in_metres(&self, unit: f64, lever: f64, sqrt_s: f64) -> Self {
        Self {
            per_particle: self.per_particle * unit,
            alpha: self.alpha * sqrt_s,
            sigma_min: self.sigma_min * unit * sqrt_s,
            sigma_max: self.sigma_max * unit * sqrt_s,
            kld_bin: self.kld_bin.map(|b| b * unit),
            turn_lever: lever,
            ..self.clone()
        }
    }

    /// Checks ranges; the message names the bad field.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |x: f64| x.is_finite() && x > 0.0;
        if !pos(self.per_particle) {
            return Err("adaptive.per_particle must be > 0".into());
        }
        if !pos(self.dispersion_sigmas) {
            return Err("adaptive.dispersion_sigmas must be > 0".into());
        }
        if self.n_min == 0 || self.n_max < self.n_min {
            return Err("adaptive.n_min must be ≥ 1 and ≤ n_max".into());
        }
        if !(self.residual_tau.is_finite() && self.residual_tau >= 0.0) {
            return Err("adaptive.residual_tau must be ≥ 0".into());
        }
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err("adaptive.alpha must be ≥ 0".into());
        }
        if !(pos(self.sigma_max) && self.sigma_min >= 0.0 && self.sigma_min <= self.sigma_max) {
            return Err("adaptive.sigma_min/sigma_max must satisfy 0 ≤ min ≤ max".into());
        }
        if !(self.kld_epsilon > 0.0 && self.kld_confidence > 0.0 && self.kld_confidence < 1.0) {
            return Err("adaptive.kld_epsilon > 0 and 0 < kld_confidence < 1".into());
        }
        if !self.kld_bin.iter().all(|&b| pos(b)) {
            return Err("adaptive.kld_bin entries must be > 0".into());
        }
        Ok(())
    }

    /// The count of \[Farina\], `ceil(dispersion / per_particle)` clamped to
    /// [`n_min`, `n_max`], for weighted standard deviations `std_r_right`,
    /// `std_r_left` (m) of the radius particles: the dispersion is
    /// `dispersion_sigmas · (std_r_right + std_r_left)`.
    pub fn dispersion_count(&self, std_r_right: f64, std_r_left: f64) -> usize {
        let dispersion = self.dispersion_sigmas * (std_r_right + std_r_left);
        let n = (dispersion / self.per_particle).ceil();
        if n.is_finite() {
            (n.max(0.0) as usize).clamp(self.n_min, self.n_max)
        } else {
            self.n_max
        }
    }

    /// The count of KLD-sampling \[Fox2001, eq. 7\], `n = χ²_{k−1, 1−δ} / (2ε)`
    /// for `k` occupied bins, with the exact χ² quantile (Fox's eq. 8 is its
    /// Wilson–Hilferty approximation), clamped.
    pub fn kld_count(&self, k: usize) -> usize {
        if k <= 1 {
            return self.n_min;
        }
        let n = chi2_quantile(self.kld_confidence, k - 1) / (2.0 * self.kld_epsilon);
        if n.is_finite() {
            (n.ceil().max(0.0) as usize).clamp(self.n_min, self.n_max)
        } else {
            self.n_max
        }
    }

    /// The residuals of eq. 11, `(V_m − V_O, W_m − W_O)`, from the measured
    /// (inverse-variance mean of the step's usable V and W measurements) and
    /// predicted (weighted-mean) velocities; a missing kind gives 0. `None`
    /// when the step has no usable measurement.
    pub fn residuals(&self, step: &CalibStep, v_o: f64, w_o: f64, floor: f64) -> Option<[f64; 2]> {
        let mean = |kind: Kind| {
            let (mut s, mut sw) = (0.0, 0.0);
            for m in step
                .measurements()
                .iter()
                .filter(|m| m.kind == kind && usable(m))
            {
                let iv = 1.0 / m.sigma.max(floor).powi(2);
                s += m.value * iv;
                sw += iv;
            }
            (sw > 0.0).then(|| s / sw)
        };
        let (vm, wm) = (mean(Kind::V), mean(Kind::W));
        if vm.is_none() && wm.is_none() {
            return None;
        }
        let ev = vm.map_or(0.0, |v| v - v_o);
        let ew = wm.map_or(0.0, |w| w - w_o);
        (ev.is_finite() && ew.is_finite()).then_some([ev, ew])
    }

    /// Eq. 11 on (averaged) residuals: `σ_ε = α·sqrt(e_V² + (ℓ·e_W)²)`,
    /// clamped.
    pub fn sigma_of(&self, e: [f64; 2]) -> f64 {
        let w = self.turn_lever * e[1];
        let s = self.alpha * (e[0] * e[0] + w * w).sqrt();
        if s.is_finite() {
            s.clamp(self.sigma_min, self.sigma_max)
        } else {
            self.sigma_max
        }
    }

    /// Folds one step's residuals (interval `dt` s) into the running average.
    pub fn average(&self, ema: &mut Option<[f64; 2]>, e: [f64; 2], dt: f64) {
        let k = if self.residual_tau > 0.0 {
            1.0 - (-dt.max(0.0) / self.residual_tau).exp()
        } else {
            1.0
        };
        *ema = Some(match *ema {
            None => e,
            Some(m) => [m[0] + k * (e[0] - m[0]), m[1] + k * (e[1] - m[1])],
        });
    }
}

/// Counts the distinct KLD bins occupied by the particles `idx` of
/// (rr, rl, d), using `keys` as scratch (no allocation once warm).
pub fn occupied_bins(
    idx: &[usize],
    rr: &[f64],
    rl: &[f64],
    d: &[f64],
    bin: [f64; 3],
    keys: &mut Vec<u64>,
) -> usize {
    keys.clear();
    for &i in idx {
        let a = (rr[i] / bin[0]).floor() as i64 as u64;
        let b = (rl[i] / bin[1]).floor() as i64 as u64;
        let c = (d[i] / bin[2]).floor() as i64 as u64;
        // Radii bins (≤ 2^21 of 0.1 mm = 200 m) and base bins pack into 64 bits.
        keys.push((a & 0x1F_FFFF) << 42 | (b & 0x1F_FFFF) << 21 | (c & 0x1F_FFFF));
    }
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dispersion_count_is_one_particle_per_hundredth_mm_of_cloud_width() {
        // The paper's rule on its 0.32 m wheels.
        let p = AdaptiveParams::default().in_metres(PAPER_RADIUS_M, 1.0, 1.0);
        // σ 0.5 mm and 0.3 mm: ±3σ widths 3.0 + 1.8 = 4.8 mm = 480 × 0.01 mm.
        assert_eq!(p.dispersion_count(0.5e-3, 0.3e-3), 480);
        // The uniform start over 30 mm (σ = 30/√12 = 8.66 mm each): 10,392.
        let s = 0.030 / 12f64.sqrt();
        assert_eq!(p.dispersion_count(s, s), 10_393);
        assert_eq!(p.dispersion_count(1e-6, 1e-6), p.n_min);
        assert_eq!(p.dispersion_count(1.0, 0.0), p.n_max);
        assert_eq!(p.dispersion_count(f64::NAN, 0.0), p.n_max);
    }

    #[test]
    fn kld_count_matches_the_chi_square_table() {
        // Fox 2001, eq. 7: n = χ²_{k−1, 1−δ} / (2ε). For k − 1 = 100 bins
        // and δ = 0.01 the tabulated quantile is 135.807 (Abramowitz and
        // Stegun, Table 26.8), so n = ⌈1358.07⌉ with ε = 0.05 (eq. 8's
        // Wilson–Hilferty form gives 1358.2, also 1359).
        let p = AdaptiveParams {
            n_min: 1,
            n_max: 1_000_000,
            ..Default::default()
        };
        assert_eq!(p.kld_count(101), 1359);
        // k − 1 = 10: χ²_{10, 0.99} = 23.2093 → ⌈232.09⌉ (eq. 8: 232.4, also 233).
        assert_eq!(p.kld_count(11), 233);
        // k − 1 = 1: χ²_{1, 0.99} = 6.6349 → ⌈66.35⌉; eq. 8 gives 65.9, so 66.
        assert_eq!(p.kld_count(2), 67);
        assert_eq!(p.kld_count(1), p.n_min);
    }

    #[test]
    fn process_sigma_follows_disagreement() {
        let p = AdaptiveParams::default().in_metres(PAPER_RADIUS_M, 1.0, SQRT_PAPER_STEP);
        let s = CalibStep::new(0.0, 0.02, 1.0, 1.0)
            .with(Kind::V, 1.3, 0.05)
            .with(Kind::W, 0.4, 0.01);
        let e = p.residuals(&s, 1.0, 0.0, 1e-3).unwrap();
        assert!((p.sigma_of(e) - 1e-4 * 0.5).abs() < 1e-15);
        // With the turn rate weighed by half a 0.65 m wheel base, the same
        // residuals (0.3 m/s, 0.4 rad/s) give α·sqrt(0.3² + 0.13²).
        let lever = AdaptiveParams::default().in_metres(PAPER_RADIUS_M, 0.325, SQRT_PAPER_STEP);
        let want = 1e-4 * (0.09f64 + 0.13 * 0.13).sqrt();
        assert!(
            (lever.sigma_of(e) - want).abs() < 1e-15,
            "{}",
            lever.sigma_of(e)
        );
        let none = CalibStep::new(0.0, 0.02, 1.0, 1.0).with(Kind::V, 1.0, f64::INFINITY);
        assert!(p.residuals(&none, 0.0, 0.0, 1e-3).is_none());
        // A persistent residual survives the average, alternating noise does not.
        let (mut a, mut b) = (None, None);
        for i in 0..500 {
            p.average(&mut a, [0.1, 0.0], 0.02);
            p.average(&mut b, [if i % 2 == 0 { 0.1 } else { -0.1 }, 0.0], 0.02);
        }
        assert!((a.unwrap()[0] - 0.1).abs() < 1e-9 && b.unwrap()[0].abs() < 0.01);
    }

    #[test]
    fn in_metres_scales_lengths_by_the_unit_and_rates_by_root_seconds() {
        // Lengths per particle and bin sizes are in wheel radii (× unit);
        // α is per √s (× √s); σ_ε's clamps are both (× unit × √s).
        let p = AdaptiveParams {
            per_particle: 2.0,
            alpha: 3.0,
            sigma_min: 5.0,
            sigma_max: 7.0,
            kld_bin: [11.0, 13.0, 17.0],
            ..Default::default()
        };
        let m = p.in_metres(0.5, 0.3, 0.1);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(m.per_particle, 1.0), "{m:?}");
        assert!(close(m.alpha, 0.3), "{m:?}");
        assert!(
            close(m.sigma_min, 0.25) && close(m.sigma_max, 0.35),
            "{m:?}"
        );
        assert!(close(m.kld_bin[0], 5.5) && close(m.kld_bin[1], 6.5) && close(m.kld_bin[2], 8.5));
        assert_eq!(m.turn_lever, 0.3);
        // Counts, the rule and the dimensionless settings are kept.
        assert_eq!((m.n_min, m.n_max, m.rule), (p.n_min, p.n_max, p.rule));
        assert_eq!((m.dispersion_sigmas, m.residual_tau), (6.0, 1.0));
    }

    #[test]
    fn the_turn_lever_is_not_configured_and_reads_as_1_m() {
        // ℓ = 1 is eq. 11 as printed, until the filter sets the robot's.
        let p: AdaptiveParams = serde_json::from_str(r#"{"alpha": 2.0}"#).unwrap();
        assert_eq!((p.alpha, p.turn_lever), (2.0, 1.0));
    }

    #[test]
    fn validate_accepts_the_defaults_and_every_bound_and_names_each_bad_field() {
        let ok = |f: &dyn Fn(&mut AdaptiveParams)| {
            let mut p = AdaptiveParams::default();
            f(&mut p);
            p.validate()
        };
        assert_eq!(ok(&|_| {}), Ok(()));
        // On the bounds: counts equal, τ, α and σ_min zero, σ_min = σ_max.
        assert_eq!(ok(&|p| (p.n_min, p.n_max) = (300, 300)), Ok(()));
        assert_eq!(ok(&|p| p.residual_tau = 0.0), Ok(()));
        assert_eq!(ok(&|p| p.alpha = 0.0), Ok(()));
        assert_eq!(ok(&|p| p.sigma_min = 0.0), Ok(()));
        assert_eq!(ok(&|p| p.sigma_min = p.sigma_max), Ok(()));
        let bad: [(&str, &dyn Fn(&mut AdaptiveParams)); 20] = [
            ("per_particle", &|p| p.per_particle = 0.0),
            ("per_particle", &|p| p.per_particle = f64::INFINITY),
            ("dispersion_sigmas", &|p| p.dispersion_sigmas = -1.0),
            ("n_min", &|p| p.n_min = 0),
            ("n_min", &|p| (p.n_min, p.n_max) = (301, 300)),
            ("residual_tau", &|p| p.residual_tau = -0.1),
            ("residual_tau", &|p| p.residual_tau = f64::INFINITY),
            ("alpha", &|p| p.alpha = -1e-9),
            ("alpha", &|p| p.alpha = f64::INFINITY),
            ("sigma_min/sigma_max", &|p| {
                (p.sigma_min, p.sigma_max) = (0.0, 0.0)
            }),
            ("sigma_min/sigma_max", &|p| p.sigma_min = -1e-9),
            ("sigma_min/sigma_max", &|p| p.sigma_min = 2.0 * p.sigma_max),
            ("kld_epsilon", &|p| p.kld_epsilon = 0.0),
            ("kld_epsilon", &|p| p.kld_confidence = 0.0),
            ("kld_epsilon", &|p| p.kld_confidence = -0.5),
            ("kld_epsilon", &|p| p.kld_confidence = 1.0),
            ("kld_bin", &|p| p.kld_bin[1] = 0.0),
            ("kld_bin", &|p| p.kld_bin[2] = f64::NAN),
            ("per_particle", &|p| p.per_particle = f64::NAN),
            ("dispersion_sigmas", &|p| {
                p.dispersion_sigmas = f64::INFINITY
            }),
        ];
        for (field, f) in bad {
            let e = ok(f).unwrap_err();
            assert!(e.contains(field), "{field}: {e}");
        }
    }

    #[test]
    fn residuals_average_each_kind_by_inverse_variance_and_a_missing_kind_gives_zero() {
        let p = AdaptiveParams::default();
        // V 1.0 (σ 0.1) and 2.0 (σ 0.2): weights 100 and 25, mean
        // (100 + 50)/125 = 1.2; no W, so W's residual is 0.
        let v = CalibStep::new(0.0, 0.02, 1.0, 1.0)
            .with(Kind::V, 1.0, 0.1)
            .with(Kind::V, 2.0, 0.2);
        let e = p.residuals(&v, 0.5, 0.3, 1e-3).unwrap();
        assert!((e[0] - 0.7).abs() < 1e-12 && e[1] == 0.0, "{e:?}");
        // W 0.4 (σ 0.01) and 0.1 (σ 0.02): weights 10⁴ and 2500, mean
        // (4000 + 250)/12500 = 0.34; both σ under a floor of 0.05 weigh
        // alike, mean 0.25.
        let w = CalibStep::new(0.0, 0.02, 1.0, 1.0)
            .with(Kind::W, 0.4, 0.01)
            .with(Kind::W, 0.1, 0.02);
        let e = p.residuals(&w, 0.5, 0.3, 1e-3).unwrap();
        assert!(e[0] == 0.0 && (e[1] - 0.04).abs() < 1e-12, "{e:?}");
        let e = p.residuals(&w, 0.5, 0.3, 0.05).unwrap();
        assert!((e[1] + 0.05).abs() < 1e-12, "{e:?}");
        // A prediction that is not finite gives no residual.
        assert!(p.residuals(&v, f64::NAN, 0.0, 1e-3).is_none());
        assert!(p.residuals(&w, 0.0, f64::INFINITY, 1e-3).is_none());
    }

    #[test]
    fn the_average_moves_each_residual_by_1_minus_exp_of_minus_dt_over_tau() {
        // τ = 0.5 s, dt = 0.1 s: k = 1 − e^(−0.2) = 0.18127; the first
        // residual is taken as it is.
        let p = AdaptiveParams {
            residual_tau: 0.5,
            ..Default::default()
        };
        let mut ema = None;
        p.average(&mut ema, [1.0, -2.0], 0.1);
        assert_eq!(ema, Some([1.0, -2.0]));
        p.average(&mut ema, [3.0, 4.0], 0.1);
        let k = 1.0 - (-0.2f64).exp();
        let [a, b] = ema.unwrap();
        assert!((a - (1.0 + 2.0 * k)).abs() < 1e-12, "{a}");
        assert!((b - (-2.0 + 6.0 * k)).abs() < 1e-12, "{b}");
        // τ = 0: the latest residual, even over an interval of zero.
        let now = AdaptiveParams {
            residual_tau: 0.0,
            ..Default::default()
        };
        now.average(&mut ema, [5.0, 6.0], 0.0);
        assert_eq!(ema, Some([5.0, 6.0]));
    }

    #[test]
    fn occupied_bins_counts_the_distinct_cells_of_all_three_coordinates() {
        // Bins of 0.1 (R_R), 0.1 (R_L) and 1 (D): particles 1, 2 and 3 each
        // leave particle 0's cell along one coordinate only; particle 4
        // shares particle 0's cell.
        let rr = [0.05, 0.15, 0.05, 0.05, 0.06];
        let rl = [0.05, 0.05, 0.15, 0.05, 0.07];
        let d = [0.5, 0.5, 0.5, 1.5, 0.9];
        let bin = [0.1, 0.1, 1.0];
        let mut keys = Vec::new();
        let count =
            |idx: &[usize], keys: &mut Vec<u64>| occupied_bins(idx, &rr, &rl, &d, bin, keys);
        assert_eq!(count(&[0, 1, 2, 3, 4], &mut keys), 4);
        assert_eq!(count(&[0, 4, 4], &mut keys), 1);
        for other in 1..4 {
            assert_eq!(count(&[0, other], &mut keys), 2, "particle {other}");
        }
        assert_eq!(count(&[], &mut keys), 0);
    }

    #[test]
    fn occupied_bins_divides_by_each_bin_and_keeps_negative_cells_apart() {
        // Bins 0.2 (R_R), 0.5 (R_L) and 0.25 (D), none of them 1: cells
        // (0, 0, 2) for particle 0, and particles 1, 2, 3 one cell further
        // along one coordinate each (0.3/0.2 = 1.5, 0.7/0.5 = 1.4,
        // 0.8/0.25 = 3.2).
        let rr = [0.1, 0.3, 0.1, 0.1, 0.1, 0.3, 0.1, 0.3];
        let rl = [0.2, 0.2, 0.7, 0.2, -0.2, -0.2, 0.2, 0.2];
        let d = [0.6, 0.6, 0.6, 0.8, 0.6, 0.6, -0.1, -0.1];
        let bin = [0.2, 0.5, 0.25];
        let mut keys = Vec::new();
        let count =
            |idx: &[usize], keys: &mut Vec<u64>| occupied_bins(idx, &rr, &rl, &d, bin, keys);
        for other in 1..4 {
            assert_eq!(count(&[0, other], &mut keys), 2, "particle {other}");
        }
        assert_eq!(count(&[0, 0, 1, 1], &mut keys), 2);
        // Particles 4 and 5 (R_L in cell −1) and 6 and 7 (D in cell −1)
        // differ only in R_R's cell, 0 against 1: a negative cell of one
        // coordinate must not spill into the other coordinates' cells.
        assert_eq!(count(&[4, 5], &mut keys), 2);
        assert_eq!(count(&[6, 7], &mut keys), 2);
        assert_eq!(count(&[0, 1, 2, 3, 4, 5, 6, 7], &mut keys), 8);
    }
}
