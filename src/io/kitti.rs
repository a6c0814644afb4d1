//! KITTI odometry pose files: one pose a line, the 12 numbers of the 3×4 matrix
//! `[R | t]` row by row (`camera0_from_camera_i` in KITTI's own frames), with
//! the stamps (s) in a separate file, one a line, in the same order.

use super::columns::{data_lines, fields, read_text};
use crate::error::InputError;
use crate::eval::traj3::Trajectory3;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};
use std::path::Path;

const KIND: &str = "KITTI";
/// Largest ‖RᵀR − I‖ (Frobenius) accepted as a rotation (files print 6–9 digits).
const ORTHO_TOL: f64 = 1e-3;

/// Reads a KITTI pose file and its timestamps file as a 3D trajectory.
pub fn read_kitti(poses: &Path, times: &Path) -> Result<Trajectory3, InputError> {
    parse_kitti(
        &read_text(poses)?,
        &poses.display().to_string(),
        &read_text(times)?,
        &times.display().to_string(),
    )
}

/// Parses KITTI pose text and timestamp text. Errors name the file and line:
/// wrong field count, non-numbers, NaN/inf, a matrix that is not a rotation,
/// a coordinate or stamp beyond the TUM reader's bounds,
/// stamps that do not strictly increase, unequal counts, fewer than 2 poses.
pub fn parse_kitti(
    poses: &str,
    poses_file: &str,
    times: &str,
    times_file: &str,
) -> Result<Trajectory3, InputError> {
    let mut out = Vec::new();
    for (line_no, line) in data_lines(poses) {
        let v = fields::<12>(poses_file, KIND, line_no, line)?;
        let r = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let err = (r.transpose() * r - Matrix3::identity()).norm();
        if err > ORTHO_TOL || r.determinant() <= 0.0 {
            return Err(InputError::new(
                poses_file,
                format!(
                    "rotation part is not a rotation (‖RᵀR − I‖ = {err:.2e}, det {:.3})",
                    r.determinant()
                ),
            )
            .topic(KIND)
            .at(format!("line {line_no}")));
        }
        super::tum::check_bounds(None, &[v[3], v[7], v[11]]).map_err(|m| {
            InputError::new(poses_file, m)
                .topic(KIND)
                .at(format!("line {line_no}"))
        })?;
        let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
        out.push(Isometry3::from_parts(
            Translation3::new(v[3], v[7], v[11]),
            rot,
        ));
    }
    let mut stamps: Vec<f64> = Vec::new();
    for (line_no, line) in data_lines(times) {
        let [t] = fields::<1>(times_file, "timestamps", line_no, line)?;
        super::tum::check_bounds(Some(t), &[]).map_err(|m| {
            InputError::new(times_file, m)
                .topic("timestamps")
                .at(format!("line {line_no}"))
        })?;
        if stamps.last().is_some_and(|&p| t <= p) {
            return Err(
                InputError::new(times_file, format!("timestamp {t} does not increase"))
                    .topic("timestamps")
                    .at(format!("line {line_no}")),
            );
        }
        stamps.push(t);
    }
    if stamps.len() != out.len() {
        return Err(InputError::new(
            times_file,
            format!(
                "{} timestamps for {} poses in {poses_file}",
                stamps.len(),
                out.len()
            ),
        )
        .topic("timestamps"));
    }
    if out.len() < 2 {
        return Err(InputError::new(
            poses_file,
            format!("{} pose(s); a trajectory needs at least 2", out.len()),
        )
        .topic(KIND));
    }
    Ok(Trajectory3 { stamps, poses: out })
}
