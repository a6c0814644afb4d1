//! Absolute pose error, as evo's `metrics.APE`: translation part ‖t_est − t_ref‖
//! (m) and rotation angle of inv(est) ⊕ ref (rad, deg), each summarised by
//! [`Stats`]; also the RMSE x,y and RMSE θ of [Farina, Table II].

use super::stats::Stats;
use super::sync::Matched;
use super::EvalError;
use crate::geom::wrap_angle;
use nalgebra::UnitQuaternion;
use serde::{Deserialize, Serialize};

/// Angle (rad, in [0, π]) of a rotation, computed stably as 2·atan2(‖v‖, |w|).
pub fn rotation_angle(q: &UnitQuaternion<f64>) -> f64 {
    let c = q.coords;
    2.0 * c.xyz().norm().atan2(c.w.abs())
}

/// APE of matched (and aligned) pairs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ape {
    /// Translation error statistics (m), evo `-r trans_part`.
    pub trans: Stats,
    /// Rotation angle statistics (rad), evo `-r angle_rad`.
    pub rot_rad: Stats,
    /// Rotation angle statistics (deg), evo `-r angle_deg`.
    pub rot_deg: Stats,
    /// sqrt(mean(Δx² + Δy²)) (m): the RMSE x,y of [Farina, Table II].
    pub rmse_xy: f64,
    /// sqrt(mean(wrap(yaw_est − yaw_ref)²)) (rad): the RMSE θ of [Farina, Table II].
    pub rmse_theta: f64,
    /// Per-pair translation error (m), in pair order.
    pub trans_errors: Vec<f64>,
    /// Per-pair rotation angle error (rad), in pair order.
    pub rot_errors: Vec<f64>,
}

fn yaw(q: &UnitQuaternion<f64>) -> f64 {
    let r = q.to_rotation_matrix();
    r[(1, 0)].atan2(r[(0, 0)])
}

/// Computes the APE over every pair; an error for no pairs or a non-finite result.
pub fn ape(m: &Matched) -> Result<Ape, EvalError> {
    let n = m.len();
    let mut trans_errors = Vec::with_capacity(n);
    let mut rot_errors = Vec::with_capacity(n);
    let (mut sxy, mut sth) = (0.0, 0.0);
    for (r, e) in m.reference.iter().zip(&m.estimate) {
        let d = e.translation.vector - r.translation.vector;
        trans_errors.push(d.norm());
        rot_errors.push(rotation_angle(&(e.rotation.inverse() * r.rotation)));
        sxy += d.x * d.x + d.y * d.y;
        let dth = wrap_angle(yaw(&e.rotation) - yaw(&r.rotation));
        sth += dth * dth;
    }
    let bad = || EvalError::NonFinite {
        what: "matched poses",
        index: 0,
    };
    let trans = Stats::of(&trans_errors).ok_or_else(bad)?;
    let rot_rad = Stats::of(&rot_errors).ok_or_else(bad)?;
    let deg: Vec<f64> = rot_errors.iter().map(|a| a.to_degrees()).collect();
    let rot_deg = Stats::of(&deg).ok_or_else(bad)?;
    Ok(Ape {
        trans,
        rot_rad,
        rot_deg,
        rmse_xy: (sxy / n as f64).sqrt(),
        rmse_theta: (sth / n as f64).sqrt(),
        trans_errors,
        rot_errors,
    })
}
