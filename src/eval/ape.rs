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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Translation3, Vector3};

    fn pose(x: f64, y: f64, z: f64, yaw: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
        )
    }

    #[test]
    fn rotation_angle_is_the_angle_about_any_axis() {
        let about_x = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.3);
        assert!((rotation_angle(&about_x) - 0.3).abs() < 1e-12);
        // 6 rad about z is 2π − 6 ≈ 0.283 rad the short way.
        let big = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 6.0);
        assert!((rotation_angle(&big) - (std::f64::consts::TAU - 6.0)).abs() < 1e-12);
    }

    #[test]
    fn errors_of_two_hand_computed_pairs() {
        // Pair 1: 3-4-5 in the plane and 0.5 rad of yaw. Pair 2: 2 m straight
        // up (in the translation error, not in RMSE x,y) and yaws 3 and −3,
        // 6 rad apart, i.e. 2π − 6 the short way (wrapped).
        let m = Matched {
            ref_stamps: vec![0.0, 1.0],
            est_stamps: vec![0.0, 1.0],
            reference: vec![pose(0.0, 0.0, 0.0, 0.0), pose(1.0, 0.0, 0.0, 3.0)],
            estimate: vec![pose(3.0, 4.0, 0.0, 0.5), pose(1.0, 0.0, 2.0, -3.0)],
        };
        let a = ape(&m).unwrap();
        let short = std::f64::consts::TAU - 6.0;
        assert_eq!(a.trans_errors.len(), 2);
        assert!((a.trans_errors[0] - 5.0).abs() < 1e-12 && (a.trans_errors[1] - 2.0).abs() < 1e-12);
        assert!((a.rot_errors[0] - 0.5).abs() < 1e-12 && (a.rot_errors[1] - short).abs() < 1e-12);
        assert!((a.trans.rmse - 14.5f64.sqrt()).abs() < 1e-12);
        assert!((a.rot_deg.max - 0.5f64.to_degrees()).abs() < 1e-9);
        // RMSE x,y = √((25 + 0) / 2); RMSE θ = √((0.25 + short²) / 2).
        assert!((a.rmse_xy - 12.5f64.sqrt()).abs() < 1e-12);
        assert!((a.rmse_theta - ((0.25 + short * short) / 2.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn no_pairs_is_an_error() {
        let m = Matched {
            ref_stamps: vec![],
            est_stamps: vec![],
            reference: vec![],
            estimate: vec![],
        };
        assert!(ape(&m).is_err());
    }
}
