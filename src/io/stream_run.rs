//! `odocal icp` and `odocal calibrate --input` on an MCAP bag in flat memory:
//! samples stream from [`McapStream`] into [`StreamIcp`], motions into the
//! motions CSV, the ICP trajectory and (for calibration) [`StepBuilder`] and
//! the calibrator, whose history and trajectory are written row by row. Each
//! output is an [`AtomicWriter`], committed only when the whole run succeeded.
//! Results equal the in-memory pipeline's (`pipeline::icp::run`,
//! `pipeline::calibrate::run`) on the same bag, except wall-clock timings.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::stream::{Item, McapStream, StreamInfo};
use super::stream_icp::{IcpTally, PriorKind, StreamIcp};
use super::stream_out::AtomicWriter;
use super::ReadOptions;
use crate::calib::StepBuilder;
use crate::calib::{self, CalibParams, CalibStep, CalibSummary, Calibrator, Estimate};
use crate::error::InputError;
use crate::geom::Pose2;
use crate::icp::{IcpParams, IcpStats};
use crate::motion::{Motion, VelocityObs};
use crate::robot::{DiffDrive, RobotConfig};

/// Sees a streamed calibration as it goes, e.g. to record it for a viewer.
/// Every method has a no-op default; calls come in the run's order and the
/// observer keeps (and reports) its own failures.
pub trait RunObserver {
    /// The run starts on a bag with these streams (from the reader's first pass).
    fn start(&mut self, _info: &StreamInfo) {}
    /// A sample read from the bag, in the order the stream yields it.
    fn item(&mut self, _item: &Item) {}
    /// A pose of the integrated ICP trajectory (odometry frame) at `t` (s).
    fn icp_pose(&mut self, _t: f64, _pose: &Pose2) {}
    /// A scan pair matched or flagged by ICP.
    fn motion(&mut self, _motion: &Motion) {}
    /// A filter step: its estimate and, for particle filters, the cloud.
    fn step(&mut self, _estimate: &Estimate, _cloud: Option<calib::CloudView<'_>>) {}
    /// A pose of the calibrated odometry (odometry frame) at `t` (s).
    fn calibrated_pose(&mut self, _t: f64, _pose: &Pose2) {}
}

/// An observer that ignores the run.
pub struct NoObserver;

impl RunObserver for NoObserver {}

/// Why a streamed run failed.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// The bag cannot be used (names file, topic, position).
    #[error(transparent)]
    Input(#[from] InputError),
    /// A setting or the bag's content does not allow the run.
    #[error("{0}")]
    BadArgument(String),
    /// An output could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The output.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
}

fn write_err(path: &Path) -> impl Fn(std::io::Error) -> StreamError + '_ {
    move |source| StreamError::Write {
        path: path.to_path_buf(),
        source,
    }
}

/// Summary of a streamed ICP run.
#[derive(Debug, Clone)]
pub struct IcpRunSummary {
    /// Pair counts, iterations, failures; timings of the matching loop.
    pub stats: IcpStats,
    /// Length (m) of the chained ICP trajectory.
    pub path_length: f64,
    /// Poses of the chained trajectory.
    pub poses: usize,
}

/// How the calibrator is fed besides ICP.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroUse {
    /// Use the gyro's yaw rate as a W measurement when the bag has one.
    pub use_gyro: bool,
    /// σ of one gyro sample (rad/s).
    pub gyro_sigma: f64,
}

/// The trajectory file being written: TUM rows as poses come.
struct TumOut {
    out: AtomicWriter,
    path: PathBuf,
    poses: usize,
}

impl TumOut {
    fn create(path: &Path) -> Result<Self, StreamError> {
        let mut out = AtomicWriter::create(path).map_err(write_err(path))?;
        writeln!(out.writer(), "{}", super::tum::TUM_HEADER).map_err(write_err(path))?;
        Ok(Self {
            out,
            path: path.to_path_buf(),
            poses: 0,
        })
    }

    fn pose(&mut self, t: f64, p: &Pose2) -> Result<(), StreamError> {
        self.poses += 1;
        super::tum::write_pose_2d(self.out.writer(), t, p).map_err(write_err(&self.path))
    }

