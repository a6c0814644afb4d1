//! One registration: iterate closest points on the reference and the
//! closed-form alignment until the pose stops changing.

use super::align::Aligner;
use super::covariance::{self, Correspondence, Uncertainty};
use super::reference::Reference;

/// Settings of one registration (a slice of `IcpParams`).
#[derive(Debug, Clone, Copy)]
pub struct RegisterSettings {
    /// Correspondence gate (m); the Geman–McClure scale is a third of it.
    pub threshold: f64,
    /// Iteration cap.
    pub max_iterations: u32,
    /// Stop when one iteration moves the pose less than this (m, rad × 1 m).
    pub convergence: f64,
    /// Fewest correspondences to accept an iteration.
    pub min_correspondences: usize,
    /// Covariance inflation factor.
    pub cov_inflation: f64,
}

/// Lever arm (m) that makes rotation steps comparable with translation steps.
const LEVER: f64 = 5.0;
/// Largest extrapolation factor of one accelerated step.
const MAX_EXTRAPOLATION: f64 = 20.0;

fn norm_l(d: &[f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + (d[2] * LEVER).powi(2)).sqrt()
}

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

/// Registers `source` (points in their own frame) onto `reference` starting
/// from `init` = `[x, y, θ]`. Each iteration (Besl & McKay 1992):
/// 1. move every source point by the current pose,
/// 2. find its closest point on the reference polyline (kd-tree + segment),
/// 3. drop pairs farther than the gate, weight the rest with Geman–McClure
///    `w = (κ² / (κ² + r²))²`, κ = gate / 3 (as KISS-ICP),
/// 4. solve the weighted closed-form alignment of the original source points
///    onto their targets (`align.rs`).
///
/// `corrs` is scratch space; it ends holding the last iteration's pairs.
pub fn register(
    reference: &Reference,
    source: &[[f64; 2]],
    init: [f64; 3],
    set: &RegisterSettings,
    corrs: &mut Vec<Correspondence>,
) -> Registration {
    let mut pose = init;
    let kappa2 = (set.threshold / 3.0).powi(2);
    let gate2 = set.threshold * set.threshold;
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
    let mut last_step: Option<[f64; 3]> = None;
    for it in 1..=set.max_iterations {
        out.iterations = it;
        let (s, c) = pose[2].sin_cos();
        let mut aligner = Aligner::new();
        corrs.clear();
        for &p in source {
            let q = [c * p[0] - s * p[1] + pose[0], s * p[0] + c * p[1] + pose[1]];
            let Some(cl) = reference.closest(q) else {
                continue;
            };
            let r2 = (q[0] - cl.target[0]).powi(2) + (q[1] - cl.target[1]).powi(2);
            if r2 > gate2 {
                continue;
            }
            let w = (kappa2 / (kappa2 + r2)).powi(2);
            aligner.add(p, cl.target, w);
            corrs.push(Correspondence {
                p,
                q: cl.target,
                normal: cl.normal,
                w,
            });
        }
        out.inliers = corrs.len();
        if corrs.len() < set.min_correspondences {
            return out;
        }
        let Some(next) = aligner.solve() else {
            return out;
        };
        let d = [
            next[0] - pose[0],
            next[1] - pose[1],
            crate::geom::wrap_angle(next[2] - pose[2]),
        ];
        let step = (d[0] * d[0] + d[1] * d[1]).sqrt() + d[2].abs();
        pose = [next[0], next[1], crate::geom::wrap_angle(next[2])];
        if step < set.convergence {
            out.converged = true;
            out.pose = pose;
            break;
        }
        // Besl & McKay's acceleration: along a sliding direction the closed-form
        // step shrinks geometrically (ratio ρ); when two successive steps are
        // nearly parallel, jump to the limit of that series, δ ρ / (1 − ρ).
        if let Some(prev) = last_step {
            let dot = d[0] * prev[0] + d[1] * prev[1] + d[2] * prev[2] * LEVER * LEVER;
            let (n1, n0) = (norm_l(&d), norm_l(&prev));
            let rho = n1 / n0;
            if dot > 0.99 * n1 * n0 && rho < 0.95 {
                let k = (rho / (1.0 - rho)).min(MAX_EXTRAPOLATION);
                pose = [
                    pose[0] + k * d[0],
                    pose[1] + k * d[1],
                    crate::geom::wrap_angle(pose[2] + k * d[2]),
                ];
                last_step = None;
                out.pose = pose;
                continue;
            }
        }
        last_step = Some(d);
        out.pose = pose;
    }
    out.uncertainty = covariance::estimate(corrs, pose, set.cov_inflation);
    out
}
