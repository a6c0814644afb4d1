//! One blind run: the simulator writes a bag with the case's effects hidden
//! (the truth stays in memory, never in the bag), the bag is read back as a
//! user's would be, ICP matches its scans, and the diagnosis of the nominal
//! robot is scored against what was hidden.

use super::cases::{Case, Group};
use super::BlindParams;
use crate::diagnose::{Diagnosis, Verdict};
use crate::effects::{Effect, FaultEffect};
use crate::experiments::ExperimentInputs;
use crate::io::{ReadOptions, TopicConfig};
use crate::pipeline::PipelineError;
use crate::sim::SimConfig;
use serde::Serialize;
use std::path::Path;

/// How one run came out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlindRun {
    /// The case's label.
    pub case: String,
    /// The case's family.
    pub group: Group,
    /// Scenario driven.
    pub scenario: String,
    /// Simulator seed.
    pub seed: u64,
    /// The verdict (design.md's word).
    pub verdict: String,
    /// Every name the diagnosis gave: causes, then faults.
    pub named: Vec<String>,
    /// Names it gave that were not hidden.
    pub false_causes: Vec<String>,
    /// Hidden ones it did not name.
    pub missed: Vec<String>,
    /// Named right: every hidden one named, nothing else, and the verdict
    /// fits (a null run `no-discrepancy`).
    pub right: bool,
    /// Every estimate of a rightly named effect within tolerance (20 % of
    /// the true value or 2 standard errors, whichever is wider; a radius
    /// step's time within 2 s; a floor slip's size); `None` when nothing
    /// was rightly named.
    pub estimates_ok: Option<bool>,
    /// The estimates outside tolerance, as `effect.key: got (true)`.
    pub estimate_misses: Vec<String>,
    /// Relative held-out gain of the extension.
    pub gain: f64,
}

/// Simulates the case on `scenario` with `seed`, writes the bag into
/// `dir`, diagnoses it blind and scores it. The bag is removed afterwards.
pub fn run_case(
    case: &Case,
    scenario: &str,
    seed: u64,
    p: &BlindParams,
    inp: &ExperimentInputs<'_>,
    dir: &Path,
) -> Result<BlindRun, PipelineError> {
    let mut cfg = SimConfig {
        seed,
        duration_s: p.duration_s,
        ..SimConfig::default()
    };
    cfg.scenario.name = scenario.to_string();
    cfg.laser.rate_hz = p.laser_rate_hz;
    cfg.faults = super::cases::placed(case, scenario);
    let mut robot = inp.robot.clone();
    robot.laser.get_or_insert_with(Default::default);
    let bag = dir.join(format!("blind-{scenario}-{seed}.mcap"));
    crate::pipeline::simulate::simulate(
        &cfg,
        &TopicConfig::default(),
        &robot,
        &case.effects,
        &bag,
        None,
        &mut |_| {},
    )?;
    // From here on only the bag and the nominal robot.
    let rec = crate::io::read_recording(&bag, &ReadOptions::for_robot(&robot));
    let _ = std::fs::remove_file(&bag);
    let d = crate::pipeline::diagnose::run_recording(&rec?, &robot, inp.icp, inp.diagnose)?;
    Ok(score(case, scenario, seed, &d))
}

/// Scores a diagnosis against the hidden case.
pub fn score(case: &Case, scenario: &str, seed: u64, d: &Diagnosis) -> BlindRun {
    let mut named: Vec<String> = d.causes.iter().map(|c| c.effect.clone()).collect();
    named.extend(d.faults.iter().map(|f| f.name.clone()));
    let false_causes: Vec<String> = named
        .iter()
        .filter(|n| !case.expect.contains(n) && !case.allowed.contains(n))
        .cloned()
        .collect();
    let missed: Vec<String> = case
        .expect
        .iter()
        .filter(|n| !named.contains(n))
        .cloned()
        .collect();
    let verdict_fits = match case.group {
        Group::Null => d.verdict == Verdict::NoDiscrepancy,
        _ => d.verdict != Verdict::NoDiscrepancy,
    };
    let right = false_causes.is_empty() && missed.is_empty() && verdict_fits;
    let mut estimate_misses = estimate_misses(&case.effects, d);
    let slip = slip_miss(case, d);
    let rightly: bool = case
        .effects
        .iter()
        .any(|e| d.causes.iter().any(|c| c.effect == e.name()))
        || slip.is_some();
    estimate_misses.extend(slip.flatten());
    BlindRun {
        case: case.label.clone(),
        group: case.group,
        scenario: scenario.to_string(),
        seed,
        verdict: serde_json::to_value(d.verdict)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default(),
        named,
        false_causes,
        missed,
        right,
        estimates_ok: rightly.then_some(estimate_misses.is_empty()),
        estimate_misses,
        gain: d.gain.relative,
    }
}

/// A floor slip's size against the hidden one (within 20 % of it or 2
/// standard errors, whichever is wider): `None` when no floor slip was both
/// hidden and named, `Some(None)` when its size is within tolerance.
fn slip_miss(case: &Case, d: &Diagnosis) -> Option<Option<String>> {
    let want = case.faults.iter().find_map(|f| match *f {
        FaultEffect::FloorSlip { slip, .. } => Some(slip),
        _ => None,
    })?;
    let f = d.faults.iter().find(|f| f.name == "floor_slip")?;
    let got = f.parameters.get("slip").copied().unwrap_or(f64::NAN);
    let se = f.parameters.get("slip_stderr").copied().unwrap_or(0.0);
    let ok = (got - want).abs() <= (0.2 * want).max(2.0 * se);
    Some((!ok).then(|| format!("floor_slip.slip: {got:.4} ({want})")))
}

/// The estimates of the hidden table effects that the diagnosis named, out
/// of tolerance. Effects of one kind add (two radius steps are matched one
/// to one by time).
fn estimate_misses(hidden: &[Effect], d: &Diagnosis) -> Vec<String> {
    let mut out = Vec::new();
    let mut used = vec![false; d.causes.len()];
    for e in hidden {
        let Some(i) = (0..d.causes.len())
            .filter(|i| !used[*i] && d.causes[*i].effect == e.name())
            .min_by(|a, b| {
                let dt = |i: usize| {
                    let t = |x: &std::collections::BTreeMap<String, f64>| {
                        x.get("time").copied().unwrap_or(0.0)
                    };
                    (t(&d.causes[i].parameters) - e.params().first().map_or(0.0, |p| p.1)).abs()
                };
                dt(*a).total_cmp(&dt(*b))
            })
        else {
            continue;
        };
        used[i] = true;
        let c = &d.causes[i];
        for (k, want) in e.params() {
            let Some(got) = c.parameters.get(k) else {
                continue;
            };
            let tol = match (e, k) {
                (Effect::RadiusStep { .. }, "time") => 2.0,
                _ => (0.2 * want.abs()).max(2.0 * c.stderr.get(k).copied().unwrap_or(0.0)),
            };
            if (got - want).abs() > tol {
                out.push(format!("{}.{k}: {got:.4} ({want})", e.name()));
            }
        }
    }
    out
}
