//! `odocal._core`: the Python package's bridge to the odocal library. Each
//! function runs the same pipeline step as the command of the same name and
//! returns what that command's `--json` prints (as a JSON string the Python
//! layer parses), or numpy arrays of a recording. Errors raise
//! `InputError` (a `ValueError`: the command's exit-2 message) or
//! `OutputError` (an `OSError`: exit 1). The GIL is released while Rust
//! works, so Python threads and Ray tasks run in parallel.

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use odocal::pipeline::calibrate::{CalibSource, CalibrateJob, CalibratorChoice};
use odocal::pipeline::diagnose::DiagnoseJob;
use odocal::pipeline::evaluate::EvalJob;
use odocal::pipeline::fleet::{self, FleetJob, Item, Plan};
use odocal::pipeline::icp::IcpJob;
use odocal::pipeline::simulate::SimulateJob;
use odocal::pipeline::{self, Common, NoObserver, PipelineError};
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

create_exception!(
    _core,
    InputError,
    PyValueError,
    "Bad input or arguments (the CLI's exit 2)."
);
create_exception!(
    _core,
    OutputError,
    PyOSError,
    "An output could not be written (the CLI's exit 1)."
);

/// The exception for a pipeline error, with the CLI's message.
fn raise(e: PipelineError) -> PyErr {
    match e.exit_code() {
        2 => InputError::new_err(e.to_string()),
        _ => OutputError::new_err(e.to_string()),
    }
}

fn bad(m: impl std::fmt::Display) -> PyErr {
    InputError::new_err(m.to_string())
}

fn json<T: serde::Serialize>(v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| OutputError::new_err(e.to_string()))
}

fn common(robot: Option<PathBuf>, config: Option<PathBuf>) -> Common {
    Common { config, robot }
}

/// Parses an option the way the CLI does (`adaptive-pf`, `systematic`, …).
fn parse<T: std::str::FromStr>(what: &str, v: Option<String>) -> PyResult<Option<T>>
where
    T::Err: std::fmt::Display,
{
    v.map(|s| {
        s.parse::<T>()
            .map_err(|e| bad(format!("{what} '{s}': {e}")))
    })
    .transpose()
}

/// Reads a recording: a dict of numpy arrays (see `odocal.read`).
#[pyfunction]
#[pyo3(signature = (path, robot=None, config=None))]
fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let rec = py
        .detach(|| {
            let (cfg, nominal) = common(robot, config).load_nominal()?;
            pipeline::read_recording(&path, &cfg, &nominal.robot)
        })
        .map_err(raise)?;
    let d = PyDict::new(py);
    d.set_item("source", &rec.source)?;
    let n = rec.scans.len();
    let col = |f: &dyn Fn(&odocal::scan::LaserScan) -> f64| -> Vec<f64> {
        rec.scans.iter().map(f).collect()
    };
    d.set_item("scan_stamps", col(&|s| s.stamp).into_pyarray(py))?;
    d.set_item("angle_min", col(&|s| s.angle_min).into_pyarray(py))?;
    d.set_item(
        "angle_increment",
        col(&|s| s.angle_increment).into_pyarray(py),
    )?;
    d.set_item("range_min", col(&|s| s.range_min).into_pyarray(py))?;
    d.set_item("range_max", col(&|s| s.range_max).into_pyarray(py))?;
    let beams: Vec<usize> = rec.scans.iter().map(|s| s.ranges.len()).collect();
    if n > 0 && beams.iter().all(|&b| b == beams[0]) {
        let flat: Vec<f32> = rec
            .scans
            .iter()
            .flat_map(|s| s.ranges.iter().copied())
            .collect();
        let a = PyArray1::from_vec(py, flat).reshape([n, beams[0]])?;
        d.set_item("ranges", a)?;
    } else {
        let list: Vec<Bound<'py, PyArray1<f32>>> = rec
            .scans
            .iter()
            .map(|s| PyArray1::from_slice(py, &s.ranges))
            .collect();
        d.set_item("ranges", list)?;
    }
    let table = |rows: Vec<Vec<f64>>, cols: usize| -> PyResult<Bound<'py, PyArray2<f64>>> {
        if rows.is_empty() {
            return Ok(PyArray1::<f64>::from_vec(py, Vec::new()).reshape([0, cols])?);
        }
        PyArray2::from_vec2(py, &rows).map_err(|e| bad(e.to_string()))
    };
    d.set_item(
        "wheels",
        table(
            rec.wheels
                .iter()
                .map(|w| vec![w.stamp, w.left, w.right])
                .collect(),
            3,
        )?,
    )?;
    d.set_item(
        "gyro",
        table(rec.gyro.iter().map(|g| vec![g.stamp, g.wz]).collect(), 2)?,
    )?;
    let poses = |v: &[odocal::recording::StampedPose]| {
        v.iter()
            .map(|p| {
                vec![
                    p.stamp,
                    p.pose.translation.x,
                    p.pose.translation.y,
                    p.pose.rotation.angle(),
                ]
            })
            .collect::<Vec<_>>()
    };
    d.set_item("odom", table(poses(&rec.odom), 4)?)?;
    d.set_item("reference", table(poses(&rec.reference), 4)?)?;
    let mount = rec
        .base_from_laser
        .map(|p| vec![p.translation.x, p.translation.y, p.rotation.angle()].into_pyarray(py));
    d.set_item("base_from_laser", mount)?;
    Ok(d)
}

