//! `odocal eval`: load an estimate and a reference (TUM, KITTI, or a bag's
//! reference topic) and/or relations, and evaluate.

use super::PipelineError;
use crate::error::InputError;
use crate::eval::{self, EvalOptions, EvalReport, Trajectory3};
use crate::io::{self, ReadOptions};
use std::path::Path;

/// Loads a trajectory: an MCAP's reference stream (or, without one, its
/// odometry), a KITTI pose file when `times` is given, else a TUM file.
/// The flag is true for position-only sources (PointStamped references).
pub fn load_trajectory(
    path: &Path,
    times: Option<&Path>,
    read: &ReadOptions,
) -> Result<(Trajectory3, bool), PipelineError> {
    if let Some(t) = times {
        return Ok((io::kitti::read_kitti(path, t)?, false));
    }
    let file = path.display().to_string();
    let mut head = [0u8; 8];
    let is_mcap = std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .map(|_| head.starts_with(mcap::MAGIC))
        .unwrap_or(false);
    if !is_mcap {
        return Ok((io::tum::read_tum(path)?, false));
    }
    let rec = io::read_recording(path, read)?;
    let stream = if !rec.reference.is_empty() {
        &rec.reference
    } else {
        &rec.odom
    };
    let (traj, _repeated) = eval::trajectory_from_stamped(stream);
    if traj.len() < 2 {
        return Err(InputError::new(
            &file,
            format!(
                "no trajectory: topics {} and {} hold fewer than 2 poses",
                read.topics.reference, read.topics.odom
            ),
        )
        .into());
    }
    let position_only = stream.iter().any(|s| !s.has_heading);
    Ok((Trajectory3::from_2d(&traj), position_only))
}

/// Evaluates `estimate` against `reference` and/or `relations`.
pub fn run(
    estimate: &Trajectory3,
    reference: Option<&Trajectory3>,
    relations: Option<&Path>,
    opts: &EvalOptions,
) -> Result<EvalReport, PipelineError> {
    let rels = match relations {
        Some(p) => Some(io::relations::read_relations(p)?),
        None => None,
    };
    Ok(eval::evaluate(estimate, reference, rels.as_deref(), opts)?)
}
