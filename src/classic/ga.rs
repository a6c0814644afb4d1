//! The offline calibration of \[GAHeading\]: a genetic algorithm fits `[k1, k2, b]`
//! (metres per encoder pulse of the left and right rear wheel, wheel base) so
//! that short runs (1.5–3 m), replayed from their pulse counts, end where they
//! were measured to end. The rear-axle model is the same for a differential
//! drive and for a tricycle whose rear wheels carry the encoders.
//!
//! The GA follows [GAHeading, Table 1] with MATLAB `ga` semantics: population 50,
//! rank fitness scaling, roulette selection, 2 elites, crossover fraction 0.8
//! with scattered crossover, Gaussian mutation whose σ shrinks linearly to 0
//! over the generations, 150 generations, bounds enforced by clamping.

use super::error::{check_finite, ClassicError};
use crate::geom::{self, Pose2};
use crate::recording::WheelSample;
use crate::robot::DiffDrive;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The parameters of \[GAHeading\]: metres per pulse of each wheel and the wheel base.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TickParams {
    /// k1: left wheel travel per pulse (m).
    pub k_left: f64,
    /// k2: right wheel travel per pulse (m).
    pub k_right: f64,
    /// b: wheel base (m).
    pub wheel_base: f64,
}

impl TickParams {
    /// From radii: k = 2π r / ticks_per_rev.
    pub fn from_diff_drive(k: &DiffDrive, ticks_per_rev: f64) -> Self {
        let t = 2.0 * PI / ticks_per_rev;
        Self {
            k_left: k.r_left * t,
            k_right: k.r_right * t,
            wheel_base: k.wheel_base,
        }
    }

    /// Back to radii: r = k · ticks_per_rev / 2π.
    pub fn to_diff_drive(&self, ticks_per_rev: f64) -> DiffDrive {
        let t = ticks_per_rev / (2.0 * PI);
        DiffDrive {
            r_right: self.k_right * t,
            r_left: self.k_left * t,
            wheel_base: self.wheel_base,
        }
    }

    fn from_array(a: [f64; 3]) -> Self {
        Self {
            k_left: a[0],
            k_right: a[1],
            wheel_base: a[2],
        }
    }
}

/// Search box of the GA.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaBounds {
    /// Lower bound of k1 and k2 (m/pulse).
    pub k_min: f64,
    /// Upper bound of k1 and k2 (m/pulse).
    pub k_max: f64,
    /// Lower bound of b (m).
    pub b_min: f64,
    /// Upper bound of b (m).
    pub b_max: f64,
}

impl Default for GaBounds {
    /// The restrictions of [GAHeading, Table 1]: 3.0e-4 < k < 4.5e-4 m/pulse, 0.35 < b < 0.39 m.
    fn default() -> Self {
        Self {
            k_min: 3.0e-4,
            k_max: 4.5e-4,
            b_min: 0.35,
            b_max: 0.39,
        }
    }
}

impl GaBounds {
    /// A box of ± `rel` (e.g. 0.1) around nominal parameters.
    pub fn around(nominal: &TickParams, rel: f64) -> Self {
        let k = 0.5 * (nominal.k_left + nominal.k_right);
        Self {
            k_min: k * (1.0 - rel),
            k_max: k * (1.0 + rel),
            b_min: nominal.wheel_base * (1.0 - rel),
            b_max: nominal.wheel_base * (1.0 + rel),
        }
    }

    fn lo_hi(&self) -> ([f64; 3], [f64; 3]) {
        (
            [self.k_min, self.k_min, self.b_min],
            [self.k_max, self.k_max, self.b_max],
        )
    }
}

/// GA settings ([GAHeading, Table 1]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaParams {
    /// Individuals per generation.
    pub population: usize,
    /// Best individuals copied unchanged.
    pub elites: usize,
    /// Fraction of the non-elite children made by crossover (rest by mutation).
    pub crossover_fraction: f64,
    /// Generations (the stop criterion).
    pub generations: usize,
    /// Initial mutation σ as a fraction of each bound's range.
    pub mutation_scale: f64,
    /// How much σ shrinks by the last generation (1 = to zero).
    pub mutation_shrink: f64,
    /// Weight of the end-heading error in the cost (m per rad).
    pub heading_weight: f64,
    /// Search box.
    pub bounds: GaBounds,
    /// Random seed.
    pub seed: u64,
}

