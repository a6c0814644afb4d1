//! One robot's recordings into its parameter trends and alarms.

use super::series::{candidate_steps, fit, Fit, Point};
use super::{Alarm, AlarmKind, Entry, FleetParams, Outcome, Refusal};
use serde::Serialize;
use std::collections::BTreeMap;

/// A change of a parameter between recordings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    /// The first day after it.
    pub day: f64,
    /// Its size (m).
    pub size_m: f64,
    /// Its std (m), widened by the Birge ratio.
    pub std_m: f64,
    /// How much it lowers the series' χ² (scaled by the Birge ratio).
    pub delta_chi2: f64,
}

/// One parameter's history fitted: offset, rate and the steps found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trend {
    /// `r_right`, `r_left` or `wheel_base`.
    pub parameter: String,
    /// Calibrated recordings the fit uses.
    pub recordings: usize,
    /// Rate (m/day).
    pub rate_m_per_day: f64,
    /// Its std (m/day), widened by the Birge ratio.
    pub rate_std_m_per_day: f64,
    /// Steps found (each beyond `step_chi2`).
    pub steps: Vec<Step>,
    /// χ² per degree of freedom of the final fit (`None` without a degree
    /// of freedom).
    pub reduced_chi2: Option<f64>,
}

/// A robot's trends and alarms.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotAnalysis {
    /// The robot.
    pub robot: String,
    /// Recordings, calibrated and refused.
    pub recordings: usize,
    /// Per parameter; empty with fewer than `min_recordings` calibrations.
    pub trends: Vec<Trend>,
    /// Alarms, in order of day.
    pub alarms: Vec<Alarm>,
}

pub(super) const PARAMETERS: [&str; 3] = ["r_right", "r_left", "wheel_base"];

/// The points of `parameter` among the calibrated entries, each std
/// multiplied by `std_factor`.
fn points(entries: &[Entry], parameter: &str, std_factor: f64) -> Vec<Point> {
    entries
        .iter()
        .filter_map(|e| match &e.outcome {
            Outcome::Calibrated { params, std, .. } => {
                let pick = |d: &crate::robot::DiffDrive| match parameter {
                    "r_right" => d.r_right,
                    "r_left" => d.r_left,
                    _ => d.wheel_base,
                };
                Some(Point {
                    day: e.day,
                    value: pick(params),
                    std: pick(std) * std_factor,
                })
            }
            Outcome::Refused { .. } => None,
        })
        .collect()
}

/// Whether every segment between consecutive steps holds `min_side` points.
fn segments_hold(points: &[Point], steps: &[f64], min_side: usize) -> bool {
    let bounds: Vec<f64> = std::iter::once(f64::NEG_INFINITY)
        .chain(steps.iter().copied())
        .chain(std::iter::once(f64::INFINITY))
        .collect();
    bounds.windows(2).all(|w| {
        points
            .iter()
            .filter(|p| p.day >= w[0] && p.day < w[1])
            .count()
            >= min_side
    })
}

/// The best fit with one more step than `steps`, if any candidate fits.
fn best_extra_step(points: &[Point], steps: &[f64], p: &FleetParams) -> Option<(Vec<f64>, Fit)> {
    candidate_steps(points, p.min_side)
        .into_iter()
        .filter(|s| !steps.contains(s))
        .filter_map(|s| {
            let mut trial = steps.to_vec();
            trial.push(s);
            trial.sort_by(f64::total_cmp);
            if !segments_hold(points, &trial, p.min_side) {
                return None;
            }
            fit(points, &trial).map(|f| (trial, f))
        })
        .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))
}

/// Fits one parameter: a rate over time, and steps added one at a time
/// while each lowers χ² (scaled by the larger model's Birge ratio) by more
/// than `step_chi2` and is larger than `min_step_m`.
fn trend(parameter: &str, points: &[Point], p: &FleetParams) -> Option<Trend> {
    let mut steps: Vec<f64> = Vec::new();
    let mut best = fit(points, &steps)?;
    let mut found: Vec<f64> = Vec::new(); // Δχ² of each step, in day order of `steps`
    while steps.len() < p.max_steps {
        let Some((trial, f)) = best_extra_step(points, &steps, p) else {
            break;
        };
        let added = trial.iter().position(|s| !steps.contains(s)).unwrap_or(0);
        let delta = (best.chi2 - f.chi2) / f.scale();
        if !(delta > p.step_chi2 && f.coef[2 + added].abs() > p.min_step_m) {
            break;
        }
        found.insert(added, delta);
        steps = trial;
        best = f;
    }
    Some(Trend {
        parameter: parameter.to_string(),
        recordings: points.len(),
        rate_m_per_day: best.coef[1],
        rate_std_m_per_day: best.std(1),
        steps: steps
            .iter()
            .enumerate()
            .map(|(k, &day)| Step {
                day,
                size_m: best.coef[2 + k],
                std_m: best.std(2 + k),
                delta_chi2: found[k],
            })
            .collect(),
        reduced_chi2: (best.dof > 0).then(|| best.chi2 / best.dof as f64),
    })
}

