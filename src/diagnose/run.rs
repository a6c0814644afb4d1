//! The diagnosis driver: rows from the measured streams, outliers dropped,
//! a training and a held-out part, forward selection confirmed on the
//! held-out part, then the gain, the structure tests and the verdict.

use super::data::{
    drop_outliers, gyro_rows, icp_rows, merge_motions, GyroRow, IcpRow, Part, GROUPS,
};
use super::diagnosis::{Cause, Diagnosis, Fault, Remaining, Verdict};
use super::faults::{self, OUT_OF_ROUND};
use super::fit::Fit;
use super::floor::{self, FloorSettings};
use super::gain::heldout_gain;
use super::load::{self, Nuisance, Reading};
use super::model::Replay;
use super::remaining::{remaining_tests, wheel_regressors, RemainingTest, PERIODIC};
use super::residuals::{stream_stats, structure};
use super::select::{forward, SelectSettings, Selection};
use super::series::series;
use super::stability::{self, StabilitySettings};
use super::trajectory::trajectory_gain;
use super::{DiagnoseError, DiagnoseParams, Measured};
use crate::effects::{Departures, Effect, EffectKind};
use crate::robot::RobotConfig;
use std::collections::BTreeMap;

/// Runs replay, selection, gain and tests (params already validated).
pub fn run(
    robot: &RobotConfig,
    m: &Measured,
    p: &DiagnoseParams,
) -> Result<Diagnosis, DiagnoseError> {
    let origin = m.origin();
    // Wheels wired the wrong way are rewired before anything else is fitted.
    let rewired = faults::rewire(m.wheels, faults::wiring(m.wheels, m.motions));
    let wheels = rewired.as_ref().map_or(m.wheels, |r| r.0.as_slice());
    let replay = Replay::new(robot, wheels, origin, p.wheel_smoothing);
    let span = replay
        .span()
        .filter(|s| replay.len() >= 2 && s.1 > s.0)
        .ok_or_else(|| DiagnoseError::TooLittleData("fewer than 2 wheel samples".into()))?;
    let merged = merge_motions(m.motions, p.min_interval);
    let icp0 = icp_rows(&merged, span, p.margin);
    let gyro0 = gyro_rows(m.gyro, span, p.margin, p.gyro_window);
    let mut found: Vec<Fault> = rewired.into_iter().map(|r| r.1).collect();
    // The gyro is compared with the scan matching's turns read on the
    // instrument's scale (its own turn-rate error per pair taken out).
    let icp_turns = p.instrument.turns_debiased(&icp0);
    let gyro0 = match checked_gyro(&icp_turns, &gyro0, &p.gyro_check) {
        Some(fault) => {
            // A gyro whose scale is wrong says nothing the fit can use about
            // the robot's turning: it is left out, as on a robot without one.
            found.push(fault);
            Vec::new()
        }
        None => gyro0,
    };
    // Without a gyro the scan matching alone times the turns: its turn
    // rates are read on the instrument's scale, and the table's spread,
    // what it cannot vouch for, is what a turn-rate effect must exceed.
    let read_on_scale;
    let (icp0, p) = if gyro0.is_empty() && p.instrument.enabled {
        read_on_scale = DiagnoseParams {
            instrument: p.instrument.turn_errors_taken_out(),
            ..p.clone()
        };
        (icp_turns, &read_on_scale)
    } else {
        (icp0, p)
    };
    let rows = Rows {
        replay: &replay,
        span,
        origin,
        reference: m.reference,
    };
    if let Some((pass, fault)) = floor_slip(&rows, &icp0, &gyro0, robot, p) {
        found.push(fault);
        return Ok(pass.diagnosis(&replay, m, p, robot, found));
    }
    let pass = select_twice(&rows, &icp0, &gyro0, p)?;
    if let Some((pass, fault)) = out_of_round(&rows, &pass, &icp0, &gyro0, robot, p) {
        found.push(fault);
        return Ok(pass.diagnosis(&replay, m, p, robot, found));
    }
    if let Some((pass, fault, either)) = load_transfer(&rows, &pass, &icp0, &gyro0, robot, p) {
        found.push(fault);
        let mut d = pass.diagnosis(&replay, m, p, robot, found);
        if let Some(r) = either {
            // Not a finding: which of the two laws it is stays open.
            d.remaining.push(r);
            d.remaining_structure = true;
            d.verdict = verdict(&d.causes, &d.remaining, &d.faults);
        }
        return Ok(d);
    }
    Ok(pass.diagnosis(&replay, m, p, robot, found))
}

