//! An output set is one run's: two concurrent runs on the same `--out DIR`
//! either run one after the other or the second is refused naming the lock,
//! and the files left are always those of one run (the summary's final
//! estimate is the history's last row, its iteration count the history's
//! length); a run that fails mid-way leaves neither temporary files nor its
//! lock behind, and the previous set as it was.

use crate::support::scratch;
use std::path::Path;
use std::process::{Child, Command, Stdio};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

fn calibrate(input: &Path, out: &Path, method: &str) -> Child {
    Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["calibrate", "--input"])
        .arg(input)
        .args(["--method", method, "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run odocal")
}

/// Names in `dir` that are not one of calibrate's three outputs.
fn strays(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            ![
                "calibration.csv",
                "trajectory.tum",
                "summary.json",
                "ros2_control.yaml",
            ]
            .contains(&n.as_str())
        })
        .collect()
}

/// The summary's method and whether its final estimate and iteration count
/// are those of the history file beside it (i.e. both come from one run).
fn one_run(dir: &Path) -> String {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let history = std::fs::read_to_string(dir.join("calibration.csv")).unwrap();
    let yaml = std::fs::read_to_string(dir.join("ros2_control.yaml")).unwrap();
    assert_eq!(
        yaml,
        summary["ros2_control"]["yaml"].as_str().unwrap(),
        "summary and controller parameters from different runs"
    );
    let rows: Vec<&str> = history.lines().skip(1).collect();
    assert_eq!(
        summary["iterations"].as_u64().unwrap() as usize,
        rows.len(),
        "summary and history from different runs"
    );
    let last: Vec<f64> = rows
        .last()
        .unwrap()
        .split(',')
        .take(9)
        .map(|x| x.parse().unwrap())
        .collect();
    for (i, key) in ["r_right", "r_left", "wheel_base"].iter().enumerate() {
        let s = summary["final"][key].as_f64().unwrap();
        assert!(
            (s - last[i + 1]).abs() < 1e-8,
            "{key}: summary {s} but history {}: files of two runs",
            last[i + 1]
        );
    }
    summary["method"].as_str().unwrap().to_string()
}

#[test]
fn concurrent_runs_on_one_directory_never_mix() {
    let d = scratch("sets_concurrent");
    let out = d.join("cal");
    let mut refused = 0;
    for round in 0..3 {
        let a = calibrate(Path::new(BUNDLED), &out, "adaptive-pf");
        let b = calibrate(Path::new(BUNDLED), &out, "dkf");
        for child in [a, b] {
            let o = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            match o.status.code() {
                Some(0) => {}
                Some(2) => {
                    assert!(err.contains(".cal.lock"), "round {round}: {err}");
                    assert!(err.contains("is being written"), "round {round}: {err}");
                    refused += 1;
                }
                c => panic!("round {round}: exit {c:?}: {err}"),
            }
        }
        let method = one_run(&out);
        assert!(["adaptive-pf", "dkf"].contains(&method.as_str()));
        assert!(strays(&out).is_empty(), "left: {:?}", strays(&out));
        assert!(!d.join(".cal.lock").exists(), "lock removed");
    }
    eprintln!("concurrent calibrations: {refused} of 3 second runs refused");
}

#[test]
fn a_run_failing_mid_way_leaves_the_previous_set_and_no_temporaries() {
    let d = scratch("sets_midway");
    let out = d.join("cal");
    let o = calibrate(Path::new(BUNDLED), &out, "dkf")
        .wait_with_output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let set = [
        "calibration.csv",
        "trajectory.tum",
        "summary.json",
        "ros2_control.yaml",
    ];
    let before: Vec<Vec<u8>> = set
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    // The bundled bag cut at 60 %: the stream fails after many rows.
    let bytes = std::fs::read(BUNDLED).unwrap();
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
    let o = calibrate(&cut, &out, "adaptive-pf")
        .wait_with_output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("cut.mcap"), "{err}");
    let after: Vec<Vec<u8>> = set
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    assert!(before == after, "the previous set is untouched");
    assert_eq!(one_run(&out), "dkf");
    assert!(strays(&out).is_empty(), "left: {:?}", strays(&out));
    assert!(!d.join(".cal.lock").exists(), "lock removed");
}
