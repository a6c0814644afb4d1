//! A pipeline run into a [`Logger`] (design.md's Rerun entities): map,
//! trajectories, registered scans, ICP quality, the calibrator's estimates.
//! Particle clouds are logged while the filter runs ([`particle_logger`]).

use super::{icp, PipelineError};
use crate::calib::{self, CalibrationRun};
use crate::geom::Pose2;
use crate::recording::Recording;
use crate::robot::RobotConfig;
use crate::traj::Trajectory;
use crate::viz::{CalibEstimate, Logger, Stamp, TrajectoryKind, VizError};
use nalgebra::Point2;

/// What one run produced, for the recording; absent parts are not logged.
pub struct RunRecord<'a> {
    /// The recording the run read (scans for `world/scan`), if any.
    pub recording: Option<&'a Recording>,
    /// Nominal robot (laser mounting).
    pub robot: &'a RobotConfig,
    /// The world's walls `[x0, y0, x1, y1]` (m), when known (simulated runs).
    pub walls: Option<&'a [[f64; 4]]>,
    /// Scan matching result.
    pub icp: Option<&'a icp::IcpOutput>,
    /// Nominal wheel odometry.
    pub raw: Option<&'a Trajectory>,
    /// The calibrator whose trajectory and estimates are logged.
    pub calibrated: &'a CalibrationRun,
    /// Reference trajectory (world frame): the other paths start on it.
    pub reference: Option<&'a Trajectory>,
    /// Time origin of the `time` timeline (s, recording clock).
    pub t_start: f64,
    /// Stamps that define the `scan` timeline (s): the scans, or the motions' ends.
    pub scan_stamps: &'a [f64],
}

/// The `scan` timeline index of time `t`: how many scan stamps are ≤ `t`.
pub fn scan_index(stamps: &[f64], t: f64) -> i64 {
    stamps.partition_point(|s| *s <= t) as i64
}

/// `world_from_estimate` that puts the estimate's first pose on the reference.
pub fn anchor(est: &Trajectory, reference: Option<&Trajectory>) -> Pose2 {
    match (est.stamps.first(), est.poses.first(), reference) {
        (Some(&t0), Some(p0), Some(r)) => r
            .pose_at(t0)
            .or_else(|| r.poses.first().copied())
            .map(|w| w * p0.inverse())
            .unwrap_or_else(Pose2::identity),
        _ => Pose2::identity(),
    }
}

/// The estimate's poses placed in the world by `world_from_est`.
pub fn in_world(est: &Trajectory, world_from_est: &Pose2) -> Vec<Pose2> {
    est.poses.iter().map(|p| world_from_est * p).collect()
}

fn viz_err(e: VizError) -> PipelineError {
    PipelineError::Write {
        path: "visualisation".into(),
        message: e.to_string(),
    }
}

/// A filter-step callback that logs the particle cloud at every step; the
/// first logging error is kept in `error` (later steps are then skipped).
pub fn particle_logger<'a>(
    logger: &'a mut dyn Logger,
    scan_stamps: &'a [f64],
    t_start: f64,
    error: &'a mut Option<VizError>,
) -> impl FnMut(&calib::Estimate, Option<calib::CloudView<'_>>) + 'a {
    move |e, cloud| {
        if let (Some(c), None) = (cloud, &*error) {
            let at = Stamp::new(scan_index(scan_stamps, e.t), e.t - t_start);
            if let Err(err) = logger.particles(at, c.r_right, c.r_left, c.weights) {
                *error = Some(err);
            }
        }
    }
}

/// Logs everything but the particle clouds, then finishes the recording.
pub fn record(r: &RunRecord<'_>, logger: &mut dyn Logger) -> Result<(), PipelineError> {
    if let Some(walls) = r.walls {
        let segs: Vec<[Point2<f64>; 2]> = walls
            .iter()
            .map(|w| [Point2::new(w[0], w[1]), Point2::new(w[2], w[3])])
            .collect();
        logger.map(&segs).map_err(viz_err)?;
    }
    if let Some(reference) = r.reference {
        logger
            .trajectory(TrajectoryKind::Reference, &reference.poses)
            .map_err(viz_err)?;
    }
    if let Some(raw) = r.raw {
        logger
            .trajectory(
                TrajectoryKind::RawOdometry,
                &in_world(raw, &anchor(raw, r.reference)),
            )
            .map_err(viz_err)?;
    }
    let cal = &r.calibrated.trajectory;
    logger
        .trajectory(
            TrajectoryKind::Calibrated,
            &in_world(cal, &anchor(cal, r.reference)),
        )
        .map_err(viz_err)?;
    if let Some(icp_out) = r.icp {
        let w_icp = anchor(&icp_out.trajectory, r.reference);
        logger
            .trajectory(TrajectoryKind::Icp, &in_world(&icp_out.trajectory, &w_icp))
            .map_err(viz_err)?;
        if let Some(rec) = r.recording {
            // Scans at the ICP pose (laser frame → world), ICP quality per pair.
            let base_from_laser = icp::base_from_laser(rec, r.robot);
            let mut pts = Vec::new();
            for (i, scan) in rec.scans.iter().enumerate() {
                let at = Stamp::new(i as i64, scan.stamp - r.t_start);
                if let Some(p) = icp_out.trajectory.pose_at(scan.stamp) {
                    scan.points_into(&mut pts);
                    logger
                        .scan(at, &(w_icp * p * base_from_laser), &pts)
                        .map_err(viz_err)?;
                }
                if i > 0 {
                    if let Some(m) = icp_out.motions.get(i - 1) {
                        logger
                            .icp(at, m.iterations, m.cov.trace())
                            .map_err(viz_err)?;
                    }
                }
            }
        }
    }
    for h in &r.calibrated.history {
        let at = Stamp::new(scan_index(r.scan_stamps, h.t), h.t - r.t_start);
        logger
            .estimate(
                at,
                &CalibEstimate {
                    params: [h.r_right, h.r_left, h.wheel_base],
                    std: [h.std_r_right, h.std_r_left, h.std_wheel_base],
                    particles: h.particles,
                    process_sigma: h.process_sigma,
                },
            )
            .map_err(viz_err)?;
    }
    logger.finish().map_err(viz_err)
}
