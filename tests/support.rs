//! Shared helpers for the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The shared real-data folder: `$ODOCAL_DATA`, else `../shared/data` beside
/// the crate. Outside CI a missing folder makes the calling test skip (and say
/// so); under CI (`CI` set) it is an error, so a broken setup cannot pass.
pub fn shared_data(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("ODOCAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var_os("CI").is_some() {
        panic!(
            "{test}: shared data not found at {} (set ODOCAL_DATA)",
            dir.display()
        );
    }
    eprintln!(
        "SKIP {test}: shared data not found at {} (set ODOCAL_DATA)",
        dir.display()
    );
    None
}

/// A python3 that has the given modules importable, or `None` (skip outside
/// CI, panic under CI where `.ci/run` installs them).
pub fn python_with(test: &str, modules: &[&str]) -> Option<String> {
    let py = std::env::var("ODOCAL_PYTHON").unwrap_or_else(|_| "python3".into());
    let code = modules
        .iter()
        .map(|m| format!("import {m}"))
        .collect::<Vec<_>>()
        .join(";");
    let ok = std::process::Command::new(&py)
        .args(["-c", &code])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if ok {
        return Some(py);
    }
    if std::env::var_os("CI").is_some() {
        panic!("{test}: python modules {modules:?} missing (.ci/run installs them)");
    }
    eprintln!("SKIP {test}: python modules {modules:?} not installed");
    None
}

/// Runs `tools/NAME` with the python `py` (from [`python_with`]) and
/// `args`; fails the test with the tool's stderr unless it succeeds, and
/// returns what it printed.
pub fn python_tool<A: AsRef<std::ffi::OsStr>>(py: &str, name: &str, args: &[A]) -> Vec<u8> {
    let tool = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tools")
        .join(name);
    let o = std::process::Command::new(py)
        .arg(tool)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("run {name}: {e}"));
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o.stdout
}

/// Asserts that `estimate` recovers a hidden departure: within `tol` of
/// `truth`, where the departure of `truth` from the `nominal` (what an
/// estimator that does nothing answers) is at least three times `tol`. The
/// nominal is put through the same check first and must fail it (the
/// negative control), so the assertion cannot pass on the do-nothing answer.
pub fn assert_recovered(what: &str, estimate: f64, truth: f64, nominal: f64, tol: f64) {
    let within = |x: f64| (x - truth).abs() < tol;
    // A departure written as exactly three tolerances (0.03 against 0.01)
    // may come back from the truth file a rounding under it.
    assert!(
        (truth - nominal).abs() >= 3.0 * tol * (1.0 - 1e-12) && !within(nominal),
        "{what}: the departure {truth} − {nominal} is under three times the tolerance {tol}"
    );
    assert!(
        within(estimate),
        "{what}: {estimate} vs truth {truth} (tolerance {tol}, nominal {nominal})"
    );
}

/// A fresh, empty scratch directory for one test, inside the target
/// directory (Cargo's `CARGO_TARGET_TMPDIR`): each run empties and reuses
/// the one its test had, so runs do not pile up (the suite writes about
/// 270 MB), and `cargo clean` removes them. Names are the tests' own, one
/// directory a test; two runs of the suite on one target directory at the
/// same time would share them.
pub fn scratch(test: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("odocal-test-{test}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The one JSON object a successful `odocal … --json` printed; fails the
/// test with odocal's stderr when it did not succeed.
pub fn ok_json(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "odocal failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON object ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// Runs the `odocal` binary with `args`.
pub fn odocal(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(args)
        .output()
        .expect("run odocal")
}

/// Factors on the default convergence bound of the scan matcher that make
/// the ensemble a chaotic figure is judged over (see [`convergence_ensemble`]).
pub const CONVERGENCE_FACTORS: [f64; 5] = [0.8, 0.9, 1.0, 1.1, 1.2];

/// The default scan-matcher settings with the convergence bound at each of
/// [`CONVERGENCE_FACTORS`]. A registration stops anywhere below the bound,
/// so the members' motions differ by micrometres per pair; but a local map
/// chains them, and at the few hard pairs of a run (a fast turn under a late
/// odometry, a reversal the odometry missed, a door edge at the threshold of
/// what counts as measured) such differences decide between two outcomes.
/// A figure that follows those pairs (long relations, a calibration from
/// the door pairs of a corridor) then moves by far more than its members'
/// differences (docs/results.md, "Run to run"): asserted on one member it asserts
/// that draw, and any harmless change of the numerics flips it. Over the
/// ensemble, its median (or mean) is what the method gives.
pub fn convergence_ensemble() -> Vec<odocal::icp::IcpParams> {
    let base = odocal::icp::IcpParams::default();
    CONVERGENCE_FACTORS
        .iter()
        .map(|f| odocal::icp::IcpParams {
            convergence: f * base.convergence,
            ..base.clone()
        })
        .collect()
}

/// Every file below `dir` (recursively) whose path `keep` accepts, skipping
/// folders named `target`, `__pycache__` or starting with a dot; sorted.
pub fn files_below(dir: &Path, keep: &dyn Fn(&Path) -> bool) -> Vec<PathBuf> {
    fn walk(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy();
            if p.is_dir() {
                if name != "target" && name != "__pycache__" && !name.starts_with('.') {
                    walk(&p, keep, out);
                }
            } else if keep(&p) {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, keep, &mut out);
    out.sort();
    out
}