/// The recording of `robot` at `day` (the first one), for an alarm.
fn recording_at(entries: &[Entry], day: f64) -> String {
    entries
        .iter()
        .find(|e| e.day >= day)
        .map(|e| e.recording.clone())
        .unwrap_or_default()
}

/// A wear alarm when a radius's rate is beyond `wear_sigma` std and
/// `min_wear_m_per_day`; the evidence gives both radii's rates.
fn wear_alarm(robot: &str, entries: &[Entry], trends: &[Trend], p: &FleetParams) -> Option<Alarm> {
    let radii: Vec<&Trend> = trends
        .iter()
        .filter(|t| t.parameter != "wheel_base")
        .collect();
    let worn = radii.iter().any(|t| {
        t.rate_m_per_day.abs() > p.min_wear_m_per_day
            && t.rate_m_per_day.abs() > p.wear_sigma * t.rate_std_m_per_day
    });
    if !worn {
        return None;
    }
    let mut values = BTreeMap::new();
    let mut words = Vec::new();
    for t in &radii {
        values.insert(format!("{}_m_per_day", t.parameter), t.rate_m_per_day);
        values.insert(
            format!("{}_std_m_per_day", t.parameter),
            t.rate_std_m_per_day,
        );
        words.push(format!(
            "{} {:+.4} ± {:.4} mm/day ({:.1} σ)",
            t.parameter,
            1e3 * t.rate_m_per_day,
            1e3 * t.rate_std_m_per_day,
            t.rate_m_per_day.abs() / t.rate_std_m_per_day
        ));
    }
    let calibrated: Vec<&Entry> = entries
        .iter()
        .filter(|e| matches!(e.outcome, Outcome::Calibrated { .. }))
        .collect();
    let (first, last) = (calibrated.first()?, calibrated.last()?);
    values.insert("recordings".into(), calibrated.len() as f64);
    Some(Alarm {
        robot: robot.to_string(),
        kind: AlarmKind::Wear,
        day: last.day,
        recording: last.recording.clone(),
        evidence: format!(
            "radius trend over days {}–{} ({} recordings): {}",
            first.day,
            last.day,
            calibrated.len(),
            words.join(", ")
        ),
        values,
    })
}

/// One step alarm per step day, naming every parameter that changed there.
fn step_alarms(robot: &str, entries: &[Entry], trends: &[Trend]) -> Vec<Alarm> {
    let mut by_day: BTreeMap<i64, Vec<(&str, &Step)>> = BTreeMap::new();
    for t in trends {
        for s in &t.steps {
            by_day
                .entry((s.day * 1e6).round() as i64)
                .or_default()
                .push((&t.parameter, s));
        }
    }
    by_day
        .into_values()
        .map(|found| {
            let day = found[0].1.day;
            let mut values = BTreeMap::new();
            let words: Vec<String> = found
                .iter()
                .map(|(name, s)| {
                    values.insert(format!("{name}_step_m"), s.size_m);
                    values.insert(format!("{name}_step_std_m"), s.std_m);
                    format!(
                        "{name} {:+.2} ± {:.2} mm (Δχ² {:.0})",
                        1e3 * s.size_m,
                        1e3 * s.std_m,
                        s.delta_chi2
                    )
                })
                .collect();
            Alarm {
                robot: robot.to_string(),
                kind: AlarmKind::Step,
                day,
                recording: recording_at(entries, day),
                evidence: format!("change from day {day} on: {}", words.join(", ")),
                values,
            }
        })
        .collect()
}