/// Tyres whose radius follows their load ([`load`]), compared with the
/// encoder gain whose law they share at one speed: when the selection named
/// a gain, with the radii and the wheel base fitted again beside each; when
/// it named radii and no gain, with the radii alone, on the rows read on
/// the scan matcher's scale. When the load law is the reading, or either
/// is, the table effects are selected again on the rows with the load's
/// part taken out, and the fault is named if that selection names no
/// encoder gain. Returns the pass on the corrected rows, the fault and,
/// when the run cannot tell the two laws apart, what is left open with the
/// gain's reading in full, so that neither is presented as the finding.
fn load_transfer(
    r: &Rows,
    pass: &Pass,
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    robot: &RobotConfig,
    p: &DiagnoseParams,
) -> Option<(Pass, Fault, Option<Remaining>)> {
    let model = pass.model();
    let xm = Departures::of(&model.effects);
    let on_scale;
    let (nuisance, icp): (Nuisance, &[IcpRow]) = if xm.encoder_gain != 0.0 {
        (Nuisance::RadiiAndBase, &pass.icp)
    } else if xm.radius_scale != [0.0; 2] && p.instrument.enabled {
        on_scale = p.instrument.debiased(&pass.icp);
        (Nuisance::Radii, &on_scale)
    } else {
        return None;
    };
    let all = Part {
        replay: r.replay,
        icp,
        gyro: &pass.gyro,
    };
    let fit = load::compare(all, &xm, robot, &model.scale, &p.load, nuisance)?;
    let reading = fit.reading(&p.load);
    if reading == Reading::Gain {
        return None;
    }
    // The gain's reading: the selection's own when it named one, else the
    // radii it named moved by the gain's fit, and that gain.
    let gain_reading = if xm.encoder_gain != 0.0 {
        model.effects.clone()
    } else {
        gain_reading(&model.effects, &fit)
    };
    let gain = Departures::of(&gain_reading).encoder_gain;
    let either = (reading == Reading::Either).then(|| faults::load_or_gain(&fit, &gain_reading));
    let alt = faults::GainAlternative::of(&fit, reading, gain);
    let kappa = fit.load;
    let rows = Part {
        replay: r.replay,
        icp: icp0,
        gyro: gyro0,
    };
    let (icp, gyro) = load::without_load(rows, &xm, robot, kappa.kappa);
    let again = select_twice(r, &icp, &gyro, p).ok()?;
    let gain_left = again
        .model()
        .effects
        .iter()
        .any(|e| e.kind() == EffectKind::EncoderGain);
    if gain_left {
        return None;
    }
    let on_scale = nuisance == Nuisance::Radii;
    Some((
        again,
        faults::tyre_load_transfer(&kappa, alt, on_scale),
        either,
    ))
}

/// The selected `effects` read as an encoder gain instead ([`load::compare`]
/// with the radii fitted again): the radius scales moved by the gain fit's,
/// and its gain.
fn gain_reading(effects: &[Effect], fit: &load::LoadFit) -> Vec<Effect> {
    let [dr, dl] = fit.gain_radii;
    let mut out: Vec<Effect> = effects
        .iter()
        .map(|e| match *e {
            Effect::RadiusScale { right, left } => Effect::RadiusScale {
                right: right + dr,
                left: left + dl,
            },
            other => other,
        })
        .collect();
    out.push(Effect::EncoderGain { k: fit.gain });
    out
}

/// The gyro's fault when its turn scale is one ([`super::gyro_check`]);
/// `None` when it is not, or the check is off.
fn checked_gyro(
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    c: &super::gyro_check::GyroCheck,
) -> Option<Fault> {
    let s = super::gyro_check::gyro_scale(icp0, gyro0, c).filter(|s| c.enabled && s.is_fault(c))?;
    Some(faults::gyro_scale(&s))
}

