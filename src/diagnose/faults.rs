//! Faults outside the effect table, named by their own names and never
//! fitted as a table effect: wheels wired the wrong way (swapped joints, an
//! encoder counting backwards) and out-of-round wheels.
//!
//! Wiring: the calibration's own test ([`crate::calib::Evidence::wiring`]:
//! the measured turn rate and speed regressed on the two wheel rates, seed
//! 000 Eq. 1 wants W rising with the right wheel and falling with the left)
//! on the ICP motions; a miswired stream is corrected before the replay, so
//! the table effects are still diagnosed, and the fault is reported with its
//! fix.

use super::diagnosis::{Fault, Remaining};
use crate::calib::{Evidence, Wiring};
use crate::motion::{Motion, VelocityObs};
use crate::recording::WheelSample;
use std::collections::BTreeMap;

/// The wiring the wheel rates show against the scan matching.
pub fn wiring(wheels: &[WheelSample], motions: &[Motion]) -> Wiring {
    let obs: Vec<VelocityObs> = motions
        .iter()
        .filter_map(VelocityObs::from_motion)
        .collect();
    let mut ev = Evidence::default();
    for s in crate::calib::steps(&obs, wheels, &[], 1.0) {
        ev.add(&s);
    }
    ev.wiring()
}

/// How a miswired sample is put right: (right, left) from the sample.
type Rewire = fn(&WheelSample) -> (f64, f64);

/// The wheel streams as they should have been wired, and the fault, when
/// the wiring is wrong (`None` when it is consistent or cannot be told).
pub fn rewire(wheels: &[WheelSample], w: Wiring) -> Option<(Vec<WheelSample>, Fault)> {
    let (name, map): (&str, Rewire) = match w {
        Wiring::Swapped => ("swapped_wheels", |s| (s.left, s.right)),
        Wiring::LeftReversed => ("reversed_left_encoder", |s| (s.right, -s.left)),
        Wiring::RightReversed => ("reversed_right_encoder", |s| (-s.right, s.left)),
        Wiring::BothReversed => ("reversed_encoders", |s| (-s.right, -s.left)),
        Wiring::Consistent | Wiring::Inconclusive => return None,
    };
    let fixed = wheels
        .iter()
        .map(|s| {
            let (right, left) = map(s);
            WheelSample {
                stamp: s.stamp,
                right,
                left,
            }
        })
        .collect();
    let fault = Fault {
        name: name.into(),
        parameters: BTreeMap::new(),
        evidence: "the scan-matched turn rate regressed on the two wheel rates has the signs \
                   of this wiring (W must rise with the right wheel and fall with the left); \
                   the diagnosis below replays the wheels rewired"
            .into(),
        fix: w.fault().unwrap_or_default().to_string(),
    };
    Some((fixed, fault))
}

/// The name of an out-of-round wheel's fault.
pub const OUT_OF_ROUND: &str = "wheel_out_of_round";

/// An out-of-round wheel from the periodic structure the extended model
/// leaves in stream `g` (`periodic` that test's finding, `coefficients` on
/// ω_R cos φ_R, ω_R sin φ_R, ω_L cos φ_L, ω_L sin φ_L in the stream's unit
/// per rad/s): each wheel's radius wobble relative to its radius.
pub fn out_of_round(
    periodic: &Remaining,
    coefficients: &[f64; 4],
    g: usize,
    robot: &crate::robot::RobotConfig,
) -> Fault {
    let rel = |a: f64, b: f64| super::remaining::wobble(a.hypot(b), g, robot);
    let mut parameters = BTreeMap::new();
    parameters.insert("right".to_string(), rel(coefficients[0], coefficients[1]));
    parameters.insert("left".to_string(), rel(coefficients[2], coefficients[3]));
    Fault {
        name: OUT_OF_ROUND.into(),
        parameters,
        evidence: format!(
            "the {} residual follows the sine and cosine of the wheel angles, once per \
             revolution (p = {:.1e}, Newey–West); sizes are each wheel's radius wobble \
             relative to its radius",
            periodic.stream, periodic.p_value
        ),
        fix: "true the wheel or replace the tyre; no constant calibration removes a \
              once-per-revolution radius change"
            .into(),
    }
}

/// The name of a gyro whose turn scale the scan matching contradicts.
pub const GYRO_SCALE: &str = "gyro_scale";

