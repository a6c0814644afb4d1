//! Weighted nonlinear least squares (Levenberg–Marquardt [Levenberg1944;
//! Marquardt1963], forward-difference Jacobian) of the free parameters of a
//! set of effects, with per-stream σ scales profiled out, parameter standard
//! errors from (JᵀWJ)⁻¹ and BIC \[Schwarz1978\].

use super::data::Part;
use super::free::{dof, free_params, free_steps, with_free};
use crate::effects::{Departures, Effect};
use nalgebra::{DMatrix, DVector};

/// A fitted extension on the training part.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The effects with fitted parameters.
    pub effects: Vec<Effect>,
    /// Standard error of each effect's free parameters.
    pub stderr: Vec<Vec<f64>>,
    /// Covariance of all free parameters (in effect order).
    pub cov: DMatrix<f64>,
    /// Σ of squared σ-normalised residuals per group (training).
    pub rss: [f64; 4],
    /// Profiled σ scale per group: √(rss/n), the factor by which the given σ
    /// under- (>1) or over-states (<1) the residual noise.
    pub scale: [f64; 4],
    /// Bayesian information criterion \[Schwarz1978\] (profiled per-group σ).
    pub bic: f64,
    /// Whether JᵀWJ was well conditioned (every parameter identifiable).
    pub identifiable: bool,
}

/// BIC = Σ_g n_g ln(RSS_g / n_g) + k ln N (Gaussian likelihood with each
/// group's σ scale profiled out).
pub fn bic(rss: &[f64; 4], counts: &[usize; 4], k: usize) -> f64 {
    let n: usize = counts.iter().sum();
    let mut b = k as f64 * (n.max(1) as f64).ln();
    for g in 0..4 {
        if counts[g] > 0 {
            b += counts[g] as f64 * (rss[g].max(1e-300) / counts[g] as f64).ln();
        }
    }
    b
}

/// Profiled scales √(rss_g / n_g) (1 for empty groups).
pub fn scales(rss: &[f64; 4], counts: &[usize; 4]) -> [f64; 4] {
    let mut s = [1.0; 4];
    for g in 0..4 {
        if counts[g] > 0 {
            s[g] = (rss[g] / counts[g] as f64).sqrt().max(1e-9);
        }
    }
    s
}

fn unpack(effects: &[Effect], theta: &[f64]) -> Vec<Effect> {
    let mut i = 0;
    effects
        .iter()
        .map(|e| {
            let n = free_params(e).len();
            let out = with_free(e, &theta[i..i + n]);
            i += n;
            out
        })
        .collect()
}

struct Lsq<'a> {
    part: Part<'a>,
    effects: &'a [Effect],
    scale: [f64; 4],
    buf: [Vec<f64>; 4],
}

impl Lsq<'_> {
    fn residual(&mut self, theta: &[f64], out: &mut Vec<f64>) {
        let x = Departures::of(&unpack(self.effects, theta));
        self.part.normalised(&x, &mut self.buf);
        out.clear();
        for g in 0..4 {
            let s = self.scale[g];
            out.extend(self.buf[g].iter().map(|e| e / s));
        }
    }

    /// Forward-difference Jacobian of the residual at θ (residual `r0` given).
    fn jacobian(&mut self, theta: &[f64], r0: &[f64], steps: &[f64]) -> DMatrix<f64> {
        let (m, p) = (r0.len(), theta.len());
        let mut j = DMatrix::zeros(m, p);
        let mut rp = Vec::new();
        let mut th = theta.to_vec();
        for c in 0..p {
            th[c] = theta[c] + steps[c];
            self.residual(&th, &mut rp);
            th[c] = theta[c];
            for r in 0..m {
                j[(r, c)] = (rp[r] - r0[r]) / steps[c];
            }
        }
        j
    }
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|e| e * e).sum()
}

