//! The relation metric of \[Kummerle2009\] ("On measuring the accuracy of SLAM
//! algorithms", Autonomous Robots 27(4), 2009): a trajectory is judged by the
//! relative motions it implies between pairs of instants, compared with
//! reference relative motions.
//!
//! For a relation (t1, t2, δ*) with δ* = inv(X(t1)) ⊕ X(t2) and the estimate's
//! δ = inv(x̂(t1)) ⊕ x̂(t2) (poses interpolated at t1 and t2), the error is
//! e = inv(δ*) ⊕ δ; translational error ‖t(e)‖ = ‖t(δ) − t(δ*)‖ (m),
//! rotational error |θ(e)| = |wrap(θ(δ) − θ(δ*))| (reported in deg).

use super::stats::mean_std;
use super::EvalError;
use crate::geom::{self, Pose2};
use crate::traj::Trajectory;
use serde::{Deserialize, Serialize};

/// Relations shorter than this (|t2 − t1|, s) count as "local".
pub const LOCAL_SPAN_S: f64 = 10.0;

/// One reference relation: the robot pose at `t2` in the robot frame at `t1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// First instant (s).
    pub t1: f64,
    /// Second instant (s); may precede `t1` (some benchmark files have such lines).
    pub t2: f64,
    /// `base(t1)_from_base(t2)` = inv(X(t1)) ⊕ X(t2) (m, rad).
    pub delta: Pose2,
}

/// The error of the estimate on one relation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RelationError {
    /// First instant (s).
    pub t1: f64,
    /// Second instant (s).
    pub t2: f64,
    /// Translational error ‖t(δ) − t(δ*)‖ (m).
    pub trans: f64,
    /// Rotational error |wrap(θ(δ) − θ(δ*))| (deg).
    pub rot_deg: f64,
}

/// Mean ± population standard deviation (÷ N) of relation errors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RelationSummary {
    /// Relations evaluated.
    pub count: usize,
    /// Mean translational error (m).
    pub trans_mean: f64,
    /// Standard deviation of the translational error (m).
    pub trans_std: f64,
    /// Mean rotational error (deg).
    pub rot_mean_deg: f64,
    /// Standard deviation of the rotational error (deg).
    pub rot_std_deg: f64,
}

impl RelationSummary {
    /// Summary of a non-empty set of errors; `None` when empty.
    pub fn of(errors: &[RelationError]) -> Option<Self> {
        if errors.is_empty() {
            return None;
        }
        let t: Vec<f64> = errors.iter().map(|e| e.trans).collect();
        let r: Vec<f64> = errors.iter().map(|e| e.rot_deg).collect();
        let (trans_mean, trans_std) = mean_std(&t);
        let (rot_mean_deg, rot_std_deg) = mean_std(&r);
        Some(Self {
            count: errors.len(),
            trans_mean,
            trans_std,
            rot_mean_deg,
            rot_std_deg,
        })
    }
}

/// Relation metric over a whole relations file: all evaluated relations, the
/// local ones (|t2 − t1| < 10 s), how many were skipped, and each error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelationStats {
    /// Over every relation inside the trajectory's time span.
    #[serde(flatten)]
    pub all: RelationSummary,
    /// Over the local relations; `None` (JSON null) when there are none.
    pub local: Option<RelationSummary>,
    /// Relations skipped because an endpoint lies outside the trajectory's span.
    pub skipped: usize,
    /// Per-relation errors in input order (for plots); not in the JSON summary.
    #[serde(skip)]
    pub errors: Vec<RelationError>,
}

/// Error of one relation, or `None` when an endpoint is outside the trajectory.
pub fn relation_error(traj: &Trajectory, rel: &Relation) -> Option<RelationError> {
    let a = traj.pose_at(rel.t1)?;
    let b = traj.pose_at(rel.t2)?;
    let est = geom::between(&a, &b);
    let e = geom::between(&rel.delta, &est);
    let trans = e.translation.vector.norm();
    let rot = geom::wrap_angle(geom::heading(&est) - geom::heading(&rel.delta)).abs();
    Some(RelationError {
        t1: rel.t1,
        t2: rel.t2,
        trans,
        rot_deg: rot.to_degrees(),
    })
}

