//! Before a calibrated number is reported: is each parameter excited by the
//! motion of the run (observability), and is the estimate physically
//! plausible against the nominal robot? A parameter the motion cannot
//! determine is refused with the motion it needs; a weak one is flagged and
//! its standard deviation widened; an absurd estimate is an error, not a
//! result.

use super::evidence::Evidence;
use crate::robot::DiffDrive;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Thresholds of the checks (`[calib.checks]` in the configuration).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CheckParams {
    /// Fewest steps with a measurement for any parameter.
    pub min_steps: usize,
    /// Distance the radii need, in nominal wheel bases.
    pub min_distance_wheel_bases: f64,
    /// Rotation the wheel base needs, summed over both directions (rad).
    pub min_rotation_rad: f64,
    /// Straight distance the radius ratio needs to be firm, in wheel bases.
    pub min_straight_wheel_bases: f64,
    /// The lesser turning direction's share below which the turns count as
    /// one-sided.
    pub min_turn_balance: f64,
    /// A weak parameter's reported standard deviation is multiplied by this.
    pub weak_widening: f64,
    /// Estimate / nominal outside `[lo, hi]` is refused.
    pub multiplier_bounds: [f64; 2],
    /// An estimate within this fraction of its search range's width from an
    /// edge has run into the range, not found the value.
    pub range_edge: f64,
    /// Reduced χ² of V or W about the best fixed law of the wheel rates
    /// above which the std is widened by √χ² (see [`observability`]).
    pub max_fit_chi2: f64,
}

impl Default for CheckParams {
    fn default() -> Self {
        Self {
            min_steps: 20,
            min_distance_wheel_bases: 5.0,
            min_rotation_rad: std::f64::consts::FRAC_PI_2,
            min_straight_wheel_bases: 2.0,
            min_turn_balance: 0.1,
            weak_widening: 3.0,
            multiplier_bounds: [0.8, 1.25],
            range_edge: 0.01,
            max_fit_chi2: 10.0,
        }
    }
}

/// One parameter's observability.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamObservability {
    /// Whether the run's motion determines it.
    pub observable: bool,
    /// Determined, but on thin evidence: its std is widened.
    pub weak: bool,
    /// The reported standard deviation (m), widened when weak.
    pub std: f64,
    /// What motion is missing, when any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub missing: Option<String>,
}

/// Per parameter (`r_right`, `r_left`, `wheel_base`), and the evidence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Observability {
    /// By parameter name.
    pub parameters: BTreeMap<String, ParamObservability>,
    /// The motion the run showed.
    pub excitation: Evidence,
}

impl Observability {
    /// The parameters the motion cannot determine, with what is missing.
    pub fn unobservable(&self) -> Vec<String> {
        self.parameters
            .iter()
            .filter(|(_, p)| !p.observable)
            .map(|(k, p)| format!("{k}: {}", p.missing.as_deref().unwrap_or("not excited")))
            .collect()
    }
}

/// What the run's motion lacks, per kind of excitation (`None`: enough).
struct Gaps {
    few: Option<String>,
    short: Option<String>,
    no_turns: Option<String>,
    one_sided: Option<String>,
    no_straight: Option<String>,
}

fn gaps(ev: &Evidence, d0: f64, p: &CheckParams) -> Gaps {
    let rotation = ev.turn_left_rad + ev.turn_right_rad;
    let lesser = ev.turn_left_rad.min(ev.turn_right_rad);
    Gaps {
        few: (ev.steps < p.min_steps)
            .then(|| format!("only {} steps with a measurement (need {})", ev.steps, p.min_steps)),
        short: (ev.distance_m < p.min_distance_wheel_bases * d0).then(|| {
            format!(
                "the robot drove {:.2} m; the radii need ≥ {:.2} m of travel",
                ev.distance_m,
                p.min_distance_wheel_bases * d0
            )
        }),
        no_turns: (rotation < p.min_rotation_rad).then(|| {
            format!(
                "the robot turned {rotation:.2} rad in all; the wheel base needs turns (≥ {:.2} rad)",
                p.min_rotation_rad
            )
        }),
        one_sided: (lesser < p.min_turn_balance * rotation).then(|| {
            format!(
                "turns in one direction only ({:.2} rad left, {:.2} rad right): a turn-dependent \
                 error (e.g. the laser's offset) is confounded with the wheel base",
                ev.turn_left_rad, ev.turn_right_rad
            )
        }),
        no_straight: (ev.straight_m < p.min_straight_wheel_bases * d0).then(|| {
            format!(
                "{:.2} m of straight driving; the radius ratio is firm with ≥ {:.2} m",
                ev.straight_m,
                p.min_straight_wheel_bases * d0
            )
        }),
    }
}

