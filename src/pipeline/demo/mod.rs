//! `odocal demo`: the whole pipeline on one recording — ICP, every calibrator,
//! evaluation against the recording's reference — into a directory with a
//! report, plots, trajectories and a Rerun recording.

pub mod bundled;
mod figures;
mod report;

use crate::calib::{CalibrationRun, Method};
use crate::error::InputError;
use crate::eval::{self, Alignment, EvalOptions, Trajectory3, TrajectoryMetrics};
use crate::geom::Pose2;
use crate::io::{RecordingSource, SampleSource};
use crate::pipeline::calibrate;
use crate::pipeline::drive;
use crate::pipeline::icp::IcpOutput;
use crate::pipeline::observe::Observers;
use crate::pipeline::outputs::{check_outputs, CalibFiles, Collect, IcpFiles};
use crate::pipeline::recorder::{RecorderOptions, StreamRecorder};
use crate::pipeline::viewer::{open_logger, Viewer};
use crate::pipeline::{Common, Config, Nominal, PipelineError};
use crate::recording::Recording;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::sim::Truth;
use crate::traj::Trajectory;
use crate::viz::{Logger, NullLogger};
use nalgebra::Point2;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Methods the demo runs, the proposed one first.
pub const DEMO_METHODS: [Method; 5] = [
    Method::AdaptivePf,
    Method::Dkf,
    Method::Akf,
    Method::Pf,
    Method::None,
];

/// One calibrator's figures in the demo.
#[derive(Debug, Clone, Serialize)]
pub struct MethodResult {
    /// Method name.
    pub method: String,
    /// Final `[R_R, R_L, D]` (m).
    pub final_params: [f64; 3],
    /// Final errors against the truth `[R_R, R_L, D]` (m), when a truth file is given.
    pub final_errors: Option<[f64; 3]>,
    /// Whether the method estimates the parameters (`none` keeps its prior:
    /// no convergence is reported for it).
    pub estimates: bool,
    /// First time (s from start) after which both radii stay within 0.5 % of
    /// the truth; `None` when they never settle, without a truth, or for a
    /// method that does not estimate.
    pub convergence_s: Option<f64>,
    /// Mean time per filter step (ms).
    pub mean_iteration_ms: f64,
    /// The calibrated odometry against the reference (origin-aligned): each
    /// step integrated with the estimate after that step, as online.
    pub eval: Option<TrajectoryMetrics>,
    /// The wheel odometry of the whole recording dead-reckoned with the
    /// method's final parameters, against the reference: what the
    /// calibration is worth afterwards.
    pub eval_final: Option<TrajectoryMetrics>,
    /// The wheel odometry over 10 s windows, each dead-reckoned with the
    /// estimate in effect at its start, against the reference's motion over
    /// the window: the odometry a robot runs on while it calibrates (none
    /// against a reference without headings, or for `none`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub windowed: Option<eval::WindowedError>,
}

/// What `odocal demo` prints with `--json` and writes as `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct DemoSummary {
    /// The recording.
    pub input: String,
    /// Laser scans in the recording.
    pub scans: usize,
    /// Recording length (s).
    pub duration_s: f64,
    /// ICP summary.
    pub icp: crate::icp::IcpStats,
    /// ICP trajectory against the reference.
    pub icp_eval: Option<TrajectoryMetrics>,
    /// Raw (nominal) wheel odometry against the reference.
    pub raw_odometry_eval: Option<TrajectoryMetrics>,
    /// Every calibrator.
    pub methods: Vec<MethodResult>,
    /// What changed at each firing of the proposed filter's change
    /// detector (or the laser-mounting watch), named as `calibrate` names it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub changes: Vec<crate::diagnose::onset::NamedChange>,
    /// Where each nominal value came from, the laser mounting and the scan
    /// matcher's prior among them (as `calibrate` states them).
    pub assumptions: crate::assumptions::Assumptions,
    /// Why a trajectory has no figures against the reference (no reference
    /// in the recording, or an evaluation that could not be made).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eval_notes: Vec<String>,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
}

/// Inputs of a demo run.
pub struct DemoInput<'a> {
    /// The recording, already read.
    pub recording: &'a Recording,
    /// Its file name, for the report.
    pub name: &'a str,
    /// The simulator's truth, when the recording is simulated.
    pub truth: Option<&'a Truth>,
    /// Nominal robot, with where each value came from.
    pub nominal: &'a Nominal,
    /// Stage settings.
    pub config: &'a Config,
}

