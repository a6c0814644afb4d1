//! UMBmark against the core kinematics: signs, correction factors, improvement.

use odocal::classic::{umbmark, umbmark_runs, DriveParams, Turn};
use odocal::experiments::umbmark_experiment;
use odocal::robot::DiffDrive;

const NOMINAL: DiffDrive = DiffDrive {
    r_right: 0.32,
    r_left: 0.32,
    wheel_base: 0.65,
};

#[test]
fn umbmark_signs_match_the_derivation() {
    let d = DriveParams::default();
    // Pure type A: true wheel base 2 % larger → under-turns → α > 0, E_b ≈ 1.02.
    let truth = DiffDrive {
        wheel_base: 0.663,
        ..NOMINAL
    };
    let r = umbmark(
        &umbmark_runs(&NOMINAL, &truth, 4.0, 1, &d, 0),
        4.0,
        &NOMINAL,
    )
    .unwrap();
    assert!(r.alpha_rad > 0.0 && r.beta_rad.abs() < 1e-3 * r.alpha_rad.abs().max(1e-9) + 1e-9);
    assert!((r.e_b - 0.663 / 0.65).abs() < 2e-3, "E_b {}", r.e_b);
    // Both runs end at x ≈ −2Lα, y ≈ ±2Lα (ccw +, cw −).
    assert!(r.cg_cw[1] < 0.0 && r.cg_ccw[1] > 0.0 && r.cg_cw[0] < 0.0);
    // Pure type B: right wheel 1 % larger → curves left → β > 0, E_d ≈ 1.01.
    let truth = DiffDrive {
        r_right: 0.3232,
        ..NOMINAL
    };
    let r = umbmark(
        &umbmark_runs(&NOMINAL, &truth, 4.0, 1, &d, 0),
        4.0,
        &NOMINAL,
    )
    .unwrap();
    assert!(r.beta_rad > 0.0);
    assert!((r.e_d - 1.01).abs() < 1e-3, "E_d {}", r.e_d);
    assert!(
        r.c_right > 1.0 && r.c_left < 1.0 && ((r.c_left + r.c_right) / 2.0 - 1.0).abs() < 1e-12
    );
    assert!(umbmark(
        &umbmark_runs(&NOMINAL, &truth, 4.0, 1, &d, 0)[..1],
        4.0,
        &NOMINAL
    )
    .is_err());
}

#[test]
fn umbmark_correction_improves_fresh_runs() {
    // Unequal radii (+0.5 %, −0.3 %) and a wheel base 1.5 % larger than nominal,
    // 8800-tick encoders, 4 m squares, 5 runs each way.
    let truth = DiffDrive {
        r_right: 0.32 * 1.005,
        r_left: 0.32 * 0.997,
        wheel_base: 0.65 * 1.015,
    };
    let clean = DriveParams {
        ticks_per_rev: 8800.0,
        ..DriveParams::default()
    };
    let slip = DriveParams {
        slip_sigma: 0.01,
        ..clean
    };
    let mut figures = Vec::new();
    for (name, d) in [("no slip", clean), ("1 % slip", slip)] {
        for passes in [1, 2] {
            let x = umbmark_experiment(&NOMINAL, &truth, 4.0, 5, &d, passes, 42).unwrap();
            println!(
                "UMBmark L=4 m, {name}, {passes} pass(es): E_max,syst before {:.4} m, after {:.4} m, improvement {:.1}x; E_d {:.5} (truth {:.5}), E_b {:.5}",
                x.before.e_max_syst, x.after.e_max_syst, x.improvement, x.before.e_d, truth.r_right / truth.r_left, x.before.e_b
            );
            assert_eq!(x.runs_before.len(), 10);
            assert_eq!(
                x.runs_before.iter().filter(|r| r.dir == Turn::Cw).count(),
                5
            );
            figures.push(x);
        }
    }
    // One pass (the paper's procedure): first-order formulas leave an α·β residual.
    assert!(figures[0].improvement > 8.0, "{}", figures[0].improvement);
    assert!(figures[2].improvement > 5.0, "{}", figures[2].improvement);
    // A second pass removes it down to the encoder quantisation / slip floor.
    assert!(figures[1].improvement > 100.0, "{}", figures[1].improvement);
    assert!(figures[3].improvement > 10.0, "{}", figures[3].improvement);
    // After two passes the diameter ratio and the ratio b / r_mean that turns
    // depend on are recovered.
    let turn = |b: f64, rr: f64, rl: f64| b / (rr + rl);
    let recovered = |k: &DiffDrive| -> Result<(), String> {
        let ratio = k.r_right / k.r_left - truth.r_right / truth.r_left;
        let rel = turn(k.wheel_base, k.r_right, k.r_left)
            / turn(truth.wheel_base, truth.r_right, truth.r_left)
            - 1.0;
        if ratio.abs() < 2e-4 && rel.abs() < 5e-4 {
            Ok(())
        } else {
            Err(format!("{k:?}: ratio off by {ratio}, b / r_mean by {rel}"))
        }
    };
    recovered(&figures[1].corrected).unwrap();
    // The negative control: the nominal robot (ratio 1, b / r_mean 1.5 %
    // short) fails the same check.
    assert!(recovered(&NOMINAL).is_err());
}