/// An out-of-round wheel, looked for in what the selected model leaves:
/// when a stream's residuals follow the wheel angles once per revolution,
/// the table effects are selected again on the rows with that periodic part
/// taken out of every stream (each by its own fit), so that no constant
/// effect stands in for part of it (a wobble seen through the turns the run
/// made reads as turn slip or a wheel base). Returns the pass on the
/// corrected rows and the fault, sized from the stream that shows it most
/// clearly.
fn out_of_round(
    r: &Rows,
    pass: &Pass,
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    robot: &RobotConfig,
    p: &DiagnoseParams,
) -> Option<(Pass, Fault)> {
    let all = Part {
        replay: r.replay,
        icp: &pass.icp,
        gyro: &pass.gyro,
    };
    let xm = Departures::of(&pass.model().effects);
    let (fault, icp, gyro) = without_periodic(r, all, &xm, icp0, gyro0, robot, p)?;
    let pass = select_twice(r, &icp, &gyro, p).ok()?;
    Some((pass, fault))
}

/// When the rows of `all` left by model `x` show a once-per-revolution
/// structure (an out-of-round wheel, [`leftover`]), the fault and the rows
/// `icp0`, `gyro0` with that periodic part (each stream's own fit of the
/// wheel regressors) taken out.
fn without_periodic(
    r: &Rows,
    all: Part,
    x: &Departures,
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    robot: &RobotConfig,
    p: &DiagnoseParams,
) -> Option<(Fault, Vec<IcpRow>, Vec<GyroRow>)> {
    let tests = structure_tests(all, x, robot, p);
    let mut faults = Vec::new();
    leftover(&tests, robot, &mut faults);
    let fault = faults.pop()?;
    let periodic: Vec<Option<[f64; 4]>> = GROUPS
        .iter()
        .map(|g| {
            tests
                .iter()
                .find(|t| t.found.stream == *g && t.found.structure == PERIODIC)
                .and_then(|t| t.coefficients.get(1..5)?.try_into().ok())
        })
        .collect();
    // Stream g's periodic part at the wheel regressors x.
    let part = |x: &[f64; 4], g: usize| {
        periodic[g].map_or(0.0, |b| (0..4).map(|j| b[j] * x[j]).sum::<f64>())
    };
    let icp: Vec<IcpRow> = icp0
        .iter()
        .map(|row| {
            let x = wheel_regressors(r.replay, row.t0, row.t1);
            IcpRow {
                z: std::array::from_fn(|g| row.z[g] - part(&x, g)),
                ..*row
            }
        })
        .collect();
    let gyro: Vec<GyroRow> = gyro0
        .iter()
        .map(|row| GyroRow {
            w: row.w - part(&wheel_regressors(r.replay, row.t0, row.t1), 3),
            ..*row
        })
        .collect();
    Some((fault, icp, gyro))
}

/// What every selection pass shares: the replay, the wheel span, the time
/// origin and the reference.
struct Rows<'a> {
    replay: &'a Replay,
    span: (f64, f64),
    origin: f64,
    reference: &'a [crate::recording::StampedPose],
}

/// Screens gross failures against the nominal model and selects, then
/// rejects outliers against the selected model and selects again on those
/// rows.
fn select_twice(
    r: &Rows,
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    p: &DiagnoseParams,
) -> Result<Pass, DiagnoseError> {
    let pass = |x: &Departures, sigma: f64| {
        Pass::new(
            r.replay,
            icp0,
            gyro0,
            x,
            sigma,
            r.span,
            p,
            r.origin,
            r.reference,
        )
    };
    let first = pass(&Departures::default(), 4.0 * p.outlier_sigma)?;
    pass(&Departures::of(&first.model().effects), p.outlier_sigma)
}