/// The recording's reference for evaluation, and whether it has positions
/// only (PointStamped, or orientations that carry nothing).
pub(super) struct DemoReference {
    /// The planar reference.
    pub(super) traj: Trajectory,
    /// The same in 3D.
    traj3: Trajectory3,
    /// No orientation.
    position_only: bool,
}

impl DemoReference {
    fn of(rec: &Recording) -> Option<Self> {
        if rec.reference.len() < 2 {
            return None;
        }
        let traj = eval::trajectory_from_stamped(&rec.reference).0;
        let traj3 = Trajectory3::from_2d(&traj);
        let position_only =
            rec.reference.iter().any(|s| !s.has_heading) || traj3.orientation_undefined();
        Some(Self {
            traj,
            traj3,
            position_only,
        })
    }
}

/// Origin alignment of `est` onto the reference, as the table's.
fn origin_options(reference: &DemoReference) -> EvalOptions {
    EvalOptions {
        align: Alignment::Origin,
        position_only: reference.position_only,
        ..Default::default()
    }
}

/// `world_from_estimate` for the plots: the estimate's first pose on the
/// reference's; against a position-only reference the origin alignment of
/// the table (first position, heading of the first metre), since its poses
/// carry no heading.
pub(super) fn plot_anchor(est: &Trajectory, reference: &DemoReference) -> Pose2 {
    if reference.position_only {
        let fitted = eval::report::against_reference(
            &Trajectory3::from_2d(est),
            &reference.traj3,
            &origin_options(reference),
        );
        if let Ok((_, d)) = fitted {
            let iso = d.transform.isometry;
            let v = iso.translation.vector;
            return crate::geom::pose(v.x, v.y, iso.rotation.euler_angles().2);
        }
    }
    crate::pipeline::recorder::anchor(est, Some(&reference.traj))
}

/// `est` against the reference with origin alignment (the heading of the
/// reference's first metre for a position-only one); a failure goes to
/// `notes` under `name` rather than vanishing.
fn origin_eval(
    name: &str,
    est: &Trajectory,
    reference: Option<&DemoReference>,
    notes: &mut Vec<String>,
) -> Option<TrajectoryMetrics> {
    let reference = reference?;
    let opts = origin_options(reference);
    match eval::report::against_reference(&Trajectory3::from_2d(est), &reference.traj3, &opts) {
        Ok((m, _)) => Some(m),
        Err(e) => {
            notes.push(format!("{name}: not evaluated against the reference: {e}"));
            None
        }
    }
}

/// The windowed odometry error of `run` over `wheels` against `reference`
/// (10 s windows from the first estimate on).
fn windowed(
    run: &CalibrationRun,
    wheels: &[crate::recording::WheelSample],
    reference: &Trajectory,
) -> Option<eval::WindowedError> {
    let increments: Vec<eval::WheelIncrement> = wheels
        .windows(2)
        .map(|w| eval::WheelIncrement {
            t0: w[0].stamp,
            t1: w[1].stamp,
            d_right: w[1].right - w[0].right,
            d_left: w[1].left - w[0].left,
        })
        .collect();
    let estimates: Vec<(f64, DiffDrive)> = run
        .history
        .iter()
        .map(|h| {
            let k = DiffDrive {
                r_right: h.r_right,
                r_left: h.r_left,
                wheel_base: h.wheel_base,
            };
            (h.t, k)
        })
        .collect();
    eval::windowed_error(&increments, &estimates, &|t| reference.pose_at(t), 10.0)
}

fn convergence(run: &CalibrationRun, truth: &Truth, t_start: f64) -> Option<f64> {
    let mut settled: Option<f64> = None;
    for h in &run.history {
        let p = truth.parameters_at(h.t - t_start)?;
        let ok = ((h.r_right - p.r_right) / p.r_right).abs() < 0.005
            && ((h.r_left - p.r_left) / p.r_left).abs() < 0.005;
        match (ok, settled) {
            (true, None) => settled = Some(h.t - t_start),
            (false, _) => settled = None,
            _ => {}
        }
    }
    settled
}

pub(super) fn xy(poses: &[Pose2]) -> Vec<[f64; 2]> {
    poses
        .iter()
        .map(|p| [p.translation.x, p.translation.y])
        .collect()
}

