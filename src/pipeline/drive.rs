//! The one driver of a run: samples from a [`SampleSource`] go through the
//! incremental ICP matcher ([`crate::icp::StreamMatcher`]) and, for a calibration,
//! the step builder and the calibration [`Runner`]; everything else (files,
//! Rerun, progress, in-memory results) is a [`RunObserver`]. A bag streamed
//! from disk and the same recording in memory therefore take the same path
//! and give the same numbers.

use std::time::Instant;

use super::observe::RunObserver;
use super::odometry::WheelOdometry;
use super::{Mount, PipelineError};
use crate::calib::batch::{LaserMotion, P3};
use crate::calib::online::{FrontEnd, Mounted, Started};
use crate::calib::{
    self, CalibParams, CalibStep, CalibSummary, Calibrator, Ranges, Runner, StepBuilder,
};
use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::icp::{IcpParams, IcpStats, Prior, StreamMatcher, Tally};
use crate::io::{Item, SampleSource, StreamInfo};
use crate::motion::{Motion, VelocityObs};
use crate::recording::{GyroSample, WheelSample};
use crate::robot::DiffDrive;
use crate::robot::RobotConfig;
use serde::{Deserialize, Serialize};

/// How measurements other than ICP enter the calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeasurementConfig {
    /// Use the gyro's yaw rate as a W measurement when the recording has one.
    pub use_gyro: bool,
    /// σ of one gyro sample (rad/s).
    pub gyro_sigma: f64,
}

impl Default for MeasurementConfig {
    fn default() -> Self {
        Self {
            use_gyro: true,
            gyro_sigma: 0.003,
        }
    }
}

/// Summary of the ICP part of a run.
#[derive(Debug, Clone)]
pub struct IcpRunSummary {
    /// Pair counts, iterations, failures; timings of the matching loop.
    pub stats: IcpStats,
    /// Length (m) of the chained ICP trajectory.
    pub path_length: f64,
    /// The laser mounting the scans were matched with, and its source.
    pub mount: Mount,
    /// The stream each pair's initial guess came from.
    pub prior: Prior,
    /// Where every nominal value came from (filled by the command).
    pub assumptions: crate::assumptions::Assumptions,
}

/// The ICP stage: the matcher fed the scans and the prior's samples, and the
/// tally that chains the motions into the ICP trajectory.
struct IcpStage {
    matcher: StreamMatcher,
    mount: Mount,
    /// Whether the recording or robot file stated the mounting (else the
    /// scans are matched in the laser's own frame).
    stated: bool,
    /// The robot file's scanner corrections, applied to every scan.
    scanner: crate::robot::ScannerCorrection,
    prior: Prior,
    tally: Tally,
    wheels_seen: usize,
    odom_seen: usize,
    matching_s: f64,
}

impl IcpStage {
    /// The stage for a source with `info`; `robot` gives the laser mount when
    /// the source states none, and the nominal wheel odometry prior. With
    /// `unstated_ok`, no mounting stated anywhere matches in the laser's own
    /// frame (the calibration estimates it) instead of refusing.
    fn new(
        info: &StreamInfo,
        source: &str,
        robot: &RobotConfig,
        params: &IcpParams,
        unstated_ok: bool,
    ) -> Result<Self, PipelineError> {
        if info.scans < 2 {
            return Err(InputError::new(
                source,
                format!(
                    "{} laser scans: scan matching needs at least 2 (the scans are read from \
                     [topics] scan in the --config file, default /scan; `odocal inspect {source}` \
                     lists the recording's LaserScan topics)",
                    info.scans
                ),
            )
            .into());
        }
        let prior = Prior::choose(params.prior, info.wheels, info.odom, robot.diff_drive())
            .map_err(|e| InputError::new(source, e))?;
        let (mount, stated) = match Mount::resolve(info.into(), robot, source) {
            Ok(m) => (m, true),
            Err(_) if unstated_ok => (
                Mount {
                    pose: Pose2::identity(),
                    origin: crate::assumptions::Origin::Estimated,
                    note: Some(
                        "stated nowhere (recording or robot file): the scans were matched in \
                         the laser's own frame and the mounting estimated on the stream"
                            .into(),
                    ),
                },
                false,
            ),
            Err(e) => return Err(e),
        };
        let matcher = StreamMatcher::new(params, mount.pose, prior)
            .map_err(|e| PipelineError::BadArgument(e.to_string()))?;
        Ok(Self {
            matcher,
            mount,
            stated,
            scanner: robot.scanner,
            prior,
            tally: Tally::default(),
            wheels_seen: 0,
            odom_seen: 0,
            matching_s: 0.0,
        })
    }