    fn commit(self) -> Result<(), StreamError> {
        self.out.commit().map_err(write_err(&self.path))
    }
}

/// The ICP stage over a bag: matcher, tally, trajectory and motions outputs.
struct IcpStage<'o> {
    icp: StreamIcp,
    observer: &'o mut dyn RunObserver,
    kind: PriorKind,
    tally: IcpTally,
    traj: Option<TumOut>,
    motions: Option<(AtomicWriter, PathBuf)>,
    wheels_seen: usize,
    odom_seen: usize,
    scans_seen: usize,
    matching_s: f64,
}

impl<'o> IcpStage<'o> {
    fn new(
        info: &StreamInfo,
        source: &str,
        robot: &RobotConfig,
        params: &IcpParams,
        observer: &'o mut dyn RunObserver,
    ) -> Result<Self, StreamError> {
        if info.scans < 2 {
            return Err(InputError::new(
                source,
                format!("{} laser scans: scan matching needs at least 2", info.scans),
            )
            .into());
        }
        let kind = if info.wheels >= 2 {
            PriorKind::Wheels
        } else if info.odom >= 2 {
            PriorKind::Odom
        } else {
            PriorKind::None
        };
        let base = info.base_from_laser.unwrap_or_else(|| robot.laser.pose());
        let icp = StreamIcp::new(params, base, kind, robot.diff_drive())
            .map_err(|e| StreamError::BadArgument(e.to_string()))?;
        Ok(Self {
            icp,
            observer,
            kind,
            tally: IcpTally::default(),
            traj: None,
            motions: None,
            wheels_seen: 0,
            odom_seen: 0,
            scans_seen: 0,
            matching_s: 0.0,
        })
    }

    /// Feeds one item; the motions now final go to `on_motion`.
    fn feed(
        &mut self,
        item: &Item,
        info: &StreamInfo,
        on_motion: &mut dyn FnMut(&Motion) -> Result<(), StreamError>,
    ) -> Result<(), StreamError> {
        self.observer.item(item);
        match item {
            Item::Scan(s) => {
                self.scans_seen += 1;
                self.icp.push_scan(s.clone())
            }
            Item::Wheel(w) => {
                self.icp.push_wheel(w);
                self.wheels_seen += 1;
                if self.kind == PriorKind::Wheels && self.wheels_seen == info.wheels {
                    self.icp.end_prior();
                }
            }
            Item::Odom(p) => {
                self.icp.push_odom(p);
                self.odom_seen += 1;
                if self.kind == PriorKind::Odom && self.odom_seen == info.odom {
                    self.icp.end_prior();
                }
            }
            Item::Gyro(_) | Item::Reference(_) => return Ok(()),
        }
        self.poll(on_motion)
    }

    fn poll(
        &mut self,
        on_motion: &mut dyn FnMut(&Motion) -> Result<(), StreamError>,
    ) -> Result<(), StreamError> {
        let mut done: Vec<Motion> = Vec::new();
        let t = Instant::now();
        self.icp.poll(&mut |m| done.push(m));
        self.matching_s += t.elapsed().as_secs_f64();
        for m in &done {
            let mut res = Ok(());
            let traj = &mut self.traj;
            let observer = &mut *self.observer;
            self.tally.add(m, &mut |t, p| {
                observer.icp_pose(t, p);
                if let Some(out) = traj.as_mut() {
                    if res.is_ok() {
                        res = out.pose(t, p);
                    }
                }
            });
            res?;
            self.observer.motion(m);
            if let Some((w, path)) = self.motions.as_mut() {
                super::csv::write_motion_row(w.writer(), m).map_err(write_err(path))?;
            }
            on_motion(m)?;
        }
        Ok(())
    }

    fn finish(
        &mut self,
        on_motion: &mut dyn FnMut(&Motion) -> Result<(), StreamError>,
    ) -> Result<(), StreamError> {
        self.icp.end_prior();
        self.poll(on_motion)
    }
}

