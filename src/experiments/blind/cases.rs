//! The cases of the blind diagnosis suite: no effect at all, every effect of
//! the table alone at a realistic magnitude, pairs and triples, and the
//! faults outside the table. Each case says what the simulator hides and
//! what a right diagnosis names.

use crate::effects::{Effect, FaultEffect};
use serde::Serialize;

/// Which family a case belongs to (a row group of the table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Group {
    /// Nothing hidden: the right answer is `no-discrepancy`.
    Null,
    /// One effect of the table.
    Single,
    /// Two effects of the table.
    Pair,
    /// Three effects of the table.
    Triple,
    /// A fault outside the table, to be named under its own name.
    Fault,
}

impl Group {
    /// The name used in `[diagnose] groups` and the table.
    pub fn name(self) -> &'static str {
        match self {
            Self::Null => "null",
            Self::Single => "single",
            Self::Pair => "pair",
            Self::Triple => "triple",
            Self::Fault => "fault",
        }
    }

    /// Every group, in table order.
    pub const ALL: [Self; 5] = [
        Self::Null,
        Self::Single,
        Self::Pair,
        Self::Triple,
        Self::Fault,
    ];
}

/// One hidden configuration of the simulated robot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Case {
    /// Short label (table row).
    pub label: String,
    /// Its family.
    pub group: Group,
    /// The effects the simulator injects (never shown to the diagnosis).
    pub effects: Vec<Effect>,
    /// The faults outside the table it injects.
    pub faults: Vec<FaultEffect>,
    /// Names a right diagnosis gives: the table effects' names, or the
    /// fault's own name.
    pub expect: Vec<String>,
    /// Names a right diagnosis may give besides (a latency that changes has
    /// a mean latency; slip on part of the floor a mean radius scale).
    pub allowed: Vec<String>,
}

fn e(spec: &str) -> Effect {
    Effect::parse(spec).expect("the suite's specs are valid")
}

/// A case of table effects: named by their own names.
fn table_case(group: Group, label: &str, specs: &[&str]) -> Case {
    let effects: Vec<Effect> = specs.iter().map(|s| e(s)).collect();
    let mut expect: Vec<String> = effects.iter().map(|x| x.name().to_string()).collect();
    expect.dedup();
    Case {
        label: label.into(),
        group,
        effects,
        faults: Vec::new(),
        expect,
        allowed: Vec::new(),
    }
}

/// A case of one fault outside the table: named by the fault's own name
/// (`expect`, as the diagnosis names it).
fn fault_case(label: &str, spec: &str, expect: &str, allowed: &[&str]) -> Case {
    Case {
        label: label.into(),
        group: Group::Fault,
        effects: Vec::new(),
        faults: vec![FaultEffect::parse(spec).expect("the suite's specs are valid")],
        expect: vec![expect.into()],
        allowed: allowed.iter().map(|s| s.to_string()).collect(),
    }
}

/// A radius step at `frac` of a run of `duration` s (inside the training part).
fn step_spec(duration: f64, frac: f64, right: f64, left: f64) -> String {
    format!(
        "radius_step:time={:.1},right={right},left={left}",
        duration * frac
    )
}

/// The half of a built-in scenario's area (world x range, m) where the
/// floor-slip case's floor is slippery: the half of the path's x range
/// above its middle, so the chair crosses in and out of it.
pub fn slippery_half(scenario: &str) -> (f64, f64) {
    match scenario {
        "corridor-loop" | "hall" => (15.0, 30.0),
        "square" | "square-ccw" => (5.0, 10.0),
        "figure-eight" => (24.0, 30.0),
        _ => (10.0, 20.0),
    }
}

/// The case's faults placed in `scenario` (a floor-slip band is put on
/// [`slippery_half`]).
pub fn placed(case: &Case, scenario: &str) -> Vec<FaultEffect> {
    case.faults
        .iter()
        .map(|f| match *f {
            FaultEffect::FloorSlip { slip, .. } => {
                let (x_min, x_max) = slippery_half(scenario);
                FaultEffect::FloorSlip { x_min, x_max, slip }
            }
            other => other,
        })
        .collect()
}

/// Every case of the suite for runs of `duration` s, in table order.
/// Magnitudes are those of real chairs: radii off by 1–2 %, a wheel base
/// off by 3–4 %, a new user boarding (4–5 mm), tens of milliseconds of
/// latency, a laser a few centimetres and a degree off its drawing, a MEMS
/// gyro's bias of a few tenths of a degree per second.
pub fn cases(duration: f64) -> Vec<Case> {
    use Group::*;
    let step = step_spec(duration, 0.3, 0.004, -0.003);
    let step2 = step_spec(duration, 0.5, -0.003, 0.0);
    let mut v = vec![Case {
        label: "none".into(),
        group: Null,
        effects: Vec::new(),
        faults: Vec::new(),
        expect: Vec::new(),
        allowed: Vec::new(),
    }];
    v.extend(single_cases(&step));
    v.extend(combination_cases(&step, &step2));
    v.extend(fault_cases(duration));
    v
}

