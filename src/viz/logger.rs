//! The [`Logger`] contract: what the pipeline reports to a viewer, as plain
//! data, on the two timelines of design.md (`time`, sensor time in s, and
//! `scan`, the scan index).

use super::VizError;
use crate::geom::Pose2;
use nalgebra::Point2;

/// Entity paths and timeline names of the recording (design.md, "Rerun
/// recording"); scripts that read the `.rrd` rely on them.
pub mod entity {
    /// Timeline of sensor time (s since the recording's first stamp or epoch).
    pub const TIME: &str = "time";
    /// Timeline of the scan index.
    pub const SCAN: &str = "scan";
    /// The world's map as line segments (static), world frame.
    pub const MAP: &str = "world/map";
    /// The robot's base: a transform (`base_link` in the world at each scan's
    /// time), under which the laser and the scan hang.
    pub const ROBOT: &str = "world/robot";
    /// An arrow along the robot's x axis (static, robot frame).
    pub const ROBOT_HEADING: &str = "world/robot/heading";
    /// The laser on the robot: its mounting `base_from_laser` (static transform).
    pub const LASER: &str = "world/robot/laser";
    /// The current scan's points in the laser frame.
    pub const SCAN_POINTS: &str = "world/robot/laser/scan";
    /// The scan-matching covariance of the pair ending at a scan: its 1σ
    /// position ellipse at the matched pose, magnified (world frame).
    pub const ICP_COVARIANCE: &str = "world/icp_covariance";
    /// Every scan match's ellipse up to the cursor, as a trail: the entities
    /// below this one, one per power-of-two block of matches
    /// ([`crate::viz::Trail`], [`trail_level`]).
    pub const ICP_COVARIANCE_TRAIL: &str = "world/icp_covariance/trail";

    /// The trail's entity of level `level` (blocks of 2^level ellipses).
    pub fn trail_level(level: usize) -> String {
        format!("{ICP_COVARIANCE_TRAIL}/{level:02}")
    }
    /// ICP-integrated trajectory (line strip, world frame).
    pub const TRAJ_ICP: &str = "world/trajectory/icp";
    /// Raw wheel odometry with nominal parameters.
    pub const TRAJ_RAW: &str = "world/trajectory/raw_odometry";
    /// Wheel odometry with the calibrated parameters.
    pub const TRAJ_CALIBRATED: &str = "world/trajectory/calibrated";
    /// The recording's reference trajectory (e.g. LOAM, ground truth).
    pub const TRAJ_REFERENCE: &str = "world/trajectory/reference";
    /// Particles in the (R_R, R_L) plane (m), coloured and sized by weight.
    pub const PARTICLES: &str = "calib/particles";
    /// How many particles `calib/particles` shows at a step (the subsample).
    pub const PARTICLES_SHOWN: &str = "calib/particles_shown";
    /// Estimated right wheel radius R_R (m).
    pub const EST_R_RIGHT: &str = "calib/estimate/r_right";
    /// Estimated left wheel radius R_L (m).
    pub const EST_R_LEFT: &str = "calib/estimate/r_left";
    /// Estimated wheel base D (m).
    pub const EST_WHEEL_BASE: &str = "calib/estimate/wheel_base";
    /// Standard deviation of R_R (m).
    pub const STD_R_RIGHT: &str = "calib/std/r_right";
    /// Standard deviation of R_L (m).
    pub const STD_R_LEFT: &str = "calib/std/r_left";
    /// Standard deviation of D (m).
    pub const STD_WHEEL_BASE: &str = "calib/std/wheel_base";
    /// Number of particles of the filter.
    pub const PARTICLES_COUNT: &str = "calib/particles_count";
    /// Process noise σ of the filter at this step.
    pub const PROCESS_SIGMA: &str = "calib/process_sigma";
    /// ICP iterations of the scan pair ending at this scan.
    pub const ICP_ITERATIONS: &str = "icp/iterations";
    /// Trace of the ICP motion covariance (m², rad² mixed; a quality gauge).
    pub const ICP_COV_TRACE: &str = "icp/covariance_trace";
    /// What changed where the change detector fired (text log).
    pub const CHANGES: &str = "calib/changes";
}

/// Where on the timelines an item belongs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stamp {
    /// Scan index (timeline `scan`).
    pub scan: i64,
    /// Sensor time (s, timeline `time`); must be finite.
    pub time: f64,
}

impl Stamp {
    /// A stamp at scan index `scan` and sensor time `time` (s).
    pub fn new(scan: i64, time: f64) -> Self {
        Stamp { scan, time }
    }

    /// Checks that the time is finite (Rerun timelines cannot hold NaN).
    pub fn check(&self) -> Result<(), VizError> {
        if self.time.is_finite() {
            Ok(())
        } else {
            Err(VizError::Input(format!(
                "non-finite time at scan {}",
                self.scan
            )))
        }
    }
}

/// Which of the four trajectories of the world view.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TrajectoryKind {
    /// Integrated ICP motions.
    Icp,
    /// Wheel odometry with the nominal parameters.
    RawOdometry,
    /// Wheel odometry with the calibrated parameters.
    Calibrated,
    /// The recording's reference (ground truth, LOAM, ...).
    Reference,
}

impl TrajectoryKind {
    /// All kinds, in drawing order.
    pub const ALL: [TrajectoryKind; 4] = [
        TrajectoryKind::Reference,
        TrajectoryKind::RawOdometry,
        TrajectoryKind::Icp,
        TrajectoryKind::Calibrated,
    ];