impl Default for GaParams {
    /// 50 individuals, 2 elites, 0.8 crossover, 150 generations, mutation σ
    /// 0.1 × the bound range shrinking to 0, heading weight 1 m/rad, seed 1.
    /// \[GAHeading\] does not state σ; MATLAB's default (1 × range) leaves 0.2–1 %
    /// parameter errors on noise-free runs, 0.1 × range about 0.01–0.03 %.
    fn default() -> Self {
        Self {
            population: 50,
            elites: 2,
            crossover_fraction: 0.8,
            generations: 150,
            mutation_scale: 0.1,
            mutation_shrink: 1.0,
            heading_weight: 1.0,
            bounds: GaBounds::default(),
            seed: 1,
        }
    }
}

/// One calibration run: pulse-count increments and the measured start and end poses.
#[derive(Debug, Clone, PartialEq)]
pub struct GaRun {
    /// (left, right) pulse increments, in order.
    pub ticks: Vec<(f64, f64)>,
    /// Measured start pose `world_from_base`.
    pub start: Pose2,
    /// Measured end pose.
    pub end: Pose2,
}

impl GaRun {
    /// From a wheel-angle stream (rad): angles become whole pulse counts
    /// (rounded, as an encoder counts), one increment per sample.
    pub fn from_wheels(
        wheels: &[WheelSample],
        ticks_per_rev: f64,
        start: Pose2,
        end: Pose2,
    ) -> Self {
        let per_rad = ticks_per_rev / (2.0 * PI);
        let count = |a: f64| (a * per_rad).round();
        let ticks = wheels
            .windows(2)
            .map(|w| {
                (
                    count(w[1].left) - count(w[0].left),
                    count(w[1].right) - count(w[0].right),
                )
            })
            .collect();
        Self { ticks, start, end }
    }
}

/// Replays pulse increments with the model of [GAHeading, eqs. 1–7]: Δs = pulses · k,
/// Δθ = (Δs_r − Δs_l)/b, advance (Δs_r + Δs_l)/2 along the mid-step heading.
/// \[GAHeading\] measures θ from the y axis; this is the same model in REP 103.
pub fn replay_ticks(p: &TickParams, ticks: &[(f64, f64)], start: &Pose2) -> Pose2 {
    let [mut x, mut y, mut th] = geom::xyt(start);
    for &(pl, pr) in ticks {
        let (sl, sr) = (pl * p.k_left, pr * p.k_right);
        let dth = (sr - sl) / p.wheel_base;
        let du = 0.5 * (sr + sl);
        let mid = th + 0.5 * dth;
        x += du * mid.cos();
        y += du * mid.sin();
        th += dth;
    }
    geom::pose(x, y, th)
}

/// Cost of parameters: Σ over runs of |end position error| + w·|end heading error|.
pub fn ga_cost(p: &TickParams, runs: &[GaRun], heading_weight: f64) -> f64 {
    runs.iter()
        .map(|r| {
            let e = geom::between(&r.end, &replay_ticks(p, &r.ticks, &r.start));
            e.translation.vector.norm() + heading_weight * geom::heading(&e).abs()
        })
        .sum()
}

/// The GA's answer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GaResult {
    /// Best parameters found.
    pub params: TickParams,
    /// Their cost (m, heading weighted).
    pub cost: f64,
    /// Cost of the best individual after each generation.
    pub best_cost_history: Vec<f64>,
    /// Cost evaluations made.
    pub evaluations: usize,
}

/// Runs the GA on the calibration runs. Same params and runs → same result.
pub fn ga_calibrate(runs: &[GaRun], p: &GaParams) -> Result<GaResult, ClassicError> {
    let bounds = check_inputs(runs, p)?;
    let (lo, hi) = bounds;
    let mut rng = StdRng::seed_from_u64(p.seed);
    let cost = |pop: &[[f64; 3]]| -> Vec<f64> {
        pop.par_iter()
            .map(|g| ga_cost(&TickParams::from_array(*g), runs, p.heading_weight))
            .collect()
    };
    // Uniform initial population inside the bounds.
    let mut pop: Vec<[f64; 3]> = (0..p.population)
        .map(|_| std::array::from_fn(|i| rng.random_range(lo[i]..hi[i])))
        .collect();
    let mut costs = cost(&pop);
    let mut evaluations = pop.len();
    let mut history = Vec::with_capacity(p.generations);
    for g in 0..p.generations {
        let (next, elite_costs) = next_generation(&pop, &costs, p, g, bounds, &mut rng);
        let kid_costs = cost(&next[p.elites..]);
        evaluations += kid_costs.len();
        costs = elite_costs.into_iter().chain(kid_costs).collect();
        pop = next;
        history.push(costs.iter().copied().fold(f64::INFINITY, f64::min));
    }
    let best = (0..p.population)
        .min_by(|&a, &b| costs[a].total_cmp(&costs[b]))
        .unwrap_or(0);
    Ok(GaResult {
        params: TickParams::from_array(pop[best]),
        cost: costs[best],
        best_cost_history: history,
        evaluations,
    })
}

