//! One registration: iterate closest points on the reference surface and a
//! Gauss–Newton step on the point-to-line residual until the pose stops
//! changing.
//!
//! Why Gauss–Newton rather than the closed-form [Arun1987; Umeyama1991] alignment of
//! each point onto its closest surface point: the closed form minimises the
//! point-to-point distance to targets that were themselves projected onto the
//! surface, so its step has the right gradient but an isotropic curvature —
//! along a wall the pull is weak and the pose slides there geometrically
//! (≈ 20 iterations per pair, and an early stop leaves a bias towards the
//! initial guess). The Gauss–Newton step uses the curvature of the
//! point-to-line cost itself and lands on its minimum for fixed
//! correspondences, so a pair converges in 3–5 iterations.

use super::covariance::{self, Correspondence, Uncertainty};
use super::metric::{self, Placement};
use super::reference::{Closest, Reference};

use nalgebra::{Matrix3, Vector3};

/// Settings of one registration (a slice of `IcpParams`).
#[derive(Debug, Clone, Copy)]
pub struct RegisterSettings {
    /// Correspondence gate on the point-to-line distance (m); the robust
    /// kernel's scale is at most a third of it.
    pub threshold: f64,
    /// Largest distance (m) from a source point to its nearest reference
    /// point beyond the gate (the surface link length).
    pub max_gap: f64,
    /// Cosine of the largest angle between the source point's own surface
    /// normal and the reference line's normal.
    pub min_normal_cos: f64,
    /// Smallest Geman–McClure \[GemanMcClure1987\] scale (m): the kernel never gets narrower than
    /// the sensor noise floor, however well a pair fits.
    pub min_kappa: f64,
    /// Iteration cap.
    pub max_iterations: u32,
    /// Stop when one iteration moves the pose less than this (m, rad × 1 m).
    pub convergence: f64,
    /// Fewest correspondences to accept an iteration.
    pub min_correspondences: usize,
    /// Covariance inflation factor.
    pub cov_inflation: f64,
    /// The error minimised: point-to-line, or point-to-point (the same
    /// correspondences, the distance from the nearest point itself).
    pub metric: metric::Metric,
    /// Inverse variances (1/m², 1/m², 1/rad²) of a prior centred on the
    /// initial guess; zeros for none. Holds the directions the geometry
    /// leaves loose (a corridor's axis) at the guess, and barely moves the
    /// others, where hundreds of residuals outweigh it.
    pub prior_precision: [f64; 3],
}

/// Lever arm (m) that turns a rotation step into a point displacement when
/// limiting steps and choosing the correspondence search.
const LEVER: f64 = 5.0;
/// Steps that move points less than this (m) keep the previous iteration's
/// nearest points as search hints.
const HINT_STEP: f64 = 0.02;
/// Steps that move points less than this (m) freeze the correspondences: from
/// then on the iteration is Gauss–Newton on one fixed least-squares problem,
/// which converges quadratically instead of cycling between neighbouring
/// reference samples at the 10 µm level.
const FREEZE_STEP: f64 = 2e-4;
/// Geman–McClure scale in robust standard deviations of the residuals.
const KAPPA_PER_SIGMA: f64 = 2.0;
/// Relative Levenberg damping: directions the geometry does not constrain
/// (a featureless corridor) stay at the initial guess instead of drifting.
const DAMPING: f64 = 1e-9;

/// Outcome of one registration.
#[derive(Debug, Clone)]
pub struct Registration {
    /// `reference_from_source` as `[x, y, θ]` (m, rad).
    pub pose: [f64; 3],
    /// Iterations run.
    pub iterations: u32,
    /// Whether the pose change fell below the convergence bound.
    pub converged: bool,
    /// Correspondences of the last iteration.
    pub inliers: usize,
    /// Covariance and conditioning, when the information is invertible.
    pub uncertainty: Option<Uncertainty>,
}

/// Scratch space of [`register`], kept between pairs so that a registration
/// allocates nothing in steady state.
#[derive(Debug, Default)]
pub struct Scratch {
    /// Correspondences of the last iteration (`tilt_var` filled in once
    /// `register` gets to the covariance, NaN before).
    pub corrs: Vec<Correspondence>,
    /// Nearest reference point of each source point (search hint).
    hints: Vec<usize>,
    /// Reference line each source point was matched to (held when frozen).
    lines: Vec<usize>,
    /// The absolute residuals' median (scratch, and the last one).
    median: Median,
    /// Reference line of each correspondence in `corrs`.
    corr_lines: Vec<usize>,
}