    /// The entity path (`world/trajectory/...`): the trajectory up to the
    /// time cursor, growing along the `time` timeline and, placed at the last
    /// scan logged at or before each time, along `scan`.
    pub fn entity(self) -> &'static str {
        match self {
            TrajectoryKind::Icp => entity::TRAJ_ICP,
            TrajectoryKind::RawOdometry => entity::TRAJ_RAW,
            TrajectoryKind::Calibrated => entity::TRAJ_CALIBRATED,
            TrajectoryKind::Reference => entity::TRAJ_REFERENCE,
        }
    }

    /// The whole trajectory, static, faint (`world/trajectory/.../full`).
    pub fn full_entity(self) -> &'static str {
        match self {
            TrajectoryKind::Icp => "world/trajectory/icp/full",
            TrajectoryKind::RawOdometry => "world/trajectory/raw_odometry/full",
            TrajectoryKind::Calibrated => "world/trajectory/calibrated/full",
            TrajectoryKind::Reference => "world/trajectory/reference/full",
        }
    }

    /// Display colour (sRGB), shared by the recording and the plots.
    pub fn color(self) -> [u8; 3] {
        match self {
            TrajectoryKind::Reference => [40, 40, 40],
            TrajectoryKind::RawOdometry => [214, 39, 40],
            TrajectoryKind::Icp => [31, 119, 180],
            TrajectoryKind::Calibrated => [44, 160, 44],
        }
    }
}

/// The calibration filter's state after one step: estimate, its standard
/// deviation, and the filter's size and process noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibEstimate {
    /// Estimated `[R_R, R_L, D]` (m).
    pub params: [f64; 3],
    /// Standard deviations of `params` (m).
    pub std: [f64; 3],
    /// Number of particles (0 for Kalman filters).
    pub particles: usize,
    /// Process noise σ used at this step (filter units).
    pub process_sigma: f64,
}

/// Receives the pipeline's results for display. Every method takes plain
/// data; implementations decide how much to keep. Methods return an error
/// only for unusable input or a failed sink, never panic.
pub trait Logger {
    /// The map as line segments `[a, b]` (world frame, m); static.
    fn map(&mut self, segments: &[[Point2<f64>; 2]]) -> Result<(), VizError>;

    /// One scan's points (sensor frame, m) from a robot at `world_from_base`
    /// whose laser sits at `base_from_sensor`.
    fn scan(
        &mut self,
        at: Stamp,
        world_from_base: &Pose2,
        base_from_sensor: &Pose2,
        points: &[Point2<f64>],
    ) -> Result<(), VizError>;

    /// A whole trajectory (world frame) with each pose's time (s, timeline
    /// `time`): the full line (static) and the line up to each time (on
    /// `scan` too, at the last scan logged at or before that time).
    fn trajectory(
        &mut self,
        kind: TrajectoryKind,
        times: &[f64],
        poses: &[Pose2],
    ) -> Result<(), VizError>;

    /// The covariance (m², 2×2, base frame) of the scan match ending at `at`,
    /// whose matched pose is `world_from_base`: shown as the latest match's
    /// ellipse and in the trail of every match up to the cursor.
    fn icp_covariance(
        &mut self,
        at: Stamp,
        world_from_base: &Pose2,
        cov_xy: [[f64; 2]; 2],
    ) -> Result<(), VizError> {
        let _ = (at, world_from_base, cov_xy);
        Ok(())
    }

    /// The particle cloud after a filter step: per particle R_R, R_L (m) and
    /// weight (any non-negative scale). Long clouds are shown as a
    /// weight-driven subsample whose size is logged too.
    fn particles(
        &mut self,
        at: Stamp,
        r_right: &[f64],
        r_left: &[f64],
        weights: &[f64],
    ) -> Result<(), VizError>;

    /// The filter's estimate after a step.
    fn estimate(&mut self, at: Stamp, estimate: &CalibEstimate) -> Result<(), VizError>;

    /// ICP quality for the scan pair ending at `at`.
    fn icp(&mut self, at: Stamp, iterations: u32, covariance_trace: f64) -> Result<(), VizError>;

    /// What the recording leaves out or thins, for the user (empty when
    /// nothing).
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }

    /// A text entry at `at` on `entity::CHANGES`: what changed where the
    /// change detector fired.
    fn change(&mut self, _at: Stamp, _text: &str) -> Result<(), VizError> {
        Ok(())
    }

    /// Sends everything still buffered and closes the sink (a file is
    /// complete and in place only after this). Calling it twice is harmless.
    fn finish(&mut self) -> Result<(), VizError>;
}

/// A logger that discards everything: the default when no recording is asked
/// for or the `rerun` feature is off.
#[derive(Clone, Copy, Debug, Default)]
pub struct NullLogger;

impl Logger for NullLogger {
    fn map(&mut self, _: &[[Point2<f64>; 2]]) -> Result<(), VizError> {
        Ok(())
    }
    fn scan(&mut self, _: Stamp, _: &Pose2, _: &Pose2, _: &[Point2<f64>]) -> Result<(), VizError> {
        Ok(())
    }
    fn trajectory(&mut self, _: TrajectoryKind, _: &[f64], _: &[Pose2]) -> Result<(), VizError> {
        Ok(())
    }
    fn particles(&mut self, _: Stamp, _: &[f64], _: &[f64], _: &[f64]) -> Result<(), VizError> {
        Ok(())
    }
    fn estimate(&mut self, _: Stamp, _: &CalibEstimate) -> Result<(), VizError> {
        Ok(())
    }
    fn icp(&mut self, _: Stamp, _: u32, _: f64) -> Result<(), VizError> {
        Ok(())
    }
    fn finish(&mut self) -> Result<(), VizError> {
        Ok(())
    }
}