    /// Feeds one sample; the motions now final go to the observer and `out`.
    fn feed(
        &mut self,
        item: &Item,
        info: &StreamInfo,
        obs: &mut dyn RunObserver,
        out: &mut dyn FnMut(&Motion),
    ) {
        match item {
            Item::Scan(s) if self.scanner.is_none() => self.matcher.push_scan(s.clone()),
            Item::Scan(s) => self
                .matcher
                .push_scan(s.corrected(self.scanner.angle_increment, self.scanner.range_offset)),
            Item::Wheel(w) => {
                self.matcher.push_wheel(w);
                self.wheels_seen += 1;
                if matches!(self.prior, Prior::Wheels(_)) && self.wheels_seen == info.wheels {
                    self.matcher.end_prior();
                }
            }
            Item::Odom(p) => {
                self.matcher.push_odom(p);
                self.odom_seen += 1;
                if self.prior == Prior::Odom && self.odom_seen == info.odom {
                    self.matcher.end_prior();
                }
            }
            Item::Gyro(_) | Item::Reference(_) => return,
        }
        self.poll(obs, out);
    }

    /// Matches what the prior now covers.
    fn poll(&mut self, obs: &mut dyn RunObserver, out: &mut dyn FnMut(&Motion)) {
        let mut done: Vec<Motion> = Vec::new();
        let t = Instant::now();
        self.matcher.poll(&mut |m| done.push(m));
        self.matching_s += t.elapsed().as_secs_f64();
        for m in &done {
            self.tally.add(m, &mut |t, p| obs.icp_pose(t, p));
            obs.motion(m);
            out(m);
        }
    }

    /// The source has ended: every scan left is matched.
    fn finish(&mut self, obs: &mut dyn RunObserver, out: &mut dyn FnMut(&Motion)) {
        self.matcher.end_prior();
        self.poll(obs, out);
    }

    /// An error when the recording had scan pairs and every one failed:
    /// nothing usable came out of the stage, which must not pass as a run.
    fn check_usable(&self, source: &str, topic: &str) -> Result<(), PipelineError> {
        let stats = self.tally.stats(0.0);
        if stats.pairs == 0 || stats.failed_pairs < stats.pairs {
            return Ok(());
        }
        let reasons: Vec<String> = stats
            .failures
            .iter()
            .map(|(why, n)| format!("{why} {n}"))
            .collect();
        Err(InputError::new(
            source,
            format!(
                "every scan pair failed: {} of {} ({}); no motion to use",
                stats.failed_pairs,
                stats.pairs,
                reasons.join(", ")
            ),
        )
        .topic(topic)
        .into())
    }

    fn summary(&self) -> IcpRunSummary {
        IcpRunSummary {
            stats: IcpStats {
                prior_time_offset: self.matcher.time_offset_fit(),
                prior_scale: self.matcher.prior_scale(),
                ..self.tally.stats(self.matching_s)
            },
            path_length: self.tally.path_length(),
            mount: self.mount.clone(),
            prior: self.prior,
            assumptions: Default::default(),
        }
    }
}

