//! Checks that inputs which parsed also make sense together, before they
//! reach a filter: motions read from a file (finite, a positive
//! semidefinite covariance, within the speed limits ICP itself enforces)
//! and a simulator truth file against the recording it claims to describe.
//! Each refusal names the file and the line or quantity that disagrees.

use super::PipelineError;
use crate::error::InputError;
use crate::icp::IcpParams;
use crate::motion::Motion;
use crate::recording::Recording;
use crate::sim::Truth;
use std::path::Path;

/// Relative tolerance on a covariance's eigenvalues: an eigenvalue below
/// −1e-9 × the largest one is a negative variance, not rounding.
const PSD_TOLERANCE: f64 = 1e-9;

/// Checks every valid motion of a motions file (`(line, motion)` pairs as
/// [`crate::io::csv::read_motions_numbered`] gives them): `t1 > t0`, a
/// covariance that is positive semidefinite, and a motion within `icp`'s
/// speed and turn-rate limits over its `t1 − t0`
/// ([`IcpParams::within_limits`], the gate every match passes). Failed
/// pairs are left as they are: they never become observations.
pub fn check_motions(
    file: &Path,
    motions: &[(usize, Motion)],
    icp: &IcpParams,
) -> Result<(), PipelineError> {
    for (line, m) in motions.iter().filter(|(_, m)| m.is_valid()) {
        let at = |msg: String| {
            PipelineError::from(
                InputError::new(file.display().to_string(), msg).at(format!("line {line}")),
            )
        };
        let dt = m.t1 - m.t0;
        if !(dt > 0.0) {
            return Err(at(format!(
                "a valid motion must span time: t0 {} s, t1 {} s",
                m.t0, m.t1
            )));
        }
        let eig = m.cov.symmetric_eigen().eigenvalues;
        let scale = eig.amax().max(f64::MIN_POSITIVE);
        if eig.min() < -PSD_TOLERANCE * scale {
            return Err(at(format!(
                "covariance is not positive semidefinite (eigenvalues {:.3e}, {:.3e}, {:.3e}): \
                 a variance cannot be negative",
                eig[0], eig[1], eig[2]
            )));
        }
        if !icp.within_limits([m.dx, m.dy, m.dtheta], &m.cov, dt) {
            return Err(at(format!(
                "motion ({} m, {} m, {} rad) in {dt} s is beyond the robot's limits \
                 (max_speed {} m/s, max_turn_rate {} rad/s, 3σ and slack included; [icp] in \
                 --config sets them)",
                m.dx, m.dy, m.dtheta, icp.max_speed, icp.max_turn_rate
            )));
        }
    }
    Ok(())
}

/// Seconds by which a truth file's length may differ from its recording's
/// span: one second (the first and last sensor samples fall inside the run,
/// not on its ends) plus 2 % of the run.
fn duration_tolerance(duration_s: f64) -> f64 {
    1.0 + 0.02 * duration_s
}

/// Checks that the truth file `truth_path` describes the recording
/// `rec_path`: the truth's run length agrees with the recording's time span
/// and its trajectory's stamps (relative to the run's start) fall within
/// that span. A mismatch names both files and the numbers.
pub fn check_truth(
    truth_path: &Path,
    truth: &Truth,
    rec_path: &Path,
    rec: &Recording,
) -> Result<(), PipelineError> {
    let mismatch = |what: String| {
        PipelineError::from(InputError::new(
            truth_path.display().to_string(),
            format!(
                "this truth file does not describe the recording {}: {what}",
                rec_path.display()
            ),
        ))
    };
    let Some((a, b)) = rec.time_span() else {
        return Ok(());
    };
    let span = b - a;
    let tol = duration_tolerance(truth.duration_s);
    if (span - truth.duration_s).abs() > tol {
        return Err(mismatch(format!(
            "the truth's run lasts {} s (scenario {}, seed {}) but the recording spans {span:.3} \
             s (tolerance {tol:.2} s)",
            truth.duration_s, truth.scenario, truth.seed
        )));
    }
    if let (Some(first), Some(last)) = (truth.trajectory.first(), truth.trajectory.last()) {
        if first.t < -tol || last.t > span + tol {
            return Err(mismatch(format!(
                "the true trajectory runs from {} s to {} s after the start, outside the \
                 recording's {span:.3} s",
                first.t, last.t
            )));
        }
    }
    Ok(())
}
