//! Outputs under SIGKILL: `odocal simulate` and `odocal icp` killed while
//! writing over an existing output leave that output intact (or, had the
//! rename already happened, the complete new file), never a torn one. A killed
//! run may leave its temporary sibling `.NAME.tmp-PID`; such names never
//! collide with an output, and the next run writing the same output removes
//! them.
#![cfg(unix)]

use crate::support::scratch;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn odocal() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_odocal"));
    c.stdout(Stdio::null()).stderr(Stdio::null());
    c
}

/// Temporary siblings of `out` (`.NAME.tmp-PID`).
fn temps(out: &Path) -> Vec<PathBuf> {
    let prefix = format!(".{}.tmp-", out.file_name().unwrap().to_string_lossy());
    std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .map(|e| e.path())
        .collect()
}

/// Starts `cmd`, waits until `ready` holds (polling every millisecond, at
/// most `limit`), then kills it with SIGKILL. Returns whether it was still
/// running when killed.
fn kill_when(mut cmd: Command, ready: impl Fn() -> bool, limit: Duration) -> bool {
    let mut child = cmd.spawn().unwrap();
    let start = Instant::now();
    while !ready() && start.elapsed() < limit {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let running = child.try_wait().unwrap().is_none();
    child.kill().unwrap(); // SIGKILL on unix
    child.wait().unwrap();
    running
}

fn simulate(out: &Path, duration: &str) -> Command {
    let mut c = odocal();
    c.args([
        "simulate",
        "--scenario",
        "square",
        "--seed",
        "3",
        "--duration",
    ])
    .arg(duration)
    .arg("--out")
    .arg(out);
    c
}

#[test]
fn killed_simulate_leaves_the_previous_bag_or_the_complete_new_one() {
    let d = scratch("killed_simulate");
    let reference = d.join("reference.mcap");
    assert!(simulate(&reference, "20").status().unwrap().success());
    let full = std::fs::read(&reference).unwrap();
    let out = d.join("run.mcap");
    let previous = b"previous output, not a bag".to_vec();
    let mut killed_while_writing = 0;
    for attempt in 0..6 {
        if killed_while_writing > 0 {
            break;
        }
        std::fs::write(&out, &previous).unwrap();
        // Kill as soon as the temporary file shows up: mid-write.
        let running = kill_when(
            simulate(&out, "20"),
            || !temps(&out).is_empty(),
            Duration::from_secs(120),
        );
        let now = std::fs::read(&out).unwrap();
        assert!(
            now == previous || now == full,
            "attempt {attempt}: torn output ({} bytes)",
            now.len()
        );
        killed_while_writing += usize::from(running && now == previous);
        for t in temps(&out) {
            // A leftover is never mistaken for the output: other name, and
            // no reader is pointed at it.
            assert_ne!(t, out);
        }
    }
    assert!(killed_while_writing > 0, "never killed mid-write");
    // The next run completes, and removes the leftovers.
    assert!(simulate(&out, "20").status().unwrap().success());
    assert_eq!(std::fs::read(&out).unwrap(), full);
    assert!(temps(&out).is_empty(), "{:?}", temps(&out));
}

#[test]
fn killed_icp_leaves_the_previous_outputs_and_no_temp_after_a_rerun() {
    let d = scratch("killed_icp");
    let bag = d.join("run.mcap");
    assert!(simulate(&bag, "60").status().unwrap().success());
    let tum = d.join("icp.tum");
    let csv = d.join("motions.csv");
    let icp = || {
        let mut c = odocal();
        c.args(["icp", "--input"])
            .arg(&bag)
            .arg("--out")
            .arg(&tum)
            .arg("--motions")
            .arg(&csv);
        c
    };
    let (old_tum, old_csv) = (
        b"# previous trajectory\n".to_vec(),
        b"previous,csv\n".to_vec(),
    );
    std::fs::write(&tum, &old_tum).unwrap();
    std::fs::write(&csv, &old_csv).unwrap();
    // Kill once rows have reached the temporary trajectory: mid-stream.
    let streaming = || {
        temps(&tum)
            .iter()
            .any(|t| std::fs::metadata(t).is_ok_and(|m| m.len() > 0))
    };
    let running = kill_when(icp(), streaming, Duration::from_secs(300));
    assert!(running, "icp finished before it could be killed");
    assert_eq!(std::fs::read(&tum).unwrap(), old_tum, "trajectory torn");
    assert_eq!(std::fs::read(&csv).unwrap(), old_csv, "motions torn");
    assert!(
        !temps(&tum).is_empty(),
        "the killed run's temporary file is left"
    );
    // A complete run replaces both outputs and leaves no temporary file.
    assert!(icp().status().unwrap().success());
    let traj = odocal::io::tum::read_tum_2d(&tum).unwrap();
    assert!(traj.len() > 900, "{} poses", traj.len());
    assert!(std::fs::read_to_string(&csv).unwrap().lines().count() > 900);
    assert!(temps(&tum).is_empty() && temps(&csv).is_empty());
}
