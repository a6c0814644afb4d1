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