pub(super) fn viz_err(e: crate::viz::VizError) -> PipelineError {
    PipelineError::Write {
        path: "visualisation".into(),
        message: e.to_string(),
    }
}

/// What `odocal demo` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct DemoJob {
    /// The output directory.
    pub out: PathBuf,
    /// Another recording instead of the bundled one.
    pub input: Option<PathBuf>,
    /// The simulator's truth file of the recording (with the bundled
    /// recording, its own truth file by default).
    pub truth: Option<PathBuf>,
    /// A running or spawned Rerun viewer instead of `OUT/demo.rrd`.
    pub viewer: Option<Viewer>,
    /// Configuration and robot files.
    pub common: Common,
}

/// Runs `odocal demo`: reads the recording (the bundled one, from memory,
/// by default) and its truth, runs everything into `job.out` and records it
/// for Rerun (`OUT/demo.rrd` unless a viewer is named; nothing without the
/// `rerun` feature). `progress` receives the stage name and the fraction done.
pub fn run(
    job: &DemoJob,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<DemoSummary, PipelineError> {
    let (cfg, nominal) = job.common.load_nominal()?;
    let robot = &nominal.robot;
    let inputs: Vec<&Path> = job
        .input
        .iter()
        .chain(&job.truth)
        .map(PathBuf::as_path)
        .collect();
    let outputs = output_files(&job.out);
    let outputs: Vec<&Path> = outputs.iter().map(PathBuf::as_path).collect();
    check_outputs(&inputs, &outputs)?;
    let _lock = crate::pipeline::outputs::lock_outputs(&[&job.out])?;
    let truth = match (&job.truth, &job.input) {
        (Some(p), _) => Some(load_truth(p)?),
        (None, None) => Some(
            Truth::from_json(bundled::TRUTH)
                .map_err(|e| InputError::new("bundled truth", e.to_string()))?,
        ),
        (None, Some(_)) => None,
    };
    let (rec, name) = match &job.input {
        Some(p) => (
            crate::pipeline::read_recording(p, &cfg, robot)?,
            p.display().to_string(),
        ),
        None => {
            let read = crate::pipeline::read_options(&cfg, robot);
            let rec =
                crate::io::read_mcap_bytes(bundled::RECORDING, bundled::RECORDING_NAME, &read)?;
            (rec, bundled::RECORDING_NAME.to_string())
        }
    };
    if let (Some(t), Some(p)) = (&truth, &job.truth) {
        crate::pipeline::sense::check_truth(p, t, Path::new(&name), &rec)?;
    }
    std::fs::create_dir_all(&job.out).map_err(|e| PipelineError::write(&job.out, e))?;
    let viewer = job
        .viewer
        .clone()
        .or_else(|| cfg!(feature = "rerun").then(|| Viewer::File(job.out.join("demo.rrd"))));
    let mut logger = open_logger(viewer.as_ref())?.unwrap_or_else(|| Box::new(NullLogger));
    let demo = DemoInput {
        recording: &rec,
        name: &name,
        truth: truth.as_ref(),
        nominal: &nominal,
        config: &cfg,
    };
    run_on(&demo, &job.out, logger.as_mut(), progress)
}

/// Every file the demo writes into `out`.
fn output_files(out: &Path) -> Vec<PathBuf> {
    let top = [
        "report.md",
        "summary.json",
        "icp.tum",
        "motions.csv",
        "raw_odometry.tum",
        "radii.png",
        "particles.png",
        "trajectories.png",
        "errors.png",
        "demo.rrd",
    ];
    let methods = DEMO_METHODS
        .iter()
        .flat_map(|m| CalibFiles::paths(&out.join(m.as_str())));
    top.iter().map(|f| out.join(f)).chain(methods).collect()
}

/// Reads a simulator truth file.
pub fn load_truth(path: &Path) -> Result<Truth, PipelineError> {
    let name = path.display().to_string();
    let file = std::fs::File::open(path)
        .map_err(|e| InputError::new(&name, format!("cannot read: {e}")))?;
    let truth = Truth::from_reader(std::io::BufReader::new(file));
    Ok(truth.map_err(|e| InputError::new(&name, e.to_string()))?)
}

/// Runs the demo on a recording in memory into `out` (created), logging to
/// `logger`; `progress` receives the stage name and the fraction done.
pub fn run_on(
    input: &DemoInput<'_>,
    out: &Path,
    logger: &mut dyn Logger,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<DemoSummary, PipelineError> {
    let start = std::time::Instant::now();
    let rec = input.recording;
    std::fs::create_dir_all(out).map_err(|e| PipelineError::write(out, e))?;
    let t_start = rec.time_span().map(|s| s.0).unwrap_or(0.0);
    if let Some(t) = input.truth {
        log_walls(&t.walls, logger)?;
    }
    let Calibrated {
        icp: icp_out,
        runs,
        assumptions,
    } = calibrate_all(input, out, logger, progress)?;
    progress("report", 1.0);
    let reference = DemoReference::of(rec);
    let mut notes = Vec::new();
    if reference.is_none() {
        notes.push(format!(
            "the recording has no reference trajectory (topic {}): no accuracy figures",
            input.config.topics.reference
        ));
    }
    let r = reference.as_ref();
    let raw = wheel_odometry(
        &input.nominal.robot.diff_drive(),
        &rec.wheels,
        Pose2::identity(),
    );
    let raw_path = out.join("raw_odometry.tum");
    crate::io::tum::write_tum_2d(&raw_path, &raw)
        .map_err(|e| PipelineError::write(&raw_path, e))?;
    let mut summary = DemoSummary {
        input: input.name.to_string(),
        scans: rec.scans.len(),
        duration_s: rec.time_span().map(|(a, b)| b - a).unwrap_or(0.0),
        icp: icp_out.stats.clone(),
        icp_eval: origin_eval("ICP", &icp_out.trajectory, r, &mut notes),
        raw_odometry_eval: origin_eval("raw odometry", &raw, r, &mut notes),
        methods: method_results(input, &runs, r, t_start, &mut notes),
        changes: runs[0].1.summary.changes.clone(),
        assumptions,
        eval_notes: Vec::new(),
        wall_s: 0.0,
    };
    summary.eval_notes = notes;
    figures::plots(input, &icp_out.trajectory, &raw, &runs, r, t_start, out)?;
    summary.wall_s = start.elapsed().as_secs_f64();
    report::report(input, &summary, out)?;
    let js = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).expect("summary serialises");
    crate::io::atomic::write_bytes_atomic(&js, text.as_bytes())
        .map_err(|e| PipelineError::write(&js, e))?;
    Ok(summary)
}

/// The simulated world's walls `[x0, y0, x1, y1]` (m) as the map entity.
fn log_walls(walls: &[[f64; 4]], logger: &mut dyn Logger) -> Result<(), PipelineError> {
    let segs: Vec<[Point2<f64>; 2]> = walls
        .iter()
        .map(|w| [Point2::new(w[0], w[1]), Point2::new(w[2], w[3])])
        .collect();
    logger.map(&segs).map_err(viz_err)
}

/// What [`calibrate_all`] gives: ICP's output, each method's run, and the
/// run's assumptions.
struct Calibrated {
    icp: IcpOutput,
    runs: Vec<(Method, CalibrationRun)>,
    assumptions: crate::assumptions::Assumptions,
}

/// ICP and the proposed filter in one pass through the driver, recorded for
/// the viewer (scans, ICP, particle clouds, trajectories), then every other
/// calibrator on the same observations; each method's files in `OUT/METHOD/`,
/// ICP's in `OUT/icp.tum` and `OUT/motions.csv`. Also the run's assumptions.
fn calibrate_all(
    input: &DemoInput<'_>,
    out: &Path,
    logger: &mut dyn Logger,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Calibrated, PipelineError> {
    let (rec, robot, cfg) = (input.recording, &input.nominal.robot, input.config);
    progress("icp", 0.0);
    // As `calibrate` runs them: the online front end sets each filter's
    // start and search.
    let params_for = |m: Method| {
        let mut p = cfg.calib.clone();
        p.method = m;
        p
    };
    let mut recorder = StreamRecorder::new(
        logger,
        RecorderOptions::default(),
        robot.diff_drive(),
        robot
            .laser
            .map(|l| l.pose())
            .unwrap_or_else(crate::geom::Pose2::identity),
    );
    let mut collect = Collect::default();
    let mut icp_files = IcpFiles::create(&out.join("icp.tum"), Some(&out.join("motions.csv")))?;
    let first = DEMO_METHODS[0];
    let first_params = params_for(first);
    let mut files = CalibFiles::create(&out.join(first.as_str()))?;
    if first_params.change.naming.enabled {
        files = files.naming_changes(robot, &first_params.change.naming);
    }
    let mut source = RecordingSource::new(rec);
    let icp_params = input.nominal.icp_params(&cfg.icp, source.info());
    let (icp_done, mut done) = drive::run_calibration(
        &mut source,
        robot,
        &icp_params,
        &first_params,
        &cfg.measurements,
        &mut Observers(vec![
            &mut collect,
            &mut recorder,
            &mut icp_files,
            &mut files,
        ]),
    )?;
    done.summary.changes = files.changes();
    icp_files.commit()?;
    files.commit(&done.summary)?;
    recorder.changes(&super::changes::entries(&done.summary.changes));
    recorder.finish().map_err(viz_err)?;
    let info = crate::io::StreamInfo::of(rec);
    let assumptions =
        calibrate::calibration_assumptions(input.nominal, &icp_done, cfg.icp.prior, &info);
    let icp_out = collect.icp(icp_done.stats);
    let mut runs = vec![(first, collect.calibration(done.summary, done.weight_resets))];
    // Every other method through the same driver (ICP and the online front
    // end), so that each figure is what `calibrate --method M` gives.
    for (i, m) in DEMO_METHODS.iter().enumerate().skip(1) {
        progress(m.as_str(), i as f64 / DEMO_METHODS.len() as f64);
        let mut files = CalibFiles::create(&out.join(m.as_str()))?;
        let mut collect = Collect::default();
        let mut source = RecordingSource::new(rec);
        let (_, done) = drive::run_calibration(
            &mut source,
            robot,
            &icp_params,
            &params_for(*m),
            &cfg.measurements,
            &mut Observers(vec![&mut collect, &mut files]),
        )?;
        files.commit(&done.summary)?;
        runs.push((*m, collect.calibration(done.summary, done.weight_resets)));
    }
    Ok(Calibrated {
        icp: icp_out,
        runs,
        assumptions,
    })
}

/// Each calibrator's figures: final parameters, errors and convergence
/// against the truth, and its trajectory against the reference.
fn method_results(
    input: &DemoInput<'_>,
    runs: &[(Method, CalibrationRun)],
    reference: Option<&DemoReference>,
    t_start: f64,
    notes: &mut Vec<String>,
) -> Vec<MethodResult> {
    let truth_end = input.truth.and_then(|t| {
        t.parameters
            .last()
            .map(|p| [p.r_right, p.r_left, p.wheel_base])
    });
    // One set of final parameters cannot describe a run whose true
    // parameters change: that column is left out then, and says why.
    let changing = input.truth.is_some_and(|t| {
        t.parameters.windows(2).any(|w| {
            (w[0].r_right, w[0].r_left, w[0].wheel_base)
                != (w[1].r_right, w[1].r_left, w[1].wheel_base)
        })
    });
    if changing {
        notes.push(
            "the true parameters change during the recording, so no single set of final \
             parameters describes it: no odometry with the final parameters"
                .into(),
        );
    }
    runs.iter()
        .map(|(m, run)| {
            let f = &run.summary.final_params;
            let final_params = [f.r_right, f.r_left, f.wheel_base];
            let estimates = *m != Method::None;
            let fixed = wheel_odometry(f, &input.recording.wheels, Pose2::identity());
            MethodResult {
                estimates,
                method: m.as_str().into(),
                final_params,
                final_errors: truth_end.map(|t| {
                    [
                        final_params[0] - t[0],
                        final_params[1] - t[1],
                        final_params[2] - t[2],
                    ]
                }),
                convergence_s: input
                    .truth
                    .filter(|_| estimates)
                    .and_then(|t| convergence(run, t, t_start)),
                mean_iteration_ms: run.summary.mean_iteration_ms,
                eval: origin_eval(
                    &format!("calibrated by {}", m.as_str()),
                    &run.trajectory,
                    reference,
                    notes,
                ),
                windowed: reference
                    .filter(|r| estimates && !r.position_only)
                    .and_then(|r| windowed(run, &input.recording.wheels, &r.traj)),
                eval_final: (!changing)
                    .then(|| {
                        origin_eval(
                            &format!("final parameters of {}", m.as_str()),
                            &fixed,
                            reference,
                            notes,
                        )
                    })
                    .flatten(),
            }
        })
        .collect()
}
