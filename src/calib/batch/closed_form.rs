//! The closed-form initialisation of [Censi2013, Sec. IV]: first
//! J21 = −r_L/b and J22 = r_R/b by linear least squares on the rotation
//! ([Censi2013, eq. 12]), then the wheel base and the laser mounting from the
//! translation equation (Eq. 14–17), homogeneous in
//! x = (ℓx, ℓy, b, cos ℓθ, sin ℓθ) under cos² + sin² = 1.

use super::model::{robot_motion, Unknowns};
use super::BatchError;
use nalgebra::{Matrix2, Matrix3, Matrix5, SMatrix, Vector2};

/// The rotation's least-squares condition number above which the wheels
/// never moved in two independent ways (Censi's solver refuses above 75 on
/// unweighted tuples; weights and units change the scale, so this is looser).
const MAX_ROTATION_CONDITION: f64 = 1e4;

/// One interval as the closed form sees it: the total wheel increments and
/// all sub-steps, the laser displacement and the weights of its rotation and
/// translation rows (inverse variances).
pub struct Row<'a> {
    /// Sub-step increments `(Δφ_L, Δφ_R)` (rad).
    pub inc: &'a [[f64; 2]],
    /// Laser displacement `[x, y, θ]` (m, m, rad).
    pub s: [f64; 3],
    /// Weight of the rotation row (1/rad²).
    pub w_rot: f64,
    /// Weight of the translation rows (1/m²).
    pub w_tr: f64,
}

/// J21, J22 from θ_k = J21 Δφ_L,k + J22 Δφ_R,k (Eq. 12). A rank-deficient
/// system names the motion that is missing.
pub fn rotation_jacobian(rows: &[Row]) -> Result<(f64, f64), BatchError> {
    let mut a = Matrix2::zeros();
    let mut g = Vector2::zeros();
    for r in rows {
        let l = r
            .inc
            .iter()
            .fold([0.0; 2], |s, d| [s[0] + d[0], s[1] + d[1]]);
        let l = Vector2::new(l[0], l[1]);
        a += r.w_rot * l * l.transpose();
        g += r.w_rot * r.s[2] * l;
    }
    let eig = a.symmetric_eigen();
    let (lo, hi) = if eig.eigenvalues[0] < eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    if !(eig.eigenvalues[hi] > 0.0) {
        return Err(BatchError::Unobservable(
            "the wheel increments are all zero: no wheel turned".into(),
        ));
    }
    if !(eig.eigenvalues[lo] * MAX_ROTATION_CONDITION > eig.eigenvalues[hi]) {
        let n = eig.eigenvectors.column(lo);
        return Err(BatchError::Unobservable(missing_motion(n[0], n[1]).into()));
    }
    let j = a.try_inverse().ok_or_else(|| {
        BatchError::Unobservable("the wheel increments do not determine the rotation".into())
    })? * g;
    Ok((j[0], j[1]))
}

/// What the wheel increments never did, from the direction `(n_L, n_R)` in
/// which they carry no information: along one wheel's axis that wheel never
/// turned (a dead encoder or a wrong joint name); along (1, −1) left minus
/// right never varied (no turn); along (1, 1) the wheels always turned
/// opposite ways (no driving).
fn missing_motion(n_left: f64, n_right: f64) -> &'static str {
    let (l, r) = (n_left.abs(), n_right.abs());
    if r < 0.1 * l {
        "the left wheel never turned (its increments are all zero): check its encoder and \
         its joint name"
    } else if l < 0.1 * r {
        "the right wheel never turned (its increments are all zero): check its encoder and \
         its joint name"
    } else if n_left * n_right < 0.0 {
        "the wheels never turned the robot (left and right always turned alike): record turns \
         both ways"
    } else {
        "the robot only turned in place (the wheels always turned opposite ways): record \
         straight or curved driving"
    }
}

