//! An interval's laser displacement as the filters' velocity observation:
//! moved into the base frame with the laser mounting ℓ (`ℓ ⊕ s ⊕ ℓ⁻¹`, the
//! inverse of [Censi2013, eq. 5]), then the constant (V, W) whose arc best
//! explains it ([`crate::motion::arc_along_chord`]), with σ's propagated from
//! the interval's covariance.

use crate::calib::batch::{inverse, oplus, P3};
use crate::motion::{arc_along_chord, VelocityObs};
use nalgebra::Matrix3;

/// The base frame's motion `ℓ ⊕ s ⊕ ℓ⁻¹` of a laser displacement `s` and its
/// covariance (first order: the Jacobian of the map, by central
/// differences), for the mounting `laser` = base_from_laser `[x, y, yaw]`.
pub fn base_motion(s: P3, cov: &Matrix3<f64>, laser: P3) -> (P3, Matrix3<f64>) {
    let f = |x: P3| oplus(oplus(laser, x), inverse(laser));
    let j = crate::geom::jacobian3(f, s);
    (f(s), j * cov * j.transpose())
}

/// The velocity observation over `[t0, t1]` (s) of a laser displacement `s`
/// with covariance `cov`, for the mounting `laser`: `V` the arc length along
/// the chord over the duration, `W` the turn over it, `σ_V` from the
/// covariance along the chord, `σ_W` from the turn's. `None` for a duration
/// that is not positive or values that are not finite.
pub fn velocity(t0: f64, t1: f64, s: P3, cov: &Matrix3<f64>, laser: P3) -> Option<VelocityObs> {
    let dt = t1 - t0;
    if !(dt > 0.0 && dt.is_finite()) {
        return None;
    }
    let (b, c) = base_motion(s, cov, laser);
    let (ds, dth) = arc_along_chord(b[0], b[1], b[2]);
    let h = 0.5 * b[2];
    let (sh, ch) = h.sin_cos();
    let along = ch * ch * c[(0, 0)] + 2.0 * sh * ch * c[(0, 1)] + sh * sh * c[(1, 1)];
    let factor = if h.abs() < 1e-6 { 1.0 } else { h / sh };
    let obs = VelocityObs {
        t0,
        t1,
        v: ds / dt,
        w: dth / dt,
        sigma_v: factor.abs() * along.max(0.0).sqrt() / dt,
        sigma_w: c[(2, 2)].max(0.0).sqrt() / dt,
    };
    [obs.v, obs.w, obs.sigma_v, obs.sigma_w]
        .iter()
        .all(|x| x.is_finite())
        .then_some(obs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_laser_behind_the_axle_facing_back_sees_the_robot_s_arc() {
        // The robot drives an arc of 0.5 m at 0.4 rad in 1 s; the laser sits
        // 0.45 m behind the axle, turned round (the wheelchair's). Its own
        // displacement, moved back with that mounting, gives V and W again.
        let laser = [-0.45, 0.0, std::f64::consts::PI];
        let o = crate::geom::xyt(&crate::geom::arc_increment(0.5, 0.4, 1.0));
        let s = oplus(oplus(inverse(laser), o), laser);
        let cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-6, 4e-6, 1e-6));
        let v = velocity(2.0, 3.0, s, &cov, laser).unwrap();
        assert!(
            (v.v - 0.5).abs() < 1e-9 && (v.w - 0.4).abs() < 1e-12,
            "{v:?}"
        );
        // Turned round, the laser's x is the base's −x: σ along the chord is
        // the laser's x σ (1 mm), nearly; the turn's σ is unchanged.
        assert!((v.sigma_w - 1e-3).abs() < 1e-12);
        assert!((v.sigma_v - 1e-3).abs() < 2e-4, "{}", v.sigma_v);
        // With the mounting ignored (identity), the same displacement reads
        // as a robot driving backwards.
        assert!(velocity(2.0, 3.0, s, &cov, [0.0; 3]).unwrap().v < 0.0);
        assert!(velocity(2.0, 2.0, s, &cov, laser).is_none());
    }

    #[test]
    fn v_sigma_is_the_covariance_along_the_chord_times_the_arc_over_it() {
        // A quarter turn in 1 s, the laser on the axle: the chord lies at
        // 45° to the start heading, so its variance is
        // ½ σ²x + σxy + ½ σ²y = (0.5 + 0.5 + 0.5) · 1e-4 with the
        // correlated x and y below; the arc is π/4 / sin(π/4) = 1.1107 times
        // the chord.
        let q = std::f64::consts::FRAC_PI_2;
        let s = crate::geom::xyt(&crate::geom::arc_increment(0.5, q, 1.0));
        let cov = Matrix3::new(1e-4, 0.5e-4, 0.0, 0.5e-4, 1e-4, 0.0, 0.0, 0.0, 1e-6);
        let o = velocity(0.0, 1.0, s, &cov, [0.0; 3]).unwrap();
        assert!((o.v - 0.5).abs() < 1e-9 && (o.w - q).abs() < 1e-12, "{o:?}");
        let expected = 1.110_720_7 * 1.5e-4f64.sqrt();
        assert!(
            (o.sigma_v - expected).abs() < 1e-8,
            "{} against {expected}",
            o.sigma_v
        );
        // Over 2 s, half the velocities and half their σ's.
        let o2 = velocity(0.0, 2.0, s, &cov, [0.0; 3]).unwrap();
        assert!((o2.sigma_v - expected / 2.0).abs() < 1e-8);
        // No finite duration: nothing.
        assert!(velocity(0.0, f64::INFINITY, s, &cov, [0.0; 3]).is_none());
        assert!(velocity(1.0, 0.0, s, &cov, [0.0; 3]).is_none());
    }
}
