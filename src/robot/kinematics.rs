//! Differential-drive kinematics (the standard model behind [Farina, eq. 3]).

use crate::geom::{self, Pose2};

/// Kinematic parameters: wheel radii (m) and wheel base (m); as JSON
/// `{r_right, r_left, wheel_base}`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffDrive {
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
}

impl DiffDrive {
    /// Body velocities from wheel rates (rad/s): `V = (ω_r R_R + ω_l R_L)/2` (m/s),
    /// `W = (ω_r R_R − ω_l R_L)/D` (rad/s).
    pub fn body_velocity(&self, omega_right: f64, omega_left: f64) -> (f64, f64) {
        let vr = omega_right * self.r_right;
        let vl = omega_left * self.r_left;
        ((vr + vl) / 2.0, (vr - vl) / self.wheel_base)
    }

    /// Wheel rates (rad/s) that produce body velocities `v` (m/s), `w` (rad/s).
    pub fn wheel_rates(&self, v: f64, w: f64) -> (f64, f64) {
        let vr = v + w * self.wheel_base / 2.0;
        let vl = v - w * self.wheel_base / 2.0;
        (vr / self.r_right, vl / self.r_left)
    }

    /// Pose increment for wheel angle increments (rad) over one step, assuming
    /// constant rates within the step (exact arc).
    pub fn increment(&self, d_right: f64, d_left: f64) -> Pose2 {
        let (ds, dth) = self.body_velocity(d_right, d_left);
        geom::arc_increment(ds, dth, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wheel_rates_invert_body_velocity() {
        let k = DiffDrive {
            r_right: 0.33,
            r_left: 0.31,
            wheel_base: 0.6,
        };
        for (v, w) in [(1.0, 0.0), (0.0, 1.0), (-0.4, 0.3), (0.7, -0.9)] {
            let (wr, wl) = k.wheel_rates(v, w);
            let (v2, w2) = k.body_velocity(wr, wl);
            assert!((v - v2).abs() < 1e-12 && (w - w2).abs() < 1e-12);
        }
    }

    #[test]
    fn spinning_in_place_turns_by_arc_over_half_base() {
        let k = DiffDrive {
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.64,
        };
        // Each wheel travels a quarter of the circle of radius D/2.
        let quarter = std::f64::consts::FRAC_PI_2 * 0.32 / 0.32;
        let d = k.increment(quarter, -quarter);
        assert!((geom::heading(&d) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(d.translation.vector.norm() < 1e-12);
    }
}