/// Slip on part of the floor, looked for on the nominal residuals before any
/// selection ([`floor::search`]); when a region stands out, the table
/// effects are selected on the rows with that slip taken out
/// ([`floor::corrected`]), and the region must still stand out in the
/// measured rows against that model ([`floor::refit`]) for the fault to be
/// named. A wheel's once-per-revolution wobble, on a path that passes the
/// same places at the same wheel angles, can read as such a region: when the
/// nominal residuals show it ([`without_periodic`]), the region must also
/// stand out on the rows with it taken out. Returns the pass on the
/// corrected rows and the fault.
fn floor_slip(
    r: &Rows,
    icp0: &[IcpRow],
    gyro0: &[GyroRow],
    robot: &RobotConfig,
    p: &DiagnoseParams,
) -> Option<(Pass, Fault)> {
    let s = FloorSettings {
        lag_seconds: p.structure_lag,
        ..Default::default()
    };
    let (mut icp, mut gyro) = (icp0.to_vec(), gyro0.to_vec());
    let nominal = Departures::default();
    drop_outliers(
        r.replay,
        &mut icp,
        &mut gyro,
        4.0 * p.outlier_sigma,
        &nominal,
    );
    let all = Part {
        replay: r.replay,
        icp: &icp,
        gyro: &gyro,
    };
    let candidate = floor::search(all, &nominal, &s).filter(|f| f.reported(&s))?;
    if let Some((_, icp_p, gyro_p)) = without_periodic(r, all, &nominal, &icp, &gyro, robot, p) {
        let round = Part {
            replay: r.replay,
            icp: &icp_p,
            gyro: &gyro_p,
        };
        floor::search(round, &nominal, &s).filter(|f| f.reported(&s))?;
    }
    let (icp_c, gyro_c) =
        floor::corrected(&icp, &gyro, &candidate.region, candidate.slip, s.margin);
    let pass = select_twice(r, &icp_c, &gyro_c, p).ok()?;
    let xm = Departures::of(&pass.model().effects);
    let confirmed =
        floor::refit(all, &xm, &candidate.region, s.lag_seconds).filter(|f| f.reported(&s))?;
    Some((pass, faults::floor_slip(&confirmed)))
}

/// One selection on the rows kept by an outlier screen.
struct Pass {
    icp: Vec<IcpRow>,
    gyro: Vec<GyroRow>,
    outliers: usize,
    split: Split,
    sel: Selection,
    kept: usize,
    heldout_rejected: Vec<Cause>,
}

impl Pass {
    /// Drops the rows beyond `sigma` robust σ of model `x`, splits and selects.
    #[allow(clippy::too_many_arguments)]
    fn new(
        replay: &Replay,
        icp0: &[IcpRow],
        gyro0: &[GyroRow],
        x: &Departures,
        sigma: f64,
        span: (f64, f64),
        p: &DiagnoseParams,
        origin: f64,
        reference: &[crate::recording::StampedPose],
    ) -> Result<Self, DiagnoseError> {
        let (mut icp, mut gyro) = (icp0.to_vec(), gyro0.to_vec());
        let outliers = drop_outliers(replay, &mut icp, &mut gyro, sigma, x);
        let split = Split::new(&icp, &gyro, span, p.holdout)?;
        let (train, held) = split.parts(replay, &icp, &gyro);
        let settings = settings(p, train, &split, origin);
        let check = Confirm {
            margin: p.heldout_margin,
            reference,
            split: split.time,
            window: p.trajectory_window,
        };
        let (sel, kept, heldout_rejected) = select_confirmed(train, held, settings, &check);
        Ok(Self {
            icp,
            gyro,
            outliers,
            split,
            sel,
            kept,
            heldout_rejected,
        })
    }

    /// The selected model (the nominal one when nothing was kept).
    fn model(&self) -> &Fit {
        if self.kept == 0 {
            &self.sel.nominal
        } else {
            &self.sel.steps[self.kept - 1]
        }
    }

