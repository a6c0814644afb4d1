//! `odocal calibrate`: ICP velocity observations (+ gyro) and wheel angles into
//! a calibrator, then the history CSV, the calibrated trajectory and a summary.
//! A bag, another recording format, a recording in memory and CSV inputs all
//! go through the one driver ([`super::drive`]).

pub use super::calibrate_job::Start;
pub use super::calibrate_job::{CalibSource, CalibrateJob, CalibrateOutcome, CalibratorChoice};
use super::drive;
pub use super::drive::MeasurementConfig;
use super::observe::{NoObserver, Observers, RunObserver};
use super::outputs::{check_outputs, lock_outputs, CalibFiles, Collect};
use super::paste::Paste;
use super::recorder::{RecorderOptions, StreamRecorder};
use super::viewer::{open_logger, Viewer};
use super::PipelineError;
use crate::assumptions::Origin;
use crate::calib::{self, CalibParams, CalibSummary, CalibrationRun, Ranges};
use crate::error::InputError;
use crate::io::out_lock::OutputLock;
use crate::motion::VelocityObs;
use crate::recording::{GyroSample, WheelSample};
use crate::robot::{DiffDrive, RobotConfig, WheelSourceKind};
use std::path::{Path, PathBuf};

/// What a calibrator is fed: wheel angles, velocity observations, gyro.
#[derive(Debug, Clone, Default)]
pub struct CalibInput {
    /// Wheel angles (rad).
    pub wheels: Vec<WheelSample>,
    /// Velocity observations (ICP), each with its σ.
    pub observations: Vec<VelocityObs>,
    /// Gyro yaw rates (empty when unused).
    pub gyro: Vec<GyroSample>,
}

/// ICP motions in the base frame (a motions CSV) and the wheel angles to
/// read them against.
struct CsvInput {
    motions: Vec<crate::motion::Motion>,
    wheels: Vec<WheelSample>,
}

/// The calibrator settings for `robot` when the calibrator starts at once
/// (observations given, no online front end): the configured ones, except
/// that without configured ranges the filters search ± the front end's
/// `search_nominal` around the robot's nominal values.
pub fn params_for_robot(params: &CalibParams, robot: &RobotConfig) -> CalibParams {
    let mut p = params.clone();
    if p.ranges.is_none() {
        p.ranges = Some(Ranges::around(
            robot.r_right,
            robot.r_left,
            robot.wheel_base,
            p.online.search_nominal,
        ));
    }
    p
}

/// Runs the configured calibrator over given streams (in memory).
pub fn from_streams(
    input: &CalibInput,
    robot: &RobotConfig,
    params: &CalibParams,
    meas: &MeasurementConfig,
) -> Result<CalibrationRun, PipelineError> {
    from_streams_observed(input, robot, params, meas, &mut NoObserver)
}

/// Like [`from_streams`], the observer seeing every step.
pub fn from_streams_observed(
    input: &CalibInput,
    robot: &RobotConfig,
    params: &CalibParams,
    meas: &MeasurementConfig,
    obs: &mut dyn RunObserver,
) -> Result<CalibrationRun, PipelineError> {
    let params = params_for_robot(params, robot);
    let mut collect = Collect::default();
    let done = drive::calibrate_streams(
        &input.wheels,
        &input.observations,
        &input.gyro,
        robot,
        &params,
        meas,
        &mut Observers(vec![&mut collect, obs]),
    )?;
    Ok(collect.calibration(done.summary, done.weight_resets))
}

/// Runs `odocal calibrate`: ICP (for a recording) and the calibrator, the
/// history, trajectory and summary written into the output directory
/// atomically, the run recorded for Rerun when asked; `watch` sees the run.
/// With `--init batch` the filter starts from the batch estimate
/// ([`super::start`]).
pub fn run(
    job: &CalibrateJob,
    watch: &mut dyn RunObserver,
) -> Result<CalibrateOutcome, PipelineError> {
    run_on(job, None, watch)
}

