//! Incremental motions between two scans (what scan matching produces) and the
//! velocity observations the calibrators consume.

use nalgebra::Matrix3;

/// Why a scan pair produced no trustworthy motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairFailure {
    /// Too few valid points in one of the scans.
    TooFewPoints,
    /// Too few correspondences survived the distance threshold.
    TooFewCorrespondences,
    /// The iteration did not converge.
    NotConverged,
    /// The geometry leaves a direction unconstrained.
    Degenerate,
    /// dt between the scans is zero, negative or not finite.
    BadTime,
    /// The scans have different beam layouts or invalid angles.
    Inconsistent,
    /// The result disagrees with the motion prior beyond plausibility.
    Implausible,
    /// The first match after failed pairs: it starts from a pose the failed
    /// pairs' prior placed, so it holds that prior's error too (right for
    /// chaining, not a measurement of this interval).
    Bridged,
}

impl PairFailure {
    /// Short machine-readable reason, as written in CSV/JSON outputs.
    pub fn as_str(&self) -> &'static str {
        match self {
            Self::TooFewPoints => "too_few_points",
            Self::TooFewCorrespondences => "too_few_correspondences",
            Self::NotConverged => "not_converged",
            Self::Degenerate => "degenerate",
            Self::BadTime => "bad_time",
            Self::Inconsistent => "inconsistent",
            Self::Implausible => "implausible",
            Self::Bridged => "bridged",
        }
    }
}

/// Motion of the robot base between the stamps of two scans, in the base frame
/// at `t0`: `(dx, dy)` in m, `dtheta` in rad, with a 3×3 covariance over
/// (dx, dy, dθ).
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// Stamp of the reference (earlier) scan (s).
    pub t0: f64,
    /// Stamp of the current scan (s).
    pub t1: f64,
    /// Forward displacement (m).
    pub dx: f64,
    /// Leftward displacement (m).
    pub dy: f64,
    /// Heading change (rad, wrapped).
    pub dtheta: f64,
    /// Covariance of (dx, dy, dθ) in m², m·rad, rad².
    pub cov: Matrix3<f64>,
    /// Iterations the matcher ran.
    pub iterations: u32,
    /// Correspondences used in the final iteration.
    pub inliers: u32,
    /// `None` when the match is trustworthy, else why not.
    pub failure: Option<PairFailure>,
    /// What the estimate owes to the scan and what to the matcher's prior
    /// term (the odometry); `None` when not known (motions from elsewhere),
    /// taken as all scan.
    pub split: Option<InfoSplit>,
}

/// The information split of a motion: per direction, how much of the
/// estimate the scan measured, and the scan's own estimate.
///
/// A scan matcher with a prior term at the odometry estimates
/// `x̂ = K x_s + (I − K) x_p` (linearised at the optimum): `x_s` the scan's
/// own estimate, `x_p` the prior's centre, `K = (I + C P)⁻¹` with `C` the
/// scan-only covariance and `P` the prior's precision. Along a corridor `K`
/// falls to 0 and `x̂` is the odometry: fed to a calibration of that
/// odometry it would pull the estimate towards the nominal model. `x_s`
/// with covariance `C` carries the scan's information alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InfoSplit {
    /// Diagonal of `K` in the base frame at `t0`, for (dx, dy, dθ): the
    /// fraction, in [0, 1], of each direction's estimate that the scan
    /// measured (1: the scan alone; 0: the prior alone).
    pub scan_share: [f64; 3],
    /// The scan's own estimate `x_s` of (dx, dy, dθ) (m, m, rad), whose
    /// covariance is the motion's `cov`.
    pub scan_only: [f64; 3],
}

/// Below this share of the forward estimate owed to the scan, a motion gives
/// no forward-velocity observation: the prior (odometry) measured most of it,
/// and the scan's own estimate along that direction rests on a
/// linearisation far from where the scan constrains it.
pub const MIN_SCAN_SHARE: f64 = 0.5;