    /// Gain, structure tests and verdict of the selected model.
    fn diagnosis(
        &self,
        replay: &Replay,
        m: &Measured,
        p: &DiagnoseParams,
        robot: &RobotConfig,
        mut faults: Vec<Fault>,
    ) -> Diagnosis {
        let (icp, gyro, split, sel) = (&self.icp, &self.gyro, &self.split, &self.sel);
        let (_, held) = split.parts(replay, icp, gyro);
        let all = Part { replay, icp, gyro };
        let model = self.model();
        let nominal = Departures::default();
        let xm = Departures::of(&model.effects);
        // Gain on the held-out part, normalised by the final training scales.
        let scale = model.scale;
        let gain = heldout_gain(
            held,
            m.reference,
            &xm,
            &scale,
            split.time,
            p.trajectory_window,
        );
        let structure_before = structure(all, &nominal, &sel.nominal.scale, p);
        let structure_after = structure(all, &xm, &scale, p);
        let causes: Vec<Cause> = (0..model.effects.len())
            .map(|i| Cause::of(model, i, sel.delta_bic[i]))
            .collect();
        let st = StabilitySettings {
            alpha: p.structure_alpha,
            lag_seconds: p.structure_lag,
            ..Default::default()
        };
        faults.extend(stability::latency_change(all, &xm, &st));
        faults.extend(stability::laser_knock(all, model, m.motions, &st));
        let tests = structure_tests(all, &xm, robot, p);
        let remaining = leftover(&tests, robot, &mut faults);
        let verdict = verdict(&causes, &remaining, &faults);
        let all_b = all.physical(&nominal);
        let all_a = all.physical(&xm);
        let train_counts = split.parts(replay, icp, gyro).0.counts();
        Diagnosis {
            assumptions: Default::default(),
            wheel_source: None,
            verdict,
            causes,
            faults,
            remaining_structure: remaining.iter().any(Remaining::is_robot),
            remaining,
            gain,
            heldout_rejected: self.heldout_rejected.clone(),
            candidates: sel.tried.clone(),
            structure_before,
            structure_after,
            stats_before: stream_stats(&all_b),
            stats_after: stream_stats(&all_a),
            noise_scale: (0..4)
                .filter(|g| train_counts[*g] > 0)
                .map(|g| (super::data::GROUPS[g].to_string(), scale[g]))
                .collect(),
            rows: split.row_counts(icp.len(), gyro.len(), self.outliers),
            series: series(replay, icp, gyro, &all_b, &all_a, split.time),
        }
    }
}

/// Every structure test of what the model `x` leaves in `all`, at the
/// diagnosis's settings.
fn structure_tests(
    all: Part,
    x: &Departures,
    robot: &RobotConfig,
    p: &DiagnoseParams,
) -> Vec<RemainingTest> {
    remaining_tests(
        all,
        x,
        p.structure_alpha,
        p.structure_lag,
        &p.floors,
        &p.instrument,
        robot,
    )
}

/// The significant structures the model leaves; a periodic one in the
/// wheel angles is an out-of-round wheel, reported as that fault once (from the
/// stream that shows it most clearly) instead of as a leftover.
fn leftover(
    tests: &[RemainingTest],
    robot: &RobotConfig,
    faults: &mut Vec<Fault>,
) -> Vec<Remaining> {
    let round = tests
        .iter()
        .filter(|t| t.significant && t.found.is_robot() && t.found.structure == PERIODIC)
        .min_by(|a, b| a.found.p_value.total_cmp(&b.found.p_value));
    // Named once: rows already cleared of it may still show a trace.
    let named = faults.iter().any(|f| f.name == OUT_OF_ROUND);
    if let Some(t) = round.filter(|_| !named) {
        let c = &t.coefficients;
        let g = super::data::GROUPS
            .iter()
            .position(|s| *s == t.found.stream)
            .unwrap_or(0);
        faults.push(faults::out_of_round(
            &t.found,
            &[c[1], c[2], c[3], c[4]],
            g,
            robot,
        ));
    }
    tests
        .iter()
        .filter(|t| t.significant && !(round.is_some() && t.found.structure == PERIODIC))
        .map(|t| t.found.clone())
        .collect()
}

/// The held-out part: the rows after `time`, the training part those before.
struct Split {
    /// Start of the held-out part (s).
    time: f64,
    /// Start of the rows (s).
    start: f64,
    /// ICP rows ending before the split.
    icp_train: usize,
    /// Gyro rows ending before the split.
    gyro_train: usize,
    /// First ICP row starting at or after the split.
    icp_held: usize,
    /// First gyro row starting at or after the split.
    gyro_held: usize,
}

impl Split {
    /// Holds out the last `holdout` fraction of the time covered by the ICP
    /// rows and the wheel `span`; refuses too few rows on either side.
    fn new(
        icp: &[IcpRow],
        gyro: &[GyroRow],
        span: (f64, f64),
        holdout: f64,
    ) -> Result<Self, DiagnoseError> {
        if icp.len() < 50 {
            return Err(DiagnoseError::TooLittleData(format!(
                "{} usable ICP motions inside the wheel stream (need ≥ 50)",
                icp.len()
            )));
        }
        let t_end = icp.last().map(|r| r.t1).unwrap_or(span.1).max(span.1);
        let start = icp[0].t0.min(span.0);
        let time = start + (1.0 - holdout) * (t_end - start);
        let split = Self {
            time,
            start,
            icp_train: icp.partition_point(|r| r.t1 <= time),
            gyro_train: gyro.partition_point(|r| r.t1 <= time),
            icp_held: icp.partition_point(|r| r.t0 < time),
            gyro_held: gyro.partition_point(|r| r.t0 < time),
        };
        if split.icp_train < 30 || icp.len() - split.icp_held < 10 {
            return Err(DiagnoseError::TooLittleData(
                "too few ICP motions in the training or held-out part".into(),
            ));
        }
        Ok(split)
    }

