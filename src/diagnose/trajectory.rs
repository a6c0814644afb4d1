//! Trajectory error against a reference on the held-out part: the model's
//! relative motion over consecutive windows (dead reckoning from the wheels)
//! against the reference's, before and after the extension.

use super::model::{Extension, Replay};
use crate::geom::{self, Pose2};
use crate::recording::StampedPose;
use serde::Serialize;

/// Relative-pose error over held-out windows (m), nominal vs extended model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrajectoryGain {
    /// Number of windows.
    pub windows: usize,
    /// Window length (s).
    pub window_s: f64,
    /// RMS translation error of the nominal model's relative motion (m).
    pub rpe_before: f64,
    /// The same for the extended model (m).
    pub rpe_after: f64,
}

/// Dead reckoning of the model from t0 to t1 in steps of about `h` s.
fn relative(replay: &Replay, x: &Extension, t0: f64, t1: f64, h: f64) -> Pose2 {
    let n = ((t1 - t0) / h).ceil().max(1.0) as usize;
    let dt = (t1 - t0) / n as f64;
    let mut p = Pose2::identity();
    for k in 0..n {
        let a = t0 + k as f64 * dt;
        let (v, w) = replay.body(x, a, a + dt);
        p *= geom::arc_increment(v, w, dt);
    }
    p
}

/// Compares the models with the reference over consecutive windows of
/// `window` s starting at `split`. With a heading the error is the
/// translation of `inv(ref_rel) · model_rel`; position-only references
/// compare the distance travelled between the window ends. `None` without
/// at least two reference windows inside the wheel span.
pub fn trajectory_gain(
    replay: &Replay,
    reference: &[StampedPose],
    before: &Extension,
    after: &Extension,
    split: f64,
    window: f64,
) -> Option<TrajectoryGain> {
    let (lo, hi) = replay.span()?;
    let refs: Vec<&StampedPose> = reference
        .iter()
        .filter(|r| r.stamp >= split.max(lo + 0.5) && r.stamp <= hi - 0.5)
        .collect();
    let (mut sb, mut sa, mut n) = (0.0, 0.0, 0usize);
    let mut i = 0;
    while i < refs.len() {
        let Some(off) = refs[i..]
            .iter()
            .position(|r| r.stamp >= refs[i].stamp + window)
        else {
            break;
        };
        let j = i + off;
        let (a, b) = (refs[i], refs[j]);
        let truth = geom::between(&a.pose, &b.pose);
        let err = |x: &Extension| {
            let m = relative(replay, x, a.stamp, b.stamp, 0.02);
            if a.has_heading && b.has_heading {
                (truth.inverse() * m).translation.vector.norm()
            } else {
                let d_ref = (b.pose.translation.vector - a.pose.translation.vector).norm();
                (m.translation.vector.norm() - d_ref).abs()
            }
        };
        let (eb, ea) = (err(before), err(after));
        sb += eb * eb;
        sa += ea * ea;
        n += 1;
        i = j;
    }
    (n >= 2).then(|| TrajectoryGain {
        windows: n,
        window_s: window,
        rpe_before: (sb / n as f64).sqrt(),
        rpe_after: (sa / n as f64).sqrt(),
    })
}