/// Levenberg–Marquardt from the given starting effects with fixed scales;
/// returns θ and the Jacobian at θ.
fn lm(l: &mut Lsq, theta0: Vec<f64>, steps: &[f64], max_iter: usize) -> (Vec<f64>, DMatrix<f64>) {
    let mut theta = theta0;
    let mut r = Vec::new();
    l.residual(&theta, &mut r);
    let mut c = cost(&r);
    let mut lambda = 1e-4;
    let mut rn = Vec::new();
    for _ in 0..max_iter {
        let j = l.jacobian(&theta, &r, steps);
        let a = j.transpose() * &j;
        let g = j.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        while lambda < 1e12 {
            let mut aa = a.clone();
            for d in 0..aa.nrows() {
                aa[(d, d)] += lambda * a[(d, d)].max(1e-12);
            }
            let Some(delta) = aa.cholesky().map(|ch| ch.solve(&(-&g))) else {
                lambda *= 10.0;
                continue;
            };
            let cand: Vec<f64> = theta.iter().zip(delta.iter()).map(|(t, d)| t + d).collect();
            l.residual(&cand, &mut rn);
            let cn = cost(&rn);
            if cn.is_finite() && cn <= c {
                let rel = (c - cn) / c.max(1e-300);
                theta = cand;
                std::mem::swap(&mut r, &mut rn);
                c = cn;
                lambda = (lambda / 10.0).max(1e-12);
                improved = rel > 1e-9;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let j = l.jacobian(&theta, &r, steps);
    (theta, j)
}

/// Fits the free parameters of `effects` (starting from their values) on the
/// training part: LM with the given σ scales, then (`rounds` = 2) once more
/// with the scales re-estimated from the residuals (profile likelihood).
pub fn fit(
    part: Part,
    effects: &[Effect],
    scale0: [f64; 4],
    max_iter: usize,
    rounds: usize,
) -> Fit {
    let counts = part.counts();
    let theta0: Vec<f64> = effects.iter().flat_map(free_params).collect();
    let steps: Vec<f64> = effects.iter().flat_map(free_steps).collect();
    let mut l = Lsq {
        part,
        effects,
        scale: scale0,
        buf: Default::default(),
    };
    let mut theta = theta0;
    let mut jac = DMatrix::zeros(0, 0);
    for _round in 0..rounds.max(1) {
        if theta.is_empty() {
            break;
        }
        let (t, j) = lm(&mut l, theta, &steps, max_iter);
        theta = t;
        jac = j;
        let fitted = unpack(effects, &theta);
        let rss = part.rss(&Departures::of(&fitted));
        let s = scales(&rss, &counts);
        // Rescale the Jacobian to the new scales instead of recomputing it.
        let mut row = 0;
        for g in 0..4 {
            let f = l.scale[g] / s[g];
            for r in row..row + counts[g] {
                for c in 0..jac.ncols() {
                    jac[(r, c)] *= f;
                }
            }
            row += counts[g];
        }
        l.scale = s;
    }
    let fitted = unpack(effects, &theta);
    let rss = part.rss(&Departures::of(&fitted));
    let scale = scales(&rss, &counts);
    let p = theta.len();
    let (cov, identifiable) = if p == 0 {
        (DMatrix::zeros(0, 0), true)
    } else {
        let a = jac.transpose() * &jac;
        let d: Vec<f64> = (0..p).map(|i| a[(i, i)].max(0.0).sqrt()).collect();
        let ok_diag = d.iter().all(|v| *v > 0.0 && v.is_finite());
        let corr = DMatrix::from_fn(p, p, |i, j| a[(i, j)] / (d[i] * d[j]).max(1e-300));
        let min_eig = corr
            .symmetric_eigenvalues()
            .iter()
            .fold(f64::INFINITY, |m, v| m.min(*v));
        let ok = ok_diag && min_eig > 1e-8;
        let cov = a
            .try_inverse()
            .unwrap_or_else(|| DMatrix::from_element(p, p, f64::INFINITY));
        (cov, ok)
    };
    let mut stderr = Vec::new();
    let mut i = 0;
    for e in &fitted {
        let n = free_params(e).len();
        stderr.push((i..i + n).map(|k| cov[(k, k)].max(0.0).sqrt()).collect());
        i += n;
    }
    Fit {
        bic: bic(&rss, &counts, dof(&fitted)),
        effects: fitted,
        stderr,
        cov,
        rss,
        scale,
        identifiable,
    }
}

/// Wald statistic θᵀ Σ⁻¹ θ of the free parameters of the effect at `index`;
/// 0 for an empty block, and 0 when the block is singular or the statistic
/// is not finite: an effect the data cannot determine is never significant.
pub fn wald(f: &Fit, index: usize) -> f64 {
    let start: usize = f.effects[..index]
        .iter()
        .map(|e| free_params(e).len())
        .sum();
    let th = free_params(&f.effects[index]);
    let n = th.len();
    if n == 0 {
        return 0.0;
    }
    let block = f.cov.view((start, start), (n, n)).into_owned();
    let Some(inv) = block.try_inverse() else {
        return 0.0;
    };
    let v = DVector::from_vec(th);
    let w = (v.transpose() * inv * &v)[(0, 0)];
    if w.is_finite() {
        w
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::data::{GyroRow, IcpRow};
    use crate::diagnose::model::Replay;
    use crate::recording::WheelSample;
    use crate::robot::RobotConfig;

    /// A robot standing still for 10 s (wheel samples at 10 Hz).
    fn standing() -> Replay {
        let wheels: Vec<WheelSample> = (0..=100)
            .map(|i| WheelSample {
                stamp: i as f64 / 10.0,
                left: 0.0,
                right: 0.0,
            })
            .collect();
        Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0)
    }

    /// Five one-second gyro windows reading 0.01, 0.03, 0.02, 0.04, 0 rad/s
    /// with σ 0.01: mean 0.02, squared deviations summing to 1e-3.
    fn gyro_rows() -> Vec<GyroRow> {
        [0.01, 0.03, 0.02, 0.04, 0.0]
            .iter()
            .enumerate()
            .map(|(i, &w)| GyroRow {
                t0: i as f64,
                t1: i as f64 + 1.0,
                w,
                sigma: 0.01,
            })
            .collect()
    }

    #[test]
    fn bic_and_scales_by_hand() {
        // 3 parameters over 7 rows: 3 ln 7, plus 2 ln(2/2) + 4 ln(8/4) +
        // 1 ln(1/1); the empty group adds nothing.
        let b = bic(&[2.0, 8.0, 5.0, 1.0], &[2, 4, 0, 1], 3);
        assert!(
            (b - (3.0 * 7f64.ln() + 4.0 * 2f64.ln())).abs() < 1e-12,
            "{b}"
        );
        // No rows at all: no penalty, no term.
        assert_eq!(bic(&[0.0; 4], &[0; 4], 2), 0.0);
        // √(rss/n) per group, 1 for an empty one, never below 1e-9.
        let s = scales(&[10.0, 3.0, 8.0, 0.0], &[5, 0, 2, 4]);
        assert!((s[0] - 2f64.sqrt()).abs() < 1e-15 && (s[2] - 2.0).abs() < 1e-15);
        assert_eq!((s[1], s[3]), (1.0, 1e-9));
    }

    #[test]
    fn a_gyro_bias_of_a_robot_standing_still_by_hand() {
        // The model predicts the bias alone: least squares gives the mean
        // 0.02, normalised residuals (−1, 1, 0, 2, −2) with RSS 10, σ scale
        // √(10/5), standard error σ·scale/√5 = √(4e-5), Wald 0.02²/4e-5 = 10
        // and BIC 5 ln(10/5) + 1·ln 5. The nominal model has RSS
        // 1 + 9 + 4 + 16 + 0 = 30 and BIC 5 ln 6.
        let replay = standing();
        let gyro = gyro_rows();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        for rounds in [1, 2] {
            let f = fit(
                part,
                &[Effect::GyroBias { bias: 0.0 }],
                [1.0; 4],
                50,
                rounds,
            );
            let Effect::GyroBias { bias } = f.effects[0] else {
                panic!("{:?}", f.effects)
            };
            assert!((bias - 0.02).abs() < 1e-9, "{bias}");
            assert!((f.rss[3] - 10.0).abs() < 1e-6, "{:?}", f.rss);
            assert_eq!(&f.rss[..3], &[0.0; 3]);
            assert!((f.scale[3] - 2f64.sqrt()).abs() < 1e-7, "{:?}", f.scale);
            assert_eq!(&f.scale[..3], &[1.0; 3]);
            assert!(
                (f.stderr[0][0] - 4e-5f64.sqrt()).abs() < 1e-9,
                "{:?}",
                f.stderr
            );
            assert!((f.cov[(0, 0)] - 4e-5).abs() < 1e-11, "{}", f.cov);
            assert!(
                (f.bic - (5.0 * 2f64.ln() + 5f64.ln())).abs() < 1e-6,
                "{}",
                f.bic
            );
            assert!((wald(&f, 0) - 10.0).abs() < 1e-5, "{}", wald(&f, 0));
            assert!(f.identifiable);
        }
        let nominal = fit(part, &[], [1.0; 4], 50, 1);
        assert!(nominal.effects.is_empty() && nominal.cov.is_empty());
        assert!((nominal.rss[3] - 30.0).abs() < 1e-9, "{:?}", nominal.rss);
        assert!(
            (nominal.bic - 5.0 * 6f64.ln()).abs() < 1e-9,
            "{}",
            nominal.bic
        );
        assert!(nominal.identifiable);
    }

    /// Wheel rates (right, left; rad/s) over 0–10 s and 10–20 s, sampled at
    /// 100 Hz on the default robot (radii 0.32 m, wheel base 0.65 m).
    fn drive(first: (f64, f64), second: (f64, f64)) -> Replay {
        let angle = |rate: (f64, f64), t: f64| {
            let (a, b) = (rate.0 * t.min(10.0), rate.1 * (t - 10.0).max(0.0));
            a + b
        };
        let wheels: Vec<WheelSample> = (0..=2000)
            .map(|i| {
                let t = i as f64 / 100.0;
                WheelSample {
                    stamp: t,
                    right: angle((first.0, second.0), t),
                    left: angle((first.1, second.1), t),
                }
            })
            .collect();
        Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0)
    }

    /// ICP rows over half seconds and gyro rows over seconds of [`drive`]
    /// with radii 0.32·(1 + scale) and a gyro bias (rad/s): v and ω from the
    /// wheels, the arc's chord over the half second.
    fn measured(
        first: (f64, f64),
        second: (f64, f64),
        scale: (f64, f64),
        bias: f64,
    ) -> (Vec<IcpRow>, Vec<GyroRow>) {
        let (rr, rl, d) = (0.32 * (1.0 + scale.0), 0.32 * (1.0 + scale.1), 0.65);
        let rates = |t: f64| if t < 10.0 { first } else { second };
        let body = |t: f64| {
            let (wr, wl) = rates(t);
            (0.5 * (wr * rr + wl * rl), (wr * rr - wl * rl) / d)
        };
        let icp = (0..40)
            .map(|k| {
                let (t0, dt) = (0.5 * k as f64, 0.5);
                let (v, w) = body(t0);
                let (x, y) = if w == 0.0 {
                    (v * dt, 0.0)
                } else {
                    (v / w * (w * dt).sin(), v / w * (1.0 - (w * dt).cos()))
                };
                IcpRow {
                    t0,
                    t1: t0 + dt,
                    z: [x / dt, y / dt, w],
                    sigma: [0.01, 0.01, 0.004],
                }
            })
            .collect();
        let gyro = (0..20)
            .map(|k| GyroRow {
                t0: k as f64,
                t1: k as f64 + 1.0,
                w: body(k as f64).1 + bias,
                sigma: 0.1,
            })
            .collect();
        (icp, gyro)
    }

    #[test]
    fn radius_scales_and_a_gyro_bias_are_recovered_from_two_curves() {
        let (first, second) = ((4.0, 2.0), (2.0, 4.0));
        let replay = drive(first, second);
        let (icp, gyro) = measured(first, second, (0.02, -0.01), 0.005);
        let part = Part {
            replay: &replay,
            icp: &icp,
            gyro: &gyro,
        };
        let start = [
            Effect::RadiusScale {
                right: 0.0,
                left: 0.0,
            },
            Effect::GyroBias { bias: 0.0 },
        ];
        for rounds in [1, 2] {
            let f = fit(part, &start, [1.0; 4], 50, rounds);
            let want = [
                Effect::RadiusScale {
                    right: 0.02,
                    left: -0.01,
                },
                Effect::GyroBias { bias: 0.005 },
            ];
            for (got, want) in f.effects.iter().zip(&want) {
                for (g, w) in got.values().iter().zip(want.values()) {
                    assert!((g - w).abs() < 1e-7, "{:?}", f.effects);
                }
            }
            assert!(f.identifiable);
            assert_eq!(f.stderr.iter().map(Vec::len).collect::<Vec<_>>(), [2, 1]);
        }
    }

    #[test]
    fn a_wheel_base_scale_is_not_identifiable_on_a_straight_drive() {
        // Both wheels alike: no turn, so the wheel base changes nothing.
        let (first, second) = ((3.0, 3.0), (3.0, 3.0));
        let replay = drive(first, second);
        let (icp, _) = measured(first, second, (0.0, 0.0), 0.0);
        let part = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        let f = fit(
            part,
            &[Effect::WheelBaseScale { scale: 0.0 }],
            [1.0; 4],
            20,
            1,
        );
        assert!(!f.identifiable);
    }

    #[test]
    fn one_lm_step_is_gauss_newton_damped_by_1e_4_and_the_next_by_1e_5() {
        // The bias enters the residuals linearly, so a step solves
        // (JᵀJ)(1 + λ) δ = −Jᵀr exactly: from 0 the first (λ = 1e-4)
        // reaches 0.02/(1 + 1e-4); an accepted step divides λ by 10, so
        // the second leaves 1e-5/(1 + 1e-5) of what was left.
        let replay = standing();
        let gyro = gyro_rows();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let bias_after = |max_iter| {
            let f = fit(
                part,
                &[Effect::GyroBias { bias: 0.0 }],
                [1.0; 4],
                max_iter,
                1,
            );
            f.effects[0].values()[0]
        };
        let one = 0.02 / (1.0 + 1e-4);
        assert!((bias_after(1) - one).abs() < 1e-13, "{}", bias_after(1));
        let two = 0.02 - (0.02 - one) * 1e-5 / (1.0 + 1e-5);
        assert!((bias_after(2) - two).abs() < 1e-13, "{}", bias_after(2));
        // No iteration at all: the start.
        assert_eq!(bias_after(0), 0.0);
    }

    /// A robot turning in place at 1 rad/s for 4 s (wheels at ±0.65/0.64
    /// rad/s on the default robot: radii 0.32 m, wheel base 0.65 m) and
    /// one-second gyro windows reading `w` (σ 0.01).
    fn turning(w: &[f64]) -> (Replay, Vec<GyroRow>) {
        let a = 0.65 / 0.64;
        let wheels: Vec<WheelSample> = (0..=400)
            .map(|i| {
                let t = i as f64 / 100.0;
                WheelSample {
                    stamp: t,
                    left: -a * t,
                    right: a * t,
                }
            })
            .collect();
        let gyro = w
            .iter()
            .enumerate()
            .map(|(k, &w)| GyroRow {
                t0: k as f64,
                t1: k as f64 + 1.0,
                w,
                sigma: 0.01,
            })
            .collect();
        (
            Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0),
            gyro,
        )
    }

    #[test]
    fn a_step_that_raises_the_cost_is_refused_and_the_damping_raised_tenfold() {
        // A wheel-base scale s turns 1 rad/s of wheels into 1/(1 + s); the
        // gyro reads 5/3 (s = −0.4). The forward difference (step h = 1e-5)
        // gives J = 1/((1 + h)σ) and the damped step from 0 is
        // δ = −(2/3)(1 + h)/(1 + λ). For λ = 1e-4, 1e-3, 1e-2, 0.1 it
        // overshoots (1/(1 + δ) = 3.00, 2.99, 2.94, 2.54: further from 5/3
        // than 1 is); λ = 1 gives 1/(1 + δ) = 1.5, which is taken.
        let (replay, gyro) = turning(&[5.0 / 3.0; 4]);
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let f = fit(
            part,
            &[Effect::WheelBaseScale { scale: 0.0 }],
            [1.0; 4],
            1,
            1,
        );
        let want = -(2.0 / 3.0) * (1.0 + 1e-5) / 2.0;
        assert!(
            (f.effects[0].values()[0] - want).abs() < 1e-10,
            "{:?}",
            f.effects
        );
        // Iterated, it reaches −0.4.
        let f = fit(
            part,
            &[Effect::WheelBaseScale { scale: 0.0 }],
            [1.0; 4],
            50,
            1,
        );
        assert!(
            (f.effects[0].values()[0] + 0.4).abs() < 1e-9,
            "{:?}",
            f.effects
        );
    }

    #[test]
    fn residuals_that_are_not_finite_leave_the_start_and_stop_the_damping_loop() {
        // A NaN reading makes JᵀJ NaN: no Cholesky factor at any damping,
        // so λ rises tenfold to its limit and the fit keeps its start.
        let replay = standing();
        let mut gyro = gyro_rows();
        gyro[2].w = f64::NAN;
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let f = fit(part, &[Effect::GyroBias { bias: 0.01 }], [1.0; 4], 50, 1);
        assert_eq!(f.effects, [Effect::GyroBias { bias: 0.01 }]);
        assert!(!f.identifiable);
    }

    #[test]
    fn the_covariance_is_rescaled_per_group_when_other_groups_come_first() {
        // The bias test above with ICP rows of a robot standing still in
        // front of the gyro rows (they do not depend on the bias): the
        // gyro's rows come after 3 × 4 ICP rows, and the Jacobian at the
        // start's σ scale 1 must be rescaled to the gyro's √2 there too:
        // variance 2·0.01²/5 = 4e-5.
        let replay = standing();
        let gyro = gyro_rows();
        let icp: Vec<IcpRow> = (0..4)
            .map(|k| IcpRow {
                t0: 1.0 + k as f64,
                t1: 1.5 + k as f64,
                z: [0.01, -0.01, 0.004 * (k % 2) as f64],
                sigma: [0.01, 0.01, 0.004],
            })
            .collect();
        let part = Part {
            replay: &replay,
            icp: &icp,
            gyro: &gyro,
        };
        let f = fit(part, &[Effect::GyroBias { bias: 0.0 }], [1.0; 4], 50, 1);
        assert!((f.cov[(0, 0)] - 4e-5).abs() < 1e-11, "{}", f.cov);
        assert!((f.stderr[0][0] - 4e-5f64.sqrt()).abs() < 1e-9);
        // RSS 4, 4 and 2 of the ICP groups (residuals of 1 σ, and 0 or 1).
        assert!((f.rss[0] - 4.0).abs() < 1e-9 && (f.rss[2] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn a_gyro_bias_and_a_wheel_base_scale_are_not_identifiable_at_one_turn_rate() {
        // At a single turn rate both only shift the gyro's reading: their
        // Jacobian columns are proportional (correlation −1), while each
        // alone is identifiable.
        let (replay, gyro) = turning(&[1.06, 1.04, 1.06, 1.04]);
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let both = [
            Effect::GyroBias { bias: 0.0 },
            Effect::WheelBaseScale { scale: 0.0 },
        ];
        assert!(!fit(part, &both, [1.0; 4], 50, 1).identifiable);
        for one in both {
            assert!(fit(part, &[one], [1.0; 4], 50, 1).identifiable, "{one:?}");
        }
    }

    #[test]
    fn convergence_is_judged_relative_to_the_cost_whatever_the_units_of_sigma() {
        // The bias test's readings with σ 10⁶ times larger (10⁴ rad/s):
        // every cost is 10⁻¹² of the above (3e-11 at the start, the first
        // step gaining 2e-11), yet the fit stops only once a step gains
        // less than 1e-9 of the cost, at the mean 0.02, not after the first
        // step (0.02/(1 + 1e-4)).
        let replay = standing();
        let gyro: Vec<GyroRow> = gyro_rows()
            .into_iter()
            .map(|g| GyroRow { sigma: 1e4, ..g })
            .collect();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let f = fit(part, &[Effect::GyroBias { bias: 0.0 }], [1.0; 4], 50, 1);
        let bias = f.effects[0].values()[0];
        assert!((bias - 0.02).abs() < 1e-9, "{bias}");
    }

    #[test]
    fn identifiability_is_judged_on_correlations_not_on_precision() {
        // The bias test's readings times 10⁵ (1000, 3000, 2000, 4000, 0
        // rad/s; σ 0.01): the bias 2000 has variance 2e6/5 = 4e5 (mean
        // square residual 1e7/5 over 5 rows), JᵀJ = 2.5e-6, yet one
        // parameter alone is identifiable: its correlation is 1.
        let replay = standing();
        let gyro: Vec<GyroRow> = gyro_rows()
            .into_iter()
            .map(|g| GyroRow { w: g.w * 1e5, ..g })
            .collect();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let f = fit(part, &[Effect::GyroBias { bias: 0.0 }], [1.0; 4], 50, 1);
        assert!(
            (f.effects[0].values()[0] - 2000.0).abs() < 1e-6,
            "{:?}",
            f.effects
        );
        // (To the rounding of a 1e-6 difference step on residuals of 2e5.)
        assert!((f.cov[(0, 0)] / 4e5 - 1.0).abs() < 1e-6, "{}", f.cov);
        assert!(f.identifiable);
    }

    #[test]
    fn each_effect_gets_the_standard_errors_of_its_own_parameters() {
        // Turning at 1 rad/s for 4 s, then standing (the windows after the
        // last wheel sample see the wheels held), the gyro reading 0.1 rad/s
        // more ± 0.01: bias 0.1 and scale 0 leave residuals ±1 (σ scale 1).
        // With J = −100 for the bias in all 8 rows and 100/(1 + h) for the
        // scale in the 4 turning ones (forward step h = 1e-5), JᵀJ =
        // [[8, −4], [−4, 4]]·10⁴ (the scale's row and column × 1/(1 + h)),
        // whose inverse is [[4, 4], [4, 8]]·10⁴/1.6e9: standard errors
        // √2.5e-5 = 0.005 for the bias (the 4 standing windows') and
        // √5e-5·(1 + h) for the scale.
        let (replay, gyro) = turning(&[1.11, 1.09, 1.11, 1.09, 0.11, 0.09, 0.11, 0.09]);
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let both = [
            Effect::GyroBias { bias: 0.0 },
            Effect::WheelBaseScale { scale: 0.0 },
        ];
        let f = fit(part, &both, [1.0; 4], 50, 1);
        assert!(
            (f.effects[0].values()[0] - 0.1).abs() < 1e-9,
            "{:?}",
            f.effects
        );
        assert!(f.effects[1].values()[0].abs() < 1e-9, "{:?}", f.effects);
        assert!((f.stderr[0][0] - 0.005).abs() < 1e-9, "{:?}", f.stderr);
        let scale = 5e-5f64.sqrt() * (1.0 + 1e-5);
        assert!((f.stderr[1][0] - scale).abs() < 1e-9, "{:?}", f.stderr);
    }
}
