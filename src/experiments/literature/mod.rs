//! Every method of the literature side by side on the same simulated runs:
//! a wheelchair with hidden radius and wheel-base errors drives UMBmark
//! squares (the calibration data of every method) and then irregular
//! evaluation paths. The classic methods (\[Paryanto\], UMBmark, \[GAHeading\]) see
//! wheels and the true square ends; the Adaptive-PF of \[Farina\] and the DKF see
//! wheels, laser-like velocities and a gyro on the same squares. Each ends
//! with parameters, scored on the held-out paths by its odometry.

mod filters;
mod findings;
mod markdown;
mod output;
mod summary;

pub(super) use output::literature_output;
pub use summary::LiteratureRow;

use super::compare::{
    classic_methods, ClassicResult, CompareParams, CompareScenario, ComparisonRuns, Evaluation,
};
use super::repetitions::{at_least_one, draw_hidden_truth};
use crate::calib::CalibParams;
use crate::classic::{
    chained_steps, drive_segments, irregular_path, session_speeds, square_segments,
    tachometer_session, ClassicError, DriveParams, EncoderChain, LaserObsParams, SimRun,
    TachometerSensor, Turn,
};
use crate::robot::DiffDrive;
use serde::{Deserialize, Serialize};

/// Settings of the literature comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiteratureParams {
    /// Squares, GA, heading filter (its `seed` is replaced per run).
    pub compare: CompareParams,
    /// Hidden radius errors are drawn uniformly in ± this (relative).
    pub radius_error: f64,
    /// Hidden wheel-base error drawn uniformly in ± this (relative).
    pub wheel_base_error: f64,
    /// Length of each irregular evaluation path (m).
    pub evaluation_length_m: f64,
    /// How the chair drives (speed, wheel rate, slip, encoder resolution).
    pub drive: DriveParams,
    /// Noise of the laser velocities and gyro the filters of \[Farina\] use.
    pub laser: LaserObsParams,
    /// Particle count of the Adaptive-PF; `None` = the calibrator settings'.
    pub particles: Option<usize>,
    /// The laser tachometer of the session of \[Paryanto\] (its own errors).
    pub tachometer: TachometerSensor,
    /// Speeds of the session (≥ 2), spread over the chair's wheel rates.
    pub tachometer_speeds: usize,
    /// A new user boards after calibration: R_R, R_L grow by this (m) on a
    /// second set of evaluation paths ([Farina, Fig. 6b]: 4 and 2 mm);
    /// [0, 0] = no such table.
    pub load_change: [f64; 2],
}

impl Default for LiteratureParams {
    /// 6 m squares ×5 each way, poses measured to 5 mm and 0.3° at their
    /// corners (the GA) and ends (UMBmark, heading gain),
    /// 3 evaluation paths of 60 m, radii ± 1 %,
    /// wheel base ± 3 %, 0.4 m/s at 20 Hz, 8800 ticks/rev, 0.5 % wheel slip;
    /// then radii + 4 / + 2 mm (a new user) on fresh evaluation paths.
    fn default() -> Self {
        Self {
            compare: CompareParams {
                end_pose_sigma: [0.005, 0.005],
                ga_corners: true,
                ..CompareParams::default()
            },
            radius_error: 0.01,
            wheel_base_error: 0.03,
            evaluation_length_m: 60.0,
            drive: DriveParams {
                slip_sigma: 0.005,
                ticks_per_rev: 8800.0,
                ..DriveParams::default()
            },
            laser: LaserObsParams::default(),
            particles: None,
            tachometer: TachometerSensor::default(),
            tachometer_speeds: 6,
            load_change: [0.004, 0.002],
        }
    }
}

impl LiteratureParams {
    /// Checks the values the comparison divides by or draws from.
    pub fn validate(&self) -> Result<(), ClassicError> {
        let c = &self.compare;
        let ok = [self.radius_error, self.wheel_base_error]
            .iter()
            .all(|v| v.is_finite() && (0.0..0.2).contains(v))
            && self.evaluation_length_m.is_finite()
            && self.evaluation_length_m > 0.0
            && c.square_side.is_finite()
            && c.square_side > 0.0
            && c.runs_per_direction >= 2
            && c.evaluation_runs >= 1
            && self.drive.speed > 0.0
            && self.drive.turn_rate > 0.0
            && self.drive.rate_hz > 0.0
            && self.particles != Some(0)
            && self.tachometer_speeds >= 2;
        self.tachometer.validate()?;
        if ok {
            Ok(())
        } else {
            Err(ClassicError::invalid(
                "literature",
                "errors must be in [0, 0.2), lengths, speeds and rates > 0, \
                 runs_per_direction ≥ 2, evaluation_runs ≥ 1, particles ≥ 1, \
                 tachometer_speeds ≥ 2",
            ))
        }
    }
}

/// One repetition: the hidden truth and every method's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LiteratureRun {
    /// Seed of the repetition.
    pub seed: u64,
    /// The hidden true parameters (m).
    pub truth: DiffDrive,
    /// Every method, in table order.
    pub rows: Vec<ClassicResult>,
    /// After the load change: the classic methods keep their parameters, the
    /// Adaptive-PF and the DKF keep calibrating online (empty when off).
    pub changed: Vec<ClassicResult>,
}