/// Registers `source` (points in their own frame, with the unit normals of
/// their own surface, NaN when unknown) onto `reference` starting from
/// `init` = `[x, y, θ]`. Each iteration:
/// 1. [`associate`]: move every source point by the current pose, find the
///    nearest reference point (grid search, or a walk along the surface from the
///    previous iteration's once the steps are small) and the foot on its
///    fitted line, and drop pairs whose point-to-line distance exceeds the
///    gate or whose normals differ by more than the allowed angle,
/// 2. [`robust_scale`] and [`weigh`]: Geman–McClure weights
///    `w = (κ² / (κ² + e²))²`, κ = 2 robust σ of the residuals (MAD),
///    within [`min_kappa`, gate / 3], never widening,
/// 3. [`normal_system`] and [`add_prior`]: the reweighted Gauss–Newton
///    system of Σ ρ(e) with `e = nᵀ (R p + t − c)` (see `metric`; Newton's
///    curvature once the correspondences are frozen), plus the prior term
///    `½ σ² (x − init)ᵀ P (x − init)` (`P` = `prior_precision`, σ the
///    residuals' robust scale),
/// 4. [`damped_step`] and [`StepControl::limit`]: its damped solution,
///    halving the step length while steps reverse, never beyond the gate,
/// 5. [`converged`]: stop once the step is below `convergence`.
///
/// The returned covariance is the residuals' alone: the prior never makes a
/// loose direction look measured.
pub fn register(
    reference: &Reference,
    source: &[[f64; 2]],
    normals: &[[f64; 2]],
    init: [f64; 3],
    set: &RegisterSettings,
    scratch: &mut Scratch,
) -> Registration {
    let mut pose = init;
    let mut out = Registration {
        pose,
        iterations: 0,
        converged: false,
        inliers: 0,
        uncertainty: None,
    };
    if reference.is_empty() {
        return out;
    }
    let Scratch {
        corrs,
        hints,
        lines,
        median,
        corr_lines,
    } = scratch;
    median.last = None;
    hints.clear();
    hints.resize(source.len(), usize::MAX);
    lines.clear();
    lines.resize(source.len(), usize::MAX);
    let mut search = Search::default();
    let mut kappa = f64::INFINITY;
    let mut control = StepControl::default();
    for it in 1..=set.max_iterations {
        out.iterations = it;
        let at = Placement::new(pose);
        let memory = Memory {
            hints,
            lines,
            search,
        };
        let found = Found {
            corrs,
            lines: corr_lines,
        };
        associate(reference, source, normals, &at, set, memory, found);
        out.inliers = corrs.len();
        if corrs.len() < set.min_correspondences {
            return out;
        }
        kappa = robust_scale(corrs, median, set, kappa);
        weigh(corrs, kappa);
        let (mut h, mut g) = normal_system(corrs, &at, kappa, search.frozen, set.metric);
        add_prior(&mut h, &mut g, kappa, pose, init, set);
        let Some(d) = damped_step(h, g) else {
            return out;
        };
        let (d, moved) = control.limit(d, set.threshold);
        pose = [
            pose[0] + d.x,
            pose[1] + d.y,
            crate::geom::wrap_angle(pose[2] + d.z),
        ];
        out.pose = pose;
        search.use_hints = moved < HINT_STEP;
        // Point-to-point is never frozen: its nearest points change as the
        // pose slides along a wall, which is how it gets there at all.
        search.frozen |= moved < FREEZE_STEP && set.metric == metric::Metric::PointToLine;
        if converged(&d, set) {
            out.converged = true;
            break;
        }
    }
    for (k, &j) in corrs.iter_mut().zip(corr_lines.iter()) {
        k.tilt_var = reference.tilt_variance(j);
        if set.metric == metric::Metric::PointToPoint {
            // The covariance's point-to-point rows, from `q` itself.
            k.normal = None;
        }
    }
    out.uncertainty = covariance::estimate(corrs, pose, set.cov_inflation);
    out
}

