//! Forward selection of effects by BIC: try every candidate on top of the
//! current model, keep the best one if it improves BIC by a clear margin and
//! its parameters are significant (Wald test), repeat until nothing does.

use super::data::Part;
use super::fit::{fit, wald, Fit};
use super::free::{free_names, free_params, zero_effect};
use super::stats::chi2_sf;
use crate::effects::{Departures, Effect, EffectKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// How one candidate fared when tried on top of the model of its round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// Selection round (0 = tried on the nominal model).
    pub round: usize,
    /// Effect name.
    pub effect: String,
    /// Fitted parameters (design.md keys; units of the effect table).
    pub parameters: BTreeMap<String, f64>,
    /// Their standard errors.
    pub stderr: BTreeMap<String, f64>,
    /// BIC of the round's model minus BIC with this effect (positive = better).
    pub delta_bic: f64,
    /// Wald-test p-value that the effect's free parameters are all zero.
    pub p_value: f64,
    /// Whether every parameter was identifiable from the data.
    pub identifiable: bool,
    /// Whether the estimate is physically possible (see [`physical`]).
    pub physical: bool,
    /// Whether the instruments can time or scale it: false for a latency
    /// shorter than one encoder tick period ([`super::resolution`]) or the
    /// scan matcher's own timing error
    /// ([`super::instrument::Instrument::timing`]), and for a wheel-base
    /// scale or turn slip whose change of the turn rate lies within the scan
    /// matcher's own turn-rate error when it alone reads the turns
    /// ([`SelectSettings::min_turn_scale`]).
    pub resolvable: bool,
}

/// Whether a fitted effect is physically possible: every parameter within
/// the range the effect table allows it (either sign: a negative latency is
/// a laser stream late against the encoders), and turn slip only widening
/// the effective wheel base (wheels skid sideways in a turn, they never grip
/// better than rolling), so a negative `turn_slip` is a shorter axle seen
/// through the turns the run happened to make, left to `wheel_base_scale`.
/// A radius drift of metres per hour standing in for a step or a scale over
/// a short run is thereby refused, never returned.
pub fn physical(e: &Effect) -> bool {
    let within = e.kind().params().iter().zip(e.values()).all(|(p, v)| {
        let b = p.bounds;
        v.abs() <= b.lo.abs().max(b.hi.abs())
    });
    within && !matches!(e, Effect::TurnSlip { k } if *k < 0.0)
}

/// Settings of the selection (a slice of `DiagnoseParams`).
#[derive(Debug, Clone)]
pub struct SelectSettings {
    /// Candidate effect names.
    pub candidates: Vec<String>,
    /// Minimum BIC improvement to add an effect.
    pub bic_margin: f64,
    /// Maximum Wald p-value of an added effect.
    pub alpha: f64,
    /// Maximum number of effects.
    pub max_effects: usize,
    /// LM iterations per fit.
    pub max_iter: usize,
    /// Allowed radius-step times (s from the origin).
    pub step_range: (f64, f64),
    /// Minimum rows on each side of a radius step.
    pub step_min_rows: usize,
    /// Most radius steps in one model.
    pub max_steps: usize,
    /// Shortest latency named (s; [`super::run::min_latency`]).
    pub min_latency: f64,
    /// Smallest wheel-base scale named (relative): 0 with a gyro; without
    /// one, what the scan matcher's turn reading leaves uncertain on the
    /// rows ([`super::instrument::Instrument::turn_floor`]: the table's
    /// spread once its error is taken out), since nothing else times the
    /// turns. A turn slip k changes the turn rate by k |W|, read
    /// at `turn_rate` (rad/s, the rows' information-weighted |W|).
    pub min_turn_scale: f64,
    /// The turn rate the rows weigh most (rad/s), for the turn slip's size.
    pub turn_rate: f64,
}

/// Result of the selection.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Nominal fit (no effect).
    pub nominal: Fit,
    /// Final fit with the selected effects.
    pub model: Fit,
    /// ΔBIC at which each selected effect entered (same order as `model.effects`).
    pub delta_bic: Vec<f64>,
    /// The nested models of the selection: `steps[k]` holds the first k + 1 effects.
    pub steps: Vec<Fit>,
    /// Every candidate tried, every round.
    pub tried: Vec<CandidateScore>,
}