/// A stream that is no file (a robot's live topics) as `odocal calibrate`'s
/// input, with where its wheels come from.
pub struct LiveInput<'s> {
    /// The samples; the run ends when the source does.
    pub source: &'s mut dyn crate::io::SampleSource,
    /// How the wheel angles were read from the stream, asked once it ends.
    pub wheels: Box<dyn FnOnce() -> crate::recording::WheelSource + 's>,
    /// Told each change as soon as it is named.
    pub on_named: Option<super::outputs::OnNamed>,
}

/// [`run`] over a live stream (`job.input` is [`CalibSource::Live`]): the
/// same ICP, online filters, change naming, vetting and outputs, written
/// when the source ends.
pub fn run_live(
    job: &CalibrateJob,
    input: LiveInput<'_>,
    watch: &mut dyn RunObserver,
) -> Result<CalibrateOutcome, PipelineError> {
    run_on(job, Some(input), watch)
}

fn run_on(
    job: &CalibrateJob,
    mut live: Option<LiveInput<'_>>,
    watch: &mut dyn RunObserver,
) -> Result<CalibrateOutcome, PipelineError> {
    let (mut cfg, nominal) = job.common.load_nominal_open()?;
    job.choice.apply(&mut cfg.calib);
    if cfg.calib.method == calib::Method::Batch {
        return super::batch::run(job, watch);
    }
    if nominal.kinematics().is_none() {
        from_scratch_allowed(job, &cfg.calib)?;
    }
    let _lock = check_job_outputs(job)?;
    let started = start(job, &cfg, &nominal)?;
    let robot = started.as_ref().map_or(&nominal.robot, |s| &s.robot);
    // The online front end starts the filters.
    let params = cfg.calib.clone();
    let mut logger = open_logger(job.viewer.as_ref())?;
    let mut recorder = logger.as_deref_mut().map(|l| {
        StreamRecorder::new(
            l,
            RecorderOptions::default(),
            robot.diff_drive(),
            robot
                .laser
                .map(|l| l.pose())
                .unwrap_or_else(crate::geom::Pose2::identity),
        )
    });
    let mut quiet = NoObserver;
    let rec_obs: &mut dyn RunObserver = match recorder.as_mut() {
        Some(r) => r,
        None => &mut quiet,
    };
    let mut files = CalibFiles::create(&job.out)?;
    if params.change.naming.enabled {
        files = files.naming_changes(robot, &params.change.naming);
    }
    if let Some(f) = live.as_mut().and_then(|l| l.on_named.take()) {
        files = files.telling(f);
    }
    let mut obs = Observers(vec![&mut files, rec_obs, watch]);
    let run = Run {
        cfg: &cfg,
        nominal: &nominal,
        robot,
        params: &params,
    };
    let (done, assumptions, input, wheel_source) = match live {
        Some(l) => run.live(job, l, &mut obs)?,
        None => run.input(job, started.as_ref(), &mut obs)?,
    };
    drop(obs);
    let mut summary = done.summary.clone();
    summary.assumptions = assumptions;
    vet(
        &mut summary,
        &done,
        nominal.kinematics(),
        &params,
        &input.display().to_string(),
    )?;
    if let Some(w) = wheel_source {
        super::wheels::state(&mut summary, w);
    }
    summary.changes = files.changes();
    if let Some(s) = started {
        summary.rebase(nominal.robot.diff_drive());
        summary.start = Some(s.est);
    }
    let controller = controller(&mut summary, &nominal);
    let paste = Paste::of(&summary, &controller, &input.display().to_string());
    files.commit(&paste.with(&summary))?;
    paste.write(&job.out)?;
    let notes = match recorder {
        Some(r) => finish_recording(r, &summary)?,
        None => Vec::new(),
    };
    Ok(CalibrateOutcome {
        summary,
        notes,
        paste,
    })
}

/// The Rerun recording's last entries (what changed at each firing, a
/// firing on a change already named saying so, at the first step at or
/// after its time: the step that fired for the filter's detector), then its
/// end; returns what it left out.
fn finish_recording(
    mut r: StreamRecorder,
    summary: &CalibSummary,
) -> Result<Vec<String>, PipelineError> {
    r.changes(&super::changes::entries(&summary.changes));
    r.finish().map_err(super::viewer::viz_error)
}