/// Runs ICP over every scan of `source`; the observer sees every sample,
/// motion and ICP pose.
pub fn run_icp(
    source: &mut dyn SampleSource,
    robot: &RobotConfig,
    params: &IcpParams,
    obs: &mut dyn RunObserver,
) -> Result<IcpRunSummary, PipelineError> {
    let info = source.info().clone();
    obs.start(&info);
    let mut stage = IcpStage::new(&info, source.name(), robot, params, false)?;
    while let Some(item) = source.next_item()? {
        obs.item(&item);
        stage.feed(&item, &info, obs, &mut |_| {});
    }
    stage.finish(obs, &mut |_| {});
    stage.check_usable(source.name(), source.scan_topic())?;
    Ok(stage.summary())
}

/// Where the calibration stage's observations come from.
enum Feed {
    /// Velocity observations as given (in memory, or per motion with no
    /// front end): the calibrator starts at once from `params.ranges()`.
    Direct,
    /// The online front end ([`calib::online`]): motions composed into
    /// intervals, read at the estimated time offset, moved into the base
    /// frame with the mounting in use; the calibrator starts after its
    /// warm-up. `icp_mount` is the mounting the scan matcher used.
    Online {
        front: Box<FrontEnd>,
        icp_mount: Pose2,
        odometry: WheelOdometry,
    },
}

/// The calibration stage: the front end, the step builder aligning wheels,
/// gyro and velocity observations into filter steps, and the calibrator
/// with the runner over them (built once the stage knows where it starts).
pub struct CalibStage {
    feed: Feed,
    steps: StepBuilder,
    params: CalibParams,
    nominal: DiffDrive,
    cal: Option<Box<dyn Calibrator + Send>>,
    runner: Runner,
    evidence: calib::Evidence,
    /// Steps that carried at least one measurement (not predict-only).
    measured: usize,
}

impl CalibStage {
    /// A stage fed velocity observations directly: the calibrator `params`
    /// names, started from `params.ranges()`; `nominal` is what the summary
    /// reports before any step; the gyro is used when `meas` says so and
    /// `has_gyro`.
    pub fn direct(
        params: &CalibParams,
        nominal: DiffDrive,
        meas: &MeasurementConfig,
        has_gyro: bool,
    ) -> Result<Self, PipelineError> {
        let cal =
            calib::build(params, nominal).map_err(|e| PipelineError::BadArgument(e.to_string()))?;
        Ok(Self::with(
            Feed::Direct,
            Some(cal),
            params,
            nominal,
            meas,
            has_gyro,
        ))
    }

    /// A stage behind the online front end ([`calib::online`]): `nominal`
    /// (`None`: none known), the `stated` mounting and its source, and the
    /// mounting the scan matcher used (`icp_mount`).
    pub fn online(
        params: &CalibParams,
        nominal: Option<DiffDrive>,
        stated: Option<(P3, String)>,
        icp_mount: Pose2,
        meas: &MeasurementConfig,
        has_gyro: bool,
    ) -> Result<Self, PipelineError> {
        params
            .validate()
            .map_err(|e| PipelineError::BadArgument(e.to_string()))?;
        let front = FrontEnd::new(
            &params.online,
            &params.batch,
            &params.checks,
            nominal,
            stated,
        );
        let feed = Feed::Online {
            front: Box::new(front),
            icp_mount,
            odometry: WheelOdometry::default(),
        };
        let shown = nominal.unwrap_or(DiffDrive {
            r_right: f64::NAN,
            r_left: f64::NAN,
            wheel_base: f64::NAN,
        });
        Ok(Self::with(feed, None, params, shown, meas, has_gyro))
    }

    fn with(
        feed: Feed,
        cal: Option<Box<dyn Calibrator + Send>>,
        params: &CalibParams,
        nominal: DiffDrive,
        meas: &MeasurementConfig,
        has_gyro: bool,
    ) -> Self {
        Self {
            feed,
            steps: StepBuilder::new(meas.use_gyro && has_gyro, meas.gyro_sigma),
            runner: Runner::new(params.method.as_str(), nominal),
            params: params.clone(),
            nominal,
            cal,
            evidence: calib::Evidence::default(),
            measured: 0,
        }
    }