/// When V (for the radii) or V and W (for the wheel base) scatter about the
/// best fixed law of the wheel rates far more than their σ allow, the
/// filters' std, which trusts those σ, is too small: it is widened by
/// √χ² (the Birge ratio \[Birge1932\] of a least-squares fit) and the reason stated.
fn misfit(ev: &Evidence, p: &CheckParams) -> [Option<(String, f64)>; 2] {
    let [v, w] = ev.fit_chi2().map(|c| c.unwrap_or(1.0));
    let why = |what: &str, chi2: f64| {
        format!(
            "{what} does not follow a fixed law of the wheel rates (χ² {chi2:.1} per \
             measurement): the parameters changed during the run, or a time offset, slip or \
             mounting error is left (`odocal diagnose` names it); the std is widened by √χ²"
        )
    };
    let radii = (v > p.max_fit_chi2).then(|| (why("the measured speed V", v), v.sqrt()));
    let worst = v.max(w);
    let base = (worst > p.max_fit_chi2).then(|| {
        let what = if w >= v {
            "the measured turn rate W"
        } else {
            "the measured speed V"
        };
        (why(what, worst), worst.sqrt())
    });
    [radii, base]
}

/// The observability of R_R, R_L and D from `ev`, with `std` the filter's
/// standard deviations (widened here where weak) and `nominal` the scale.
/// With `changed` (the filter's change detector fired), a misfit of one
/// fixed law is what the filter followed: it is stated, not widened by.
pub fn observability(
    ev: &Evidence,
    std: &DiffDrive,
    nominal: &DiffDrive,
    p: &CheckParams,
    changed: bool,
) -> Observability {
    let g = gaps(ev, nominal.wheel_base, p);
    let [fit_radii, fit_base] = misfit(ev, p).map(|f| {
        f.map(|(why, k)| match changed {
            false => (why, k),
            true => (
                format!(
                    "{}; the filter's change detector fired, so the std is the filter's after \
                     the change it followed, not widened",
                    why.trim_end_matches("; the std is widened by √χ²")
                ),
                1.0,
            ),
        })
    });
    let radius_missing = g
        .few
        .clone()
        .or(g.short)
        .or(g.no_turns.clone().filter(|_| ev.straight_m == 0.0));
    let entry =
        |std: f64, missing: Option<String>, weak: Option<String>, fit: &Option<(String, f64)>| {
            let mut notes: Vec<String> = weak.iter().cloned().collect();
            let mut factor = if weak.is_some() { p.weak_widening } else { 1.0 };
            if let Some((why, k)) = fit {
                notes.push(why.clone());
                factor *= k;
            }
            let observable = missing.is_none();
            ParamObservability {
                observable,
                weak: observable && !notes.is_empty(),
                std: if observable { std * factor } else { std },
                missing: missing.or((!notes.is_empty()).then(|| notes.join("; "))),
            }
        };
    let mut parameters = BTreeMap::new();
    parameters.insert(
        "r_right".into(),
        entry(
            std.r_right,
            radius_missing.clone(),
            g.no_straight.clone(),
            &fit_radii,
        ),
    );
    parameters.insert(
        "r_left".into(),
        entry(
            std.r_left,
            radius_missing.clone(),
            g.no_straight,
            &fit_radii,
        ),
    );
    let base_missing = g.few.or(radius_missing).or(g.no_turns);
    parameters.insert(
        "wheel_base".into(),
        entry(std.wheel_base, base_missing, g.one_sided, &fit_base),
    );
    Observability {
        parameters,
        excitation: ev.clone(),
    }
}