/// Runs ICP over the bag at `input`, writing the trajectory (TUM) to `tum`
/// and, if asked, the motions CSV, both atomically; `progress` gets the
/// fraction of scans read.
pub fn icp_file(
    input: &Path,
    read: &ReadOptions,
    robot: &RobotConfig,
    params: &IcpParams,
    tum: &Path,
    motions_csv: Option<&Path>,
    progress: &mut dyn FnMut(f64),
) -> Result<IcpRunSummary, StreamError> {
    let mut stream = McapStream::open(input, read)?;
    let info = stream.info().clone();
    let mut quiet = NoObserver;
    let mut stage = IcpStage::new(
        &info,
        &input.display().to_string(),
        robot,
        params,
        &mut quiet,
    )?;
    stage.traj = Some(TumOut::create(tum)?);
    if let Some(p) = motions_csv {
        let mut w = AtomicWriter::create(p).map_err(write_err(p))?;
        writeln!(w.writer(), "{}", super::csv::MOTIONS_HEADER).map_err(write_err(p))?;
        stage.motions = Some((w, p.to_path_buf()));
    }
    let mut none = |_: &Motion| Ok(());
    while let Some(item) = stream.next_item()? {
        stage.feed(&item, &info, &mut none)?;
        if matches!(item, Item::Scan(_)) {
            progress(stage.scans_seen as f64 / info.scans as f64);
        }
    }
    stage.finish(&mut none)?;
    let traj = stage.traj.take().expect("created above");
    let poses = traj.poses;
    traj.commit()?;
    if let Some((w, p)) = stage.motions.take() {
        w.commit().map_err(write_err(&p))?;
    }
    Ok(IcpRunSummary {
        stats: stage.tally.stats(stage.matching_s),
        path_length: stage.tally.path_length(),
        poses,
    })
}

/// The calibrator driven step by step, as `calib::run_observed` drives it,
/// writing each history row and trajectory pose as it comes.
struct CalibDriver {
    cal: Box<dyn Calibrator + Send>,
    nominal: DiffDrive,
    pose: Pose2,
    covered: Option<f64>,
    last_t: Option<f64>,
    total_s: f64,
    steps: usize,
    last: Option<Estimate>,
    history: AtomicWriter,
    history_path: PathBuf,
    traj: TumOut,
}

impl CalibDriver {
    fn push_pose(
        &mut self,
        t: f64,
        p: Pose2,
        obs: &mut dyn RunObserver,
    ) -> Result<(), StreamError> {
        if t.is_finite() && self.last_t.is_none_or(|l| t > l) {
            self.last_t = Some(t);
            self.traj.pose(t, &p)?;
            obs.calibrated_pose(t, &p);
        }
        Ok(())
    }

    fn step(&mut self, s: &CalibStep, obs: &mut dyn RunObserver) -> Result<(), StreamError> {
        if self.covered.is_none() {
            self.covered = Some(s.t0);
            self.push_pose(s.t0, Pose2::identity(), obs)?;
        }
        let t = Instant::now();
        let e = self.cal.step(s);
        self.total_s += t.elapsed().as_secs_f64();
        obs.step(&e, self.cal.cloud());
        let covered = self.covered.expect("set above");
        let dt = s.t1 - s.t0.max(covered);
        if dt > 0.0 {
            self.pose *= e.drive().increment(s.omega_right * dt, s.omega_left * dt);
            self.push_pose(s.t1, self.pose, obs)?;
            self.covered = Some(s.t1);
        }
        let row = [
            e.t,
            e.r_right,
            e.r_left,
            e.wheel_base,
            e.std_r_right,
            e.std_r_left,
            e.std_wheel_base,
            e.particles as f64,
            e.process_sigma,
        ];
        super::csv::write_history_row(self.history.writer(), &row)
            .map_err(write_err(&self.history_path))?;
        self.steps += 1;
        self.last = Some(e);
        Ok(())
    }

    fn summary(&self) -> CalibSummary {
        CalibSummary::after(
            self.cal.name(),
            self.last.as_ref(),
            self.nominal,
            self.steps,
            self.total_s,
        )
    }
}