/// A gyro reading turns (1 + `scale`) times the scan matching
/// ([`super::gyro_check`]). Parameters: `scale` (relative) and
/// `scale_stderr`, `segments` compared.
pub fn gyro_scale(s: &super::gyro_check::GyroScale) -> Fault {
    let mut parameters = BTreeMap::new();
    parameters.insert("scale".to_string(), s.scale);
    parameters.insert("scale_stderr".to_string(), s.stderr);
    parameters.insert("segments".to_string(), s.segments as f64);
    Fault {
        name: GYRO_SCALE.into(),
        parameters,
        evidence: format!(
            "over {} one-second segments the gyro's turn is {:+.2} ± {:.2} % of the \
             scan-matched turn (least squares with a bias; jackknife over stretches of the \
             run), before any effect of the robot is fitted; the fit below leaves the gyro \
             out",
            s.segments,
            100.0 * s.scale,
            100.0 * s.stderr
        ),
        fix: format!(
            "correct the gyro's scale factor (divide its rate by {:.4}) or recalibrate the \
             IMU; no wheel parameter removes a gyro scale",
            1.0 + s.scale
        ),
    }
}

/// Slip on part of the floor from the region model fitted against the
/// selected table effects ([`super::floor`]). Parameters: `slip` (relative
/// over-reading of both wheels inside the region against the rest of the
/// path) and `slip_stderr` (the Newey–West one and `slip_systematic`, what
/// the scan matching's own place-dependent scale leaves, in quadrature); the region as a band of the scan-matched path
/// (origin and axes at its start pose): `axis` (rad), `from`, `to` (m along
/// it, ±∞ when open), and the box the path covers inside it, `x_min`,
/// `x_max`, `y_min`, `y_max` (m); `share` of the ICP rows inside.
pub fn floor_slip(f: &super::floor::SlipFit) -> Fault {
    use super::floor::SYSTEMATIC_SLIP;
    let r = &f.region;
    let share = f.rows.0 as f64 / f.rows.1.max(1) as f64;
    let mut parameters = BTreeMap::new();
    for (k, v) in [
        ("slip", f.slip),
        ("slip_stderr", f.stderr.hypot(SYSTEMATIC_SLIP)),
        ("axis", r.angle),
        ("from", r.lo),
        ("to", r.hi),
        ("slip_systematic", SYSTEMATIC_SLIP),
        ("x_min", f.bbox[0]),
        ("x_max", f.bbox[1]),
        ("y_min", f.bbox[2]),
        ("y_max", f.bbox[3]),
        ("share", share),
    ] {
        // An open side of the band has no bound (JSON has no infinity).
        if v.is_finite() {
            parameters.insert(k.to_string(), v);
        }
    }
    let bound = |v: f64| {
        if v.is_finite() {
            format!("{v:.1} m")
        } else {
            "the path's end".to_string()
        }
    };
    Fault {
        name: "floor_slip".into(),
        parameters,
        evidence: format!(
            "before any effect is fitted, forward speed and turn rate both read \
             {:.1} ± {:.1} % (statistical; ± {:.1} % place-dependent scan-matching scale, \
             from null runs) more from the wheels than from the scan matching in one region \
             of the path than elsewhere (z = {:.1}, Newey–West; likelihood ratio {:.0} against \
             constant radii and wheel base (linearised); the region searched over bands of the path), and \
             still so against the effects fitted outside it; region: along the axis at \
             {:.0}° from {} to {} of the scan-matched path (origin and axes at its start \
             pose), x {:.1}…{:.1} m, y {:.1}…{:.1} m, {:.0} % of the rows; the effects \
             below are fitted with the measurements there scaled by that slip and the \
             rows within 1 m of the region's bounds left out",
            100.0 * f.slip,
            100.0 * f.stderr,
            100.0 * SYSTEMATIC_SLIP,
            f.z.abs(),
            f.lr,
            r.angle.to_degrees(),
            bound(r.lo),
            bound(r.hi),
            f.bbox[0],
            f.bbox[1],
            f.bbox[2],
            f.bbox[3],
            100.0 * share
        ),
        fix: "the floor there lets the wheels spin (wet, dusty, loose, a ramp): odometry \
              over it cannot be calibrated by constants; trust the scan matching there, \
              weight the wheels down, or keep calibration drives off that area"
            .into(),
    }
}

/// The name of tyres whose rolling radius follows their load.
pub const TYRE_LOAD_TRANSFER: &str = "tyre_load_transfer";

/// The encoder gain a load law was compared with ([`super::load::compare`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainAlternative {
    /// The selection's encoder gain (s/rad).
    pub gain: f64,
    /// Vuong's z of the load law against it (positive favours the load).
    pub vuong_z: f64,
    /// Whether the gain was rejected (else the run cannot tell them apart).
    pub told_apart: bool,
}