    /// The training and the held-out part of the rows.
    fn parts<'a>(
        &self,
        replay: &'a Replay,
        icp: &'a [IcpRow],
        gyro: &'a [GyroRow],
    ) -> (Part<'a>, Part<'a>) {
        let train = Part {
            replay,
            icp: &icp[..self.icp_train],
            gyro: &gyro[..self.gyro_train],
        };
        let held = Part {
            replay,
            icp: &icp[self.icp_held..],
            gyro: &gyro[self.gyro_held..],
        };
        (train, held)
    }

    /// Rows used in each part, and the outliers dropped before the split.
    fn row_counts(&self, icp: usize, gyro: usize, outliers: usize) -> BTreeMap<String, usize> {
        let mut rows = BTreeMap::new();
        rows.insert("icp_train".to_string(), self.icp_train);
        rows.insert("icp_heldout".to_string(), icp - self.icp_held);
        rows.insert("gyro_train".to_string(), self.gyro_train);
        rows.insert("gyro_heldout".to_string(), gyro - self.gyro_held);
        rows.insert("outliers".to_string(), outliers);
        rows
    }
}

/// Selection settings: the candidates the training part can identify (a gyro
/// bias needs at least 20 gyro rows), radius steps inside the training part
/// at least 1 s from its ends.
fn settings(p: &DiagnoseParams, train: Part, split: &Split, origin: f64) -> SelectSettings {
    let usable: Vec<String> = p
        .candidates
        .iter()
        .filter(|c| c.as_str() != EffectKind::GyroBias.name() || train.gyro.len() >= 20)
        .cloned()
        .collect();
    let [min_turn_scale, turn_rate] = turn_floor(train, p);
    SelectSettings {
        candidates: usable,
        bic_margin: p.bic_margin,
        alpha: p.alpha,
        max_effects: p.max_effects,
        max_iter: p.max_iter,
        step_range: (split.start - origin + 1.0, split.time - origin - 1.0),
        step_min_rows: 30,
        max_steps: p.max_effects,
        min_latency: min_latency(train.replay, p),
        min_turn_scale,
        turn_rate,
    }
}

/// What a turn-rate effect must exceed to be named, `[min_turn_scale,
/// turn_rate]` of [`SelectSettings`]: nothing when a gyro times the turns
/// (at least 20 rows of it), else the scan matcher's own turn-rate error on
/// the training rows ([`super::instrument::Instrument::turn_floor`]).
fn turn_floor(train: Part, p: &DiagnoseParams) -> [f64; 2] {
    if train.gyro.len() >= 20 {
        return [0.0, 0.0];
    }
    p.instrument.turn_floor(train.icp)
}

/// Shortest latency named (s): one encoder tick period at the run's wheel
/// rate ([`super::resolution`]) or the scan matcher's own timing error
/// ([`super::instrument::Instrument::timing`]), whichever is longer.
pub fn min_latency(replay: &Replay, p: &DiagnoseParams) -> f64 {
    replay.timing_resolution.max(p.instrument.timing_floor())
}

/// Forward selection on the training part whose every effect the held-out
/// part confirms. An effect the held-out part does not confirm is vetoed and
/// the selection restarts without it, so a spurious first choice (one that
/// fits the training part by accident) cannot hide a real cause behind it.
/// Returns the selection, how many of its effects are kept, and the vetoed.
fn select_confirmed(
    train: Part,
    held: Part,
    settings: SelectSettings,
    check: &Confirm,
) -> (Selection, usize, Vec<Cause>) {
    let mut settings = settings;
    let mut rejected: Vec<Cause> = Vec::new();
    loop {
        let sel = forward(train, &settings.candidates, &settings);
        let kept = confirmed(held, &sel, check);
        if kept == sel.steps.len() {
            return (sel, kept, rejected);
        }
        let f = &sel.steps[kept];
        rejected.push(Cause::of(f, kept, sel.delta_bic[kept]));
        let name = f.effects[kept].name();
        // A vetoed radius step leaves the steps kept before it.
        let earlier = f.effects[..kept]
            .iter()
            .filter(|e| e.name() == name)
            .count();
        if name == EffectKind::RadiusStep.name() && earlier > 0 {
            settings.max_steps = earlier;
        } else {
            settings.candidates.retain(|c| c != name);
        }
    }
}