/// How the correspondences of an iteration are searched.
#[derive(Debug, Clone, Copy, Default)]
struct Search {
    /// Start from the previous iteration's nearest points (small steps).
    use_hints: bool,
    /// Keep the previous iteration's lines (steps below `FREEZE_STEP`).
    frozen: bool,
}

/// Where [`associate`] puts the correspondences and, beside them, their
/// reference lines.
struct Found<'a> {
    corrs: &'a mut Vec<Correspondence>,
    lines: &'a mut Vec<usize>,
}

/// What an iteration keeps of the previous one's association: per source
/// point, and how to use it.
struct Memory<'a> {
    /// Nearest reference point (search hint), `usize::MAX` for none.
    hints: &'a mut [usize],
    /// Reference line matched to (held when frozen), `usize::MAX` for none.
    lines: &'a mut [usize],
    search: Search,
}

/// Step 1, association: each source point `p`, moved to `x = R p + t` by
/// the placement `at`, corresponds to the foot of `x` on its nearest
/// reference point's fitted line (or, frozen, on the line it had), with the
/// point-to-line residual `e = nᵀ (x − c)`. Kept when `|e| ≤ τ` (the
/// adaptive gate), the nearest point is within `τ + max_gap`, and the
/// surfaces face the same way, `|(R n_p)ᵀ n| ≥ cos α_max`. Point-to-point
/// keeps the same correspondences and stores the nearest point itself with
/// `u` and `|x − q|` of `metric::point_to_point` as its normal and residual. Each
/// correspondence's line goes beside it; its `tilt_var` is left NaN (no
/// iteration uses it: `register` fills in the last iteration's).
fn associate(
    reference: &Reference,
    source: &[[f64; 2]],
    normals: &[[f64; 2]],
    at: &Placement,
    set: &RegisterSettings,
    memory: Memory,
    found: Found,
) {
    let Found {
        corrs,
        lines: corr_lines,
    } = found;
    corrs.clear();
    corr_lines.clear();
    let reach = set.threshold + set.max_gap;
    for (((&p, hint), line), &ns) in source
        .iter()
        .zip(memory.hints.iter_mut())
        .zip(memory.lines.iter_mut())
        .zip(normals)
    {
        // A point without a surface normal of its own is never admitted
        // (`admits` refuses a NaN normal), and its hint and line serve no
        // other point: it is not searched for (every correspondence the
        // same as with the search; 13–15 % of the benchmark logs' points).
        if !ns[0].is_finite() {
            continue;
        }
        let x = at.apply(p).x;
        let Some(cl) = find(reference, x, hint, line, memory.search, reach) else {
            continue;
        };
        if !admits(&cl, at.rotate(ns), set) {
            continue;
        }
        let (q, normal, residual) = match set.metric {
            metric::Metric::PointToLine => (cl.target, cl.normal, cl.residual),
            metric::Metric::PointToPoint => {
                let q = reference.point(cl.index);
                let (u, d) = metric::point_to_point(x, q);
                (q, u, d)
            }
        };
        corrs.push(Correspondence {
            p,
            q,
            normal: Some(normal),
            residual,
            weight: 1.0,
            tilt_var: f64::NAN,
        });
        corr_lines.push(cl.index);
    }
}

/// The correspondence of the moved point `q`: on the line it had when
/// frozen, else on the line of its nearest reference point (walked to from
/// `hint` when hints are in use). A search finds only points within
/// `max_dist` m (beyond it `admits` refuses every correspondence). Updates
/// `hint` and `line`.
fn find(
    reference: &Reference,
    q: [f64; 2],
    hint: &mut usize,
    line: &mut usize,
    search: Search,
    max_dist: f64,
) -> Option<Closest> {
    let found = if search.frozen {
        if *line == usize::MAX {
            return None;
        }
        reference.on_line(q, *line)
    } else {
        let near = if search.use_hints && *hint != usize::MAX {
            reference.walk(q, *hint)
        } else {
            reference.nearest(q, max_dist)
        };
        let Some((j, d2)) = near else {
            *hint = usize::MAX;
            *line = usize::MAX;
            return None;
        };
        *hint = j;
        reference.correspondence(q, j, d2)
    };
    *line = found.map_or(usize::MAX, |c| c.index);
    found
}

