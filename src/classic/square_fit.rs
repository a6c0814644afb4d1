//! Which effects reproduce a measured square ([Paryanto, Table III])? The
//! robot is taken to have driven the actual square exactly (the chair of \[Paryanto\]
//! was guided along it), while its odometry used the nominal model; the
//! `radius_scale` and `wheel_base_scale` magnitudes whose simulated odometry
//! corners best match the measured ones are found by least squares
//! (Levenberg–Marquardt on the corner coordinates).

use super::drive::{drive_segments, square_segments, DriveParams, Turn};
use super::error::{check_finite, ClassicError};
use super::square::SquareCorner;
use crate::effects::Effect;
use crate::geom::Pose2;
use crate::robot::{wheel_odometry, DiffDrive};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

/// Odometry corners of a square of side `side` (m) driven exactly (by the true
/// kinematics), computed with `nominal`; the first corner is the start.
pub fn square_odometry_corners(
    nominal: &DiffDrive,
    truth: &DiffDrive,
    side: f64,
    dir: Turn,
) -> Vec<SquareCorner> {
    // Steps are exact arcs, so a low rate loses nothing on a noise-free run.
    let d = DriveParams {
        rate_hz: 2.0,
        ..DriveParams::default()
    };
    let run = drive_segments(truth, truth, &square_segments(side, dir), &d, 0);
    let odo = wheel_odometry(nominal, &run.wheels, Pose2::identity());
    let mut stamps = vec![0.0];
    // Corners are where the straights end (segments 0, 2, 4, 6).
    stamps.extend(run.segment_ends.iter().step_by(2).copied());
    stamps
        .iter()
        .filter_map(|&t| {
            let (o, a) = (odo.pose_at(t)?, run.truth.pose_at(t)?);
            Some(SquareCorner {
                odom_x: o.translation.x,
                odom_y: o.translation.y,
                actual_x: a.translation.x,
                actual_y: a.translation.y,
            })
        })
        .collect()
}

/// The effects fitted to a measured square and how much they explain.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SquareEffectFit {
    /// `radius_scale` and `wheel_base_scale` with the fitted magnitudes.
    pub effects: Vec<Effect>,
    /// RMS distance between measured and simulated odometry corners with no effect (m).
    pub rms_before: f64,
    /// The same with the fitted effects (m).
    pub rms_after: f64,
    /// Simulated odometry corners with the fitted effects.
    pub fitted: Vec<SquareCorner>,
}

/// Fits relative radius and wheel-base errors so that the nominal odometry of
/// an exactly driven square reproduces the measured odometry corners. The
/// actual corners must form a square starting at the origin along +x.
pub fn fit_square_effects(
    measured: &[SquareCorner],
    nominal: &DiffDrive,
) -> Result<SquareEffectFit, ClassicError> {
    let (side, dir) = measured_square(measured)?;
    let fit = SquareFit {
        measured,
        nominal,
        side,
        dir,
    };
    let a0 = [0.0; 3];
    let r0 = fit.residuals(a0);
    let rms_before = fit.rms(&r0);
    let (a, r) = fit.least_squares(a0, r0);
    let best = fit.rms(&r);
    Ok(SquareEffectFit {
        effects: vec![
            Effect::RadiusScale {
                right: a[0],
                left: a[1],
            },
            Effect::WheelBaseScale { scale: a[2] },
        ],
        rms_before,
        rms_after: best,
        fitted: fit.corners(a),
    })
}

/// Checks the measured corners (start + 4, finite, along +x first) and
/// returns the actual square's side (m) and direction.
pub fn measured_square(measured: &[SquareCorner]) -> Result<(f64, Turn), ClassicError> {
    const M: &str = "square effects";
    if measured.len() != 5 {
        return Err(ClassicError::TooFew {
            method: M,
            what: "corners (start + 4)",
            needed: 5,
            got: measured.len(),
        });
    }
    check_finite(
        M,
        "coordinate",
        measured
            .iter()
            .flat_map(|c| [c.odom_x, c.odom_y, c.actual_x, c.actual_y]),
    )?;
    let side = measured[1].actual_x - measured[0].actual_x;
    let dir = if measured[2].actual_y > measured[1].actual_y {
        Turn::Ccw
    } else {
        Turn::Cw
    };
    if side.is_nan() || side <= 0.0 {
        return Err(ClassicError::invalid(
            M,
            "the actual square must start along +x",
        ));
    }
    Ok((side, dir))
}

/// The least-squares problem: relative errors a = [right radius, left
/// radius, wheel base] whose simulated odometry corners match the measured ones.
struct SquareFit<'a> {
    measured: &'a [SquareCorner],
    nominal: &'a DiffDrive,
    side: f64,
    dir: Turn,
}