impl Motion {
    /// A valid motion over `[t0, t1]` (s) from a base-frame increment, with
    /// covariance `cov` (m², rad²) and no iteration or inlier counts yet.
    pub fn from_increment(t0: f64, t1: f64, inc: &crate::geom::Pose2, cov: Matrix3<f64>) -> Self {
        let [dx, dy, dtheta] = crate::geom::xyt(inc);
        Self {
            t0,
            t1,
            dx,
            dy,
            dtheta,
            cov,
            iterations: 0,
            inliers: 0,
            failure: None,
            split: None,
        }
    }

    /// The scan's own increment (dx, dy, dθ) and, along the direction of
    /// travel (the chord at dθ/2), the share of the estimate the scan
    /// measured: the estimate itself and 1 without a split.
    pub fn scan_measured(&self) -> ([f64; 3], f64) {
        match self.split {
            None => ([self.dx, self.dy, self.dtheta], 1.0),
            Some(s) => {
                let h = 0.5 * s.scan_only[2];
                let (c2, s2) = (h.cos().powi(2), h.sin().powi(2));
                let share = s.scan_share[0] * c2 + s.scan_share[1] * s2;
                (s.scan_only, share)
            }
        }
    }

    /// Whether the motion may be used as an observation.
    pub fn is_valid(&self) -> bool {
        self.failure.is_none()
    }
}

/// Body velocities measured over an interval, each with its own standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityObs {
    /// Interval start (s).
    pub t0: f64,
    /// Interval end (s).
    pub t1: f64,
    /// Forward velocity V_m (m/s).
    pub v: f64,
    /// Turn rate W_m (rad/s).
    pub w: f64,
    /// σ of `v` (m/s); infinite when the scan did not measure the forward
    /// motion (then `v` is no observation).
    pub sigma_v: f64,
    /// σ of `w` (rad/s).
    pub sigma_w: f64,
}

impl VelocityObs {
    /// Velocities from a valid motion: the constant (V, W) whose arc over dt
    /// best explains the scan's own estimate of the motion (see [`InfoSplit`]:
    /// never the part the matcher's odometry prior supplied; `V = arc
    /// length/dt`, `W = dθ/dt`, the arc length from the displacement
    /// projected on the arc's chord direction dθ/2, see [`arc_along_chord`]),
    /// with σ propagated from the (scan-only) covariance (`σ_V =
    /// sqrt(cov_xx)/dt`, `σ_W = sqrt(cov_θθ)/dt`). Where the scan measured
    /// less than [`MIN_SCAN_SHARE`] of the forward estimate (a corridor's
    /// axis), `σ_V` is infinite: no forward observation, only the turn rate.
    /// `None` for failed pairs or dt ≤ 0, so a failed match never becomes a
    /// confident observation.
    pub fn from_motion(m: &Motion) -> Option<Self> {
        let dt = m.t1 - m.t0;
        if !m.is_valid() || !(dt > 0.0) || !dt.is_finite() {
            return None;
        }
        let ([dx, dy, dtheta], share) = m.scan_measured();
        let (ds, dth) = arc_along_chord(dx, dy, dtheta);
        let sv = if share >= MIN_SCAN_SHARE {
            m.cov[(0, 0)].max(0.0).sqrt() / dt
        } else {
            f64::INFINITY
        };
        let sw = m.cov[(2, 2)].max(0.0).sqrt() / dt;
        let obs = Self {
            t0: m.t0,
            t1: m.t1,
            v: ds / dt,
            w: dth / dt,
            sigma_v: sv,
            sigma_w: sw,
        };
        let sv_ok = obs.sigma_v.is_finite() || share < MIN_SCAN_SHARE;
        ([obs.v, obs.w, obs.sigma_w].iter().all(|x| x.is_finite()) && sv_ok).then_some(obs)
    }
}