/// The gate of step 1 for a correspondence `cl` whose source point's own
/// normal, rotated into the reference frame, is `rn` (NaN when unknown:
/// never admitted).
fn admits(cl: &Closest, rn: [f64; 2], set: &RegisterSettings) -> bool {
    if cl.residual.abs() > set.threshold || cl.vertex_dist > set.threshold + set.max_gap {
        return false;
    }
    // Both surfaces must face the same way: a source point on a short face
    // next to a corner is otherwise pulled onto the wall of its nearest
    // reference sample.
    let n = cl.normal;
    (rn[0] * n[0] + rn[1] * n[1]).abs() >= set.min_normal_cos
}

/// Step 2, robust scale: `κ = min(κ_prev, clamp(2 · 1.4826 · median|e|,
/// min_kappa, τ / 3))`, the residuals' MAD as a standard deviation, so that
/// the Geman–McClure kernel follows the actual noise rather than the gate.
/// Never widening again keeps the iteration a descent (and convergent).
fn robust_scale(
    corrs: &[Correspondence],
    median: &mut Median,
    set: &RegisterSettings,
    kappa: f64,
) -> f64 {
    // Non-negative floats order as their bit patterns: an integer selection.
    let keys = corrs.iter().map(|k| k.residual.abs().to_bits());
    let mad = f64::from_bits(median.select(keys));
    (KAPPA_PER_SIGMA * 1.4826 * mad)
        .clamp(set.min_kappa, set.threshold / 3.0)
        .min(kappa)
}

/// Relative half-width of the bracket around the previous median in which
/// [`Median::select`] looks first.
const BRACKET: f64 = 0.15;

/// Scratch of the residuals' median, and the last one found.
#[derive(Debug, Default)]
struct Median {
    /// The keys (all of them, or those within the bracket).
    keys: Vec<u64>,
    /// The last median's key (`None` at a registration's start).
    last: Option<u64>,
}

impl Median {
    /// The upper median (the `len / 2`-th smallest, 0-based) of `keys`,
    /// non-negative floats as bit patterns (ordered as the floats): the
    /// same value as a selection over all of them, found cheaper. The
    /// residuals change little from one iteration to the next, so one pass
    /// counts the keys below `last · (1 − BRACKET)` and gathers those up to
    /// `last · (1 + BRACKET)`; when the median's rank falls among the
    /// gathered, a selection over those few gives it, else a selection over
    /// all. No keys give 0. Measured with callgrind on the first 2,500
    /// Intel scans: the medians' 107 M instructions fall to 47 M.
    fn select(&mut self, keys: impl Iterator<Item = u64> + Clone) -> u64 {
        let found = self
            .last
            .and_then(|last| self.select_near(keys.clone(), last));
        let m = found.unwrap_or_else(|| {
            self.keys.clear();
            self.keys.extend(keys);
            if self.keys.is_empty() {
                return 0;
            }
            let mid = self.keys.len() / 2;
            *self.keys.select_nth_unstable(mid).1
        });
        self.last = Some(m);
        m
    }

    /// The median of `keys` if it lies within the bracket around `last`:
    /// `below` keys are smaller than the bracket, so it is the
    /// `(mid − below)`-th smallest of those within.
    fn select_near(&mut self, keys: impl Iterator<Item = u64>, last: u64) -> Option<u64> {
        let g = f64::from_bits(last);
        let (lo, hi) = (
            (g * (1.0 - BRACKET)).to_bits(),
            (g * (1.0 + BRACKET)).to_bits(),
        );
        self.keys.clear();
        let (mut below, mut n) = (0usize, 0usize);
        for k in keys {
            n += 1;
            if k < lo {
                below += 1;
            } else if k <= hi {
                self.keys.push(k);
            }
        }
        let rank = (n / 2)
            .checked_sub(below)
            .filter(|&r| r < self.keys.len())?;
        Some(*self.keys.select_nth_unstable(rank).1)
    }
}

/// Step 2, weights: Geman–McClure `w = (κ² / (κ² + e²))²` of each residual.
fn weigh(corrs: &mut [Correspondence], kappa: f64) {
    let kappa2 = kappa * kappa;
    for k in corrs.iter_mut() {
        let e = k.residual;
        k.weight = (kappa2 / (kappa2 + e * e)).powi(2);
    }
}

