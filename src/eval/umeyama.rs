//! Least-squares similarity between two registered point sets \[Umeyama1991\]
//! ("Least-squares estimation of transformation parameters between two point
//! patterns", IEEE PAMI 13(4), 1991) — as evo's `geometry.umeyama_alignment`:
//! find R, t, c minimising Σ‖y_i − (c R x_i + t)‖².

use super::EvalError;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3, SVD};

/// Rotation, translation and scale mapping `x` onto `y` in 3D (c = 1 unless
/// `with_scale`). An error when the cross-covariance has rank < 2.
pub fn umeyama3(
    x: &[Vector3<f64>],
    y: &[Vector3<f64>],
    with_scale: bool,
) -> Result<(Matrix3<f64>, Vector3<f64>, f64), EvalError> {
    let n = x.len() as f64;
    if x.len() != y.len() || x.is_empty() {
        return Err(EvalError::DegenerateAlignment(
            "point sets differ in size or are empty".into(),
        ));
    }
    let mean_x = x.iter().sum::<Vector3<f64>>() / n;
    let mean_y = y.iter().sum::<Vector3<f64>>() / n;
    // σ²_x (eq. 36) and Σ_xy (eq. 38).
    let sigma_x = x.iter().map(|p| (p - mean_x).norm_squared()).sum::<f64>() / n;
    let mut cov = Matrix3::zeros();
    for (p, q) in x.iter().zip(y) {
        cov += (q - mean_y) * (p - mean_x).transpose();
    }
    cov /= n;
    let svd = SVD::new_unordered(cov, true, true);
    let (u, v_t, d) = (svd.u.unwrap(), svd.v_t.unwrap(), svd.singular_values);
    if d.iter().filter(|&&s| s > f64::EPSILON).count() < 2 {
        return Err(EvalError::DegenerateAlignment(
            "positions span less than a plane (rank < 2); Umeyama alignment is not possible".into(),
        ));
    }
    // S = diag(1, 1, ±1) on the smallest singular value (eq. 39, 43).
    let mut s = Vector3::new(1.0, 1.0, 1.0);
    if u.determinant() * v_t.determinant() < 0.0 {
        let smallest = (0..3).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap();
        s[smallest] = -1.0;
    }
    let r = u * Matrix3::from_diagonal(&s) * v_t;
    // c = tr(D S) / σ²_x (eq. 42), t = μ_y − c R μ_x (eq. 41).
    let c = if with_scale { d.dot(&s) / sigma_x } else { 1.0 };
    let t = mean_y - c * r * mean_x;
    Ok((r, t, c))
}