/// Signed arc length (m) and turn (rad) of the constant-velocity arc that
/// best explains a base-frame increment (dx, dy, dθ) (m, m, rad): an arc of
/// length s ends at `s·sinc(dθ/2)·(cos dθ/2, sin dθ/2)`, so under isotropic
/// noise on (dx, dy) the least-squares s projects the displacement on that
/// direction. Unlike the chord's norm, this is not inflated by noise (or a
/// mounting error) across the direction of travel, and its sign needs no
/// rule when the robot turns in place.
pub fn arc_along_chord(dx: f64, dy: f64, dtheta: f64) -> (f64, f64) {
    let h = 0.5 * dtheta;
    let along = dx * h.cos() + dy * h.sin();
    let factor = if h.abs() < 1e-6 {
        1.0 + h * h / 6.0
    } else {
        h / h.sin()
    };
    (along * factor, dtheta)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn motion() -> Motion {
        Motion {
            t0: 1.0,
            t1: 1.02,
            dx: 0.02,
            dy: 0.0,
            dtheta: 0.004,
            cov: Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-8, 1e-8, 4e-8)),
            iterations: 5,
            inliers: 500,
            failure: None,
            split: None,
        }
    }

    #[test]
    fn arc_length_ignores_displacement_across_the_chord() {
        // Exact arcs come back exactly, forwards, backwards and in place.
        for (v, w) in [(1.0, 0.0), (0.8, 0.5), (-0.3, 1.2), (0.0, 2.0), (0.5, -3.0)] {
            let [dx, dy, dth] = crate::geom::xyt(&crate::geom::arc_increment(v, w, 0.5));
            let (s, th) = arc_along_chord(dx, dy, dth);
            assert!((s - 0.5 * v).abs() < 1e-12, "{v} {w}: {s}");
            assert!((th - 0.5 * w).abs() < 1e-12);
        }
        // A sideways offset (noise, a mounting error) does not lengthen the
        // arc; the chord's norm would (0.1044 m here).
        let (s, _) = arc_along_chord(0.1, 0.03, 0.0);
        assert!((s - 0.1).abs() < 1e-15);
        // Turning in place with an offset across the chord: no travel.
        let (s, _) = arc_along_chord(-0.01 * 0.5f64.sin(), 0.01 * 0.5f64.cos(), 1.0);
        assert!(s.abs() < 1e-15);
    }

    #[test]
    fn velocities_come_from_the_scan_s_own_estimate() {
        // The estimate leans on the prior (0.02 m) where the scan says
        // 0.024 m: the observation takes the scan's value.
        let own = Motion {
            split: Some(InfoSplit {
                scan_share: [0.8, 1.0, 1.0],
                scan_only: [0.024, 0.0, 0.004],
            }),
            ..motion()
        };
        let o = VelocityObs::from_motion(&own).unwrap();
        assert!((o.v - 1.2).abs() < 1e-4, "{o:?}");
        assert!(o.sigma_v.is_finite());
        // A corridor's axis, measured by the prior: no forward observation,
        // the turn rate still.
        let axis = Motion {
            split: Some(InfoSplit {
                scan_share: [0.1, 1.0, 1.0],
                scan_only: [0.5, 0.0, 0.004],
            }),
            ..motion()
        };
        let o = VelocityObs::from_motion(&axis).unwrap();
        assert!(
            o.sigma_v.is_infinite() && (o.w - 0.2).abs() < 1e-12,
            "{o:?}"
        );
    }

    #[test]
    fn velocity_from_motion_divides_by_dt() {
        let o = VelocityObs::from_motion(&motion()).unwrap();
        assert!((o.v - 1.0).abs() < 1e-5);
        assert!((o.w - 0.2).abs() < 1e-12);
        assert!((o.sigma_v - 1e-4 / 0.02).abs() < 1e-12);
        assert!((o.sigma_w - 2e-4 / 0.02).abs() < 1e-12);
    }

    #[test]
    fn failed_pairs_and_bad_time_give_no_observation() {
        let mut m = motion();
        m.failure = Some(PairFailure::Degenerate);
        assert!(VelocityObs::from_motion(&m).is_none());
        let mut m = motion();
        m.t1 = m.t0;
        assert!(VelocityObs::from_motion(&m).is_none());
        let mut m = motion();
        m.dx = f64::NAN;
        assert!(VelocityObs::from_motion(&m).is_none());
    }
}