/// The comparison: summary rows, what they say, and every repetition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LiteratureTable {
    /// Repetitions.
    pub runs: usize,
    /// One row per method.
    pub rows: Vec<LiteratureRow>,
    /// One row per method after the load change (empty when off).
    pub changed_rows: Vec<LiteratureRow>,
    /// Where the Adaptive-PF wins, where it does not and why.
    pub findings: Vec<String>,
    /// The settings used.
    pub params: LiteratureParams,
    /// Every repetition.
    pub per_run: Vec<LiteratureRun>,
}

/// One repetition's setting: the nominal model the chair believes, its hidden
/// truth, the settings and the seed.
struct Repetition<'a> {
    nominal: &'a DiffDrive,
    truth: DiffDrive,
    p: &'a LiteratureParams,
    /// The comparison's settings for this repetition: its seed, the drive's
    /// encoder resolution when it has one, and the tachometer session's table.
    cp: CompareParams,
    seed: u64,
}

impl<'a> Repetition<'a> {
    fn new(nominal: &'a DiffDrive, p: &'a LiteratureParams, seed: u64) -> Self {
        let truth = draw_hidden_truth(nominal, p.radius_error, p.wheel_base_error, seed);
        let ticks_per_rev = if p.drive.ticks_per_rev > 0.0 {
            p.drive.ticks_per_rev
        } else {
            p.compare.ticks_per_rev
        };
        let cp = CompareParams {
            seed,
            ticks_per_rev,
            tachometer: Some(tachometer_table(nominal, p, ticks_per_rev, seed)),
            ..p.compare.clone()
        };
        Self {
            nominal,
            truth,
            p,
            cp,
            seed,
        }
    }

    /// A run of the comparison: squares driven by the nominal model,
    /// evaluation runs along an irregular path of seed `s`.
    fn drive(&self, sc: CompareScenario, s: u64) -> SimRun {
        let side = self.cp.square_side;
        let segs = match sc {
            CompareScenario::Square => square_segments(side, Turn::Cw),
            CompareScenario::SquareCcw => square_segments(side, Turn::Ccw),
            CompareScenario::Evaluation => irregular_path(self.p.evaluation_length_m, s),
        };
        drive_segments(self.nominal, &self.truth, &segs, &self.p.drive, s)
    }
}

/// The session of \[Paryanto\] on this chair before its squares: the wheels spun at
/// `tachometer_speeds` speeds over its driving range, the encoders (which
/// count true wheel rotation here: these runs have no rate-dependent encoder
/// gain) read out over 1 s as the microcontroller of \[Paryanto\] does, beside the
/// tachometer with its own errors.
fn tachometer_table(
    nominal: &DiffDrive,
    p: &LiteratureParams,
    ticks_per_rev: f64,
    seed: u64,
) -> Vec<crate::classic::TachoReading> {
    let chain = EncoderChain {
        pulses_per_rev: ticks_per_rev,
        encoder_teeth: 1.0,
        wheel_teeth: 1.0,
        period_s: 1.0,
    };
    let speeds = session_speeds(
        nominal,
        p.drive.speed,
        p.drive.turn_rate,
        p.tachometer_speeds,
    );
    tachometer_session(&chain, [0.0, 0.0], &p.tachometer, &speeds, seed)
}

/// One repetition with hidden truth drawn from `seed`: squares and evaluation
/// paths driven by the nominal model, then every method.
pub fn literature_run(
    nominal: &DiffDrive,
    calib: &CalibParams,
    p: &LiteratureParams,
    seed: u64,
) -> Result<LiteratureRun, ClassicError> {
    p.validate()?;
    let rep = Repetition::new(nominal, p, seed);
    let runs = ComparisonRuns::simulate(&rep.cp, |sc, s| Ok::<_, String>(rep.drive(sc, s)))?;
    let eval = Evaluation {
        truth: Some(&rep.truth),
        runs: &runs.evals,
    };
    let mut rows = classic_methods(nominal, &rep.cp, &runs, &eval)?;
    let steps = chained_steps(
        &runs.square_runs(),
        &p.laser,
        seed.wrapping_mul(31).wrapping_add(17),
    );
    let mut filters = Vec::new();
    for filter in filters::FILTERS {
        let (row, online) = filters::calibrate(&rep, calib, filter, &steps, &eval)?;
        rows.push(row);
        filters.push(online);
    }
    let end = steps.last().map_or(0.0, |s| s.t1);
    let changed = if p.load_change == [0.0, 0.0] {
        Vec::new()
    } else {
        filters::after_load_change(&rep, &rows, filters, end)?
    };
    Ok(LiteratureRun {
        seed,
        truth: rep.truth,
        rows,
        changed,
    })
}

/// `runs` repetitions (repetition i: seed `seed + i`, its own hidden truth),
/// summarised per method, with the findings spelled out.
pub fn literature(
    nominal: &DiffDrive,
    calib: &CalibParams,
    p: &LiteratureParams,
    runs: usize,
    seed: u64,
) -> Result<LiteratureTable, ClassicError> {
    at_least_one("literature", "runs", &[runs])?;
    let per_run: Vec<LiteratureRun> = (0..runs)
        .map(|i| literature_run(nominal, calib, p, seed.wrapping_add(i as u64)))
        .collect::<Result<_, _>>()?;
    let rows = summary::summarize(&per_run, |r| &r.rows);
    let changed_rows = summary::summarize(&per_run, |r| &r.changed);
    let mut findings = findings::findings(&rows);
    findings.extend(findings::changed_findings(&changed_rows, p.load_change));
    Ok(LiteratureTable {
        runs,
        rows,
        changed_rows,
        findings,
        params: p.clone(),
        per_run,
    })
}
