//! Null runs through the whole chain (simulate → bag → ICP → diagnose) where
//! scan-to-scan ICP's own error, not the robot, leaves a structure: along
//! the corridor loop it reads the forward speed short (the walls say nothing
//! along the axis), on the square room's in-place turns it reads the turn
//! rate short. The diagnosis puts each on the scan matcher and stays
//! `no-discrepancy`; with its instrument model off (the negative control)
//! the same runs come out `unexplained` with the structure called the
//! robot's.

use crate::support::{odocal, ok_json, scratch};
use serde_json::Value;
use std::path::Path;

fn diagnose(bag: &Path, config: Option<&Path>) -> Value {
    let mut args = vec!["diagnose", "--measured", bag.to_str().unwrap(), "--json"];
    if let Some(c) = config {
        args.extend(["--config", c.to_str().unwrap()]);
    }
    ok_json(&odocal(&args))
}

/// The remaining structures of `source`, as "stream structure".
fn left(d: &Value, source: &str) -> Vec<String> {
    d["remaining"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["source"] == source)
        .map(|r| {
            format!(
                "{} {}",
                r["stream"].as_str().unwrap(),
                r["structure"].as_str().unwrap()
            )
        })
        .collect()
}

#[test]
fn what_scan_to_scan_icp_leaves_on_null_runs_is_put_on_the_scan_matcher() {
    let dir = scratch("diagnose_nulls");
    let off = dir.join("off.toml");
    std::fs::write(&off, "[diagnose.instrument]\nenabled = false\n").unwrap();
    for (scenario, stream) in [("corridor-loop", "icp_v"), ("square", "icp_w")] {
        let bag = dir.join(format!("{scenario}.mcap"));
        let sim = odocal(&[
            "simulate",
            "--scenario",
            scenario,
            "--seed",
            "311",
            "--duration",
            "150",
            "--out",
            bag.to_str().unwrap(),
        ]);
        assert!(
            sim.status.success(),
            "{}",
            String::from_utf8_lossy(&sim.stderr)
        );
        let d = diagnose(&bag, None);
        assert_eq!(d["verdict"], "no-discrepancy", "{scenario}: {d}");
        assert!(
            d["causes"].as_array().unwrap().is_empty(),
            "{scenario}: {d}"
        );
        assert!(
            left(&d, "robot").is_empty(),
            "{scenario}: {:?}",
            left(&d, "robot")
        );
        let instrument = left(&d, "scan_matching");
        assert!(
            instrument.iter().any(|l| l.starts_with(stream)),
            "{scenario}: {instrument:?}"
        );
        for r in d["remaining"].as_array().unwrap() {
            let why = r["reason"].as_str().unwrap_or_default();
            assert!(why.contains("scan-to-scan ICP reads the"), "{r}");
        }
        // Negative control: the same run without the instrument's model.
        let d = diagnose(&bag, Some(&off));
        assert_eq!(
            d["verdict"], "unexplained",
            "{scenario} without the model: {d}"
        );
        assert!(
            left(&d, "robot").iter().any(|l| l.starts_with(stream)),
            "{scenario} without the model: {:?}",
            left(&d, "robot")
        );
        assert!(left(&d, "scan_matching").is_empty());
    }
}

/// The cells "e ± s %" of a table row, in order (the page writes − as U+2212).
fn cells(row: &str) -> Vec<[f64; 2]> {
    row.split('|')
        .filter_map(|c| {
            let c = c.trim().replace('−', "-");
            let (e, rest) = c.split_once(" ± ")?;
            let s = rest.split_once(" %")?.0;
            Some([e.parse().ok()?, s.parse().ok()?])
        })
        .collect()
}

#[test]
fn the_instrument_table_in_the_code_is_the_measured_one() {
    // docs/results/icp-instrument.md is regenerated from null runs by
    // tools/figures.py (CI checks it against the runs); the code must hold
    // the same numbers.
    let page = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/results/icp-instrument.md"),
    )
    .unwrap();
    let rows: Vec<Vec<[f64; 2]>> = page
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(cells)
        .filter(|c| !c.is_empty())
        .collect();
    let m = odocal::diagnose::instrument::Instrument::default();
    let code: Vec<Vec<[f64; 2]>> = m
        .forward
        .iter()
        .cloned()
        .chain(
            m.turn
                .iter()
                .zip(&m.turn_in_place)
                .map(|(a, b)| vec![*a, *b]),
        )
        .collect();
    assert_eq!(rows.len(), code.len(), "{rows:?}");
    for (page_row, code_row) in rows.iter().zip(&code) {
        assert_eq!(page_row.len(), code_row.len());
        for (p, c) in page_row.iter().zip(code_row) {
            for k in 0..2 {
                assert!(
                    (p[k] - 100.0 * c[k]).abs() < 0.006,
                    "page {p:?} against code {c:?} (per cent)"
                );
            }
        }
    }
}