/// An estimate that is not returned as a result, and why.
pub fn implausible(
    estimate: &DiffDrive,
    nominal: &DiffDrive,
    ranges: Option<[[f64; 2]; 3]>,
    p: &CheckParams,
) -> Option<String> {
    let names = ["r_right", "r_left", "wheel_base"];
    let est = [estimate.r_right, estimate.r_left, estimate.wheel_base];
    let nom = [nominal.r_right, nominal.r_left, nominal.wheel_base];
    let [lo, hi] = p.multiplier_bounds;
    for i in 0..3 {
        let k = est[i] / nom[i];
        if !(k.is_finite() && lo <= k && k <= hi) {
            return Some(format!(
                "{} came out {:.4} m, {k:.3}× the nominal {:.4} m (outside {lo}–{hi}): the \
                 nominal value, ticks_per_rev or the laser mounting is wrong",
                names[i], est[i], nom[i]
            ));
        }
    }
    let ranges = ranges?;
    for i in 0..3 {
        let [a, b] = ranges[i];
        let edge = p.range_edge * (b - a);
        if est[i] <= a + edge || est[i] >= b - edge {
            return Some(format!(
                "{} came out {:.4} m, at the edge of its search range [{a:.4}, {b:.4}] m: the \
                 filter ran into the range rather than finding the value. Check the nominal \
                 robot, or widen [calib.ranges]",
                names[i], est[i]
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::steps::CalibStep;
    use crate::calib::Wiring;

    fn drive(d: f64) -> DiffDrive {
        DiffDrive {
            r_right: 0.1,
            r_left: 0.1,
            wheel_base: d,
        }
    }

    /// Steps of a robot with R = 0.1 m, D = 0.5 m driving `(ω_R, ω_L)` for
    /// 0.1 s each, measured exactly; `swap` exchanges the encoders.
    fn evidence(rates: &[(f64, f64)], swap: bool) -> Evidence {
        let mut ev = Evidence::default();
        for (i, &(r, l)) in rates.iter().enumerate() {
            let (v, w) = (0.1 * (r + l) / 2.0, 0.1 * (r - l) / 0.5);
            let (er, el) = if swap { (l, r) } else { (r, l) };
            let t = i as f64 * 0.1;
            let s = CalibStep::new(t, t + 0.1, er, el)
                .with(crate::calib::Kind::V, v + 1e-4 * ((i * 7) % 5) as f64, 1e-3)
                .with(crate::calib::Kind::W, w + 1e-4 * ((i * 3) % 5) as f64, 1e-3);
            ev.add(&s);
        }
        ev
    }

    fn course() -> Vec<(f64, f64)> {
        let mut r = vec![(5.0, 5.0); 60];
        r.extend(vec![(6.0, 2.0); 30]);
        r.extend(vec![(5.0, 5.0); 30]);
        r.extend(vec![(2.0, 6.0); 30]);
        r
    }

    #[test]
    fn swapped_and_reversed_encoders_are_named() {
        assert_eq!(evidence(&course(), false).wiring(), Wiring::Consistent);
        assert_eq!(evidence(&course(), true).wiring(), Wiring::Swapped);
        let left_back: Vec<_> = course().iter().map(|&(r, l)| (r, l)).collect();
        let mut ev = Evidence::default();
        for (i, &(r, l)) in left_back.iter().enumerate() {
            let (v, w) = (0.1 * (r + l) / 2.0, 0.1 * (r - l) / 0.5);
            let t = i as f64 * 0.1;
            ev.add(
                &CalibStep::new(t, t + 0.1, r, -l)
                    .with(crate::calib::Kind::V, v, 1e-3)
                    .with(crate::calib::Kind::W, w + 1e-4 * (i % 3) as f64, 1e-3),
            );
        }
        assert_eq!(ev.wiring(), Wiring::LeftReversed);
        assert!(Wiring::Swapped.fault().unwrap().contains("Swap left_joint"));
    }

    #[test]
    fn a_straight_run_cannot_give_the_wheel_base() {
        let p = CheckParams::default();
        let straight = evidence(&vec![(5.0, 5.0); 100], false);
        let o = observability(&straight, &drive(0.001), &drive(0.5), &p, false);
        assert!(o.parameters["r_right"].observable);
        let d = &o.parameters["wheel_base"];
        assert!(
            !d.observable && d.missing.as_ref().unwrap().contains("turn"),
            "{d:?}"
        );
        let full = observability(
            &evidence(&course(), false),
            &drive(0.001),
            &drive(0.5),
            &p,
            false,
        );
        assert!(full.unobservable().is_empty(), "{:?}", full.parameters);
        assert_eq!(
            evidence(&vec![(5.0, 5.0); 100], false).wiring(),
            Wiring::Inconclusive
        );
    }

    #[test]
    fn measurements_scattering_beyond_their_sigma_widen_the_std() {
        let p = CheckParams::default();
        // The same course, V and W measured with errors of ~10 σ.
        let mut ev = Evidence::default();
        for (i, &(r, l)) in course().iter().enumerate() {
            let (v, w) = (0.1 * (r + l) / 2.0, 0.1 * (r - l) / 0.5);
            let e = 1e-2 * [1.0, -1.0, 0.5, -0.5][i % 4];
            let t = i as f64 * 0.1;
            ev.add(
                &CalibStep::new(t, t + 0.1, r, l)
                    .with(crate::calib::Kind::V, v + e, 1e-3)
                    .with(crate::calib::Kind::W, w - e, 1e-3),
            );
        }
        let [v, w] = ev.fit_chi2().map(Option::unwrap);
        assert!(v > 30.0 && w > 30.0, "{v} {w}");
        let o = observability(&ev, &drive(0.001), &drive(0.5), &p, false);
        let r = &o.parameters["r_right"];
        assert!(r.observable && r.weak && r.missing.as_ref().unwrap().contains("χ²"));
        // `drive(0.001)` as the filter's std: 0.1 m for each radius.
        assert!((r.std / 0.1 - v.sqrt()).abs() < 1e-9, "{}", r.std);
        // Exact measurements: no widening.
        let exact = observability(
            &evidence(&course(), false),
            &drive(0.001),
            &drive(0.5),
            &p,
            false,
        );
        assert_eq!(exact.parameters["r_right"].std, 0.1);
    }

    #[test]
    fn absurd_estimates_and_range_edges_are_refused() {
        let p = CheckParams::default();
        let nominal = drive(0.5);
        assert!(implausible(&drive(0.52), &nominal, None, &p).is_none());
        let far = implausible(&drive(0.75), &nominal, None, &p).unwrap();
        assert!(far.contains("wheel_base") && far.contains("1.500"), "{far}");
        let r = crate::calib::Ranges::around(0.1, 0.1, 0.5, 0.05).all();
        let edge = implausible(&drive(0.475), &nominal, Some(r), &p).unwrap();
        assert!(edge.contains("edge"), "{edge}");
    }
}