/// One alarm per run of consecutive refusals of one kind (a fault persists
/// until repaired; its first day is when it appeared).
fn refusal_alarms(robot: &str, entries: &[Entry]) -> Vec<Alarm> {
    let mut alarms: Vec<Alarm> = Vec::new();
    let mut previous: Option<Refusal> = None;
    for e in entries {
        let Outcome::Refused { kind, message } = &e.outcome else {
            previous = None;
            continue;
        };
        if previous == Some(*kind) {
            if let Some(a) = alarms.last_mut() {
                let n = a.values.get("recordings").copied().unwrap_or(1.0) + 1.0;
                a.values.insert("recordings".into(), n);
                a.values.insert("last_day".into(), e.day);
            }
        } else {
            alarms.push(Alarm {
                robot: robot.to_string(),
                kind: match kind {
                    Refusal::Fault => AlarmKind::Fault,
                    Refusal::Insufficient => AlarmKind::Insufficient,
                },
                day: e.day,
                recording: e.recording.clone(),
                evidence: message.clone(),
                values: BTreeMap::from([("recordings".into(), 1.0), ("last_day".into(), e.day)]),
            });
        }
        previous = Some(*kind);
    }
    for a in &mut alarms {
        let n = a.values["recordings"];
        if n > 1.0 {
            a.evidence = format!(
                "{n} consecutive recordings refused (days {}–{}): {}",
                a.day, a.values["last_day"], a.evidence
            );
        }
    }
    alarms
}

/// One fault alarm per run of at least `min_run` consecutive calibrated
/// recordings whose stated laser mounting the scans contradicted (a laser
/// knocked out of place persists; one contradicted recording alone is left
/// to chance), from its first day. Refused recordings neither extend nor
/// break a run. `entries` in order of day.
fn mounting_alarms(robot: &str, entries: &[Entry], min_run: usize) -> Vec<Alarm> {
    let mut alarms = Vec::new();
    let mut run: Vec<&Entry> = Vec::new();
    let calibrated = entries.iter().filter_map(|e| match &e.outcome {
        Outcome::Calibrated { mounting, .. } => Some((e, mounting)),
        Outcome::Refused { .. } => None,
    });
    let mut close = |run: &mut Vec<&Entry>| {
        if run.len() >= min_run.max(1) {
            let (first, last) = (run[0], run[run.len() - 1]);
            let note = match &first.outcome {
                Outcome::Calibrated {
                    mounting: Some(m), ..
                } => m.clone(),
                _ => String::new(),
            };
            alarms.push(Alarm {
                robot: robot.to_string(),
                kind: AlarmKind::Fault,
                day: first.day,
                recording: first.recording.clone(),
                evidence: format!(
                    "laser mounting contradicted by the scans in {} consecutive recordings \
                     (days {}–{}): {note}",
                    run.len(),
                    first.day,
                    last.day
                ),
                values: BTreeMap::from([
                    ("recordings".into(), run.len() as f64),
                    ("last_day".into(), last.day),
                ]),
            });
        }
        run.clear();
    };
    for (e, mounting) in calibrated {
        if mounting.is_some() {
            run.push(e);
        } else {
            close(&mut run);
        }
    }
    close(&mut run);
    alarms
}

/// Analyses one robot's recordings (any order): its trends, when it has
/// `min_recordings` calibrations, and its alarms ordered by day. Each
/// recording's std is multiplied by `std_factor` (`[r_right, r_left,
/// wheel_base]`; see [`super::std_factors`]).
pub fn analyse_robot(
    robot: &str,
    entries: &[Entry],
    p: &FleetParams,
    std_factor: [f64; 3],
) -> RobotAnalysis {
    let mut entries = entries.to_vec();
    entries.sort_by(|a, b| a.day.total_cmp(&b.day).then(a.recording.cmp(&b.recording)));
    let calibrated = points(&entries, "r_right", 1.0).len();
    let trends: Vec<Trend> = if calibrated >= p.min_recordings {
        PARAMETERS
            .iter()
            .zip(std_factor)
            .filter_map(|(name, f)| trend(name, &points(&entries, name, f), p))
            .collect()
    } else {
        Vec::new()
    };
    let mut alarms = refusal_alarms(robot, &entries);
    alarms.extend(mounting_alarms(robot, &entries, p.min_side));
    alarms.extend(step_alarms(robot, &entries, &trends));
    alarms.extend(wear_alarm(robot, &entries, &trends, p));
    alarms.sort_by(|a, b| a.day.total_cmp(&b.day));
    RobotAnalysis {
        robot: robot.to_string(),
        recordings: entries.len(),
        trends,
        alarms,
    }
}