/// The planar case: rotation angle (rad), translation and scale mapping `x`
/// onto `y`. The optimum over SO(2) is θ = atan2(Σ x×y, Σ x·y) of the centred
/// points, and tr(D S) = ‖(Σ x·y, Σ x×y)‖/n, equal to the SVD form above.
pub fn umeyama2(
    x: &[Vector2<f64>],
    y: &[Vector2<f64>],
    with_scale: bool,
) -> Result<(f64, Vector2<f64>, f64), EvalError> {
    let n = x.len() as f64;
    if x.len() != y.len() || x.is_empty() {
        return Err(EvalError::DegenerateAlignment(
            "point sets differ in size or are empty".into(),
        ));
    }
    let mean_x = x.iter().sum::<Vector2<f64>>() / n;
    let mean_y = y.iter().sum::<Vector2<f64>>() / n;
    let sigma_x = x.iter().map(|p| (p - mean_x).norm_squared()).sum::<f64>() / n;
    let mut cov = Matrix2::zeros();
    for (p, q) in x.iter().zip(y) {
        cov += (q - mean_y) * (p - mean_x).transpose();
    }
    cov /= n;
    let (dot, cross) = (cov[(0, 0)] + cov[(1, 1)], cov[(1, 0)] - cov[(0, 1)]);
    let trace_ds = dot.hypot(cross);
    // Written to reject NaN as well.
    if trace_ds.is_nan() || trace_ds <= f64::EPSILON || sigma_x.is_nan() || sigma_x <= 0.0 {
        return Err(EvalError::DegenerateAlignment(
            "positions do not spread in the plane; SE(2)/Sim(2) alignment is not possible".into(),
        ));
    }
    let theta = cross.atan2(dot);
    let c = if with_scale { trace_ds / sigma_x } else { 1.0 };
    let (s, co) = theta.sin_cos();
    let r = Matrix2::new(co, -s, s, co);
    let t = mean_y - c * r * mean_x;
    Ok((theta, t, c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit};

    /// `c R(θ) x + t` in the plane, written out.
    fn similar2(x: &[Vector2<f64>], theta: f64, t: Vector2<f64>, c: f64) -> Vec<Vector2<f64>> {
        let (s, co) = theta.sin_cos();
        x.iter()
            .map(|p| {
                Vector2::new(
                    c * (co * p.x - s * p.y) + t.x,
                    c * (s * p.x + co * p.y) + t.y,
                )
            })
            .collect()
    }

    fn planar_points() -> Vec<Vector2<f64>> {
        [(0.0, 0.0), (2.0, 0.5), (3.0, 3.0), (-1.0, 2.0), (1.0, -1.5)]
            .iter()
            .map(|&(x, y)| Vector2::new(x, y))
            .collect()
    }

    #[test]
    fn the_planar_fit_recovers_a_known_similarity() {
        // y = 1.3 R(0.7) x + (0.4, −2): the Sim(2) fit returns exactly that;
        // rigid data (scale 1) give the rotation, translation and scale 1.
        let x = planar_points();
        let t = Vector2::new(0.4, -2.0);
        let y = similar2(&x, 0.7, t, 1.3);
        let (theta, got_t, c) = umeyama2(&x, &y, true).unwrap();
        assert!((theta - 0.7).abs() < 1e-12, "{theta}");
        assert!((got_t - t).norm() < 1e-12, "{got_t}");
        assert!((c - 1.3).abs() < 1e-12, "{c}");
        let y = similar2(&x, -2.5, t, 1.0);
        let (theta, got_t, c) = umeyama2(&x, &y, false).unwrap();
        assert!((theta + 2.5).abs() < 1e-12, "{theta}");
        assert!((got_t - t).norm() < 1e-12, "{got_t}");
        assert_eq!(c, 1.0);
    }

    #[test]
    fn the_rigid_planar_fit_of_scaled_data_keeps_scale_one_and_centres_the_means() {
        // y = 2 R(π/2) x + (1, −1) from (0, 0), (2, 0), (0, 1): means
        // (2/3, 1/3) and (1/3, 1/3). Without scale the rotation stays a
        // quarter turn and t = μ_y − R μ_x = (1/3, 1/3) − (−1/3, 2/3).
        let x = [
            Vector2::new(0.0, 0.0),
            Vector2::new(2.0, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        let y = [
            Vector2::new(1.0, -1.0),
            Vector2::new(1.0, 3.0),
            Vector2::new(-1.0, -1.0),
        ];
        let (theta, t, c) = umeyama2(&x, &y, false).unwrap();
        assert!(
            (theta - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
            "{theta}"
        );
        assert!(
            (t - Vector2::new(2.0 / 3.0, -1.0 / 3.0)).norm() < 1e-12,
            "{t}"
        );
        assert_eq!(c, 1.0);
        let (_, t, c) = umeyama2(&x, &y, true).unwrap();
        assert!((t - Vector2::new(1.0, -1.0)).norm() < 1e-12 && (c - 2.0).abs() < 1e-12);
    }

    #[test]
    fn tracker_sized_coordinates_fit_as_exactly_as_small_ones() {
        // Positions near UTM's (611 km, 5 300 km), in the plane and in 3D
        // (z 300 m): the fit is as good as near the origin.
        let off = Vector2::new(611_234.56, 5_301_987.65);
        let x: Vec<Vector2<f64>> = planar_points().iter().map(|p| p + off).collect();
        let t = Vector2::new(-3.0, 12.0);
        let y = similar2(&x, 0.3, t, 1.0);
        let (theta, got_t, _) = umeyama2(&x, &y, false).unwrap();
        assert!((theta - 0.3).abs() < 1e-9, "{theta}");
        let back: Vec<Vector2<f64>> = similar2(&x, theta, got_t, 1.0);
        for (b, q) in back.iter().zip(&y) {
            assert!((b - q).norm() < 1e-6, "{b} vs {q}");
        }
        let x3: Vec<Vector3<f64>> = x
            .iter()
            .zip([0.0, 1.0, -0.5, 2.0, 0.3])
            .map(|(p, z)| Vector3::new(p.x, p.y, 300.0 + z))
            .collect();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3);
        let y3: Vec<Vector3<f64>> = x3
            .iter()
            .map(|p| rot * p + Vector3::new(-3.0, 12.0, 1.0))
            .collect();
        let (r, got_t, _) = umeyama3(&x3, &y3, false).unwrap();
        assert!((r - rot.matrix()).norm() < 1e-9, "{r}");
        for (p, q) in x3.iter().zip(&y3) {
            assert!(
                (r * p + got_t - q).norm() < 1e-6,
                "{}",
                (r * p + got_t - q).norm()
            );
        }
    }

    #[test]
    fn the_planar_fit_refuses_what_does_not_spread() {
        let x = planar_points();
        let same = vec![Vector2::new(1.0, 2.0); x.len()];
        // The estimate or the reference all at one point, NaN, empty or of
        // another length: no fit.
        assert!(umeyama2(&same, &x, true).is_err());
        assert!(umeyama2(&x, &same, true).is_err());
        assert!(umeyama2(&x, &same, false).is_err());
        let mut nan = x.clone();
        nan[2].x = f64::NAN;
        assert!(umeyama2(&nan, &x, false).is_err());
        assert!(umeyama2(&x, &nan, false).is_err());
        assert!(umeyama2(&[], &[], false).is_err());
        assert!(umeyama2(&x, &x[..4], false).is_err());
        assert!(umeyama2(&x[..4], &x, false).is_err());
    }

    fn spatial_points() -> Vec<Vector3<f64>> {
        [
            (0.0, 0.0, 0.0),
            (2.0, 0.5, 0.3),
            (3.0, 3.0, -1.0),
            (-1.0, 2.0, 0.5),
            (1.0, -1.5, 2.0),
        ]
        .iter()
        .map(|&(x, y, z)| Vector3::new(x, y, z))
        .collect()
    }

    #[test]
    fn the_spatial_fit_recovers_a_known_similarity() {
        // y = 1.3 R x + t, R 0.8 rad about (1, 2, 3): exactly that back; the
        // rigid fit of rigid data keeps scale 1.
        let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0));
        let rot = Rotation3::from_axis_angle(&axis, 0.8);
        let t = Vector3::new(0.5, -1.0, 2.0);
        let x = spatial_points();
        let y: Vec<Vector3<f64>> = x.iter().map(|p| 1.3 * (rot * p) + t).collect();
        let (r, got_t, c) = umeyama3(&x, &y, true).unwrap();
        assert!((r - rot.matrix()).norm() < 1e-12, "{r}");
        assert!((got_t - t).norm() < 1e-12, "{got_t}");
        assert!((c - 1.3).abs() < 1e-12, "{c}");
        let y: Vec<Vector3<f64>> = x.iter().map(|p| rot * p + t).collect();
        let (r, got_t, c) = umeyama3(&x, &y, false).unwrap();
        assert!((r - rot.matrix()).norm() < 1e-12 && (got_t - t).norm() < 1e-12);
        assert_eq!(c, 1.0);
    }

    #[test]
    fn points_in_a_plane_give_a_proper_rotation() {
        // Points with z = 0 (cross-covariance of rank 2), turned 0.8 rad
        // about (1, 2, 3) and scaled 0.9: the rotation itself, determinant +1,
        // not its mirror image in the plane.
        let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0));
        let rot = Rotation3::from_axis_angle(&axis, 0.8);
        let x: Vec<Vector3<f64>> = planar_points()
            .iter()
            .map(|p| Vector3::new(p.x, p.y, 0.0))
            .collect();
        let y: Vec<Vector3<f64>> = x.iter().map(|p| 0.9 * (rot * p)).collect();
        let (r, t, c) = umeyama3(&x, &y, true).unwrap();
        assert!((r - rot.matrix()).norm() < 1e-12, "{r}");
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!(t.norm() < 1e-12 && (c - 0.9).abs() < 1e-12, "{t} {c}");
    }

    #[test]
    fn a_mirror_image_is_fitted_by_a_rotation_not_a_reflection() {
        // y is x mirrored in the plane z = 0: no rotation maps one onto the
        // other, and the fit is a proper rotation (determinant +1) all the
        // same, leaving the mirrored axis' spread out of the scale.
        let x = spatial_points();
        let y: Vec<Vector3<f64>> = x.iter().map(|p| Vector3::new(p.x, p.y, -p.z)).collect();
        let (r, _, c) = umeyama3(&x, &y, true).unwrap();
        assert!((r.determinant() - 1.0).abs() < 1e-12, "{r}");
        assert!(c < 1.0, "{c}");
    }

    #[test]
    fn the_spatial_fit_refuses_points_on_a_line_and_mismatched_sets() {
        let line: Vec<Vector3<f64>> = (0..5)
            .map(|i| Vector3::new(1.0, 2.0, 3.0) * i as f64)
            .collect();
        let x = spatial_points();
        assert!(umeyama3(&line, &x, true).is_err());
        assert!(umeyama3(&x, &line, false).is_err());
        assert!(umeyama3(&[], &[], false).is_err());
        assert!(umeyama3(&x, &x[..4], false).is_err());
        assert!(umeyama3(&x[..4], &x, false).is_err());
    }
}