/// `odocal icp --json`: the trajectory (TUM) and motions (CSV) written; the
/// statistics and assumptions as JSON.
#[pyfunction]
#[pyo3(signature = (input, out, motions=None, robot=None, config=None))]
fn icp(
    py: Python<'_>,
    input: PathBuf,
    out: PathBuf,
    motions: Option<PathBuf>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = IcpJob {
        input,
        out,
        motions,
        common: common(robot, config),
    };
    let run = py
        .detach(|| pipeline::icp::run(&job, &mut NoObserver))
        .map_err(raise)?;
    #[derive(serde::Serialize)]
    struct IcpJson<'a> {
        #[serde(flatten)]
        stats: &'a odocal::icp::IcpStats,
        assumptions: &'a odocal::assumptions::Assumptions,
    }
    json(&IcpJson {
        stats: &run.stats,
        assumptions: &run.assumptions,
    })
}

/// `odocal calibrate --json`: the summary; the history, trajectory and
/// summary files in `out`.
#[pyfunction]
#[pyo3(signature = (out, input=None, motions=None, wheels=None, method=None, resampler=None,
    trigger=None, particles=None, seed=None, robot=None, config=None, init=None))]
#[allow(clippy::too_many_arguments)]
fn calibrate(
    py: Python<'_>,
    out: PathBuf,
    input: Option<PathBuf>,
    motions: Option<PathBuf>,
    wheels: Option<PathBuf>,
    method: Option<String>,
    resampler: Option<String>,
    trigger: Option<String>,
    particles: Option<usize>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
    init: Option<String>,
) -> PyResult<String> {
    let input = match (input, motions, wheels) {
        (Some(rec), None, None) => CalibSource::Recording(rec),
        (None, Some(m), Some(w)) => CalibSource::Csv {
            motions: m,
            wheels: w,
        },
        _ => return Err(bad("calibrate needs a recording, or motions and wheels")),
    };
    let job = CalibrateJob {
        input,
        out,
        choice: CalibratorChoice {
            method: parse("method", method)?,
            resampler: parse("resampler", resampler)?,
            trigger: parse("trigger", trigger)?,
            particles,
            seed,
        },
        viewer: None,
        common: common(robot, config),
        init: parse("init", init)?.unwrap_or_default(),
    };
    let done = py
        .detach(|| pipeline::calibrate::run(&job, &mut NoObserver))
        .map_err(raise)?;
    json(&done.paste.with(&done.summary))
}

/// `odocal eval --json`.
#[pyfunction]
#[pyo3(signature = (estimate, reference=None, relations=None, align=None, t_max_diff=None,
    t_offset=None, interpolate=false, resample_reference=None, max_gap=None, rpe_delta=None,
    rpe_unit=None, plot=None, robot=None, config=None))]
#[allow(clippy::too_many_arguments)]
fn eval(
    py: Python<'_>,
    estimate: PathBuf,
    reference: Option<PathBuf>,
    relations: Option<PathBuf>,
    align: Option<String>,
    t_max_diff: Option<f64>,
    t_offset: Option<f64>,
    interpolate: bool,
    resample_reference: Option<bool>,
    max_gap: Option<f64>,
    rpe_delta: Option<f64>,
    rpe_unit: Option<String>,
    plot: Option<PathBuf>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = EvalJob {
        estimate,
        reference,
        relations,
        estimate_times: None,
        reference_times: None,
        align: parse("align", align)?,
        t_max_diff,
        t_offset,
        interpolate,
        resample: resample_reference,
        max_gap,
        rpe_delta,
        rpe_unit: parse("rpe_unit", rpe_unit)?,
        plot,
        common: common(robot, config),
    };
    let report = py.detach(|| pipeline::evaluate::run(&job)).map_err(raise)?;
    json(&report)
}