/// The controller the parameters are pasted into: the nominal robot's; or,
/// without nominal values, one told the calibrated ones (one wheel_radius,
/// the mean, the multipliers their ratio to it), `summary`'s multipliers
/// rebased on it.
fn controller(summary: &mut CalibSummary, nominal: &super::Nominal) -> RobotConfig {
    if nominal.kinematics().is_some() {
        return nominal.robot.clone();
    }
    let f = summary.final_params;
    let r = 0.5 * (f.r_right + f.r_left);
    summary.rebase(DiffDrive {
        r_right: r,
        r_left: r,
        wheel_base: f.wheel_base,
    });
    RobotConfig {
        r_right: r,
        r_left: r,
        wheel_base: f.wheel_base,
        ..nominal.robot.clone()
    }
}

/// Refuses what cannot run without nominal kinematics: `--method none`
/// (it keeps them) and `--init batch` (the batch starts from them).
fn from_scratch_allowed(job: &CalibrateJob, calib: &CalibParams) -> Result<(), PipelineError> {
    let file = job
        .common
        .robot
        .as_deref()
        .map_or(String::new(), |p| p.display().to_string());
    let why = if calib.method == calib::Method::None {
        "--method none keeps the nominal values"
    } else if matches!(job.init, Start::Batch) {
        "--init batch starts from the batch estimate, which starts from the nominal values"
    } else {
        return Ok(());
    };
    Err(InputError::new(
        file,
        format!(
            "{why}, and the robot file states none (r_right, r_left, wheel_base): state them, \
             or run an online method without --init, which starts from a closed-form fit of \
             the first minutes"
        ),
    )
    .into())
}

/// The batch start of `--init batch` (`None` for `--init nominal`).
fn start(
    job: &CalibrateJob,
    cfg: &super::Config,
    nominal: &super::Nominal,
) -> Result<Option<super::start::FromBatch>, PipelineError> {
    match (&job.init, &job.input) {
        (Start::Nominal, _) => Ok(None),
        (Start::Batch, CalibSource::Recording(path)) => Ok(Some(super::start::from_batch(
            path, cfg, nominal, &cfg.calib,
        )?)),
        (Start::Batch, CalibSource::Live { .. }) => Err(PipelineError::BadArgument(
            "--init batch fits a whole recording first; a live stream has none (the online \
             front end estimates the time offset and mounting on the stream)"
                .into(),
        )),
        (Start::Batch, CalibSource::Csv { .. }) => Err(PipelineError::BadArgument(
            "--init batch needs --input REC (the batch estimate reads the scans and wheels); \
             CSV motions carry no laser frame or wheel clock"
                .into(),
        )),
    }
}

/// What one calibration run over a recording uses.
struct Run<'a> {
    cfg: &'a super::Config,
    nominal: &'a super::Nominal,
    robot: &'a RobotConfig,
    params: &'a CalibParams,
}

/// What a run over the job's input gives: the calibration, the
/// assumptions, the input's path (to name in messages) and where the wheels
/// came from.
type Ran<'j> = (
    drive::CalibRunSummary,
    crate::assumptions::Assumptions,
    &'j Path,
    Option<crate::recording::WheelSource>,
);