/// Named parameters of effect `i` of a fit, and their standard errors.
pub fn named(f: &Fit, i: usize) -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let e = &f.effects[i];
    let p = e
        .params()
        .iter()
        .map(|(k, v)| (k.to_string(), *v))
        .collect();
    let s = free_names(e)
        .iter()
        .zip(&f.stderr[i])
        .map(|(k, se)| (k.to_string(), *se))
        .collect();
    (p, s)
}

/// The radius-step time that best explains the residuals of `current`
/// ([`super::split::search_split`] with the step's two sizes).
pub fn search_step_time(part: Part, current: &Fit, s: &SelectSettings) -> Option<f64> {
    let step = Effect::RadiusStep {
        time: 0.0,
        right: 0.0,
        left: 0.0,
    };
    let range = super::split::SplitRange {
        time: s.step_range,
        min_rows: s.step_min_rows,
    };
    super::split::search_split(part, current, &step, range).map(|f| f.time)
}

/// Whether the instruments can resolve effect `e` at settings `s` (see
/// [`CandidateScore::resolvable`]).
fn resolvable(e: &Effect, s: &SelectSettings) -> bool {
    match *e {
        Effect::Latency { delay } => delay.abs() >= s.min_latency,
        Effect::WheelBaseScale { scale } => scale.abs() >= s.min_turn_scale,
        Effect::TurnSlip { k } => (k * s.turn_rate).abs() >= s.min_turn_scale,
        _ => true,
    }
}

fn score(round: usize, f: &Fit, base_bic: f64, s: &SelectSettings) -> CandidateScore {
    let i = f.effects.len() - 1;
    let (parameters, stderr) = named(f, i);
    let w = wald(f, i);
    CandidateScore {
        round,
        effect: f.effects[i].name().to_string(),
        parameters,
        stderr,
        delta_bic: base_bic - f.bic,
        p_value: chi2_sf(w, free_params(&f.effects[i]).len()),
        identifiable: f.identifiable,
        physical: physical(&f.effects[i]),
        resolvable: resolvable(&f.effects[i], s),
    }
}

/// Forward selection on the training part (design.md: one effect at a time,
/// while BIC improves by more than the margin and the effect is significant).
pub fn forward(part: Part, usable: &[String], s: &SelectSettings) -> Selection {
    let counts = part.counts();
    let rss0 = part.rss(&Departures::default());
    let scale0 = super::fit::scales(&rss0, &counts);
    let nominal = fit(part, &[], scale0, s.max_iter, 1);
    let mut current = nominal.clone();
    let mut delta_bic = Vec::new();
    let mut tried = Vec::new();
    let mut steps = Vec::new();
    for round in 0..s.max_effects {
        let mut best: Option<(Fit, f64)> = None;
        for name in usable {
            // Radius steps may repeat (a chair boards several users); any
            // other effect enters once.
            let repeats = name == EffectKind::RadiusStep.name();
            let present = current.effects.iter().filter(|e| e.name() == name).count();
            if present >= if repeats { s.max_steps } else { 1 } {
                continue;
            }
            let Some(mut new) = zero_effect(name) else {
                continue;
            };
            if let Effect::RadiusStep { .. } = new {
                let Some(t) = search_step_time(part, &current, s) else {
                    continue;
                };
                new = Effect::RadiusStep {
                    time: t,
                    right: 0.0,
                    left: 0.0,
                };
            }
            let mut effs = current.effects.clone();
            effs.push(new);
            let f = fit(part, &effs, current.scale, s.max_iter, 1);
            let sc = score(round, &f, current.bic, s);
            let ok = sc.identifiable
                && sc.physical
                && sc.resolvable
                && sc.delta_bic > s.bic_margin
                && sc.p_value < s.alpha;
            tried.push(sc.clone());
            if ok && best.as_ref().is_none_or(|b| sc.delta_bic > b.1) {
                best = Some((f, sc.delta_bic));
            }
        }
        match best {
            Some((f, d)) => {
                delta_bic.push(d);
                // The accepted model is refitted with re-estimated σ scales.
                current = fit(part, &f.effects, f.scale, s.max_iter, 1);
                steps.push(current.clone());
            }
            None => break,
        }
    }
    let (model, delta_bic, steps) = prune(part, current, delta_bic, steps, s);
    Selection {
        nominal,
        model,
        delta_bic,
        steps,
        tried,
    }
}