    /// A wheel sample (stamp order).
    pub fn push_wheel(&mut self, w: WheelSample) {
        if let Feed::Online {
            front, odometry, ..
        } = &mut self.feed
        {
            front.push_wheel(&w);
            odometry.push(w);
        }
        self.steps.push_wheel(w);
    }

    /// No more wheel samples.
    pub fn end_wheels(&mut self) {
        self.steps.end_wheels();
    }

    /// A gyro sample (stamp order).
    pub fn push_gyro(&mut self, g: GyroSample) {
        self.steps.push_gyro(g);
    }

    /// No more gyro samples.
    pub fn end_gyro(&mut self) {
        self.steps.end_gyro();
    }

    /// A motion of ICP: into the front end, or a velocity observation
    /// unless the pair failed.
    pub fn push_motion(&mut self, m: &Motion) {
        match &mut self.feed {
            Feed::Online {
                front, icp_mount, ..
            } => {
                front.push_motion(&LaserMotion::from_motion(m, icp_mount));
            }
            Feed::Direct => {
                if let Some(o) = VelocityObs::from_motion(m) {
                    self.steps.push_obs(o);
                }
            }
        }
    }

    /// An interval of the laser's own displacement (Censi's tuples).
    pub fn push_interval(&mut self, iv: calib::batch::Interval) {
        if let Feed::Online { front, .. } = &mut self.feed {
            front.push_interval(iv);
        }
    }

    /// A velocity observation (sorted by `t0`).
    pub fn push_obs(&mut self, o: VelocityObs) {
        self.steps.push_obs(o);
    }

    /// Runs every step that is now final (with `all_done`, every step left).
    pub fn poll(&mut self, all_done: bool, obs: &mut dyn RunObserver) -> Result<(), PipelineError> {
        let mut whole = Vec::new();
        if let Feed::Online { front, .. } = &mut self.feed {
            if all_done {
                front.finish();
            }
            if self.cal.is_none() {
                if let Some(started) = front.started() {
                    self.cal = Some(start_calibrator(&self.params, started, self.nominal)?);
                }
            }
            self.steps.set_wheel_offset(front.time_offset());
            let steps = &mut self.steps;
            front.drain(&mut |m| match m {
                Mounted::Observation(o) => steps.push_obs(o),
                Mounted::Step(s) => whole.push(s),
            });
        }
        let Some(cal) = self.cal.as_deref_mut() else {
            return Ok(());
        };
        let runner = &mut self.runner;
        let evidence = &mut self.evidence;
        let measured = &mut self.measured;
        let feed = &mut self.feed;
        let mut one = |s: CalibStep| {
            evidence.add(&s);
            *measured += usize::from(!s.measurements().is_empty());
            run_step(runner, cal, &s, feed, obs)
        };
        whole.into_iter().for_each(&mut one);
        self.steps.poll(all_done, &mut one);
        if all_done {
            if let (
                Feed::Online {
                    front, odometry, ..
                },
                Some(e),
            ) = (&mut self.feed, self.runner.last())
            {
                let mut pose = |t: f64, p: &Pose2| obs.calibrated_pose(t, p);
                odometry.advance(f64::INFINITY, front.time_offset(), &e.drive(), &mut pose);
            }
        }
        Ok(())
    }

    /// The run's results so far: the summary, the weight resets, the
    /// evidence and the detector's firings.
    pub fn run_summary(&self) -> Result<CalibRunSummary, PipelineError> {
        Ok(CalibRunSummary {
            summary: self.summary()?,
            weight_resets: self.weight_resets(),
            evidence: self.evidence().clone(),
            firings: self.runner.firings(),
        })
    }

    /// What the steps so far show of the excitation and the wiring.
    pub fn evidence(&self) -> &calib::Evidence {
        &self.evidence
    }