impl Run<'_> {
    /// The kinematics the front end starts from: the robot's (the batch's
    /// with `--init batch`), `None` when the robot file states none.
    fn nominal_kinematics(&self) -> Option<DiffDrive> {
        self.nominal.kinematics().map(|_| self.robot.diff_drive())
    }

    /// The calibration of a live stream.
    fn live<'j>(
        &self,
        job: &'j CalibrateJob,
        input: LiveInput<'_>,
        obs: &mut dyn RunObserver,
    ) -> Result<Ran<'j>, PipelineError> {
        let CalibSource::Live { name } = &job.input else {
            return Err(PipelineError::BadArgument(
                "a live stream needs a job whose input is CalibSource::Live".into(),
            ));
        };
        let (done, a) = self.recording(input.source, obs)?;
        Ok((done, a, Path::new(name.as_str()), Some((input.wheels)())))
    }

    /// The calibration of the job's input, by its kind: a recording (from
    /// the batch start's shifted copy with `--init batch`), Censi's tuples,
    /// or CSV motions and wheels.
    fn input<'j>(
        &self,
        job: &'j CalibrateJob,
        started: Option<&super::start::FromBatch>,
        obs: &mut dyn RunObserver,
    ) -> Result<Ran<'j>, PipelineError> {
        Ok(match (&job.input, started) {
            (CalibSource::Recording(path), Some(s)) => {
                let mut source = crate::io::RecordingSource::new(&s.rec);
                let (done, mut a) = self.recording(&mut source, obs)?;
                super::start::state(&mut a, &s.est, &self.nominal.robot);
                (done, a, path, Some(s.wheels.clone()))
            }
            (CalibSource::Recording(path), None)
                if crate::io::sniff(path)? == crate::io::Format::CensiTuples =>
            {
                let (done, a) = self.tuples(path, obs)?;
                (done, a, path, None)
            }
            (CalibSource::Recording(path), None) => {
                let (done, a, wheels) = self.file(path, obs)?;
                (done, a, path, Some(wheels))
            }
            (CalibSource::Live { name }, _) => {
                return Err(PipelineError::BadArgument(format!(
                    "{name}: a live stream is calibrated by `odocal live`"
                )))
            }
            (CalibSource::Csv { motions, wheels }, _) => {
                let input = read_csv_input(motions, wheels, &self.cfg.icp)?;
                let done = drive::calibrate_motions(
                    &input.motions,
                    &input.wheels,
                    self.nominal_kinematics(),
                    self.params,
                    &self.cfg.measurements,
                    obs,
                )
                .map_err(|e| name_csv_inputs(e, motions, wheels))?;
                let mut a = self.nominal.assumptions();
                if let Some(o) = &done.summary.online {
                    state_online(&mut a, o);
                }
                (done, a, motions, None)
            }
        })
    }

    /// ICP and the calibrator over `source`; the nominal values' sources
    /// with the mounting the matcher used.
    fn recording(
        &self,
        source: &mut dyn crate::io::SampleSource,
        obs: &mut dyn RunObserver,
    ) -> Result<(drive::CalibRunSummary, crate::assumptions::Assumptions), PipelineError> {
        let info = source.info().clone();
        let (icp, done) = drive::run_calibration_from(
            source,
            self.robot,
            self.nominal_kinematics(),
            &self.nominal.icp_params(&self.cfg.icp, &info),
            self.params,
            &self.cfg.measurements,
            obs,
        )?;
        let mut a = calibration_assumptions(self.nominal, &icp, self.cfg.icp.prior, &info);
        if let Some(o) = &done.summary.online {
            state_online(&mut a, o);
        }
        Ok((done, a))
    }

    /// The filters over Censi et al.'s tuples: one step per tuple through
    /// the online front end, which estimates the laser mounting the tuples
    /// are measured in (the robot file's is checked against it).
    fn tuples(
        &self,
        path: &std::path::Path,
        obs: &mut dyn RunObserver,
    ) -> Result<(drive::CalibRunSummary, crate::assumptions::Assumptions), PipelineError> {
        let tuples = crate::io::censi::read(path)?;
        let problem = super::batch::tuples_problem(&tuples);
        let stated = self
            .robot
            .laser
            .map(|l| ([l.x, l.y, l.yaw], Origin::RobotFile.as_str().to_string()));
        let done = drive::calibrate_intervals(
            problem.intervals,
            self.nominal_kinematics(),
            stated,
            self.params,
            &path.display().to_string(),
            obs,
        )?;
        let mut a = self.nominal.assumptions();
        if let Some(o) = &done.summary.online {
            state_online(&mut a, o);
        }
        a.set(
            "time_offset",
            0.0,
            Origin::Recording,
            Some(
                "the tuples pair each laser displacement with the wheel rates of its own \
                  interval (already synchronised); they carry no time to estimate an offset \
                  from"
                    .into(),
            ),
        );
        Ok((done, a))
    }

    /// [`Self::recording`] over the file at `path`, once its wheel stream
    /// is known to be there; also where the wheels came from.
    fn file(
        &self,
        path: &std::path::Path,
        obs: &mut dyn RunObserver,
    ) -> Result<
        (
            drive::CalibRunSummary,
            crate::assumptions::Assumptions,
            crate::recording::WheelSource,
        ),
        PipelineError,
    > {
        let configured = super::read_options(self.cfg, self.robot);
        // Declared before the source that may borrow it.
        let only;
        let mut source = crate::io::open(path, &configured)?;
        let mut info = source.info().clone();
        let mut found = super::wheels::Found {
            wheels: info.wheels,
            odom: info.odom,
            bag: crate::io::sniff(path)? != crate::io::Format::Text,
        };
        only = super::wheels::only_source(&configured, self.nominal, found);
        if let Some(r) = &only {
            source = crate::io::open(path, r)?;
            info = source.info().clone();
            found.wheels = info.wheels;
        }
        let read = only.as_ref().unwrap_or(&configured);
        super::wheels::require(read, self.nominal, &path.display().to_string(), found)?;
        if read.wheels.source == WheelSourceKind::Odometry && self.nominal.kinematics().is_none() {
            return Err(InputError::new(
                path.display().to_string(),
                "the wheels come from the robot's own odometry, whose twist is turned back \
                 into wheel rates with the controller's configured radii and separation: \
                 state them as r_right, r_left and wheel_base in the robot file",
            )
            .topic(read.wheel_topic())
            .into());
        }
        let (done, a) = self.recording(source.as_mut(), obs)?;
        let wheels = super::wheels::describe(read, self.nominal, info.wheels, info.wheel_values);
        Ok((done, a, wheels))
    }
}