/// Backward elimination after the forward pass: an effect that entered
/// early can be made redundant by later ones (a radius drift standing in for
/// a scale and a step until both are in), and later ones can move an
/// earlier estimate out of its physical range. While some effect is
/// unphysical, or its removal costs less than the BIC margin, or its
/// parameters are no longer significant in the joint fit, the weakest such
/// effect is removed. Returns the model,
/// each effect's ΔBIC (BIC without it minus with it) and the nested models
/// in the kept order.
fn prune(
    part: Part,
    mut current: Fit,
    delta_bic: Vec<f64>,
    steps: Vec<Fit>,
    s: &SelectSettings,
) -> (Fit, Vec<f64>, Vec<Fit>) {
    let mut removed = false;
    loop {
        let n = current.effects.len();
        if n < 2 && current.effects.iter().all(physical) {
            break;
        }
        let without: Vec<Fit> = (0..n)
            .map(|i| {
                let mut effs = current.effects.clone();
                effs.remove(i);
                fit(part, &effs, current.scale, s.max_iter, 1)
            })
            .collect();
        let weakest = (0..n)
            .map(|i| {
                let cost = without[i].bic - current.bic;
                let p = chi2_sf(wald(&current, i), free_params(&current.effects[i]).len());
                (i, cost, p)
            })
            .map(|(i, cost, p)| {
                // An estimate the joint fit moved out of its physical range
                // goes first, whatever it buys.
                let cost = if physical(&current.effects[i]) {
                    cost
                } else {
                    f64::NEG_INFINITY
                };
                (i, cost, p)
            })
            .filter(|(_, cost, p)| *cost < s.bic_margin || *p >= s.alpha)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((i, _, _)) = weakest else {
            break;
        };
        current = without[i].clone();
        removed = true;
    }
    if !removed {
        return (current, delta_bic, steps);
    }
    // The nested models of the kept effects in their order, and what each
    // removal would cost.
    let n = current.effects.len();
    let nested: Vec<Fit> = (1..=n)
        .map(|k| fit(part, &current.effects[..k], current.scale, s.max_iter, 1))
        .collect();
    let costs = (0..n)
        .map(|i| {
            let mut effs = current.effects.clone();
            effs.remove(i);
            fit(part, &effs, current.scale, s.max_iter, 1).bic - current.bic
        })
        .collect();
    (current, costs, nested)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::data::{GyroRow, IcpRow};
    use crate::diagnose::model::Replay;
    use crate::recording::WheelSample;
    use crate::robot::RobotConfig;
    use nalgebra::DMatrix;

    #[test]
    fn physical_means_within_the_table_and_turn_slip_only_widening() {
        let scale = |right, left| Effect::RadiusScale { right, left };
        // Radius scales may reach ±0.5, on the bound included.
        assert!(physical(&scale(0.4, -0.4)));
        assert!(physical(&scale(0.5, -0.5)));
        assert!(!physical(&scale(0.6, 0.0)));
        assert!(!physical(&scale(0.0, -0.51)));
        // Latency is non-negative in the table, yet either sign is allowed.
        assert!(physical(&Effect::Latency { delay: -0.3 }));
        assert!(!physical(&Effect::Latency { delay: 1.2 }));
        assert!(physical(&Effect::TurnSlip { k: 0.1 }));
        assert!(physical(&Effect::TurnSlip { k: 0.0 }));
        assert!(!physical(&Effect::TurnSlip { k: -0.1 }));
    }

    #[test]
    fn named_gives_every_parameter_and_the_errors_of_the_fitted_ones() {
        // A radius step: its time is searched (no standard error), its two
        // sizes fitted.
        let f = Fit {
            effects: vec![
                Effect::GyroBias { bias: 0.01 },
                Effect::RadiusStep {
                    time: 40.0,
                    right: 0.003,
                    left: -0.002,
                },
            ],
            stderr: vec![vec![0.001], vec![0.0004, 0.0005]],
            cov: DMatrix::zeros(3, 3),
            rss: [0.0; 4],
            scale: [1.0; 4],
            bic: 0.0,
            identifiable: true,
        };
        let (p, s) = named(&f, 1);
        let want_p: BTreeMap<String, f64> = [("time", 40.0), ("right", 0.003), ("left", -0.002)]
            .iter()
            .map(|&(k, v)| (k.to_string(), v))
            .collect();
        let want_s: BTreeMap<String, f64> = [("right", 0.0004), ("left", 0.0005)]
            .iter()
            .map(|&(k, v)| (k.to_string(), v))
            .collect();
        assert_eq!((p, s), (want_p, want_s));
    }

    /// A robot standing still for 10 s, and five one-second gyro windows
    /// reading 0.01, 0.03, 0.02, 0.04, 0 rad/s (σ 0.01).
    fn standing_with_a_biased_gyro() -> (Replay, Vec<GyroRow>) {
        let wheels: Vec<WheelSample> = (0..=100)
            .map(|i| WheelSample {
                stamp: i as f64 / 10.0,
                left: 0.0,
                right: 0.0,
            })
            .collect();
        let gyro = [0.01, 0.03, 0.02, 0.04, 0.0]
            .iter()
            .enumerate()
            .map(|(i, &w)| GyroRow {
                t0: i as f64,
                t1: i as f64 + 1.0,
                w,
                sigma: 0.01,
            })
            .collect();
        (
            Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0),
            gyro,
        )
    }

    fn settings(bic_margin: f64, alpha: f64, max_effects: usize) -> SelectSettings {
        SelectSettings {
            candidates: vec![],
            bic_margin,
            alpha,
            max_effects,
            max_iter: 50,
            step_range: (1.0, 9.0),
            step_min_rows: 2,
            max_steps: 2,
            min_latency: 0.0,
            min_turn_scale: 0.0,
            turn_rate: 0.0,
        }
    }

    #[test]
    fn a_gyro_bias_enters_when_it_pays_its_margin_and_is_significant() {
        // Bias fitted (the mean 0.02): RSS 30 → 10 over 5 rows, so ΔBIC =
        // 5 ln 6 − (5 ln 2 + ln 5) = 5 ln 3 − ln 5 = 3.884, Wald 10 and
        // p = P(χ²₁ > 10) = erfc(√5) = 0.001565. A wheel-base scale cannot
        // be seen on a robot that stands still and never enters; the bias
        // enters once.
        let (replay, gyro) = standing_with_a_biased_gyro();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let usable = ["wheel_base_scale", "gyro_bias"].map(String::from);
        let sel = forward(part, &usable, &settings(2.0, 0.05, 3));
        assert_eq!(sel.model.effects.len(), 1, "{:?}", sel.model.effects);
        assert_eq!(sel.model.effects[0].name(), "gyro_bias");
        assert_eq!(sel.steps.len(), 1);
        assert_eq!(sel.delta_bic.len(), 1);
        let d = 5.0 * 3f64.ln() - 5f64.ln();
        assert!((sel.delta_bic[0] - d).abs() < 1e-6, "{:?}", sel.delta_bic);
        assert!(sel.nominal.effects.is_empty());
        // Round 0 tried both, round 1 only the wheel-base scale.
        let tried: Vec<(usize, &str)> = sel
            .tried
            .iter()
            .map(|c| (c.round, c.effect.as_str()))
            .collect();
        assert_eq!(
            tried,
            [
                (0, "wheel_base_scale"),
                (0, "gyro_bias"),
                (1, "wheel_base_scale")
            ]
        );
        let bias = &sel.tried[1];
        assert!((bias.delta_bic - d).abs() < 1e-6, "{bias:?}");
        // The exact χ² tail (the Wilson–Hilferty approximation, 0.00175, is
        // 12 % high).
        assert!(
            (bias.p_value / 0.0015654022580025488 - 1.0).abs() < 1e-6,
            "{bias:?}"
        );
        assert!((bias.parameters["bias"] - 0.02).abs() < 1e-9, "{bias:?}");
        assert!(
            (bias.stderr["bias"] - 4e-5f64.sqrt()).abs() < 1e-9,
            "{bias:?}"
        );
        assert!(bias.identifiable && bias.physical);
        assert!(!sel.tried[0].identifiable, "{:?}", sel.tried[0]);
        // A margin above 3.88, a level below the p-value or no round at all: the
        // nominal model stays.
        for s in [
            settings(4.0, 0.05, 3),
            settings(2.0, 1e-3, 3),
            settings(2.0, 0.05, 0),
        ] {
            let sel = forward(part, &usable, &s);
            assert!(sel.model.effects.is_empty() && sel.delta_bic.is_empty());
        }
    }

    /// A robot driving straight with both wheels at 2 rad/s for 10 s
    /// (samples at 100 Hz, default robot: radii 0.32 m), and ICP rows over
    /// half seconds seeing the forward speed of radii 0.32 m up to 5 s and
    /// 0.33 m after (0.64 then 0.66 m/s, σ 0.01 m/s).
    fn straight_with_larger_radii_from_5_s() -> (Replay, Vec<IcpRow>) {
        let wheels: Vec<WheelSample> = (0..=1000)
            .map(|i| {
                let t = i as f64 / 100.0;
                WheelSample {
                    stamp: t,
                    left: 2.0 * t,
                    right: 2.0 * t,
                }
            })
            .collect();
        let icp = (0..20)
            .map(|k| {
                let t0 = 0.5 * k as f64;
                let v = if t0 < 5.0 { 0.64 } else { 0.66 };
                IcpRow {
                    t0,
                    t1: t0 + 0.5,
                    z: [v, 0.0, 0.0],
                    sigma: [0.01, 0.01, 0.004],
                }
            })
            .collect();
        (Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0), icp)
    }

    #[test]
    fn the_step_time_is_where_the_forward_speed_jumps() {
        // Every row after 5 s misses by the same 0.02 m/s, every row before
        // by nothing: a step at 5 s (between the rows centred at 4.75 and
        // 5.25 s) explains all of it, one a row earlier or later leaves a
        // row unexplained. Within 6–9 s the earliest allowed time explains
        // the most.
        let (replay, icp) = straight_with_larger_radii_from_5_s();
        let part = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        // σ scales 1: the lateral and turn rows, matched exactly, would
        // otherwise get the floor 1e-9 and weigh their rounding errors.
        let nominal = Fit {
            scale: [1.0; 4],
            ..fit(part, &[], [1.0; 4], 50, 1)
        };
        let t = search_step_time(part, &nominal, &settings(2.0, 0.05, 3));
        assert!(t.is_some_and(|t| (t - 5.0).abs() < 1e-9), "{t:?}");
        let late = SelectSettings {
            step_range: (6.0, 9.0),
            ..settings(2.0, 0.05, 3)
        };
        let t = search_step_time(part, &nominal, &late);
        assert!(t.is_some_and(|t| (t - 6.0).abs() < 1e-9), "{t:?}");
    }

    /// A robot turning in place at 1 rad/s for 4 s (wheels at ±0.65/0.64
    /// rad/s on the default robot: radii 0.32 m, wheel base 0.65 m), then
    /// standing for 4 s; one-second gyro windows reading the turn rate plus
    /// 0.1 rad/s, ± 0.01 alternately (σ 0.01).
    fn turning_then_standing_with_a_biased_gyro() -> (Replay, Vec<GyroRow>) {
        let a = 0.65 / 0.64;
        let wheels: Vec<WheelSample> = (0..=800)
            .map(|i| {
                let t = i as f64 / 100.0;
                let angle = a * t.min(4.0);
                WheelSample {
                    stamp: t,
                    left: -angle,
                    right: angle,
                }
            })
            .collect();
        let gyro = (0..8)
            .map(|k| {
                let turn = if k < 4 { 1.0 } else { 0.0 };
                let noise = if k % 2 == 0 { 0.01 } else { -0.01 };
                GyroRow {
                    t0: k as f64,
                    t1: k as f64 + 1.0,
                    w: turn + 0.1 + noise,
                    sigma: 0.01,
                }
            })
            .collect();
        (
            Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0),
            gyro,
        )
    }

    #[test]
    fn of_two_acceptable_effects_the_one_saving_more_bic_enters() {
        // Nominal: every window misses by 10 ± 1 σ, RSS 4·121 + 4·81 = 808
        // over 8 rows. A bias of 0.1 explains every window (RSS 8): ΔBIC =
        // 8 ln(808/8) − ln 8 = 8 ln 101 − ln 8 = 34.84. A wheel-base scale
        // only the turning ones: 1/(1 + s) = 1.1 leaves the four standing
        // windows at 11, 9, 11, 9 σ (RSS 4 + 404 = 408), ΔBIC = 8 ln(101/51)
        // − ln 8 = 3.39, above the margin of 2 as well. The bias enters;
        // next to it the scale explains nothing (ΔBIC = −ln 8).
        let (replay, gyro) = turning_then_standing_with_a_biased_gyro();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let usable = ["wheel_base_scale", "gyro_bias"].map(String::from);
        let sel = forward(part, &usable, &settings(2.0, 0.05, 3));
        let tried: Vec<(usize, &str)> = sel
            .tried
            .iter()
            .map(|c| (c.round, c.effect.as_str()))
            .collect();
        assert_eq!(
            tried,
            [
                (0, "wheel_base_scale"),
                (0, "gyro_bias"),
                (1, "wheel_base_scale")
            ]
        );
        let scale = &sel.tried[0];
        let d_scale = 8.0 * (101f64 / 51.0).ln() - 8f64.ln();
        assert!((scale.delta_bic - d_scale).abs() < 1e-6, "{scale:?}");
        assert!((scale.parameters["scale"] + 1.0 / 11.0).abs() < 1e-6);
        assert!(scale.identifiable && scale.physical && scale.p_value < 0.05);
        let d_bias = 8.0 * 101f64.ln() - 8f64.ln();
        assert!((sel.tried[1].delta_bic - d_bias).abs() < 1e-6);
        assert!((sel.tried[2].delta_bic + 8f64.ln()).abs() < 1e-6);
        assert_eq!(sel.model.effects.len(), 1);
        assert_eq!(sel.model.effects[0].name(), "gyro_bias");
        assert!(
            (sel.delta_bic[0] - d_bias).abs() < 1e-6,
            "{:?}",
            sel.delta_bic
        );
    }

    /// A fit of `effects` on the standing robot with its biased gyro, built
    /// by hand: the given covariance and BIC (prune reads nothing else of
    /// it but the σ scales: those of the bias fit, 1 and √2 for the gyro).
    fn by_hand(effects: Vec<Effect>, cov: &[f64], bic: f64) -> Fit {
        Fit {
            stderr: effects
                .iter()
                .map(|e| vec![0.0; free_params(e).len()])
                .collect(),
            effects,
            cov: DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(cov)),
            rss: [0.0, 0.0, 0.0, 10.0],
            scale: [1.0, 1.0, 1.0, 2f64.sqrt()],
            bic,
            identifiable: true,
        }
    }

    #[test]
    fn prune_drops_a_significant_effect_whose_removal_costs_less_than_the_margin() {
        // Bias 0.02 (Wald 0.02²/4e-5 = 10) and a wheel-base scale of 0.1
        // (Wald 0.1²/1e-4 = 100) that a standing robot cannot show: with
        // both, RSS 10 over 5 rows and BIC 5 ln 2 + 2 ln 5. Without the
        // scale BIC 5 ln 2 + ln 5 (cost −ln 5 = −1.61, below the margin
        // 0.5); without the bias RSS 30, BIC 5 ln 6 + ln 5 (cost
        // 5 ln 3 − ln 5 = 3.88). The scale goes; the bias alone then costs
        // 3.88 to remove, and the nested models are refitted.
        let (replay, gyro) = standing_with_a_biased_gyro();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let current = by_hand(
            vec![
                Effect::GyroBias { bias: 0.02 },
                Effect::WheelBaseScale { scale: 0.1 },
            ],
            &[4e-5, 1e-4],
            5.0 * 2f64.ln() + 2.0 * 5f64.ln(),
        );
        let s = settings(0.5, 0.05, 3);
        let (model, delta_bic, steps) = prune(part, current, vec![9.0, 9.0], vec![], &s);
        assert_eq!(model.effects.len(), 1, "{:?}", model.effects);
        let Effect::GyroBias { bias } = model.effects[0] else {
            panic!("{:?}", model.effects)
        };
        assert!((bias - 0.02).abs() < 1e-9);
        let d = 5.0 * 3f64.ln() - 5f64.ln();
        assert_eq!(delta_bic.len(), 1);
        assert!((delta_bic[0] - d).abs() < 1e-6, "{delta_bic:?}");
        assert_eq!(steps.len(), 1);
        assert_eq!(steps[0].effects.len(), 1);
    }

    #[test]
    fn prune_drops_an_insignificant_effect_however_much_its_removal_costs() {
        // A wheel-base scale of 0 (Wald 0, p = 1) next to the bias, with a
        // BIC B set 3 below that of the bias alone (5 ln 2 + ln 5): removing
        // the scale costs 3, more than the margin 2; removing the bias
        // (5 ln 6 + ln 5) − B = 5 ln 3 + 3, and it is significant (Wald 10,
        // p ≈ 0.002). The insignificant scale goes.
        let (replay, gyro) = standing_with_a_biased_gyro();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let current = by_hand(
            vec![
                Effect::GyroBias { bias: 0.02 },
                Effect::WheelBaseScale { scale: 0.0 },
            ],
            &[4e-5, 1.0],
            5.0 * 2f64.ln() + 5f64.ln() - 3.0,
        );
        let (model, _, _) = prune(part, current, vec![], vec![], &settings(2.0, 0.05, 3));
        assert_eq!(model.effects.len(), 1, "{:?}", model.effects);
        assert_eq!(model.effects[0].name(), "gyro_bias");
    }

    #[test]
    fn prune_keeps_a_lone_physical_effect_and_drops_a_lone_unphysical_one() {
        // The bias alone costs 5 ln 3 − ln 5 = 3.88 to remove, under a
        // margin of 4, yet the forward pass's only effect stays: nothing is
        // removed, so ΔBIC and the nested models are returned as given.
        let (replay, gyro) = standing_with_a_biased_gyro();
        let part = Part {
            replay: &replay,
            icp: &[],
            gyro: &gyro,
        };
        let s = settings(4.0, 0.05, 3);
        let bias = fit(part, &[Effect::GyroBias { bias: 0.0 }], [1.0; 4], 50, 1);
        let (model, delta_bic, steps) = prune(part, bias.clone(), vec![1.5], vec![bias], &s);
        assert_eq!(model.effects.len(), 1);
        assert_eq!((delta_bic, steps.len()), (vec![1.5], 1));
        // Windows reading 0.61…0.64 rad/s: a bias of 0.62, beyond the
        // table's ±0.5 rad/s, is removed whatever it buys.
        let high: Vec<GyroRow> = gyro
            .iter()
            .map(|g| GyroRow { w: g.w + 0.6, ..*g })
            .collect();
        let part = Part {
            gyro: &high,
            ..part
        };
        let bias = fit(part, &[Effect::GyroBias { bias: 0.0 }], [1.0; 4], 50, 1);
        assert!(!physical(&bias.effects[0]), "{:?}", bias.effects);
        let (model, delta_bic, steps) = prune(part, bias.clone(), vec![1.5], vec![bias], &s);
        assert!(model.effects.is_empty() && delta_bic.is_empty() && steps.is_empty());
    }

    /// Both wheels at 2 + sin 2t rad/s for 20 s (100 Hz, radii 0.32 m), and
    /// ICP rows over 0.1 s reading the forward speed the wheels had 20 ms
    /// earlier (the wheel stream 20 ms late), σ 0.002 m/s.
    fn wheels_20_ms_late() -> (Replay, Vec<IcpRow>) {
        let phi = |t: f64| 2.0 * t - 0.5 * (2.0 * t).cos();
        let wheels: Vec<WheelSample> = (0..=2000)
            .map(|i| {
                let t = i as f64 / 100.0;
                WheelSample {
                    stamp: t,
                    left: phi(t),
                    right: phi(t),
                }
            })
            .collect();
        let icp = (5..195)
            .map(|k| {
                let (t0, t1) = (0.1 * k as f64, 0.1 * (k + 1) as f64);
                let v = 0.32 * (phi(t1 - 0.02) - phi(t0 - 0.02)) / 0.1;
                IcpRow {
                    t0,
                    t1,
                    z: [v, 0.0, 0.0],
                    sigma: [0.002, 0.002, 0.002],
                }
            })
            .collect();
        (Replay::new(&RobotConfig::default(), &wheels, 0.0, 0.0), icp)
    }

    #[test]
    fn a_latency_under_what_the_instruments_time_is_not_named() {
        let (replay, icp) = wheels_20_ms_late();
        let part = Part {
            replay: &replay,
            icp: &icp,
            gyro: &[],
        };
        let usable = vec!["latency".to_string()];
        let named = |min_latency: f64| {
            let s = SelectSettings {
                min_latency,
                ..settings(10.0, 1e-3, 2)
            };
            forward(part, &usable, &s)
        };
        // Timed to within 10 ms: the 20 ms are named.
        let sel = named(0.01);
        assert_eq!(sel.model.effects.len(), 1, "{:?}", sel.tried);
        let Effect::Latency { delay } = sel.model.effects[0] else {
            panic!("{:?}", sel.model.effects)
        };
        assert!((delay.abs() - 0.02).abs() < 1e-3, "{delay}");
        assert!(sel.tried[0].resolvable);
        // Timed to within 30 ms only: tried, fitted, and not named.
        let sel = named(0.03);
        assert!(sel.model.effects.is_empty(), "{:?}", sel.model.effects);
        assert!(!sel.tried[0].resolvable && sel.tried[0].delta_bic > 10.0);
    }

    #[test]
    fn a_turn_effect_within_the_scan_matchers_turn_error_is_not_resolvable() {
        // Without a gyro the scan matcher's turn error on the rows is 0.5 %,
        // the rows weighing turns of 0.6 rad/s most.
        let s = SelectSettings {
            min_turn_scale: 0.005,
            turn_rate: 0.6,
            min_latency: 0.01,
            ..settings(10.0, 1e-3, 2)
        };
        let wb = |scale: f64| Effect::WheelBaseScale { scale };
        assert!(!resolvable(&wb(0.004), &s) && !resolvable(&wb(-0.0049), &s));
        assert!(resolvable(&wb(0.005), &s) && resolvable(&wb(-0.006), &s));
        // Turn slip k changes the turn rate by k |W|: 0.0075 · 0.6 = 0.45 %.
        let slip = |k: f64| Effect::TurnSlip { k };
        assert!(!resolvable(&slip(0.0075), &s));
        assert!(resolvable(&slip(0.01), &s));
        // The latency keeps its own floor; a radius is not a turn-rate
        // effect alone (it moves the forward speed too).
        assert!(!resolvable(&Effect::Latency { delay: 0.009 }, &s));
        assert!(resolvable(&Effect::Latency { delay: -0.011 }, &s));
        let radius = Effect::RadiusScale {
            right: 0.001,
            left: 0.001,
        };
        assert!(resolvable(&radius, &s));
        // With a gyro (no floor) every size is resolvable.
        let gyro = SelectSettings {
            min_turn_scale: 0.0,
            ..s
        };
        assert!(resolvable(&wb(1e-4), &gyro) && resolvable(&slip(1e-4), &gyro));
    }
}
