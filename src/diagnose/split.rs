//! When an effect began: the split time that best explains a part's
//! residuals by one effect acting from that time on, every other parameter
//! held. Linearised about the current model, the effect's free parameters
//! enter the residuals through a Jacobian J (one column per parameter, by
//! finite differences), so the residual sum of squares drops, for the rows
//! after a split, by bᵀA⁻¹b with A = JᵀJ and b = Jᵀr summed over those rows;
//! every split time follows from suffix sums in one pass over the rows
//! sorted by time. The same search serves a radius step (the diagnosis'
//! steps), the onset of any candidate at a firing of the change detector,
//! and a laser knocked during a run.

use super::data::Part;
use super::fit::Fit;
use super::free::{free_params, free_steps, with_free};
use crate::effects::{Departures, Effect};
use nalgebra::{DMatrix, DVector};

/// Where a split may fall: times (s from the replay's origin) and the
/// fewest rows on each side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitRange {
    /// Earliest and latest split time (s from the origin).
    pub time: (f64, f64),
    /// Fewest rows (all streams together) on each side.
    pub min_rows: usize,
}

/// Drop of the σ-normalised RSS within which a split time is as likely as
/// the best (the χ²₁ quantile of 0.95: a likelihood interval for the time).
const INTERVAL_DROP: f64 = 3.84;

/// A split found by [`search_split`].
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// The best split time (s from the origin).
    pub time: f64,
    /// Its drop of the σ-normalised RSS.
    pub drop: f64,
    /// Earliest and latest split times (s from the origin) whose drop is
    /// within 3.84 of the best: where the data put the change (the effect
    /// may not show for a while, e.g. a latency at constant speed).
    pub interval: (f64, f64),
    /// The effect's free parameters after the split, linearised (units of
    /// the effect table; 0 in directions the rows do not determine).
    pub params: Vec<f64>,
    /// Their standard errors, with the σ scales of the current model.
    pub stderr: Vec<f64>,
}

/// The best split of `part` for `effect` (its free parameters' values are
/// ignored: it is linearised about zero on top of `current`'s effects).
/// `None` when the part is too short or the effect moves no residual.
pub fn search_split(
    part: Part,
    current: &Fit,
    effect: &Effect,
    range: SplitRange,
) -> Option<Found> {
    let rows = jacobian_rows(part, current, effect);
    let (n, k) = (rows.len(), free_params(effect).len());
    if n < 2 * range.min_rows + 2 || k == 0 {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(k, k);
    let mut b = DVector::<f64>::zeros(k);
    let mut all: Vec<(f64, f64)> = Vec::new();
    let mut at_best: Option<(f64, DMatrix<f64>, DVector<f64>)> = None;
    for i in (1..n).rev() {
        let (_, j, r) = &rows[i];
        for p in 0..k {
            b[p] += j[p] * r;
            for q in 0..k {
                a[(p, q)] += j[p] * j[q];
            }
        }
        if n - i < range.min_rows || i < range.min_rows {
            continue;
        }
        let t = 0.5 * (rows[i - 1].0 + rows[i].0);
        if t < range.time.0 || t > range.time.1 || rows[i - 1].0 == rows[i].0 {
            continue;
        }
        if let Some(drop) = explained(&a, &b) {
            all.push((t, drop));
            if at_best.as_ref().is_none_or(|x| drop > x.0) {
                at_best = Some((drop, a.clone(), b.clone()));
            }
        }
    }
    // Latest first: among equal drops the latest split is kept.
    let &(time, drop) = all.iter().reduce(|b, x| if x.1 > b.1 { x } else { b })?;
    let near = all.iter().filter(|x| x.1 >= drop - INTERVAL_DROP);
    let lo = near.clone().map(|x| x.0).fold(time, f64::min);
    let hi = near.map(|x| x.0).fold(time, f64::max);
    let (params, stderr) = at_best.map(|(_, a, b)| solved(&a, &b))?;
    Some(Found {
        time,
        drop,
        interval: (lo, hi),
        params,
        stderr,
    })
}

/// θ = −A⁺b (the residual is r + Jθ) and √diag(A⁺) over the
/// well-determined directions (as [`explained`]).
fn solved(a: &DMatrix<f64>, b: &DVector<f64>) -> (Vec<f64>, Vec<f64>) {
    let eig = a.clone().symmetric_eigen();
    let top = eig.eigenvalues.max();
    let k = b.len();
    let mut pinv = DMatrix::<f64>::zeros(k, k);
    for (l, u) in eig.eigenvalues.iter().zip(eig.eigenvectors.column_iter()) {
        if *l > 1e-9 * top {
            pinv += u * u.transpose() / *l;
        }
    }
    let theta = -(&pinv * b);
    let se = (0..k).map(|i| pinv[(i, i)].max(0.0).sqrt()).collect();
    (theta.iter().copied().collect(), se)
}

/// bᵀA⁺b over the well-determined directions of A (eigenvalues above 10⁻⁹
/// of the largest): a parameter the rows cannot move explains nothing.
fn explained(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<f64> {
    let eig = a.clone().symmetric_eigen();
    let top = eig.eigenvalues.max();
    if !(top > 0.0) || !top.is_finite() {
        return None;
    }
    let mut drop = 0.0;
    for (l, u) in eig.eigenvalues.iter().zip(eig.eigenvectors.column_iter()) {
        if *l > 1e-9 * top {
            drop += u.dot(b).powi(2) / l;
        }
    }
    Some(drop)
}

/// Rows of every stream as (midpoint time from the origin (s), Jacobian
/// row, residual), scaled per stream by `current`'s σ scale, sorted by time.
fn jacobian_rows(part: Part, current: &Fit, effect: &Effect) -> Vec<(f64, Vec<f64>, f64)> {
    let x0 = Departures::of(&current.effects);
    let mut base: [Vec<f64>; 4] = Default::default();
    part.normalised(&x0, &mut base);
    let everywhere = match *effect {
        Effect::RadiusStep { .. } => Effect::RadiusStep {
            time: f64::NEG_INFINITY,
            right: 0.0,
            left: 0.0,
        },
        e => e,
    };
    let steps = free_steps(&everywhere);
    let cols: Vec<[Vec<f64>; 4]> = steps
        .iter()
        .enumerate()
        .map(|(p, h)| {
            let mut v = vec![0.0; steps.len()];
            v[p] = *h;
            let mut effects = current.effects.clone();
            effects.push(with_free(&everywhere, &v));
            let mut r: [Vec<f64>; 4] = Default::default();
            part.normalised(&Departures::of(&effects), &mut r);
            r
        })
        .collect();
    let mid = |t0: f64, t1: f64| 0.5 * (t0 + t1) - part.replay.origin;
    let mut rows = Vec::new();
    for g in 0..4 {
        let times: Vec<f64> = if g < 3 {
            part.icp.iter().map(|r| mid(r.t0, r.t1)).collect()
        } else {
            part.gyro.iter().map(|r| mid(r.t0, r.t1)).collect()
        };
        let sc = current.scale[g];
        for (i, t) in times.into_iter().enumerate() {
            let j = cols
                .iter()
                .zip(&steps)
                .map(|(c, h)| (c[g][i] - base[g][i]) / (h * sc))
                .collect();
            rows.push((t, j, base[g][i] / sc));
        }
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    rows
}