/// The full closed-form estimate (time offset 0): J from the rotation, then
/// min xᵀMx subject to x₄² + x₅² = 1 by the Schur complement of M onto the
/// (cos, sin) block and its smallest eigenvector (equivalent to Censi's
/// Lagrange multiplier, Eq. 17), the sign chosen for b > 0.
pub fn closed_form(rows: &[Row]) -> Result<Unknowns, BatchError> {
    let (j21, j22) = rotation_jacobian(rows)?;
    // With r_R = J22·b and r_L = −J21·b the robot's translation is b·c_k.
    let unit = Unknowns {
        r_right: j22,
        r_left: -j21,
        wheel_base: 1.0,
        laser: [0.0; 3],
        time_offset: 0.0,
    };
    let mut m = Matrix5::zeros();
    for r in rows {
        let o = robot_motion(r.inc, &unit);
        let (s, c) = o[2].sin_cos();
        let (sx, sy) = (r.s[0], r.s[1]);
        // (I − R(o_θ)) ℓ_t + R(ℓθ) s_t − b c = 0 (Eq. 14), rows in x.
        let l = SMatrix::<f64, 2, 5>::new(
            1.0 - c,
            s,
            -o[0],
            sx,
            -sy, //
            -s,
            1.0 - c,
            -o[1],
            sy,
            sx,
        );
        m += r.w_tr * l.transpose() * l;
    }
    let a: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into();
    let b: SMatrix<f64, 3, 2> = m.fixed_view::<3, 2>(0, 3).into();
    let c: Matrix2<f64> = m.fixed_view::<2, 2>(3, 3).into();
    let a_eig = a.symmetric_eigen();
    let (amin, amax) = (a_eig.eigenvalues.min(), a_eig.eigenvalues.max());
    if !(amin > 1e-12 * amax) {
        return Err(BatchError::Unobservable(
            "the robot never turned while the laser moved: the laser position needs turns".into(),
        ));
    }
    let ainv = a.try_inverse().expect("checked positive definite");
    let schur = c - b.transpose() * ainv * b;
    let se = schur.symmetric_eigen();
    let k = if se.eigenvalues[0] < se.eigenvalues[1] {
        0
    } else {
        1
    };
    let mut v: Vector2<f64> = se.eigenvectors.column(k).into();
    let mut u = -ainv * b * v;
    if u[2] < 0.0 {
        v = -v;
        u = -u;
    }
    let wheel_base = u[2];
    Ok(Unknowns {
        r_right: j22 * wheel_base,
        r_left: -j21 * wheel_base,
        wheel_base,
        laser: [u[0], u[1], v[1].atan2(v[0])],
        time_offset: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::batch::tests::{arc_by_hand, DRIVES};
    use nalgebra::Isometry2;

    /// Intervals of two sub-steps each, driven every way, and the laser's
    /// displacement `ℓ⁻¹ o ℓ` for the robot r_R = 0.10, r_L = 0.11, b = 0.5
    /// with the laser at (0.2, 0.05, 0.3).
    fn intervals() -> (Vec<Vec<[f64; 2]>>, Vec<[f64; 3]>) {
        intervals_with(Isometry2::new(nalgebra::Vector2::new(0.2, 0.05), 0.3))
    }

    /// r_R, r_L, b and the laser's x, y, yaw of `u`.
    fn flat(u: &Unknowns) -> [f64; 6] {
        [
            u.r_right,
            u.r_left,
            u.wheel_base,
            u.laser[0],
            u.laser[1],
            u.laser[2],
        ]
    }

    /// [`intervals`] with the laser mounted at `laser`.
    fn intervals_with(laser: Isometry2<f64>) -> (Vec<Vec<[f64; 2]>>, Vec<[f64; 3]>) {
        let (rr, rl, b) = (0.10, 0.11, 0.5);
        let drives = DRIVES;
        let mut incs = Vec::new();
        let mut s = Vec::new();
        for &(l, r) in &drives {
            let inc = vec![[l, r], [0.5 * l, 0.8 * r]];
            let o = inc.iter().fold(Isometry2::identity(), |o, &[dl, dr]| {
                o * arc_by_hand(dl, dr, rr, rl, b)
            });
            let d = laser.inverse() * o * laser;
            s.push([d.translation.x, d.translation.y, d.rotation.angle()]);
            incs.push(inc);
        }
        (incs, s)
    }

    #[test]
    fn recovers_the_robot_and_the_laser_from_exact_intervals() {
        let (incs, s) = intervals();
        let rows: Vec<Row> = incs
            .iter()
            .zip(&s)
            .map(|(inc, &s)| Row {
                inc,
                s,
                w_rot: 1.0,
                w_tr: 1.0,
            })
            .collect();
        let (j21, j22) = rotation_jacobian(&rows).unwrap();
        assert!((j21 + 0.11 / 0.5).abs() < 1e-12 && (j22 - 0.10 / 0.5).abs() < 1e-12);
        let u = closed_form(&rows).unwrap();
        let got = flat(&u);
        let want = [0.10, 0.11, 0.5, 0.2, 0.05, 0.3];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-9, "{got:?} vs {want:?}");
        }
        assert_eq!(u.time_offset, 0.0);
    }

    #[test]
    fn a_motion_that_cannot_determine_the_robot_is_named() {
        static STRAIGHT: [[[f64; 2]; 1]; 3] = [[[1.0, 1.0]], [[2.0, 2.0]], [[-1.0, -1.0]]];
        static SPIN: [[[f64; 2]; 1]; 3] = [[[1.0, -1.0]], [[-2.0, 2.0]], [[0.5, -0.5]]];
        let rows = |incs: &'static [[[f64; 2]; 1]; 3]| unit_rows(incs, [0.1, 0.0, 0.05]);
        let e = rotation_jacobian(&rows(&STRAIGHT)).unwrap_err().to_string();
        assert!(e.contains("never turned the robot"), "{e}");
        let e = rotation_jacobian(&rows(&SPIN)).unwrap_err().to_string();
        assert!(e.contains("only turned in place"), "{e}");
        // One wheel never turned (a dead encoder): named as that wheel, not as
        // a missing kind of driving; no wheel turned: said so.
        static LEFT_DEAD: [[[f64; 2]; 1]; 3] = [[[0.0, 1.0]], [[0.0, -2.0]], [[0.0, 0.5]]];
        static RIGHT_DEAD: [[[f64; 2]; 1]; 3] = [[[1.0, 0.0]], [[-2.0, 0.0]], [[0.5, 0.0]]];
        static STILL: [[[f64; 2]; 1]; 3] = [[[0.0, 0.0]], [[0.0, 0.0]], [[0.0, 0.0]]];
        let e = rotation_jacobian(&rows(&LEFT_DEAD))
            .unwrap_err()
            .to_string();
        assert!(e.contains("the left wheel never turned"), "{e}");
        let e = rotation_jacobian(&rows(&RIGHT_DEAD))
            .unwrap_err()
            .to_string();
        assert!(e.contains("the right wheel never turned"), "{e}");
        // (Not "all zero" alone: the dead-wheel messages say that too.)
        let e = rotation_jacobian(&rows(&STILL)).unwrap_err().to_string();
        assert!(e.contains("no wheel turned"), "{e}");
        // Negative control: both wheels turning, alike and apart, determine it.
        static MIXED: [[[f64; 2]; 1]; 3] = [[[1.0, 1.0]], [[1.0, -1.0]], [[0.5, 2.0]]];
        assert!(rotation_jacobian(&rows(&MIXED)).is_ok());
        // Turning both ways but never moving the laser while turning: no
        // laser position.
        static NO_TURN_MOVE: [[[f64; 2]; 1]; 2] = [[[1.0, 2.0]], [[2.0, 1.0]]];
        assert!(closed_form(&unit_rows(&NO_TURN_MOVE, [0.0; 3])).is_err());
    }

    #[test]
    fn a_wheel_is_named_dead_only_below_a_tenth_of_the_other() {
        // Every interval turns the left wheel by k and the right by −q·k: the
        // increments span one line, so the rotation system has no
        // information along its normal n ∝ (q, 1) (n_L = q/√(1+q²),
        // n_R = 1/√(1+q²)). The right wheel is named dead when n_L < 0.1 n_R,
        // i.e. q < 0.1: at q = 0.098 it is (it barely turned); at q = 0.1002
        // n_L = 0.099701 > 0.1·0.995017 = 0.099502, so the wheels are said
        // to turn opposite ways in a fixed ratio instead. Mirrored (left −q·k,
        // right k) for the left wheel.
        let named = |q: f64, left_dead: bool| -> String {
            let incs: Vec<[[f64; 2]; 1]> = [1.0, -2.0, 0.5]
                .iter()
                .map(|&k| {
                    if left_dead {
                        [[-q * k, k]]
                    } else {
                        [[k, -q * k]]
                    }
                })
                .collect();
            rotation_jacobian(&unit_rows(&incs, [0.1, 0.0, 0.05]))
                .unwrap_err()
                .to_string()
        };
        for (left_dead, wheel) in [(false, "the right wheel"), (true, "the left wheel")] {
            let e = named(0.098, left_dead);
            assert!(e.contains(&format!("{wheel} never turned")), "{e}");
            let e = named(0.1002, left_dead);
            assert!(e.contains("only turned in place"), "{e}");
        }
    }

    /// Rows of unit weights, one wheel increment each, all with the laser
    /// displacement `s`.
    fn unit_rows(incs: &[[[f64; 2]; 1]], s: [f64; 3]) -> Vec<Row<'_>> {
        incs.iter()
            .map(|inc| Row {
                inc,
                s,
                w_rot: 1.0,
                w_tr: 1.0,
            })
            .collect()
    }

    /// Rows of equal weights over intervals and laser displacements.
    fn rows_of<'a>(
        incs: &'a [Vec<[f64; 2]>],
        s: &[[f64; 3]],
        w_rot: f64,
        w_tr: f64,
    ) -> Vec<Row<'a>> {
        incs.iter()
            .zip(s)
            .map(|(inc, &s)| Row {
                inc,
                s,
                w_rot,
                w_tr,
            })
            .collect()
    }

    #[test]
    fn scaling_every_weight_alike_changes_nothing() {
        // Weights are relative: all of them 1e-8 or 1e8 instead of 1 give
        // the same robot and laser.
        let (incs, s) = intervals();
        let want = [0.10, 0.11, 0.5, 0.2, 0.05, 0.3];
        for w in [1e-8, 1e8] {
            let u = closed_form(&rows_of(&incs, &s, w, w)).unwrap();
            let got = flat(&u);
            for (g, v) in got.iter().zip(want) {
                assert!((g - v).abs() < 1e-9, "{w}: {got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn recovers_the_laser_mounting_at_any_angle() {
        // The laser at (−0.1, 0.15) turned anywhere in (−π, π): the mounting
        // angle is the (cos, sin) direction the closed form picks.
        for angle in [-3.0, -2.2, -1.4, -0.6, 0.0, 0.8, 1.6, 2.4, 3.1] {
            let laser = Isometry2::new(nalgebra::Vector2::new(-0.1, 0.15), angle);
            let (incs, s) = intervals_with(laser);
            let u = closed_form(&rows_of(&incs, &s, 1.0, 1.0)).unwrap();
            let got = [u.wheel_base, u.laser[0], u.laser[1], u.laser[2]];
            let want = [0.5, -0.1, 0.15, angle];
            for (g, v) in got.iter().zip(want) {
                assert!((g - v).abs() < 1e-9, "{angle}: {got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn a_rotation_condition_at_the_limit_is_refused_and_below_it_accepted() {
        // One interval on each wheel alone, the left turning 1 rad and the
        // right d rad: Σ l lᵀ = diag(1, d²), condition number d². d = 100 is
        // the limit 1e4, refused whichever wheel comes first; d = 99 is
        // inside it and J solves by hand from θ = J21·1 = 0.2 and
        // θ = J22·99 = 0.99: J = (0.2, 0.01).
        let rows = |incs: &'static [[[f64; 2]; 1]; 2], theta: [f64; 2]| -> Vec<Row<'static>> {
            incs.iter()
                .zip(theta)
                .map(|(inc, th)| Row {
                    inc,
                    s: [0.0, 0.0, th],
                    w_rot: 1.0,
                    w_tr: 1.0,
                })
                .collect()
        };
        static LIMIT: [[[f64; 2]; 1]; 2] = [[[1.0, 0.0]], [[0.0, 100.0]]];
        static LIMIT_SWAPPED: [[[f64; 2]; 1]; 2] = [[[100.0, 0.0]], [[0.0, 1.0]]];
        static INSIDE: [[[f64; 2]; 1]; 2] = [[[1.0, 0.0]], [[0.0, 99.0]]];
        assert!(rotation_jacobian(&rows(&LIMIT, [0.2, 1.0])).is_err());
        assert!(rotation_jacobian(&rows(&LIMIT_SWAPPED, [0.2, 1.0])).is_err());
        let (j21, j22) = rotation_jacobian(&rows(&INSIDE, [0.2, 0.99])).unwrap();
        assert!(
            (j21 - 0.2).abs() < 1e-12 && (j22 - 0.01).abs() < 1e-12,
            "{j21} {j22}"
        );
    }
}