/// Evaluates `traj` on the reference relations `rels` \[Kummerle2009\].
/// Relations with an endpoint outside the trajectory's time span are skipped
/// and counted; an error if none remains or a pose is not finite.
pub fn relations(traj: &Trajectory, rels: &[Relation]) -> Result<RelationStats, EvalError> {
    if let Some(index) = traj
        .poses
        .iter()
        .position(|p| !geom::xyt(p).iter().all(|v| v.is_finite()))
    {
        return Err(EvalError::NonFinite {
            what: "trajectory",
            index,
        });
    }
    let mut errors = Vec::with_capacity(rels.len());
    let mut skipped = 0;
    for rel in rels {
        match relation_error(traj, rel) {
            Some(e) if e.trans.is_finite() && e.rot_deg.is_finite() => errors.push(e),
            Some(_) => {
                return Err(EvalError::NonFinite {
                    what: "relations",
                    index: errors.len() + skipped,
                })
            }
            None => skipped += 1,
        }
    }
    let all = RelationSummary::of(&errors).ok_or(EvalError::NoRelations { total: rels.len() })?;
    let local: Vec<RelationError> = errors
        .iter()
        .filter(|e| (e.t2 - e.t1).abs() < LOCAL_SPAN_S)
        .copied()
        .collect();
    Ok(RelationStats {
        all,
        local: RelationSummary::of(&local),
        skipped,
        errors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    fn circle(n: usize) -> Trajectory {
        let mut t = Trajectory::default();
        for i in 0..n {
            let a = i as f64 * 0.05;
            t.push(
                i as f64,
                pose(5.0 * a.cos(), 5.0 * a.sin(), a + 0.5 * std::f64::consts::PI),
            );
        }
        t
    }

    #[test]
    fn exact_relations_give_zero_error_and_offsets_are_measured() {
        let truth = circle(200);
        let mut rels = Vec::new();
        for i in (0..170).step_by(7) {
            let (t1, t2) = (i as f64 + 0.25, i as f64 + 3.5 + (i % 20) as f64);
            let d = geom::between(&truth.pose_at(t1).unwrap(), &truth.pose_at(t2).unwrap());
            rels.push(Relation { t1, t2, delta: d });
        }
        // One outside the span is skipped and counted.
        rels.push(Relation {
            t1: 150.0,
            t2: 400.0,
            delta: Pose2::identity(),
        });
        // Reversed order is a legal relation too.
        let d = geom::between(&truth.pose_at(40.0).unwrap(), &truth.pose_at(30.0).unwrap());
        rels.push(Relation {
            t1: 40.0,
            t2: 30.0,
            delta: d,
        });
        let s = relations(&truth, &rels).unwrap();
        assert_eq!(s.skipped, 1);
        assert_eq!(s.all.count, rels.len() - 1);
        assert!(s.all.trans_mean < 1e-9 && s.all.rot_mean_deg < 1e-9);

        // Perturb every reference relation by a known amount: errors are exact.
        let bumped: Vec<Relation> = rels
            .iter()
            .map(|r| Relation {
                delta: r.delta * pose(0.3, -0.4, 0.02),
                ..*r
            })
            .collect();
        let s = relations(&truth, &bumped).unwrap();
        assert!((s.all.trans_mean - 0.5).abs() < 1e-9, "{:?}", s.all);
        assert!(s.all.trans_std < 1e-9);
        assert!((s.all.rot_mean_deg - 0.02f64.to_degrees()).abs() < 1e-9);
        let local = s.local.unwrap();
        assert!(local.count > 0 && local.count < s.all.count);
    }

    #[test]
    fn nothing_in_span_is_an_error() {
        let t = circle(10);
        let rels = [Relation {
            t1: 20.0,
            t2: 30.0,
            delta: Pose2::identity(),
        }];
        assert_eq!(
            relations(&t, &rels),
            Err(EvalError::NoRelations { total: 1 })
        );
    }
}