impl SquareFit<'_> {
    /// Odometry corners of the square driven by the nominal model scaled by `a`.
    fn corners(&self, a: [f64; 3]) -> Vec<SquareCorner> {
        let n = self.nominal;
        let truth = DiffDrive {
            r_right: n.r_right * (1.0 + a[0]),
            r_left: n.r_left * (1.0 + a[1]),
            wheel_base: n.wheel_base * (1.0 + a[2]),
        };
        square_odometry_corners(n, &truth, self.side, self.dir)
    }

    /// Simulated − measured odometry corner coordinates (m).
    fn residuals(&self, a: [f64; 3]) -> Vec<f64> {
        self.measured
            .iter()
            .zip(self.corners(a))
            .flat_map(|(p, q)| [q.odom_x - p.odom_x, q.odom_y - p.odom_y])
            .collect()
    }

    /// RMS distance per corner of residuals `r` (m).
    fn rms(&self, r: &[f64]) -> f64 {
        (r.iter().map(|v| v * v).sum::<f64>() / self.measured.len() as f64).sqrt()
    }

    /// Gauss-Newton with a numerical Jacobian and step halving (Levenberg
    /// damping) from `a` with residuals `r`; returns the best `a` and its residuals.
    fn least_squares(&self, mut a: [f64; 3], mut r: Vec<f64>) -> ([f64; 3], Vec<f64>) {
        let mut lambda = 1e-6;
        for _ in 0..50 {
            let (jtj, jtr) = self.normal_equations(a, &r);
            let Some((b, rb, small)) = self.damped_step(a, &r, &jtj, &jtr, &mut lambda) else {
                break;
            };
            (a, r) = (b, rb);
            if small {
                break;
            }
        }
        (a, r)
    }

    /// JᵀJ and Jᵀr at `a` (residuals `r`), J by forward differences.
    fn normal_equations(&self, a: [f64; 3], r: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
        let h = 1e-6;
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                let mut b = a;
                b[i] += h;
                self.residuals(b)
                    .iter()
                    .zip(r)
                    .map(|(x, y)| (x - y) / h)
                    .collect()
            })
            .collect();
        let mut jtj = Matrix3::<f64>::zeros();
        let mut jtr = Vector3::<f64>::zeros();
        for i in 0..3 {
            for k in 0..3 {
                jtj[(i, k)] = cols[i].iter().zip(&cols[k]).map(|(x, y)| x * y).sum();
            }
            jtr[i] = cols[i].iter().zip(r).map(|(x, y)| x * y).sum();
        }
        (jtj, jtr)
    }

    /// The first damped step that lowers the RMS, raising `lambda` ×10 until
    /// one does (and lowering it ×10 after); `None` when none does below
    /// λ = 10⁶. Returns the new `a`, its residuals, and whether the step was
    /// negligible.
    fn damped_step(
        &self,
        a: [f64; 3],
        r: &[f64],
        jtj: &Matrix3<f64>,
        jtr: &Vector3<f64>,
        lambda: &mut f64,
    ) -> Option<([f64; 3], Vec<f64>, bool)> {
        while *lambda < 1e6 {
            let damped = jtj + Matrix3::from_diagonal(&jtj.diagonal().map(|d| d * *lambda + 1e-12));
            let step = damped.lu().solve(&(-jtr))?;
            let b = [a[0] + step[0], a[1] + step[1], a[2] + step[2]];
            if b.iter().all(|v| *v > -0.5 && *v < 1.0) {
                let rb = self.residuals(b);
                if self.rms(&rb) < self.rms(r) {
                    *lambda = (*lambda / 10.0).max(1e-9);
                    return Some((b, rb, step.norm() < 1e-9));
                }
            }
            *lambda *= 10.0;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_effects_are_recovered_from_their_square() {
        let nominal = DiffDrive {
            r_right: 0.15,
            r_left: 0.15,
            wheel_base: 0.55,
        };
        let truth = DiffDrive {
            r_right: 0.15 * 0.95,
            r_left: 0.15 * 0.96,
            wheel_base: 0.55 * 1.02,
        };
        let corners = square_odometry_corners(&nominal, &truth, 6.0, Turn::Ccw);
        assert_eq!(corners.len(), 5);
        let f = fit_square_effects(&corners, &nominal).unwrap();
        assert!(f.rms_after < 2e-3 && f.rms_before > 0.2, "{f:?}");
        let Effect::RadiusScale { right, left } = f.effects[0] else {
            panic!()
        };
        assert!(
            (right + 0.05).abs() < 2e-3 && (left + 0.04).abs() < 2e-3,
            "{f:?}"
        );
    }
}
