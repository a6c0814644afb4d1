//! Our evaluation equals evo's (tools/evo_crosscheck.py runs evo 1.38 on the
//! same TUM files) to 1e-6 relative, for every alignment and RPE unit evo has.

use crate::support;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use odocal::eval::{self, Alignment, DeltaUnit, EvalOptions, RpeDelta, SyncOptions, Trajectory3};
use odocal::io::tum::{read_tum, write_tum};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use std::path::Path;
use std::process::Command;

/// A smooth 3D path (m, rad) at time t (s).
fn truth(t: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(
            4.0 * (0.2 * t).cos(),
            3.0 * (0.3 * t).sin(),
            0.5 * (0.1 * t).sin(),
        ),
        UnitQuaternion::from_euler_angles(0.05 * (0.5 * t).sin(), 0.03 * (0.4 * t).cos(), 0.3 * t),
    )
}

/// Reference every `dt_ref`, estimate every `dt_est` (both jittered), the
/// estimate scaled, shifted, noisy and with its clock `clock` seconds ahead.
fn write_pair(dir: &Path, seed: u64, dt_ref: f64, dt_est: f64, clock: f64) {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let rot_noise = Normal::new(0.0, 0.02).unwrap();
    let stamps = |dt: f64, n: usize, rng: &mut StdRng| {
        let mut t = rng.random_range(0.0..0.01);
        (0..n)
            .map(|_| {
                t += rng.random_range(0.75 * dt..1.25 * dt);
                t
            })
            .collect::<Vec<f64>>()
    };
    let rs = stamps(dt_ref, (30.0 / dt_ref) as usize, &mut rng);
    let es = stamps(dt_est, (30.0 / dt_est) as usize, &mut rng);
    let reference =
        Trajectory3::from_parts(rs.clone(), rs.iter().map(|&t| truth(t)).collect()).unwrap();
    let est_poses = es
        .iter()
        .map(|&t| {
            let p = truth(t);
            let v = p.translation.vector * 1.05
                + nalgebra::Vector3::new(0.3, -0.2, 0.1)
                + nalgebra::Vector3::from_fn(|_, _| noise.sample(&mut rng));
            let dq = UnitQuaternion::from_euler_angles(
                rot_noise.sample(&mut rng),
                rot_noise.sample(&mut rng),
                rot_noise.sample(&mut rng),
            );
            Isometry3::from_parts(Translation3::from(v), p.rotation * dq)
        })
        .collect();
    let estimate =
        Trajectory3::from_parts(es.iter().map(|t| t + clock).collect(), est_poses).unwrap();
    write_tum(&dir.join("reference.tum"), &reference).unwrap();
    write_tum(&dir.join("estimate.tum"), &estimate).unwrap();
}

fn close(ours: f64, evo: f64) -> bool {
    (ours - evo).abs() <= 1e-6 * ours.abs().max(evo.abs()) + 1e-12
}

fn check_stats(case: &str, key: &str, ours: &Option<eval::Stats>, evo: &serde_json::Value) {
    let ours = serde_json::to_value(ours.expect("present")).unwrap();
    for k in ["rmse", "mean", "median", "std", "min", "max"] {
        let (a, b) = (ours[k].as_f64().unwrap(), evo[k].as_f64().unwrap());
        assert!(close(a, b), "{case} {key}.{k}: ours {a} vs evo {b}");
    }
}

fn crosscheck(test: &str, seed: u64, dt_ref: f64, dt_est: f64, clock: f64) {
    let Some(py) = support::python_with(test, &["evo", "numpy"]) else {
        return;
    };
    let dir = support::scratch(test);
    write_pair(&dir, seed, dt_ref, dt_est, clock);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/evo_crosscheck.py");
    let out = Command::new(py)
        .arg(script)
        .args(["--ref", dir.join("reference.tum").to_str().unwrap()])
        .args(["--est", dir.join("estimate.tum").to_str().unwrap()])
        .args(["--t-offset", &format!("{}", -clock)])
        .env("MPLBACKEND", "Agg")
        .output()
        .expect("run tools/evo_crosscheck.py");
    assert!(
        out.status.success(),
        "evo_crosscheck failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let evo: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let reference = read_tum(&dir.join("reference.tum")).unwrap();
    let estimate = read_tum(&dir.join("estimate.tum")).unwrap();
    let frames = RpeDelta {
        value: 1.0,
        unit: DeltaUnit::Frames,
    };
    let metres = RpeDelta {
        value: 1.0,
        unit: DeltaUnit::Metres,
    };
    let sync = SyncOptions {
        offset: -clock,
        ..Default::default()
    };
    let cases = [
        ("none", Alignment::None, frames, false),
        ("se3", Alignment::Se3, frames, false),
        ("sim3", Alignment::Sim3, frames, false),
        ("origin", Alignment::Origin, frames, false),
        ("rpe_m", Alignment::None, metres, false),
        ("se3_rpe_m", Alignment::Se3, metres, false),
        ("interp", Alignment::None, frames, true),
    ];
    assert!(cases.len() >= 7, "every evo case is checked");
    for (name, align, rpe_delta, interpolate) in cases {
        let opts = EvalOptions {
            sync: SyncOptions {
                interpolate,
                ..sync
            },
            align,
            rpe_delta,
            position_only: false,
        };
        let r = eval::evaluate(&estimate, Some(&reference), None, &opts).unwrap();
        let m = r.trajectory.unwrap();
        let e = &evo["cases"][name];
        assert_eq!(
            m.matched as u64,
            e["matched"].as_u64().unwrap(),
            "{name}: matched"
        );
        assert!(m.matched > 100, "{name}: enough pairs to be meaningful");
        check_stats(name, "ape", &Some(m.ape), &e["ape"]);
        check_stats(name, "ape_rot_deg", &m.ape_rot_deg, &e["ape_rot_deg"]);
        check_stats(name, "rpe", &Some(m.rpe), &e["rpe"]);
        check_stats(name, "rpe_rot_deg", &m.rpe_rot_deg, &e["rpe_rot_deg"]);
    }
    // Position-only reference: APE translation and RPE point distance, paired
    // as evo does (odocal would otherwise resample a position-only reference).
    let opts = EvalOptions {
        sync: SyncOptions {
            resample: Some(false),
            ..sync
        },
        align: Alignment::Se3,
        rpe_delta: frames,
        position_only: true,
    };
    let m = eval::evaluate(&estimate, Some(&reference), None, &opts)
        .unwrap()
        .trajectory
        .unwrap();
    let e = &evo["cases"]["points_se3"];
    assert_eq!(m.matched as u64, e["matched"].as_u64().unwrap());
    check_stats("points_se3", "ape", &Some(m.ape), &e["ape"]);
    check_stats("points_se3", "rpe", &Some(m.rpe), &e["rpe"]);
    assert!(m.ape_rot_deg.is_none() && m.rpe_rot_deg.is_none());
}

#[test]
fn eval_equals_evo_with_dense_reference() {
    // Reference at ~50 Hz, estimate at ~20 Hz: the estimate drives the search;
    // some estimate stamps have no reference within 0.01 s.
    crosscheck("eval_equals_evo_with_dense_reference", 11, 0.02, 0.05, 0.0);
}

#[test]
fn eval_equals_evo_with_dense_estimate_and_clock_offset() {
    // Estimate denser than the reference and its clock 0.5 s ahead (offset −0.5).
    crosscheck(
        "eval_equals_evo_with_dense_estimate_and_clock_offset",
        12,
        0.05,
        0.02,
        0.5,
    );
}