/// `odocal diagnose --json`.
#[pyfunction]
#[pyo3(signature = (measured, holdout=None, report=None, robot=None, config=None))]
fn diagnose(
    py: Python<'_>,
    measured: PathBuf,
    holdout: Option<f64>,
    report: Option<PathBuf>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = DiagnoseJob {
        measured,
        holdout,
        report,
        common: common(robot, config),
    };
    let d = py.detach(|| pipeline::diagnose::run(&job)).map_err(raise)?;
    json(&d)
}

/// `odocal simulate --json`.
#[pyfunction]
#[pyo3(signature = (out, scenario=None, seed=None, duration=None, effects=Vec::new(), truth=None,
    robot=None, config=None, start=None))]
#[allow(clippy::too_many_arguments)]
fn simulate(
    py: Python<'_>,
    out: PathBuf,
    scenario: Option<String>,
    seed: Option<u64>,
    duration: Option<f64>,
    effects: Vec<String>,
    truth: Option<PathBuf>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
    start: Option<String>,
) -> PyResult<String> {
    let job = SimulateJob {
        scenario,
        seed,
        duration_s: duration,
        effects,
        out,
        truth,
        start,
        common: common(robot, config),
    };
    let s = py
        .detach(|| pipeline::simulate::run(&job, &mut |_| {}))
        .map_err(raise)?;
    json(&s)
}

fn fleet_job(
    source: PathBuf,
    out: PathBuf,
    method: Option<String>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<FleetJob> {
    Ok(FleetJob {
        source,
        out,
        choice: CalibratorChoice {
            method: parse("method", method)?,
            seed,
            ..Default::default()
        },
        common: common(robot, config),
    })
}

/// `odocal fleet --json` on this machine's cores.
#[pyfunction]
#[pyo3(signature = (source, out, method=None, seed=None, robot=None, config=None))]
fn fleet_run(
    py: Python<'_>,
    source: PathBuf,
    out: PathBuf,
    method: Option<String>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = fleet_job(source, out, method, seed, robot, config)?;
    let s = py.detach(|| fleet::run(&job, &|_, _| {})).map_err(raise)?;
    json(&s)
}

/// The fleet's plan: recordings, hashes, cached results (JSON).
#[pyfunction]
#[pyo3(signature = (source, out, method=None, seed=None, robot=None, config=None))]
fn fleet_plan(
    py: Python<'_>,
    source: PathBuf,
    out: PathBuf,
    method: Option<String>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = fleet_job(source, out, method, seed, robot, config)?;
    let plan = py.detach(|| fleet::plan(&job)).map_err(raise)?;
    json(&plan)
}

/// One recording of the plan calibrated: its outcome (JSON).
#[pyfunction]
#[pyo3(signature = (item, source, out, method=None, seed=None, robot=None, config=None))]
#[allow(clippy::too_many_arguments)]
fn fleet_calibrate(
    py: Python<'_>,
    item: String,
    source: PathBuf,
    out: PathBuf,
    method: Option<String>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = fleet_job(source, out, method, seed, robot, config)?;
    let item: Item = serde_json::from_str(&item).map_err(|e| bad(format!("fleet item: {e}")))?;
    let o = py
        .detach(|| fleet::calibrate_item(&job, &item))
        .map_err(raise)?;
    json(&o)
}

/// The plan and the new outcomes (a JSON list, `null` where cached) into
/// the fleet's outputs; the summary (JSON).
#[pyfunction]
#[pyo3(signature = (plan, outcomes, source, out, method=None, seed=None, robot=None, config=None))]
#[allow(clippy::too_many_arguments)]
fn fleet_finish(
    py: Python<'_>,
    plan: String,
    outcomes: String,
    source: PathBuf,
    out: PathBuf,
    method: Option<String>,
    seed: Option<u64>,
    robot: Option<PathBuf>,
    config: Option<PathBuf>,
) -> PyResult<String> {
    let job = fleet_job(source, out, method, seed, robot, config)?;
    let plan: Plan = serde_json::from_str(&plan).map_err(|e| bad(format!("fleet plan: {e}")))?;
    let outcomes: Vec<Option<odocal::fleet::Outcome>> =
        serde_json::from_str(&outcomes).map_err(|e| bad(format!("fleet outcomes: {e}")))?;
    let s = py
        .detach(|| {
            let _lock = pipeline::outputs::lock_outputs(&[job.out.as_path()])?;
            fleet::finish(&job, &plan, outcomes)
        })
        .map_err(raise)?;
    json(&s)
}

/// The extension module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("OutputError", m.py().get_type::<OutputError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(icp, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(eval, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(fleet_run, m)?)?;
    m.add_function(wrap_pyfunction!(fleet_plan, m)?)?;
    m.add_function(wrap_pyfunction!(fleet_calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(fleet_finish, m)?)?;
    Ok(())
}