    /// What the front end used and found (`None` without one).
    pub fn online_report(&self) -> Option<calib::online::OnlineReport> {
        match &self.feed {
            Feed::Online { front, .. } => Some(front.report()),
            Feed::Direct => None,
        }
    }

    /// The summary after the steps so far; an error when no step carried a
    /// measurement (the filter would only return its prior), or the filters
    /// never started (no nominal values and no fit of the window).
    pub fn summary(&self) -> Result<CalibSummary, PipelineError> {
        if self.cal.is_none() {
            let why = self
                .online_report()
                .and_then(|r| r.solves.last().and_then(|s| s.refused.clone()))
                .unwrap_or_else(|| "too few intervals were matched".into());
            return Err(PipelineError::BadArgument(format!(
                "the filters never started: without nominal wheel radii and wheel base they \
                 start from a fit of the stream's first minutes, and none succeeded ({why}); \
                 give r_right, r_left and wheel_base in the robot file, or record more \
                 driving with turns both ways"
            )));
        }
        if self.measured == 0 {
            return Err(PipelineError::BadArgument(format!(
                "nothing to calibrate: {} filter steps, none with a measurement (no velocity \
                 observation overlaps the wheel data)",
                self.runner.steps()
            )));
        }
        let mut s = self.runner.summary();
        s.online = self.online_report();
        Ok(s)
    }

    /// Steps whose weights all underflowed and were reset.
    pub fn weight_resets(&self) -> usize {
        self.runner.weight_resets()
    }
}

/// The calibrator `params` names, started where the front end says: its
/// centre ± the search (relative) unless `[calib] ranges` is configured.
fn start_calibrator(
    params: &CalibParams,
    started: &Started,
    nominal: DiffDrive,
) -> Result<Box<dyn Calibrator + Send>, PipelineError> {
    let mut p = params.clone();
    if p.ranges.is_none() {
        let c = started.centre;
        p.ranges = Some(Ranges::around(
            c.r_right,
            c.r_left,
            c.wheel_base,
            started.search,
        ));
    }
    let shown = if nominal.r_right.is_finite() {
        nominal
    } else {
        started.centre
    };
    calib::build(&p, shown).map_err(|e| PipelineError::BadArgument(e.to_string()))
}

/// One filter step, its estimate and calibrated poses handed to the observer:
/// behind the online front end the wheel samples up to the step's end,
/// integrated at their own rate with the estimate after the step; fed
/// directly, the step's own increment.
fn run_step(
    runner: &mut Runner,
    cal: &mut (dyn Calibrator + Send),
    s: &CalibStep,
    feed: &mut Feed,
    obs: &mut dyn RunObserver,
) {
    let mut poses: [Option<(f64, crate::geom::Pose2)>; 2] = [None, None];
    let e = runner.step(cal, s, &mut |t, p| {
        let slot = if poses[0].is_none() { 0 } else { 1 };
        poses[slot] = Some((t, *p));
    });
    obs.step(&e, cal.cloud());
    match feed {
        Feed::Online {
            front, odometry, ..
        } => {
            if e.changed {
                front.changed_at(s.t1);
            }
            obs.front(s.t1, front.time_offset(), front.laser());
            let mut pose = |t: f64, p: &Pose2| obs.calibrated_pose(t, p);
            odometry.advance(s.t1, front.time_offset(), &e.drive(), &mut pose);
        }
        Feed::Direct => {
            for (t, p) in poses.into_iter().flatten() {
                obs.calibrated_pose(t, &p);
            }
        }
    }
}

/// Counts each stream's samples against the source's totals, to tell the
/// step builder when the wheel and gyro streams end.
struct Ends {
    wheels: usize,
    gyro: usize,
}