/// Lower and upper bounds of the genes [k1, k2, b].
type Bounds = ([f64; 3], [f64; 3]);

/// Checks the runs (at least one, finite pulse counts and poses) and the
/// settings; returns the search box.
fn check_inputs(runs: &[GaRun], p: &GaParams) -> Result<Bounds, ClassicError> {
    const M: &str = "ga";
    if runs.is_empty() {
        return Err(ClassicError::TooFew {
            method: M,
            what: "runs",
            needed: 1,
            got: 0,
        });
    }
    check_finite(
        M,
        "pulse count",
        runs.iter()
            .flat_map(|r| r.ticks.iter().flat_map(|t| [t.0, t.1])),
    )?;
    check_finite(
        M,
        "pose",
        runs.iter()
            .flat_map(|r| geom::xyt(&r.start).into_iter().chain(geom::xyt(&r.end))),
    )?;
    let (lo, hi) = p.bounds.lo_hi();
    if (0..3).any(|i| !(lo[i] > 0.0 && hi[i] > lo[i] && hi[i].is_finite())) {
        return Err(ClassicError::invalid(
            M,
            format!("bounds must satisfy 0 < min < max: {:?}", p.bounds),
        ));
    }
    if p.population < p.elites + 2
        || p.generations == 0
        || !(0.0..=1.0).contains(&p.crossover_fraction)
    {
        return Err(ClassicError::invalid(
            M,
            "population must exceed elites + 1, generations > 0, crossover fraction in [0, 1]",
        ));
    }
    Ok((lo, hi))
}

/// Generation `g + 1` from generation `g`: the elites unchanged, then
/// children by scattered crossover and by Gaussian mutation of parents drawn
/// by rank roulette. Returns the new population and the elites' costs.
fn next_generation(
    pop: &[[f64; 3]],
    costs: &[f64],
    p: &GaParams,
    g: usize,
    (lo, hi): Bounds,
    rng: &mut StdRng,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let n = p.population;
    let n_kids = n - p.elites;
    let n_cross = (p.crossover_fraction * n_kids as f64).round() as usize;
    let n_mut = n_kids - n_cross;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
    let roulette = RankRoulette::new(&order);
    let sigma_frac =
        p.mutation_scale * (1.0 - p.mutation_shrink * (g + 1) as f64 / p.generations as f64);
    let mut next: Vec<[f64; 3]> = order[..p.elites].iter().map(|&i| pop[i]).collect();
    for _ in 0..n_cross {
        let (a, b) = (pop[roulette.pick(rng)], pop[roulette.pick(rng)]);
        // Scattered crossover: each gene from a or b by a fair coin.
        next.push(std::array::from_fn(|i| {
            if rng.random_bool(0.5) {
                a[i]
            } else {
                b[i]
            }
        }));
    }
    for _ in 0..n_mut {
        let a = pop[roulette.pick(rng)];
        next.push(std::array::from_fn(|i| {
            let z: f64 = rng.sample(StandardNormal);
            (a[i] + sigma_frac.max(0.0) * (hi[i] - lo[i]) * z).clamp(lo[i], hi[i])
        }));
    }
    let elite_costs = order[..p.elites].iter().map(|&i| costs[i]).collect();
    (next, elite_costs)
}

/// Roulette selection on rank-scaled fitness: expectation ∝ 1/√rank
/// (MATLAB fitscalingrank).
struct RankRoulette<'a> {
    /// Individuals from best to worst.
    order: &'a [usize],
    /// Expectation of each rank.
    weights: Vec<f64>,
    /// Sum of the weights.
    total: f64,
}

impl<'a> RankRoulette<'a> {
    fn new(order: &'a [usize]) -> Self {
        let weights: Vec<f64> = (0..order.len())
            .map(|r| 1.0 / ((r + 1) as f64).sqrt())
            .collect();
        let total: f64 = weights.iter().sum();
        Self {
            order,
            weights,
            total,
        }
    }

    /// Draws one individual.
    fn pick(&self, rng: &mut StdRng) -> usize {
        let mut u = rng.random_range(0.0..self.total);
        for (r, w) in self.weights.iter().enumerate() {
            if u < *w {
                return self.order[r];
            }
            u -= w;
        }
        self.order[self.order.len() - 1]
    }
}