/// Runs ICP and the calibrator over the bag at `input`, writing
/// `DIR/calibration.csv`, `DIR/trajectory.tum` and `DIR/summary.json`
/// atomically. `calib` is used as given (the caller adapts its ranges to the robot).
// Each argument is a separate stage input the callers hold apart.
#[allow(clippy::too_many_arguments)]
pub fn calibrate_file(
    input: &Path,
    read: &ReadOptions,
    robot: &RobotConfig,
    icp: &IcpParams,
    calib: &CalibParams,
    gyro: GyroUse,
    dir: &Path,
    progress: &mut dyn FnMut(f64),
    observer: &mut dyn RunObserver,
) -> Result<CalibSummary, StreamError> {
    let mut stream = McapStream::open(input, read)?;
    let info = stream.info().clone();
    observer.start(&info);
    let mut stage = IcpStage::new(&info, &input.display().to_string(), robot, icp, observer)?;
    if info.wheels < 2 {
        return Err(StreamError::BadArgument(
            "the input has no wheel encoder data (JointState) to calibrate".into(),
        ));
    }
    let nominal = robot.diff_drive();
    let cal = calib::build(calib, nominal).map_err(|e| StreamError::BadArgument(e.to_string()))?;
    let history_path = dir.join("calibration.csv");
    let mut history = AtomicWriter::create(&history_path).map_err(write_err(&history_path))?;
    writeln!(history.writer(), "{}", super::csv::HISTORY_HEADER)
        .map_err(write_err(&history_path))?;
    let mut driver = CalibDriver {
        cal,
        nominal,
        pose: Pose2::identity(),
        covered: None,
        last_t: None,
        total_s: 0.0,
        steps: 0,
        last: None,
        history,
        history_path,
        traj: TumOut::create(&dir.join("trajectory.tum"))?,
    };
    let mut steps = StepBuilder::new(gyro.use_gyro && info.gyro > 0, gyro.gyro_sigma);
    if info.gyro == 0 {
        steps.end_gyro();
    }
    let (mut wheels_seen, mut gyro_seen) = (0usize, 0usize);
    let mut failed: Option<StreamError> = None;
    let mut feed_steps = |steps: &mut StepBuilder,
                          all_done: bool,
                          driver: &mut CalibDriver,
                          obs: &mut dyn RunObserver| {
        steps.poll(all_done, &mut |s| {
            if failed.is_none() {
                if let Err(e) = driver.step(&s, obs) {
                    failed = Some(e);
                }
            }
        });
    };
    while let Some(item) = stream.next_item()? {
        match &item {
            Item::Wheel(w) => {
                steps.push_wheel(*w);
                wheels_seen += 1;
                if wheels_seen == info.wheels {
                    steps.end_wheels();
                }
            }
            Item::Gyro(g) => {
                steps.push_gyro(*g);
                gyro_seen += 1;
                if gyro_seen == info.gyro {
                    steps.end_gyro();
                }
            }
            _ => {}
        }
        stage.feed(&item, &info, &mut |m| {
            if let Some(o) = VelocityObs::from_motion(m) {
                steps.push_obs(o);
            }
            Ok(())
        })?;
        feed_steps(&mut steps, false, &mut driver, &mut *stage.observer);
        if matches!(item, Item::Scan(_)) {
            progress(stage.scans_seen as f64 / info.scans as f64);
        }
    }
    stage.finish(&mut |m| {
        if let Some(o) = VelocityObs::from_motion(m) {
            steps.push_obs(o);
        }
        Ok(())
    })?;
    steps.end_wheels();
    steps.end_gyro();
    feed_steps(&mut steps, true, &mut driver, &mut *stage.observer);
    if let Some(e) = failed {
        return Err(e);
    }
    if driver.steps == 0 {
        return Err(StreamError::BadArgument(
            "nothing to calibrate: no wheel data overlapping the velocity observations".into(),
        ));
    }
    let summary = driver.summary();
    let CalibDriver {
        history,
        history_path,
        traj,
        ..
    } = driver;
    history.commit().map_err(write_err(&history_path))?;
    traj.commit()?;
    let js = dir.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).expect("summary serialises");
    super::atomic::write_bytes_atomic(&js, text.as_bytes()).map_err(write_err(&js))?;
    Ok(summary)
}