impl Ends {
    fn feed(&mut self, item: &Item, info: &StreamInfo, stage: &mut CalibStage) {
        match item {
            Item::Wheel(w) => {
                stage.push_wheel(*w);
                self.wheels += 1;
                if self.wheels == info.wheels {
                    stage.end_wheels();
                }
            }
            Item::Gyro(g) => {
                stage.push_gyro(*g);
                self.gyro += 1;
                if self.gyro == info.gyro {
                    stage.end_gyro();
                }
            }
            _ => {}
        }
    }
}

/// What a calibration gives besides what its observers saw.
#[derive(Debug, Clone)]
pub struct CalibRunSummary {
    /// The calibration summary (design.md's keys).
    pub summary: CalibSummary,
    /// Steps whose weights all underflowed and were reset.
    pub weight_resets: usize,
    /// The excitation and wiring the steps showed.
    pub evidence: calib::Evidence,
    /// Steps at which the change detector fired.
    pub firings: usize,
}

/// Runs ICP and the calibrator `calib` names over `source` and gives both
/// summaries: each motion goes through the online front end
/// ([`calib::online`]), which composes the motions into intervals, estimates
/// the time offset and checks the laser mounting on the stream, and starts
/// the calibrator after its warm-up; the observations are aligned with the
/// wheels (and gyro) into filter steps as soon as they are final. Without a
/// stated mounting the scans are matched in the laser's own frame and the
/// mounting is the front end's estimate.
pub fn run_calibration(
    source: &mut dyn SampleSource,
    robot: &RobotConfig,
    icp: &IcpParams,
    calib: &CalibParams,
    meas: &MeasurementConfig,
    obs: &mut dyn RunObserver,
) -> Result<(IcpRunSummary, CalibRunSummary), PipelineError> {
    let nominal = Some(robot.diff_drive());
    run_calibration_from(source, robot, nominal, icp, calib, meas, obs)
}

/// [`run_calibration`] with the nominal kinematics given apart: `None` for
/// a robot whose file states none (the filters then start from the front
/// end's closed-form fit; `robot`'s own values are not used).
pub fn run_calibration_from(
    source: &mut dyn SampleSource,
    robot: &RobotConfig,
    nominal: Option<DiffDrive>,
    icp: &IcpParams,
    calib: &CalibParams,
    meas: &MeasurementConfig,
    obs: &mut dyn RunObserver,
) -> Result<(IcpRunSummary, CalibRunSummary), PipelineError> {
    let info = source.info().clone();
    obs.start(&info);
    let mut icp_stage = IcpStage::new(&info, source.name(), robot, icp, true)?;
    if info.wheels < 2 {
        return Err(InputError::new(
            source.name(),
            format!(
                "no wheel encoder data to calibrate: {} wheel samples ([wheels] source and topic in \
                 the robot file name the stream; for JointState, left_joint and right_joint \
                 name the joints: '{}' and '{}'; `odocal inspect {}` proposes them)",
                info.wheels,
                robot.left_joint,
                robot.right_joint,
                source.name()
            ),
        )
        .into());
    }
    let stated = icp_stage.stated.then(|| {
        (
            geom::xyt(&icp_stage.mount.pose),
            icp_stage.mount.origin.as_str().to_string(),
        )
    });
    let mut stage = CalibStage::online(
        calib,
        nominal,
        stated,
        icp_stage.mount.pose,
        meas,
        info.gyro > 0,
    )?;
    if info.gyro == 0 {
        stage.end_gyro();
    }
    let mut ends = Ends { wheels: 0, gyro: 0 };
    while let Some(item) = source.next_item()? {
        obs.item(&item);
        ends.feed(&item, &info, &mut stage);
        icp_stage.feed(&item, &info, obs, &mut |m| stage.push_motion(m));
        if source.gyro_ended() {
            stage.end_gyro();
        }
        stage.poll(false, obs)?;
    }
    icp_stage.finish(obs, &mut |m| stage.push_motion(m));
    icp_stage.check_usable(source.name(), source.scan_topic())?;
    stage.end_wheels();
    stage.end_gyro();
    stage.poll(true, obs)?;
    let calibration = finish(&stage, source.name())?;
    Ok((icp_stage.summary(), calibration))
}

