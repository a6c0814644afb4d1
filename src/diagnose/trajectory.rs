//! Trajectory error against a reference on the held-out part: the model's
//! relative motion over consecutive windows (dead reckoning from the wheels)
//! against the reference's, before and after the extension.

use super::model::Replay;
use crate::effects::Departures;
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
    /// Position-only references: RMS position error (m) of the nominal
    /// model's dead reckoning over the whole held-out part, after the
    /// rigid 2D alignment (rotation + translation) that minimises it; this
    /// is what exposes heading errors when the reference has no heading.
    pub ate_before: Option<f64>,
    /// The same for the extended model (m).
    pub ate_after: Option<f64>,
}

/// Dead reckoning of the model from t0 to t1 in steps of about `h` s.
fn relative(replay: &Replay, x: &Departures, t0: f64, t1: f64, h: f64) -> Pose2 {
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

/// RMS distance (m) between two point sets after the rigid 2D motion of
/// `a` onto `b` that minimises it (closed form: centroids, then the angle
/// atan2(Σ a×b, Σ a·b) of the centred points).
pub fn aligned_rms(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let n = a.len().min(b.len());
    if n == 0 {
        return 0.0;
    }
    let mean = |p: &[[f64; 2]]| {
        let s = p[..n]
            .iter()
            .fold([0.0, 0.0], |m, q| [m[0] + q[0], m[1] + q[1]]);
        [s[0] / n as f64, s[1] / n as f64]
    };
    let (ca, cb) = (mean(a), mean(b));
    let (mut dot, mut cross) = (0.0, 0.0);
    for k in 0..n {
        let (p, q) = (
            [a[k][0] - ca[0], a[k][1] - ca[1]],
            [b[k][0] - cb[0], b[k][1] - cb[1]],
        );
        dot += p[0] * q[0] + p[1] * q[1];
        cross += p[0] * q[1] - p[1] * q[0];
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    let mut sum = 0.0;
    for k in 0..n {
        let p = [a[k][0] - ca[0], a[k][1] - ca[1]];
        let r = [c * p[0] - s * p[1] + cb[0], s * p[0] + c * p[1] + cb[1]];
        sum += (r[0] - b[k][0]).powi(2) + (r[1] - b[k][1]).powi(2);
    }
    (sum / n as f64).sqrt()
}

/// Dead reckoning of the model from the first to the last reference stamp,
/// aligned to the reference positions: the held-out ATE (m).
fn held_out_ate(replay: &Replay, x: &Departures, refs: &[&StampedPose], h: f64) -> f64 {
    let mut p = Pose2::identity();
    let mut model = Vec::with_capacity(refs.len());
    let mut truth = Vec::with_capacity(refs.len());
    model.push([0.0, 0.0]);
    truth.push(refs[0].pose.translation.vector.into());
    for w in refs.windows(2) {
        p *= relative(replay, x, w[0].stamp, w[1].stamp, h);
        model.push(p.translation.vector.into());
        truth.push(w[1].pose.translation.vector.into());
    }
    aligned_rms(&model, &truth)
}

/// Compares the models with the reference over consecutive windows of
/// `window` s starting at `split`. With a heading the error is the
/// translation of `inv(ref_rel) · model_rel`; position-only references
/// compare the distance travelled between the window ends. `None` without
/// at least two reference windows inside the wheel span.
pub fn trajectory_gain(
    replay: &Replay,
    reference: &[StampedPose],
    before: &Departures,
    after: &Departures,
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
        let err = |x: &Departures| {
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
    let position_only = refs.iter().any(|r| !r.has_heading);
    let ate = |x: &Departures| {
        (position_only && refs.len() >= 3).then(|| held_out_ate(replay, x, &refs, 0.02))
    };
    (n >= 2).then(|| TrajectoryGain {
        windows: n,
        window_s: window,
        rpe_before: (sb / n as f64).sqrt(),
        rpe_after: (sa / n as f64).sqrt(),
        ate_before: ate(before),
        ate_after: ate(after),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_rms_removes_a_rigid_motion_but_not_a_shape_change() {
        let a: Vec<[f64; 2]> = (0..20)
            .map(|k| {
                let t = k as f64 * 0.3;
                [t.cos() * 2.0, t.sin()]
            })
            .collect();
        let (s, c) = 0.7f64.sin_cos();
        let b: Vec<[f64; 2]> = a
            .iter()
            .map(|p| [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 1.0])
            .collect();
        assert!(aligned_rms(&a, &b) < 1e-12);
        let scaled: Vec<[f64; 2]> = b.iter().map(|p| [1.1 * p[0], 1.1 * p[1]]).collect();
        assert!(aligned_rms(&a, &scaled) > 0.05);
    }
}
