//! What users paste after `calibrate`: the ros2_control YAML read back with
//! a YAML parser gives, through diff_drive_controller's own arithmetic
//! (radius × multiplier, separation × multiplier), the radii and axle Censi
//! et al. published for their Khepera; the URDF joint and the
//! static-transform line put the laser where the authors found it. Both are
//! in `--json` and `summary.json` and written into the output directory.

use crate::support::{scratch, shared_data};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn calibrate(input: &Path, robot: &str, method: &str, out: &Path) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["calibrate", "--input"])
        .arg(input)
        .args(["--robot", robot, "--method", method, "--out"])
        .arg(out)
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `diff_drive_controller`'s effective right radius, left radius and
/// separation from the YAML file, as the controller computes them.
fn effective(yaml: &str) -> [f64; 3] {
    let v: serde_yaml_ng::Value = serde_yaml_ng::from_str(yaml).expect("valid YAML");
    let p = &v["diff_drive_controller"]["ros__parameters"];
    let f = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k} in {yaml}"));
    [
        f("wheel_radius") * f("right_wheel_radius_multiplier"),
        f("wheel_radius") * f("left_wheel_radius_multiplier"),
        f("wheel_separation") * f("wheel_separation_multiplier"),
    ]
}

/// The `<origin xyz=".." rpy=".."/>` numbers of a URDF joint.
fn origin(urdf: &str) -> [f64; 6] {
    let attr = |name: &str| -> Vec<f64> {
        let at = urdf.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
        let end = at + urdf[at..].find('"').unwrap();
        urdf[at..end]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let (xyz, rpy) = (attr("xyz"), attr("rpy"));
    [xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]]
}

#[test]
fn pasted_parameters_give_the_authors_khepera_and_laser() {
    let Some(d) = shared_data("paste_censi") else {
        return;
    };
    let out = scratch("paste_censi");
    let tuples = d.join("censi-calibration/lstraight.tuple");
    let v = calibrate(&tuples, "khepera", "batch", &out);
    let yaml = std::fs::read_to_string(out.join("ros2_control.yaml")).unwrap();
    assert_eq!(yaml, v["ros2_control"]["yaml"].as_str().unwrap());
    // Authors (lstraight_results.json): diameters, axle, laser pose.
    let a: Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("censi-calibration/lstraight_results.json")).unwrap(),
    )
    .unwrap();
    let num = |k: &str| a[k].as_f64().unwrap();
    let want = [num("r_diam") / 2.0, num("l_diam") / 2.0, num("axle")];
    let laser = [num("l_x"), num("l_y"), num("l_theta")];
    // Radii and axle within 0.2 %, the laser within 0.5 mm and 1 mrad (the
    // batch on these tuples: 0.07 %, 0.04 mm, 0.1 mrad).
    let agrees = |kin: [f64; 3], mount: [f64; 3]| -> Result<(), String> {
        for (got, want) in kin.iter().zip(want) {
            if (got / want - 1.0).abs() >= 0.002 {
                return Err(format!("{got} vs {want}"));
            }
        }
        for (k, (got, want)) in mount.iter().zip(laser).enumerate() {
            if (got - want).abs() >= [5e-4, 5e-4, 1e-3][k] {
                return Err(format!("laser {k}: {got} vs {want}"));
            }
        }
        Ok(())
    };
    // The Khepera's nominal 21 mm radius is the controller's wheel_radius.
    let p = &v["ros2_control"]["parameters"];
    assert_eq!(p["wheel_radius"], 0.021);
    assert_eq!(p["wheel_separation"], 0.09);
    // Tuples carry no joint names.
    assert!(p.get("left_wheel_names").is_none());

    let urdf = std::fs::read_to_string(out.join("laser_mount.urdf")).unwrap();
    let o = origin(&urdf);
    agrees(effective(&yaml), [o[0], o[1], o[5]]).unwrap();
    // The negative control: the robot file's nominal values (21 / 21 / 90
    // mm, the laser at the origin) fail the same check.
    assert!(agrees([0.021, 0.021, 0.090], [0.0; 3]).is_err());
    assert_eq!([o[2], o[3], o[4]], [0.0, 0.0, 0.0]);
    let line = v["laser_mount"]["static_transform"].as_str().unwrap();
    assert!(line.contains("--frame-id base_link") && line.contains(&format!("--x {:.6}", o[0])));
    assert!(
        urdf.contains(line),
        "the URDF file carries the command line too"
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ros2_control"], v["ros2_control"]);
    assert_eq!(summary["laser_mount"], v["laser_mount"]);
}

#[test]
fn a_filter_run_writes_the_controller_yaml_with_its_estimate_and_joints() {
    let out = scratch("paste_filter");
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/wheelchair-corridor.mcap");
    let v = calibrate(&bundled, "wheelchair", "dkf", &out);
    let yaml = std::fs::read_to_string(out.join("ros2_control.yaml")).unwrap();
    let e = effective(&yaml);
    let f = &v["final"];
    let fin = [&f["r_right"], &f["r_left"], &f["wheel_base"]].map(|x| x.as_f64().unwrap());
    for (a, b) in e.iter().zip(fin) {
        assert!((a - b).abs() < 2e-6, "{a} vs {b}");
    }
    // The simulator's truth (scans/wheelchair-corridor.truth.json) at the end
    // of the run: radii 318.84 / 321.44 mm, wheel base 0.65 m. Each within
    // 1 %, and the left radius's lead over the right (2.60 mm, the step
    // the run holds) within 20 % (the DKF: 2.86 mm).
    let truth = [0.31884, 0.32144, 0.65];
    let agrees = |k: [f64; 3]| -> Result<(), String> {
        for (a, t) in k.iter().zip(truth) {
            if (a / t - 1.0).abs() >= 0.01 {
                return Err(format!("{a} vs truth {t}"));
            }
        }
        let (lead, want) = (k[1] - k[0], truth[1] - truth[0]);
        if (lead - want).abs() >= 0.2 * want {
            return Err(format!("left over right {lead} m vs {want} m"));
        }
        Ok(())
    };
    agrees(e).unwrap();
    // The negative control: the chair's nominal 0.32 / 0.32 / 0.65 m fails.
    assert!(agrees([0.32, 0.32, 0.65]).is_err());
    let ys: serde_yaml_ng::Value = serde_yaml_ng::from_str(&yaml).unwrap();
    let p = &ys["diff_drive_controller"]["ros__parameters"];
    assert_eq!(p["left_wheel_names"][0].as_str(), Some("left_wheel"));
    assert_eq!(p["right_wheel_names"][0].as_str(), Some("right_wheel"));
    // No mounting was estimated: no URDF snippet.
    assert!(v.get("laser_mount").is_none());
    assert!(!out.join("laser_mount.urdf").exists());
}