/// The stage's results; a failure names the input.
fn finish(stage: &CalibStage, input: &str) -> Result<CalibRunSummary, PipelineError> {
    stage.run_summary().map_err(|e| match e {
        PipelineError::BadArgument(m) => InputError::new(input, m).into(),
        other => other,
    })
}

/// Runs the calibrator over intervals of the laser's own displacement
/// with their wheel motion and no time (Censi et al.'s tuples) through the
/// online front end: one filter step per interval once the window's fit
/// gives the mounting (the tuples state none) and the residuals' σ's.
pub fn calibrate_intervals(
    intervals: Vec<calib::batch::Interval>,
    nominal: Option<DiffDrive>,
    stated: Option<(P3, String)>,
    calib: &CalibParams,
    input: &str,
    obs: &mut dyn RunObserver,
) -> Result<CalibRunSummary, PipelineError> {
    let meas = MeasurementConfig::default();
    let mut stage = CalibStage::online(calib, nominal, stated, Pose2::identity(), &meas, false)?;
    stage.end_gyro();
    stage.end_wheels();
    obs.start(&StreamInfo::default());
    for iv in intervals {
        stage.push_interval(iv);
        stage.poll(false, obs)?;
    }
    stage.poll(true, obs)?;
    finish(&stage, input)
}

/// Runs the calibrator over base-frame motions (a motions CSV: the laser's
/// frame is the base's, the mounting the identity) and wheel angles through
/// the online front end, as [`run_calibration`] does over a recording.
pub fn calibrate_motions(
    motions: &[Motion],
    wheels: &[WheelSample],
    nominal: Option<DiffDrive>,
    calib: &CalibParams,
    meas: &MeasurementConfig,
    obs: &mut dyn RunObserver,
) -> Result<CalibRunSummary, PipelineError> {
    let stated = Some(([0.0; 3], "motions_csv".to_string()));
    let mut stage = CalibStage::online(calib, nominal, stated, Pose2::identity(), meas, false)?;
    obs.start(&StreamInfo {
        wheels: wheels.len(),
        ..StreamInfo::default()
    });
    for w in wheels {
        obs.item(&Item::Wheel(*w));
        stage.push_wheel(*w);
    }
    stage.end_wheels();
    stage.end_gyro();
    for m in motions {
        stage.push_motion(m);
        stage.poll(false, obs)?;
    }
    stage.poll(true, obs)?;
    stage.run_summary()
}

/// Runs the calibrator `calib` names over given wheel angles, velocity
/// observations (sorted by `t0`) and gyro rates: the same stage as
/// [`run_calibration`] without the front end, fed whole streams, the
/// calibrator starting from `calib.ranges()`. The observer sees the wheel
/// and gyro samples as items, then the steps.
pub fn calibrate_streams(
    wheels: &[WheelSample],
    observations: &[VelocityObs],
    gyro: &[GyroSample],
    robot: &RobotConfig,
    calib: &CalibParams,
    meas: &MeasurementConfig,
    obs: &mut dyn RunObserver,
) -> Result<CalibRunSummary, PipelineError> {
    let mut stage = CalibStage::direct(calib, robot.diff_drive(), meas, !gyro.is_empty())?;
    obs.start(&StreamInfo {
        wheels: wheels.len(),
        gyro: gyro.len(),
        ..StreamInfo::default()
    });
    for w in wheels {
        obs.item(&Item::Wheel(*w));
        stage.push_wheel(*w);
    }
    stage.end_wheels();
    for g in gyro {
        obs.item(&Item::Gyro(*g));
        stage.push_gyro(*g);
    }
    stage.end_gyro();
    observations.iter().for_each(|o| stage.push_obs(*o));
    stage.poll(true, obs)?;
    stage.run_summary()
}