/// What a calibration over a recording with `info`'s streams assumed: the
/// nominal robot (the wheel keys its wheel samples use), the laser mounting
/// and prior its scan matching took (`icp`; the prior from `[icp] prior` =
/// `given`), and the wheels' clock.
pub(super) fn calibration_assumptions(
    nominal: &super::Nominal,
    icp: &drive::IcpRunSummary,
    given: crate::icp::PriorChoice,
    info: &crate::io::StreamInfo,
) -> crate::assumptions::Assumptions {
    let mut a = nominal.assumptions_with(&icp.mount);
    nominal.drop_unused_wheel_keys(&mut a, info.wheel_values);
    nominal.state_prior(&mut a, &icp.prior, given, info.wheels);
    state_clock(&mut a, icp.stats.prior_time_offset.as_ref(), &icp.prior);
    a
}

/// States that the filters pair the scans' motions with the wheel rates of
/// the same stamps (`time_offset` = 0, default), with what the scan
/// matcher's clock check found when it checked the wheels (their odometry
/// was its prior); `--init batch` replaces it with its estimate.
fn state_clock(
    a: &mut crate::assumptions::Assumptions,
    fit: Option<&crate::icp::TimeOffsetFit>,
    prior: &crate::icp::Prior,
) {
    let fit = fit.filter(|_| matches!(prior, crate::icp::Prior::Wheels(_)));
    let note = match (fit, prior) {
        (None, crate::icp::Prior::Wheels(_)) => "wheel and laser stamps of one instant taken as \
                 equal (too few matched pairs to check)"
            .to_string(),
        (None, _) => "wheel and laser stamps of one instant taken as equal; not checked: the \
                 scan matcher's prior, whose clock the check compares with the scans', is not \
                 the wheels (--init batch estimates the offset)"
            .to_string(),
        // The check compares its best with the prior's offset, which is then
        // not the filters' 0: say both rather than judge against the wrong one.
        (Some(f), _) if f.used_s != 0.0 => format!(
            "wheel and laser stamps of one instant taken as equal by the filters; the scan \
             matcher's prior was read at [icp] time_offset = {:+.3} s, and the odometry's turns \
             fit the scans' best at {:+.3} s; --init batch estimates the offset and moves the \
             wheel stamps by it",
            f.used_s, f.best_s
        ),
        (Some(f), _) if f.contradicts_used() => format!(
            "wheel and laser stamps of one instant taken as equal, but the odometry's turns fit \
             the scans' best at {:+.3} s (heading increments {:.4} rad RMS per pair there, {:.4} \
             at 0): the filters compare the scans' speeds with wheel rates of another instant; \
             --init batch estimates the offset and moves the wheel stamps by it",
            f.best_s, f.rms_best_rad, f.rms_used_rad
        ),
        (Some(f), _) => format!(
            "wheel and laser stamps of one instant taken as equal; the odometry's turns agree \
             (best fit at {:+.3} s)",
            f.best_s
        ),
    };
    a.set(
        "time_offset",
        0.0,
        crate::assumptions::Origin::Default,
        Some(note),
    );
}

