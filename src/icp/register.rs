//! One registration: iterate closest points on the reference surface and a
//! Gauss–Newton step on the point-to-line residual until the pose stops
//! changing.
//!
//! Why Gauss–Newton rather than the closed-form (Arun/Umeyama) alignment of
//! each point onto its closest surface point: the closed form minimises the
//! point-to-point distance to targets that were themselves projected onto the
//! surface, so its step has the right gradient but an isotropic curvature —
//! along a wall the pull is weak and the pose slides there geometrically
//! (≈ 20 iterations per pair, and an early stop leaves a bias towards the
//! initial guess). The Gauss–Newton step uses the curvature of the
//! point-to-line cost itself and lands on its minimum for fixed
//! correspondences, so a pair converges in 3–5 iterations.

use super::covariance::{self, Correspondence, Uncertainty};
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
    /// Smallest Geman–McClure scale (m): the kernel never gets narrower than
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
    /// Correspondences of the last iteration.
    pub corrs: Vec<Correspondence>,
    /// Nearest reference point of each source point (search hint).
    hints: Vec<usize>,
    /// Reference line each source point was matched to (held when frozen).
    lines: Vec<usize>,
    abs_res: Vec<f64>,
}

/// Registers `source` (points in their own frame, with the unit normals of
/// their own surface, NaN when unknown) onto `reference` starting from
/// `init` = `[x, y, θ]`. Each iteration:
/// 1. move every source point by the current pose,
/// 2. find the nearest reference point (kd-tree, or a walk along the surface
///    from the previous iteration's once the steps are small) and the foot on
///    its fitted line,
/// 3. drop pairs whose point-to-line distance exceeds the gate or whose
///    normals differ by more than the allowed angle, weight the
///    rest with Geman–McClure `w = (κ² / (κ² + e²))²`, κ = 2 robust σ of
///    the residuals (MAD), within [`min_kappa`, gate / 3], never widening,
/// 4. take the reweighted Gauss–Newton step of Σ ρ(e) with
///    `e = nᵀ (R p + t − c)` (Newton's curvature once the correspondences
///    are frozen), plus the prior term `½ σ² (x − init)ᵀ P (x − init)`
///    (`P` = `prior_precision`, σ the residuals' robust scale), halving the
///    step length while steps reverse.
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
        abs_res,
    } = scratch;
    hints.clear();
    hints.resize(source.len(), usize::MAX);
    lines.clear();
    lines.resize(source.len(), usize::MAX);
    let mut use_hints = false;
    let mut kappa = f64::INFINITY;
    let mut frozen = false;
    // Step length factor: halved whenever a step reverses the previous one
    // (two correspondence sets pulling the pose back and forth), regrown
    // while successive steps agree.
    let mut trust = 1.0f64;
    let mut prev_step: Option<Vector3<f64>> = None;
    for it in 1..=set.max_iterations {
        out.iterations = it;
        let (s, c) = pose[2].sin_cos();
        corrs.clear();
        for (((&p, hint), line), &ns) in source
            .iter()
            .zip(hints.iter_mut())
            .zip(lines.iter_mut())
            .zip(normals)
        {
            let rp = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
            let q = [rp[0] + pose[0], rp[1] + pose[1]];
            let found: Option<Closest> = if frozen {
                if *line == usize::MAX {
                    continue;
                }
                reference.on_line(q, *line)
            } else {
                let near = if use_hints && *hint != usize::MAX {
                    reference.walk(q, *hint)
                } else {
                    reference.nearest(q)
                };
                let Some((j, d2)) = near else {
                    continue;
                };
                *hint = j;
                reference.correspondence(q, j, d2)
            };
            *line = found.map_or(usize::MAX, |c| c.index);
            let Some(cl) = found else {
                continue;
            };
            let e = cl.residual;
            if e.abs() > set.threshold || cl.vertex_dist > set.threshold + set.max_gap {
                continue;
            }
            // Both surfaces must face the same way: a source point on a
            // short face next to a corner is otherwise pulled onto the wall
            // of its nearest reference sample.
            let n = cl.normal;
            let rn = [c * ns[0] - s * ns[1], s * ns[0] + c * ns[1]];
            if !((rn[0] * n[0] + rn[1] * n[1]).abs() >= set.min_normal_cos) {
                continue;
            }
            corrs.push(Correspondence {
                p,
                q: cl.target,
                normal: Some(n),
                w: e,
            });
        }
        out.inliers = corrs.len();
        if corrs.len() < set.min_correspondences {
            return out;
        }
        // Robust scale of the residuals (MAD), so that the Geman–McClure
        // kernel follows the actual noise rather than the gate.
        abs_res.clear();
        abs_res.extend(corrs.iter().map(|k| k.w.abs()));
        let mid = abs_res.len() / 2;
        let mad = *abs_res.select_nth_unstable_by(mid, f64::total_cmp).1;
        // Never widening again keeps the iteration a descent (and convergent).
        kappa = (KAPPA_PER_SIGMA * 1.4826 * mad)
            .clamp(set.min_kappa, set.threshold / 3.0)
            .min(kappa);
        let kappa2 = kappa * kappa;
        let mut h = Matrix3::<f64>::zeros();
        let mut g = Vector3::<f64>::zeros();
        for k in corrs.iter_mut() {
            let e = k.w;
            let w = (kappa2 / (kappa2 + e * e)).powi(2);
            let n = k.normal.unwrap_or_default();
            let rp = [c * k.p[0] - s * k.p[1], s * k.p[0] + c * k.p[1]];
            let j = Vector3::new(n[0], n[1], n[1] * rp[0] - n[0] * rp[1]);
            // Once the correspondences are fixed, Newton's curvature of the
            // Geman–McClure cost, ρ'' = w (κ² − 3e²) / (κ² + e²), clamped at
            // zero: quadratic convergence where the reweighting alone
            // (curvature w) converges linearly at a rate of about one half.
            // Before, the reweighting curvature: always at least as large, so
            // the steps stay short while correspondences still change.
            let curv = if frozen {
                w * ((kappa2 - 3.0 * e * e) / (kappa2 + e * e)).max(0.0)
            } else {
                w
            };
            h += curv * j * j.transpose();
            g += (w * e) * j;
            k.w = w;
        }
        // The prior in the units of this cost: Σ ρ(e) is the negative
        // log-likelihood times the residual variance, which the kernel's
        // scale estimates (and the covariance inflation corrects for the
        // residuals' correlation, as in `covariance`).
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
        let damp = DAMPING * h.trace();
        for k in 0..3 {
            h[(k, k)] += damp;
        }
        let Some(chol) = h.cholesky() else {
            return out;
        };
        let mut d = -chol.solve(&g);
        if !d.iter().all(|v| v.is_finite()) {
            return out;
        }
        // A step that undoes the previous one means the correspondences
        // flip between two sets: shorten the steps until they settle.
        if let Some(prev) = prev_step {
            let lever = Vector3::new(1.0, 1.0, LEVER * LEVER);
            let dot = d.component_mul(&lever).dot(&prev);
            if dot < 0.0 {
                trust = (trust * 0.5).max(1.0 / 64.0);
            } else {
                trust = (trust * 2.0).min(1.0);
            }
        }
        d *= trust;
        // Never jump farther than the gate in one step: beyond it the
        // correspondences of this iteration say nothing.
        let moved = d.xy().norm() + d.z.abs() * LEVER;
        if moved > set.threshold {
            d *= set.threshold / moved;
        }
        pose = [
            pose[0] + d.x,
            pose[1] + d.y,
            crate::geom::wrap_angle(pose[2] + d.z),
        ];
        out.pose = pose;
        use_hints = moved < HINT_STEP;
        frozen |= moved < FREEZE_STEP;
        prev_step = Some(d);
        if d.xy().norm() + d.z.abs() < set.convergence {
            out.converged = true;
            break;
        }
    }
    out.uncertainty = covariance::estimate(corrs, pose, set.cov_inflation);
    out
}