/// Relative increase of a trajectory error against the reference that
/// counts as worse: refitting the earlier effects alongside a new one (a
/// gyro bias, a laser mount, which leave the wheel odometry alone) moves
/// that error by a per cent or two either way.
const TRAJECTORY_TOLERANCE: f64 = 0.05;

/// Absolute increase (m) of a trajectory error that counts as worse on top
/// of [`TRAJECTORY_TOLERANCE`]: once an extension has brought the error down
/// to a centimetre or so, refitting moves it by that much relative to itself.
const TRAJECTORY_FLOOR: f64 = 0.01;

/// What the held-out part must show for an effect to be kept.
struct Confirm<'a> {
    /// Least drop of the held-out χ².
    margin: f64,
    /// Reference poses (may be empty).
    reference: &'a [crate::recording::StampedPose],
    /// Start of the held-out part (s).
    split: f64,
    /// Window of the trajectory comparison (s).
    window: f64,
}

/// How many of the nested models of the selection, in order, each drop the
/// held-out χ² (normalised by the model's noise scales) by at least the
/// margin and, where a reference covers the held-out part, make neither
/// trajectory error against it worse (the windows' relative-pose error and,
/// where the reference allows it, the 2D-aligned ATE): an independent
/// measurement of where the robot went outranks a better fit to ICP.
fn confirmed(held: Part, sel: &Selection, c: &Confirm) -> usize {
    let sse = |x: &Departures, scale: &[f64; 4]| {
        let mut e: [Vec<f64>; 4] = Default::default();
        held.normalised(x, &mut e);
        (0..4)
            .map(|g| e[g].iter().map(|v| (v / scale[g]).powi(2)).sum::<f64>())
            .sum::<f64>()
    };
    let mut kept = 0;
    for (k, step) in sel.steps.iter().enumerate() {
        let prev = if k == 0 {
            Departures::default()
        } else {
            Departures::of(&sel.steps[k - 1].effects)
        };
        let next = Departures::of(&step.effects);
        let drop = sse(&prev, &step.scale) - sse(&next, &step.scale);
        // A latency says which clock the laser keeps against the wheels, not
        // which one the reference keeps: the odometry is compared unshifted,
        // and a latency entering is not judged by the reference at all.
        let unshifted = |x: &Departures| Departures {
            latency: 0.0,
            ..x.clone()
        };
        let (a, b) = (unshifted(&prev), unshifted(&next));
        let clock = step
            .effects
            .last()
            .is_some_and(|e| e.kind() == EffectKind::Latency);
        let worse = !clock
            && trajectory_gain(held.replay, c.reference, &a, &b, c.split, c.window).is_some_and(
                |t| {
                    let worse =
                        |b: f64, a: f64| a > b * (1.0 + TRAJECTORY_TOLERANCE) + TRAJECTORY_FLOOR;
                    let ate =
                        matches!((t.ate_before, t.ate_after), (Some(b), Some(a)) if worse(b, a));
                    ate || worse(t.rpe_before, t.rpe_after)
                },
            );
        if drop < c.margin || worse {
            break;
        }
        kept = k + 1;
    }
    kept
}

/// `explained` when causes (or faults) are named and nothing of the robot's
/// is left, `partly-explained` when something is; without causes,
/// `unexplained` when the nominal model leaves structure of the robot's and
/// `no-discrepancy` when it does not. What the scan matcher's own error
/// accounts for (`source: scan_matching`) never counts.
pub fn verdict(causes: &[Cause], remaining: &[Remaining], faults: &[Fault]) -> Verdict {
    let robot_left = remaining.iter().any(Remaining::is_robot);
    match (causes.is_empty() && faults.is_empty(), !robot_left) {
        (false, true) => Verdict::Explained,
        (false, false) => Verdict::PartlyExplained,
        (true, false) => Verdict::Unexplained,
        (true, true) => Verdict::NoDiscrepancy,
    }
}