/// Step 3, the normal system `H = Σ ρ''ᵢ Jᵢ Jᵢᵀ`, `g = Σ wᵢ eᵢ Jᵢ` of the
/// weighted residuals at the placement `at` (`J` from `metric::jacobian`),
/// in correspondence order, each correspondence's rows of `metric::rows`
/// (point-to-point: the row across `u` has residual 0, so its curvature is
/// `w` and it adds nothing to `g`: the Hessian of `ρ(|x − q|)` in the plane).
fn normal_system(
    corrs: &[Correspondence],
    at: &Placement,
    kappa: f64,
    frozen: bool,
    metric: metric::Metric,
) -> (Matrix3<f64>, Vector3<f64>) {
    let kappa2 = kappa * kappa;
    // Plain sums rather than nalgebra's outer product: the same products
    // `(ρ'' J_r) J_c` and `(w e) J_r`, summed in the same order, without the
    // general matrix product's loops; of `H` only the lower triangle
    // (`h[r][c]`, c ≤ r, row by row), all that the Cholesky factorisation of
    // `damped_step` reads.
    let mut h = [0.0; 6];
    let mut g = [0.0; 3];
    for k in corrs {
        let rp = at.rotate(k.p);
        let (rows, n) = metric::rows(metric, k.normal.unwrap_or_default(), k.residual);
        for &(normal, e) in &rows[..n] {
            let w = k.weight;
            let j = metric::jacobian(rp, normal);
            let curv = curvature(e, w, kappa2, frozen);
            let cj = [curv * j.x, curv * j.y, curv * j.z];
            h[0] += cj[0] * j.x;
            h[1] += cj[1] * j.x;
            h[2] += cj[1] * j.y;
            h[3] += cj[2] * j.x;
            h[4] += cj[2] * j.y;
            h[5] += cj[2] * j.z;
            let we = w * e;
            g[0] += we * j.x;
            g[1] += we * j.y;
            g[2] += we * j.z;
        }
    }
    #[rustfmt::skip]
    let h = Matrix3::new(
        h[0], h[1], h[3],
        h[1], h[2], h[4],
        h[3], h[4], h[5],
    );
    (h, Vector3::from(g))
}

/// The curvature `ρ''` a residual `e` of weight `w` contributes. Once the
/// correspondences are fixed, Newton's curvature of the Geman–McClure cost,
/// `ρ'' = w (κ² − 3e²) / (κ² + e²)`, clamped at zero: quadratic convergence
/// where the reweighting alone (curvature `w`) converges linearly at a rate
/// of about one half. Before, the reweighting curvature `w`: always at least
/// as large, so the steps stay short while correspondences still change.
fn curvature(e: f64, w: f64, kappa2: f64, frozen: bool) -> f64 {
    if frozen {
        w * ((kappa2 - 3.0 * e * e) / (kappa2 + e * e)).max(0.0)
    } else {
        w
    }
}

/// Step 3, the weak prior term `½ σ² (x − init)ᵀ P (x − init)`:
/// `H += σ² P`, `g += σ² P (x − init)` (θ wrapped), with
/// `σ² = (κ / 2)² · cov_inflation`. That is the prior in the units of this
/// cost: Σ ρ(e) is the negative log-likelihood times the residual variance,
/// which the kernel's scale estimates (and the covariance inflation corrects
/// for the residuals' correlation, as in `covariance`).
fn add_prior(
    h: &mut Matrix3<f64>,
    g: &mut Vector3<f64>,
    kappa: f64,
    pose: [f64; 3],
    init: [f64; 3],
    set: &RegisterSettings,
) {
    let var = (kappa / KAPPA_PER_SIGMA).powi(2) * set.cov_inflation;
    let off = [
        pose[0] - init[0],
        pose[1] - init[1],
        crate::geom::wrap_angle(pose[2] - init[2]),
    ];
    for k in 0..3 {
        h[(k, k)] += var * set.prior_precision[k];
        g[k] += var * set.prior_precision[k] * off[k];
    }
}

/// Step 4, the damped Gauss–Newton step: `(H + λ tr(H) I) d = −g`,
/// `λ` = `DAMPING`, solved by Cholesky; `None` when `H` is not positive
/// definite or the step is not finite.
fn damped_step(mut h: Matrix3<f64>, g: Vector3<f64>) -> Option<Vector3<f64>> {
    let damp = DAMPING * h.trace();
    for k in 0..3 {
        h[(k, k)] += damp;
    }
    let d = -h.cholesky()?.solve(&g);
    d.iter().all(|v| v.is_finite()).then_some(d)
}