/// The particle filters' search ranges in a run: as configured, else where
/// the online front end started them.
fn summary_ranges(summary: &CalibSummary, params: &CalibParams) -> [[f64; 2]; 3] {
    let started = summary.online.as_ref().and_then(|o| o.warmup.as_ref());
    match (&params.ranges, started) {
        (Some(r), _) => r.all(),
        (None, Some(w)) => {
            let c = w.centre;
            Ranges::around(c.r_right, c.r_left, c.wheel_base, w.search).all()
        }
        (None, None) => params.ranges().all(),
    }
}

/// States what the online front end used: the time offset it estimated
/// (with its std and when it settled), the laser mounting (estimated, or the
/// stated one with what the data said of it) and where the filters started.
fn state_online(a: &mut crate::assumptions::Assumptions, o: &calib::online::OnlineReport) {
    let t = &o.time_offset;
    if t.source == "estimated" {
        let settled = t
            .converged_s
            .map_or("not settled by the end".to_string(), |s| {
                format!("settled at {s:.1} s")
            });
        a.set(
            "time_offset",
            t.value,
            Origin::Estimated,
            Some(format!(
                "± {:.4} s, wheel stamp minus laser stamp of one instant, estimated on the \
                 stream by the joint fit of a sliding window ({} fits; {settled}); every \
                 observation is read against the wheels at the offset in use then",
                t.std,
                o.solves.len()
            )),
        );
    }
    let l = &o.laser;
    let mount = crate::robot::LaserMount {
        x: l.x.value,
        y: l.y.value,
        yaw: l.yaw.value,
    };
    if l.source == "estimated" {
        let note = l.check.clone().unwrap_or_else(|| {
            format!(
                "stated nowhere: estimated on the stream (± {:.4} m, {:.4} m, {:.4} rad)",
                l.x.std, l.y.std, l.yaw.std
            )
        });
        a.set("laser", mount, Origin::Estimated, Some(note));
    } else if let (Some(check), Some(prev)) = (&l.check, a.0.get("laser").cloned()) {
        a.set("laser", mount, prev.source, Some(check.clone()));
    }
    if let Some(w) = &o.warmup {
        let note = match w.from {
            "warm-up" => format!(
                "the filters started at {:.1} s from the window's estimate, searching ± {:.0} % \
                 around it",
                w.t,
                100.0 * w.search
            ),
            _ => format!(
                "no fit of the window succeeded by {:.1} s: the filters started from the nominal \
                 values, searching ± {:.0} % around them",
                w.t,
                100.0 * w.search
            ),
        };
        let origin = if w.from == "warm-up" {
            Origin::Estimated
        } else {
            Origin::RobotFile
        };
        a.set("start", w.centre, origin, Some(note));
    }
}

