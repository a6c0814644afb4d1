//! TUM trajectory files: one pose a line, `t x y z qx qy qz qw` (s, m, unit
//! quaternion), `#` comments — what evo and most tools read. Kept in full 3D so
//! results compare one-to-one with evo; [`read_tum_2d`] gives the planar view.

use super::atomic::write_atomic;
use super::columns::{data_lines, fields, read_text};
use crate::error::InputError;
use crate::eval::traj3::{pose3_from_2d, Pose3, Trajectory3};
use crate::traj::Trajectory;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::io::{self, Write};
use std::path::Path;

const KIND: &str = "TUM";

/// Largest coordinate (m) a pose may have: 10,000 km, beyond any robot's
/// map (Earth-centred coordinates stay below 6,400 km); larger values are a
/// corrupt file, and their squares would overflow the error statistics.
pub const MAX_COORDINATE: f64 = 1e7;
/// Largest stamp magnitude (s): about year 2286 in Unix time.
pub const MAX_STAMP: f64 = 1e10;

/// Whether a stamp (s) and coordinates (m) are within [`MAX_STAMP`] and
/// [`MAX_COORDINATE`]; `Err` says which value is not.
pub(crate) fn check_bounds(t: Option<f64>, xyz: &[f64]) -> Result<(), String> {
    if let Some(t) = t.filter(|t| t.abs() > MAX_STAMP) {
        return Err(format!(
            "timestamp {t:e} s is beyond ±{MAX_STAMP:e} s: not a time"
        ));
    }
    match xyz.iter().find(|v| v.abs() > MAX_COORDINATE) {
        Some(v) => Err(format!(
            "coordinate {v:e} m is beyond ±{MAX_COORDINATE:e} m (10,000 km): not a position"
        )),
        None => Ok(()),
    }
}

/// Reads a TUM file as a 3D trajectory.
pub fn read_tum(path: &Path) -> Result<Trajectory3, InputError> {
    parse_tum(&read_text(path)?, &path.display().to_string())
}

/// Reads a TUM file and keeps x, y and yaw (rotation about z).
pub fn read_tum_2d(path: &Path) -> Result<Trajectory, InputError> {
    Ok(read_tum(path)?.to_2d())
}

/// Parses TUM text; `file` names the source in errors. Errors name the line:
/// wrong field count, non-numbers, NaN/inf, coordinates beyond
/// [`MAX_COORDINATE`] or stamps beyond [`MAX_STAMP`], a zero quaternion,
/// stamps that do not strictly increase; also fewer than two poses.
pub fn parse_tum(text: &str, file: &str) -> Result<Trajectory3, InputError> {
    let mut stamps: Vec<f64> = Vec::new();
    let mut poses = Vec::new();
    let mut last_line = 0;
    for (line_no, line) in data_lines(text) {
        let [t, x, y, z, qx, qy, qz, qw] = fields::<8>(file, KIND, line_no, line)?;
        let at = || format!("line {line_no}");
        check_bounds(Some(t), &[x, y, z])
            .map_err(|m| InputError::new(file, m).topic(KIND).at(at()))?;
        let q = Quaternion::new(qw, qx, qy, qz);
        if !(q.norm() > 1e-9 && q.norm().is_finite()) {
            let what = if q.norm().is_finite() {
                "zero quaternion"
            } else {
                "quaternion too large to normalise"
            };
            return Err(InputError::new(file, what).topic(KIND).at(at()));
        }
        if let Some(&prev) = stamps.last() {
            if t <= prev {
                let what = if t == prev { "duplicate" } else { "decreasing" };
                return Err(InputError::new(
                    file,
                    format!("{what} timestamp {t} (line {last_line} has {prev}); stamps must strictly increase"),
                )
                .topic(KIND)
                .at(at()));
            }
        }
        stamps.push(t);
        poses.push(Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_quaternion(q),
        ));
        last_line = line_no;
    }
    if stamps.len() < 2 {
        return Err(InputError::new(
            file,
            format!("{} pose(s); a trajectory needs at least 2", stamps.len()),
        )
        .topic(KIND));
    }
    Ok(Trajectory3 { stamps, poses })
}

fn write_line(w: &mut impl Write, t: f64, p: &Pose3) -> io::Result<()> {
    let v = p.translation.vector;
    let q = p.rotation.coords; // (x, y, z, w)
    writeln!(
        w,
        "{t} {} {} {} {} {} {} {}",
        v.x, v.y, v.z, q.x, q.y, q.z, q.w
    )
}

/// Writes a 3D trajectory as TUM text (shortest exact decimal of every value),
/// atomically.
pub fn write_tum(path: &Path, traj: &Trajectory3) -> io::Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "# timestamp tx ty tz qx qy qz qw")?;
        for (t, p) in traj.stamps.iter().zip(&traj.poses) {
            write_line(w, *t, p)?;
        }
        Ok(())
    })
}

/// Writes a planar trajectory as TUM text (z = 0, rotation about z), atomically.
pub fn write_tum_2d(path: &Path, traj: &Trajectory) -> io::Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "{TUM_HEADER}")?;
        for (t, p) in traj.stamps.iter().zip(&traj.poses) {
            write_pose_2d(w, *t, p)?;
        }
        Ok(())
    })
}

/// The comment line that starts every TUM file odocal writes.
pub const TUM_HEADER: &str = "# timestamp tx ty tz qx qy qz qw";

/// One TUM line of a planar pose at `t` (s), as [`write_tum_2d`] writes it.
pub fn write_pose_2d(w: &mut impl Write, t: f64, p: &crate::geom::Pose2) -> io::Result<()> {
    write_line(w, t, &pose3_from_2d(p))
}