/// Step 4, the step length: a factor halved whenever a step reverses the
/// previous one (two correspondence sets pulling the pose back and forth),
/// regrown while successive steps agree.
#[derive(Debug, Clone, Copy)]
struct StepControl {
    trust: f64,
    prev: Option<Vector3<f64>>,
}

impl Default for StepControl {
    fn default() -> Self {
        Self {
            trust: 1.0,
            prev: None,
        }
    }
}

impl StepControl {
    /// The step `d` to take: scaled by the trust factor, whose update tests
    /// `dᵀ diag(1, 1, L²) d_prev < 0` (L = `LEVER`), then shortened to move
    /// points by at most the gate `threshold` (m), `|d_xy| + L |d_θ| ≤ τ`:
    /// beyond it the correspondences of this iteration say nothing. Also
    /// returns that displacement before the gate's cap.
    fn limit(&mut self, mut d: Vector3<f64>, threshold: f64) -> (Vector3<f64>, f64) {
        if let Some(prev) = self.prev {
            let lever = Vector3::new(1.0, 1.0, LEVER * LEVER);
            let dot = d.component_mul(&lever).dot(&prev);
            if dot < 0.0 {
                self.trust = (self.trust * 0.5).max(1.0 / 64.0);
            } else {
                self.trust = (self.trust * 2.0).min(1.0);
            }
        }
        d *= self.trust;
        let moved = d.xy().norm() + d.z.abs() * LEVER;
        if moved > threshold {
            d *= threshold / moved;
        }
        self.prev = Some(d);
        (d, moved)
    }
}

