//! The filters of \[Farina\] on the comparison's runs: the Adaptive-PF and the DKF
//! calibrate online on the squares' laser velocities and gyro, and keep
//! calibrating on fresh paths after a load change, where the classic
//! methods keep the parameters of their calibration runs.

use super::{LiteratureParams, Repetition};
use crate::calib::{self, build, CalibParams, CalibStep, Calibrator, Method, Ranges};
use crate::classic::{chained_steps_from, drive_segments, irregular_path, ClassicError, SimRun};
use crate::experiments::compare::{Calibrated, ClassicMethod, ClassicResult, Evaluation};
use crate::robot::DiffDrive;
use std::time::Instant;

/// The filters compared, in table order: the calibrator and its table name.
pub(super) const FILTERS: [(Method, ClassicMethod); 2] = [
    (Method::AdaptivePf, ClassicMethod::AdaptivePf),
    (Method::Dkf, ClassicMethod::Dkf),
];

/// A filter with the state it ended the squares in, to continue online.
pub(super) type OnlineFilter = (ClassicMethod, Box<dyn Calibrator + Send>);

/// A filter's row and the filter as it ended the squares.
type FilterOutcome = (ClassicResult, OnlineFilter);

/// Calibrator settings for the comparison: `base` with the method, a seed per
/// repetition, and initial ranges that contain the nominal robot (the base's
/// if they do, else ± 5 % radii and ± 15 % wheel base around nominal).
fn filter_params(
    base: &CalibParams,
    method: Method,
    nominal: &DiffDrive,
    p: &LiteratureParams,
    seed: u64,
) -> CalibParams {
    let inside = |r: [f64; 2], x: f64| r[0] <= x && x <= r[1];
    let b = &base.ranges();
    let ranges = if inside(b.r_right, nominal.r_right)
        && inside(b.r_left, nominal.r_left)
        && inside(b.wheel_base, nominal.wheel_base)
    {
        b.clone()
    } else {
        let r = Ranges::around(nominal.r_right, nominal.r_left, nominal.wheel_base, 0.05);
        Ranges {
            wheel_base: [nominal.wheel_base * 0.85, nominal.wheel_base * 1.15],
            ..r
        }
    };
    CalibParams {
        method,
        seed: base.seed.wrapping_add(seed),
        particles: match method {
            Method::AdaptivePf => p.particles.or(base.particles),
            _ => base.particles,
        },
        ranges: Some(ranges),
        ..base.clone()
    }
}

/// Runs filter `kind` over the squares' `steps` and scores its final
/// parameters by odometry as `method`; returns the row and the filter as it
/// ends.
pub(super) fn calibrate(
    rep: &Repetition<'_>,
    calib: &CalibParams,
    (kind, method): (Method, ClassicMethod),
    steps: &[CalibStep],
    eval: &Evaluation<'_>,
) -> Result<FilterOutcome, ClassicError> {
    let nominal = rep.nominal;
    let params = filter_params(calib, kind, nominal, rep.p, rep.seed);
    let t0 = Instant::now();
    let mut cal =
        build(&params, *nominal).map_err(|e| ClassicError::invalid("literature", e.to_string()))?;
    let r = calib::run(cal.as_mut(), steps, *nominal);
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let details = serde_json::json!({
        "iterations": r.summary.iterations,
        "mean_iteration_ms": r.summary.mean_iteration_ms,
        "std": r.summary.std,
        "particles": params.initial_particles(),
    });
    let row = eval.odometry(Calibrated {
        method,
        params: r.final_drive(),
        ms,
        details,
    })?;
    Ok((row, (method, cal)))
}

/// The evaluation after a load change: fresh paths with the radii changed;
/// the classic methods' parameters as they were, the filters continuing
/// online from where the squares left them (time continuing from `end`).
pub(super) fn after_load_change(
    rep: &Repetition<'_>,
    rows: &[ClassicResult],
    filters: Vec<OnlineFilter>,
    end: f64,
) -> Result<Vec<ClassicResult>, ClassicError> {
    let truth = DiffDrive {
        r_right: rep.truth.r_right + rep.p.load_change[0],
        r_left: rep.truth.r_left + rep.p.load_change[1],
        ..rep.truth
    };
    let paths = changed_paths(rep, &truth);
    let eval = Evaluation {
        truth: Some(&truth),
        runs: &paths,
    };
    let mut out = Vec::new();
    for r in rows.iter().filter(|r| {
        !matches!(
            r.method,
            ClassicMethod::HeadingPf | ClassicMethod::AdaptivePf | ClassicMethod::Dkf
        )
    }) {
        out.push(eval.odometry(Calibrated {
            method: r.method,
            params: r.final_params,
            ms: 0.0,
            details: serde_json::Value::Null,
        })?);
    }
    for (method, mut cal) in filters {
        out.push(follow_online(rep, method, cal.as_mut(), &eval, end)?);
    }
    Ok(out)
}

/// The evaluation paths after the load change, driven by the nominal model
/// with the changed `truth` (path i seeded from the repetition's seed).
fn changed_paths(rep: &Repetition<'_>, truth: &DiffDrive) -> Vec<SimRun> {
    let p = rep.p;
    (0..rep.cp.evaluation_runs)
        .map(|i| {
            let s = rep.seed.wrapping_mul(15_485_863).wrapping_add(i as u64);
            let segs = irregular_path(p.evaluation_length_m, s);
            drive_segments(rep.nominal, truth, &segs, &p.drive, s)
        })
        .collect()
}

/// A filter calibrating online along the evaluation paths one after the
/// other (time continuing from `end`), scored by its own trajectories.
fn follow_online(
    rep: &Repetition<'_>,
    method: ClassicMethod,
    cal: &mut dyn Calibrator,
    eval: &Evaluation<'_>,
    end: f64,
) -> Result<ClassicResult, ClassicError> {
    let t0 = Instant::now();
    let mut offset = end;
    let mut trajs = Vec::with_capacity(eval.runs.len());
    let mut last = *rep.nominal;
    for (i, run) in eval.runs.iter().enumerate() {
        let st = chained_steps_from(
            &[run],
            &rep.p.laser,
            rep.seed.wrapping_mul(77).wrapping_add(i as u64),
            offset,
        );
        let shift = offset - run.wheels.first().map_or(0.0, |w| w.stamp);
        offset = st.last().map_or(offset, |s| s.t1);
        let r = calib::run(cal, &st, last);
        last = r.final_drive();
        let mut t = r.trajectory;
        for s in &mut t.stamps {
            *s -= shift;
        }
        trajs.push(t);
    }
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let c = Calibrated {
        method,
        params: last,
        ms,
        details: serde_json::json!({ "online": true }),
    };
    eval.estimates(c, trajs.iter().map(Ok))
}
