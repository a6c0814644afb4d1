//! The ros2_control YAML odocal writes, read back by an independent YAML
//! parser: whatever the joint names and the comment text (a file name, a
//! note), the file parses, holds exactly the controller's keys, and gives
//! back every number to its six printed decimals and every name exactly.
#![no_main]
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;
use odocal::pipeline::paste::{controller_yaml, ControllerParams, CONTROLLER};
use serde_yaml_ng::Value;

#[derive(Debug, Arbitrary)]
struct Input {
    numbers: [f64; 5],
    names: Option<(Vec<String>, Vec<String>)>,
    comments: Vec<String>,
}

fuzz_target!(|input: Input| {
    // Calibrated values are finite and of a robot's size.
    let numbers = input
        .numbers
        .map(|v| if v.is_finite() { v % 1e6 } else { 1.0 });
    let (left, right) = input.names.clone().unzip();
    let p = ControllerParams {
        wheel_radius: numbers[0],
        wheel_separation: numbers[1],
        left_wheel_radius_multiplier: numbers[2],
        right_wheel_radius_multiplier: numbers[3],
        wheel_separation_multiplier: numbers[4],
        left_wheel_names: left,
        right_wheel_names: right,
    };
    let yaml = controller_yaml(&p, &input.comments);
    let doc: Value = serde_yaml_ng::from_str(&yaml)
        .unwrap_or_else(|e| panic!("odocal's YAML does not parse: {e}\n{yaml}"));
    let root = doc.as_mapping().expect("a mapping");
    assert_eq!(root.len(), 1, "one controller key:\n{yaml}");
    let params = &doc[CONTROLLER]["ros__parameters"];
    let keys = [
        "wheel_radius",
        "wheel_separation",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
        "wheel_separation_multiplier",
    ];
    for (k, want) in keys.iter().zip(numbers) {
        let got = params[*k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number:\n{yaml}"));
        assert!(
            (got - want).abs() <= 5.0e-7 + 1e-12 * (1.0 + want.abs()),
            "{k}: {got} vs {want}"
        );
    }
    let names = |k: &str| -> Option<Vec<String>> {
        params[k].as_sequence().map(|s| {
            s.iter()
                .map(|v| v.as_str().expect("a name is a string").to_string())
                .collect()
        })
    };
    match &input.names {
        Some((l, r)) => {
            assert_eq!(names("left_wheel_names").as_ref(), Some(l), "{yaml}");
            assert_eq!(names("right_wheel_names").as_ref(), Some(r), "{yaml}");
        }
        None => assert!(params.get("left_wheel_names").is_none(), "{yaml}"),
    }
});