impl GainAlternative {
    /// The comparison `f` read at `reading`, the gain `gain` (s/rad).
    pub fn of(f: &super::load::LoadFit, reading: super::load::Reading, gain: f64) -> Self {
        Self {
            gain,
            vuong_z: f.vuong_z,
            told_apart: reading == super::load::Reading::Load,
        }
    }
}

/// Tyres whose radius follows their load ([`super::load`]): each radius
/// shorter on the outer wheel and longer on the inner by κ v ω, compared
/// with the encoder gain `alt` (`on_scale`: on ICP rows read on the scan
/// matcher's scale). Parameters: `kappa` (relative radius change per m/s²
/// of lateral acceleration, s²/m) and `kappa_stderr` (Newey–West),
/// `encoder_gain_alternative` (the gain, s/rad), `vuong_z` (the load law
/// against it; positive favours the load) and `told_apart` (1 when the
/// gain is rejected, 0 when the run's speeds cannot tell the two apart).
pub fn tyre_load_transfer(k: &super::load::Kappa, alt: GainAlternative, on_scale: bool) -> Fault {
    let mut parameters = BTreeMap::new();
    for (key, v) in [
        ("kappa", k.kappa),
        ("kappa_stderr", k.stderr),
        ("encoder_gain_alternative", alt.gain),
        ("vuong_z", alt.vuong_z),
        ("told_apart", f64::from(u8::from(alt.told_apart))),
    ] {
        parameters.insert(key.to_string(), v);
    }
    let against = if alt.told_apart {
        format!(
            "an encoder over-reading with its rate fits worse (Vuong z = {:+.1})",
            alt.vuong_z
        )
    } else {
        format!(
            "an encoder over-reading with its rate (encoder_gain k = {:.4} s/rad) fits as \
             well (Vuong z = {:+.1}): at one speed the two are one law, and this run's \
             changes of speed do not tell them apart; a drive that takes the same turns \
             at two speeds does",
            alt.gain, alt.vuong_z
        )
    };
    let rows = if on_scale {
        " (on ICP's rows read on the scan matcher's own scale: along a corridor ICP \
         reads the forward speed short by about what the load makes the radii short)"
    } else {
        ""
    };
    Fault {
        name: TYRE_LOAD_TRANSFER.into(),
        parameters,
        evidence: format!(
            "the wheels over-read in turns by a lateral-acceleration law: each radius \
             {:.2} ± {:.2} % shorter on the outer wheel and longer on the inner per m/s² \
             of v·ω (Newey–West), what tyres deflecting under the load a turn moves \
             outwards do{rows}; {against}; the effects below are fitted with that part \
             taken out",
            100.0 * k.kappa,
            100.0 * k.stderr
        ),
        fix: "the tyres deflect with load (pressure low, soft tyres, a high centre of \
              mass): inflate or stiffen them, or calibrate at the turns and speeds the \
              robot drives; constant radii hold only on average"
            .into(),
    }
}

/// What stays open when a run cannot tell tyres deflecting under load from
/// an encoder gain ([`super::load::Reading::Either`]): the over-reading in
/// the turn-rate stream, with the gain's reading in full (`gain_reading`:
/// the effects that reading names) in its reason.
pub fn load_or_gain(
    f: &super::load::LoadFit,
    gain_reading: &[crate::effects::Effect],
) -> Remaining {
    let p_value = f.load.p_value;
    let effects: Vec<String> = gain_reading
        .iter()
        .map(|e| {
            let p: Vec<String> = e
                .params()
                .iter()
                .map(|(k, v)| format!("{k} {v:.4}"))
                .collect();
            format!("{} ({})", e.name(), p.join(", "))
        })
        .collect();
    Remaining {
        stream: "icp_w".into(),
        structure: "speed-dependent".into(),
        size: crate::effects::Departures::of(gain_reading).encoder_gain,
        unit: "s/rad (the encoder gain's k)".into(),
        p_value,
        source: super::diagnosis::ROBOT.into(),
        reason: Some(format!(
            "the wheels over-read with speed in turns, either by tyres deflecting under \
             load ({TYRE_LOAD_TRANSFER}: the causes and the fault named) or by encoders \
             over-reading with their rate (then: {}); this run's speeds cannot tell them \
             apart (Vuong z = {:+.1}); drive the same turns at two speeds to decide",
            effects.join(", "),
            f.vuong_z
        )),
    }
}