/// Every table effect alone.
fn single_cases(step: &str) -> Vec<Case> {
    use Group::*;
    let mut v = Vec::new();
    for (label, spec) in [
        (
            "radius_scale (+1.5 %, −1 %)",
            "radius_scale:right=0.015,left=-0.01",
        ),
        (
            "radius_scale (+1 %, +2 %)",
            "radius_scale:right=0.01,left=0.02",
        ),
        ("wheel_base_scale (+4 %)", "wheel_base_scale:scale=0.04"),
        ("wheel_base_scale (−3 %)", "wheel_base_scale:scale=-0.03"),
        ("radius_step (+4, −3 mm)", step),
        (
            "radius_drift (−0.08, −0.03 m/h)",
            "radius_drift:right=-0.08,left=-0.03",
        ),
        ("encoder_gain (0.01 s/rad)", "encoder_gain:k=0.01"),
        ("latency (40 ms)", "latency:delay=0.04"),
        (
            "laser_offset (5 cm, 2 cm, 1.1°)",
            "laser_offset:x=0.05,y=0.02,yaw=0.02",
        ),
        ("gyro_bias (0.3 °/s)", "gyro_bias:bias=0.005"),
        ("turn_slip (0.1 s/rad)", "turn_slip:k=0.1"),
    ] {
        v.push(table_case(Single, label, &[spec]));
    }
    v
}

/// Two radius steps, pairs and triples of table effects.
fn combination_cases(step: &str, step2: &str) -> Vec<Case> {
    use Group::*;
    let steps = [step, step2];
    let mut v = Vec::new();
    v.push(table_case(Single, "two radius steps", &steps));
    for (label, specs) in [
        (
            "radius_scale + latency",
            &["radius_scale:right=0.015,left=-0.01", "latency:delay=0.04"][..],
        ),
        (
            "wheel_base_scale + laser_offset",
            &[
                "wheel_base_scale:scale=0.04",
                "laser_offset:x=0.05,y=0.02,yaw=0.02",
            ][..],
        ),
        (
            "radius_scale + radius_step",
            &["radius_scale:right=0.012,left=-0.008", step][..],
        ),
        (
            "gyro_bias + turn_slip",
            &["gyro_bias:bias=0.005", "turn_slip:k=0.1"][..],
        ),
    ] {
        v.push(table_case(Pair, label, specs));
    }
    v.push(table_case(
        Triple,
        "radius_scale + wheel_base_scale + latency",
        &[
            "radius_scale:right=0.015,left=-0.01",
            "wheel_base_scale:scale=0.04",
            "latency:delay=0.04",
        ],
    ));
    v.push(table_case(
        Triple,
        "radius_step + laser_offset + gyro_bias",
        &[
            step,
            "laser_offset:x=0.05,y=0.02,yaw=0.02",
            "gyro_bias:bias=0.005",
        ],
    ));
    v
}

/// The faults outside the table.
fn fault_cases(duration: f64) -> Vec<Case> {
    let mut v = Vec::new();
    let change = format!("latency_change:time={:.1},delay=0.06", 0.5 * duration);
    let knock = format!(
        "laser_knock:time={:.1},dx=0,dy=0,dyaw=0.035",
        0.5 * duration
    );
    for (label, spec, expect, allowed) in [
        (
            "swapped wheels",
            "swapped_wheels",
            "swapped_wheels",
            &[][..],
        ),
        (
            "left encoder reversed",
            "reversed_left_encoder",
            "reversed_left_encoder",
            &[],
        ),
        (
            "right wheel out of round (1 %)",
            "wheel_out_of_round:right=0.01,left=0",
            "wheel_out_of_round",
            &[],
        ),
        (
            "slip on part of the floor (10 %, half the area)",
            "floor_slip:x_min=0,x_max=0,slip=0.1",
            "floor_slip",
            &["radius_scale", "radius_step", "radius_drift"],
        ),
        (
            "latency +60 ms halfway",
            change.as_str(),
            "latency_change",
            &["latency"],
        ),
        (
            "laser knocked 2° halfway",
            knock.as_str(),
            "laser_knock",
            &["laser_offset"],
        ),
    ] {
        v.push(fault_case(label, spec, expect, allowed));
    }
    v
}