/// Step 5, convergence: `|d_xy| + |d_θ| < convergence` (m, rad × 1 m).
fn converged(d: &Vector3<f64>, set: &RegisterSettings) -> bool {
    d.xy().norm() + d.z.abs() < set.convergence
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The normal system is `Σ ρ'' J Jᵀ` and `Σ w e J` (nalgebra's outer
    /// products here), whole and exactly symmetric although only its lower
    /// triangle is summed.
    #[test]
    fn normal_system_is_the_symmetric_sum_of_outer_products() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let at = Placement::new([0.3, -0.2, 0.7]);
        let kappa: f64 = 0.02;
        let mut corrs: Vec<Correspondence> = (0..50)
            .map(|_| {
                let a = rng.random::<f64>() * std::f64::consts::TAU;
                let e = (rng.random::<f64>() - 0.5) * 0.06;
                Correspondence {
                    p: [
                        rng.random::<f64>() * 8.0 - 4.0,
                        rng.random::<f64>() * 8.0 - 4.0,
                    ],
                    q: [0.0; 2],
                    normal: Some([a.cos(), a.sin()]),
                    residual: e,
                    weight: 1.0,
                    tilt_var: f64::NAN,
                }
            })
            .collect();
        weigh(&mut corrs, kappa);
        for frozen in [false, true] {
            let (h, g) = normal_system(&corrs, &at, kappa, frozen, metric::Metric::PointToLine);
            let (mut h_want, mut g_want) = (Matrix3::zeros(), Vector3::zeros());
            for k in &corrs {
                let j = metric::jacobian(at.rotate(k.p), k.normal.unwrap());
                let curv = curvature(k.residual, k.weight, kappa * kappa, frozen);
                h_want += curv * j * j.transpose();
                g_want += k.weight * k.residual * j;
            }
            assert_eq!(h, h.transpose(), "frozen {frozen}");
            let scale = h_want.norm();
            assert!(
                (h - h_want).norm() <= 1e-12 * scale,
                "frozen {frozen}: {h} vs {h_want}"
            );
            assert!((g - g_want).norm() <= 1e-12 * g_want.norm().max(1e-300));
        }
    }

    /// A room corner as a reference: the wall y = 2 (x from −2 to 2) and the
    /// wall x = 2.5 (y from −1 to 2), sampled every 3 cm with ±2 mm of noise;
    /// also its two walls' sample counts.
    fn corner_reference() -> (Reference, usize, usize) {
        use super::super::preprocess::ScanPoints;
        let noise = |i: usize| 0.002 * (((i * 7919) % 17) as f64 / 8.0 - 1.0);
        let wall_a = |i: usize| [-2.0 + 0.03 * i as f64, 2.0 + noise(i)];
        let wall_b = |i: usize| [2.5 + noise(i + 500), -1.0 + 0.03 * i as f64];
        let (na, nb) = (134, 100);
        let mut pts: Vec<[f64; 2]> = (0..na).map(wall_a).collect();
        pts.extend((0..nb).map(wall_b));
        let link = (0..na + nb)
            .map(|i| i + 1 != na && i + 1 != na + nb)
            .collect();
        let sp = ScanPoints {
            range: vec![2.0; pts.len()],
            pts,
            link,
        };
        let mut reference = Reference::new(8, 0.3);
        reference.set(&sp);
        (reference, na, nb)
    }

    /// Settings that register the corner: a wide gate, point-to-line, no prior.
    fn corner_settings() -> RegisterSettings {
        RegisterSettings {
            threshold: 0.3,
            max_gap: 0.5,
            min_normal_cos: 0.5f64.cos(),
            min_kappa: 0.005,
            max_iterations: 60,
            convergence: 1e-5,
            min_correspondences: 15,
            cov_inflation: 1.7,
            metric: metric::Metric::PointToLine,
            prior_precision: [0.0; 3],
        }
    }

    /// Source points (m, in their own frame) with their unit normals.
    type Sampled = Vec<([f64; 2], [f64; 2])>;

    /// The corner's walls sampled between the reference's samples, seen from
    /// `truth` (reference_from_source), with their normals; then the same
    /// with clutter without a normal interleaved, on the walls and off them.
    fn corner_source(truth: [f64; 3], na: usize, nb: usize) -> (Sampled, Sampled) {
        let (s, c) = truth[2].sin_cos();
        let into_source = |p: [f64; 2]| {
            let (dx, dy) = (p[0] - truth[0], p[1] - truth[1]);
            [c * dx + s * dy, -s * dx + c * dy]
        };
        let (normal_a, normal_b) = ([s, c], [c, -s]);
        let mut walls = Vec::new();
        for i in 0..na - 1 {
            walls.push((into_source([-1.985 + 0.03 * i as f64, 2.0]), normal_a));
        }
        for i in 0..nb - 1 {
            walls.push((into_source([2.5, -0.985 + 0.03 * i as f64]), normal_b));
        }
        let mut all = Vec::new();
        for (k, w) in walls.iter().enumerate() {
            all.push(*w);
            if k % 4 == 0 {
                let on_wall = into_source([-1.9 + 0.011 * k as f64, 2.0]);
                let off = into_source([0.3 + 0.007 * k as f64, 1.5 - 0.004 * k as f64]);
                let p = if k % 8 == 0 { on_wall } else { off };
                all.push((p, [f64::NAN; 2]));
            }
        }
        (walls, all)
    }

    /// Source points without a normal of their own (clutter, isolated
    /// returns) never take part: a registration with them, even lying on
    /// the walls and interleaved with the others, ends bit for bit where
    /// it ends without them, in as many iterations and with as many
    /// correspondences; and it finds the corner's true pose.
    #[test]
    fn points_without_a_normal_never_change_a_registration() {
        let (reference, na, nb) = corner_reference();
        let truth: [f64; 3] = [0.03, -0.02, 0.01];
        let (walls, all) = corner_source(truth, na, nb);
        let set = corner_settings();
        let run = |pairs: &[([f64; 2], [f64; 2])]| {
            let (src, normals): (Vec<_>, Vec<_>) = pairs.iter().copied().unzip();
            register(
                &reference,
                &src,
                &normals,
                [0.0; 3],
                &set,
                &mut Scratch::default(),
            )
        };
        let (with, without) = (run(&all), run(&walls));
        assert!(all.len() > walls.len() + 40);
        let bits = |p: [f64; 3]| p.map(f64::to_bits);
        assert_eq!(bits(with.pose), bits(without.pose));
        assert_eq!(
            (with.iterations, with.converged, with.inliers),
            (without.iterations, without.converged, without.inliers)
        );
        let cov = |r: &Registration| r.uncertainty.map(|u| u.cov.map(f64::to_bits));
        assert_eq!(cov(&with), cov(&without));
        // The setting is one a registration solves.
        assert!(without.converged && without.inliers > 200, "{without:?}");
        let err = [0, 1, 2].map(|k| (without.pose[k] - truth[k]).abs());
        assert!(err[0] < 2e-3 && err[1] < 2e-3 && err[2] < 1e-3, "{err:?}");
    }

    /// Point-to-point against point-to-line on a source made of the
    /// reference's own noisy samples seen from `truth`, from a guess a few
    /// millimetres off (within half the 3 cm sample spacing: from 4 cm
    /// point-to-point settles with every point on a neighbour's sample, its
    /// well-known local minimum): point-to-point puts every point back on
    /// its own sample (the pose exactly, residuals 0), point-to-line on the
    /// fitted lines, the samples' ±2 mm of noise off them (residuals of
    /// that size, the pose within a millimetre).
    #[test]
    fn point_to_point_puts_the_samples_back_on_themselves() {
        let (reference, na, nb) = corner_reference();
        let truth: [f64; 3] = [0.04, -0.03, 0.02];
        let (s, c) = truth[2].sin_cos();
        let (mut src, mut normals) = (Vec::new(), Vec::new());
        for j in 0..na + nb {
            let Some(n) = reference.normal(j) else {
                continue;
            };
            let q = reference.point(j);
            let (dx, dy) = (q[0] - truth[0], q[1] - truth[1]);
            src.push([c * dx + s * dy, -s * dx + c * dy]);
            normals.push([c * n[0] + s * n[1], -s * n[0] + c * n[1]]);
        }
        let run = |metric| {
            let set = RegisterSettings {
                min_kappa: 1e-4,
                max_iterations: 100,
                convergence: 1e-9,
                cov_inflation: 1.0,
                metric,
                ..corner_settings()
            };
            let init = [truth[0] - 0.006, truth[1] + 0.004, truth[2] - 0.002];
            register(
                &reference,
                &src,
                &normals,
                init,
                &set,
                &mut Scratch::default(),
            )
        };
        let (pp, pl) = (
            run(metric::Metric::PointToPoint),
            run(metric::Metric::PointToLine),
        );
        let err = |r: &Registration| [0, 1, 2].map(|k| (r.pose[k] - truth[k]).abs());
        assert!(pp.converged && pp.inliers > 200, "{pp:?}");
        assert!(err(&pp).iter().all(|e| *e < 1e-7), "{:?}", err(&pp));
        let rms = |r: &Registration| r.uncertainty.unwrap().rms;
        assert!(rms(&pp) < 1e-7, "{}", rms(&pp));
        assert!(
            pl.converged && err(&pl).iter().all(|e| *e < 1e-3),
            "{:?}",
            err(&pl)
        );
        assert!(rms(&pl) > 3e-4 && rms(&pl) < 3e-3, "{}", rms(&pl));
        // Its covariance holds the point-to-point rows' information: both
        // axes and the turn, each as `[I | ∂(R p)/∂θ]` sums it.
        let u = pp.uncertainty.unwrap();
        assert!(
            u.cov.iter().all(|v| v.is_finite()) && u.conditioning > 1e-3,
            "{u:?}"
        );
    }

    /// The bracketed selection gives the sorted keys' upper median whatever
    /// the previous median: near, far below, far above, zero, and with ties.
    #[test]
    fn median_is_the_sorted_upper_median_whatever_the_last_one() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut m = Median::default();
        assert_eq!(m.select(std::iter::empty()), 0);
        for n in [1usize, 2, 3, 10, 101, 500] {
            for round in 0..40 {
                let vals: Vec<f64> = (0..n)
                    .map(|_| match round % 4 {
                        // Ties: a few distinct values only.
                        0 => f64::from(rng.random_range(0..4u8)) * 0.01,
                        _ => rng.random::<f64>().powi(2) * 0.05,
                    })
                    .collect();
                let mut sorted = vals.clone();
                sorted.sort_by(f64::total_cmp);
                let want = sorted[n / 2];
                for last in [
                    None,
                    Some(want),
                    Some(want * 1.1),
                    Some(0.0),
                    Some(1e-9),
                    Some(9.0),
                ] {
                    m.last = last.map(f64::to_bits);
                    let keys = vals.iter().map(|v| v.to_bits());
                    assert_eq!(f64::from_bits(m.select(keys)), want, "n {n} last {last:?}");
                }
            }
        }
    }
}