/// Before a calibration is reported: the encoders' wiring, the parameters'
/// observability (weak ones get a widened std) and the estimate's
/// plausibility. What the data cannot support is an error naming `input`.
fn vet(
    summary: &mut CalibSummary,
    done: &drive::CalibRunSummary,
    nominal: Option<DiffDrive>,
    params: &CalibParams,
    input: &str,
) -> Result<(), PipelineError> {
    let evidence = &done.evidence;
    let refuse = |m: String| -> PipelineError { InputError::new(input, m).into() };
    if let Some(fault) = evidence.wiring().fault() {
        return Err(refuse(format!("wheel encoders wired wrongly: {fault}")));
    }
    if params.method == calib::Method::None {
        return Ok(());
    }
    // Without nominal values the estimate sets the scale, and no estimate
    // is judged against a nominal one (only against its search range).
    let nominal = nominal.unwrap_or(summary.final_params);
    let o = calib::observability(
        evidence,
        &summary.std,
        &nominal,
        &params.checks,
        done.firings > 0,
    );
    let missing = o.unobservable();
    if !missing.is_empty() {
        return Err(refuse(format!(
            "the recording's motion cannot determine every parameter ({}); record a drive \
             with straight runs and turns both ways",
            missing.join("; ")
        )));
    }
    let pf = matches!(params.method, calib::Method::AdaptivePf | calib::Method::Pf);
    let ranges = pf.then(|| summary_ranges(summary, params));
    if let Some(m) = calib::implausible(&summary.final_params, &nominal, ranges, &params.checks) {
        let whose = match summary.assumptions.source("wheel_base") {
            Some(crate::assumptions::Origin::Default) => {
                " (the nominal values are the wheelchair's: give --robot ROBOT.toml)"
            }
            _ => "",
        };
        return Err(refuse(format!("calibration refused: {m}{whose}")));
    }
    summary.std.r_right = o.parameters["r_right"].std;
    summary.std.r_left = o.parameters["r_left"].std;
    summary.std.wheel_base = o.parameters["wheel_base"].std;
    summary.observability = Some(o);
    Ok(())
}

/// `odocal calibrate`'s outputs against its inputs ([`check_outputs`]),
/// then locked for the run ([`lock_outputs`]: the directory and the `.rrd`).
fn check_job_outputs(job: &CalibrateJob) -> Result<Vec<OutputLock>, PipelineError> {
    let inputs: Vec<&Path> = match &job.input {
        CalibSource::Recording(p) => vec![p],
        CalibSource::Csv { motions, wheels } => vec![motions, wheels],
        CalibSource::Live { .. } => Vec::new(),
    };
    let mut files = CalibFiles::paths(&job.out).to_vec();
    files.extend(Paste::paths(&job.out, false));
    let mut outputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    if let Some(Viewer::File(rrd)) = &job.viewer {
        outputs.push(rrd);
    }
    check_outputs(&inputs, &outputs)?;
    let mut sets = vec![job.out.as_path()];
    if let Some(Viewer::File(rrd)) = &job.viewer {
        sets.push(rrd);
    }
    lock_outputs(&sets)
}

/// A calibration from CSV files that found nothing to calibrate names both
/// files (the motions and the wheels did not overlap in time).
fn name_csv_inputs(e: PipelineError, motions: &Path, wheels: &Path) -> PipelineError {
    match e {
        PipelineError::BadArgument(m) => {
            InputError::new(format!("{} and {}", motions.display(), wheels.display()), m).into()
        }
        other => other,
    }
}

/// The calibration input of the CSV files: the motions (base frame) and the
/// wheel angles; at least two wheel samples and one valid motion (without
/// any, the filters would only return their prior).
fn read_csv_input(
    motions_csv: &Path,
    wheels: &Path,
    icp: &crate::icp::IcpParams,
) -> Result<CsvInput, PipelineError> {
    let motions = crate::io::csv::read_motions_numbered(motions_csv)?;
    super::sense::check_motions(motions_csv, &motions, icp)?;
    let input = CsvInput {
        wheels: crate::io::csv::read_wheels(wheels)?,
        motions: motions.into_iter().map(|(_, m)| m).collect(),
    };
    if input.wheels.len() < 2 {
        return Err(InputError::new(
            wheels.display().to_string(),
            format!(
                "{} wheel samples: calibration needs at least 2",
                input.wheels.len()
            ),
        )
        .into());
    }
    if !input
        .motions
        .iter()
        .any(|m| VelocityObs::from_motion(m).is_some())
    {
        return Err(InputError::new(
            motions_csv.display().to_string(),
            format!(
                "no velocity observation to calibrate from: {} motions, none valid \
                 (failed pairs give none)",
                input.motions.len()
            ),
        )
        .into());
    }
    Ok(input)
}
