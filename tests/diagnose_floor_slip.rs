//! A slip of 3 % on half of the square room's floor through the whole chain
//! (simulate → bag → ICP → diagnose): named as `floor_slip` with its size
//! within 20 %, and no table effect beside it. The negative control is the
//! same run with the slip left out, on which the same assertion fails.

use crate::support::{odocal, ok_json, scratch};
use serde_json::Value;

/// The diagnosis of a 90 s square run (seed 302) whose wheels over-read by
/// `slip` where the world's x lies in [5, 10) m (none for `None`).
fn square(slip: Option<f64>) -> Value {
    let dir = scratch("diagnose_floor_slip");
    let name = slip.map_or("none".to_string(), |s| format!("{s}"));
    let bag = dir.join(format!("square-{name}.mcap"));
    let mut args = vec![
        "simulate".to_string(),
        "--scenario".into(),
        "square".into(),
        "--seed".into(),
        "302".into(),
        "--duration".into(),
        "90".into(),
        "--out".into(),
        bag.to_str().unwrap().into(),
    ];
    if let Some(s) = slip {
        args.extend([
            "--effect".into(),
            format!("floor_slip:x_min=5,x_max=10,slip={s}"),
        ]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let sim = odocal(&args);
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    ok_json(&odocal(&[
        "diagnose",
        "--measured",
        bag.to_str().unwrap(),
        "--json",
    ]))
}

/// Whether `d` names a floor slip within 20 % of `want` and no table effect.
fn names_the_slip(d: &Value, want: f64) -> Result<(), String> {
    let slip = d["faults"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["name"] == "floor_slip")
        .and_then(|f| f["parameters"]["slip"].as_f64())
        .ok_or_else(|| format!("no floor_slip: {}", d["faults"]))?;
    if (slip / want - 1.0).abs() > 0.2 {
        return Err(format!("slip {slip} against {want}"));
    }
    let causes = d["causes"].as_array().unwrap();
    if !causes.is_empty() {
        return Err(format!("table effects beside it: {causes:?}"));
    }
    Ok(())
}

#[test]
fn a_three_percent_floor_slip_is_named_as_the_floor() {
    let d = square(Some(0.03));
    names_the_slip(&d, 0.03).unwrap_or_else(|e| panic!("{e}: {d}"));
    assert_ne!(d["verdict"], "no-discrepancy", "{d}");
    // Negative control: the same run without the slip.
    let clean = square(None);
    assert!(names_the_slip(&clean, 0.03).is_err(), "{clean}");
}
