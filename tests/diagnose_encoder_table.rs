//! The encoder-versus-tachometer table of [Paryanto, Table I]: a constant scale
//! against the speed-dependent encoder gain ω_meas = ω (1 + k |ω|), per wheel,
//! by BIC. The numbers are checked against an independent closed-form
//! computation (numpy, one-regressor least squares) of the same data.

use crate::support::shared_data;
use odocal::diagnose::encoder_table::{fit_table, parse_table};

#[test]
fn wheelchair_encoder_table_right_wheel_prefers_speed_dependent_gain_left_a_constant_scale() {
    let Some(dir) = shared_data("wheelchair_encoder_table") else {
        return;
    };
    let text = std::fs::read_to_string(dir.join("seed-tables/encoder_vs_tachometer.csv")).unwrap();
    let rows = parse_table(&text).unwrap();
    assert_eq!(rows.len(), 6);
    // Both instruments print whole rpm: σ of the difference √(2/12) rpm.
    let f = fit_table(&rows, (2.0f64 / 12.0).sqrt()).unwrap();
    let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * b.abs();
    // Right wheel: s = 1.02809, k = 0.0023869 s/rad (± 0.000155);
    // RSS 0.023023 vs 0.018808 (rad/s)²: the gain fits better, ΔBIC = +2.31
    // ("positive" evidence, weak), +1.21 with σ profiled, +6.44 with relative errors.
    assert!(close(f.right.scale, 1.028087, 1e-5));
    assert!(close(f.right.k, 0.00238694, 1e-4));
    assert!(close(f.right.k_se, 0.000155472, 1e-4));
    assert!(close(f.right.rss_scale, 0.0230231, 1e-4));
    assert!(close(f.right.rss_gain, 0.0188077, 1e-4));
    assert!(close(f.right.delta_bic, 2.30636, 1e-4));
    assert!(close(f.right.delta_bic_profiled, 1.21338, 1e-4));
    assert!(close(f.right.delta_bic_relative, 6.43789, 1e-4));
    assert!(f.right.delta_bic > 2.0 && f.right.k / f.right.k_se > 10.0);
    // Left wheel: reads exactly 33 rpm at 33 rpm, then a flat ~3.5 % over:
    // a constant scale (s = 1.03527) fits far better, ΔBIC = −14.75; only a
    // relative-error weighting (not what whole-rpm rounding implies) tilts it
    // weakly towards the gain (+1.40).
    assert!(close(f.left.scale, 1.035266, 1e-5));
    assert!(close(f.left.k, 0.00292194, 1e-4));
    assert!(close(f.left.rss_scale, 0.0183409, 1e-4));
    assert!(close(f.left.rss_gain, 0.0453055, 1e-4));
    assert!(close(f.left.delta_bic, -14.7533, 1e-4));
    assert!(close(f.left.delta_bic_profiled, -5.42578, 1e-4));
    assert!(close(f.left.delta_bic_relative, 1.39788, 1e-3));
    assert!(f.left.delta_bic < -10.0);
}

#[test]
fn encoder_table_parser_refuses_bad_rows() {
    assert!(parse_table("tachometer_rpm,a,b\n1,2\n").is_err());
    assert!(parse_table("1,2,x\n").is_err());
    assert_eq!(parse_table("# c\n1,2,3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
}
