//! report.md: settings, tables and images end up in the file as markdown.

use crate::support::scratch;
use odocal::viz::report::{num, Report};

#[test]
fn report_md_contains_settings_tables_and_images() {
    let dir = scratch("report_md");
    let path = dir.join("report.md");
    let mut r = Report::new();
    r.heading(1, "odocal demo")
        .kv(&[("method", "adaptive-pf"), ("seed", "7")])
        .heading(2, "Calibration");
    r.table(
        &["method", "R_R (m)", "R_L (m)", "D (m)"],
        &[
            vec![
                "adaptive-pf".to_string(),
                num(0.32012, 4),
                num(0.31987, 4),
                num(0.6503, 4),
            ],
            vec![
                "dkf".to_string(),
                num(0.3207, 4),
                num(f64::NAN, 4),
                num(0.649, 4),
            ],
        ],
    )
    .unwrap();
    r.image("radius.png", "Radius evolution");
    r.write(&path).unwrap();
    let md = std::fs::read_to_string(&path).unwrap();
    assert!(md.starts_with("# odocal demo\n\n- **method**: adaptive-pf\n- **seed**: 7\n"));
    assert!(md.contains("| method | R_R (m) | R_L (m) | D (m) |\n| --- | --- | --- | --- |\n"));
    assert!(md.contains("| adaptive-pf | 0.3201 | 0.3199 | 0.6503 |\n"));
    assert!(md.contains("| dkf | 0.3207 | — | 0.6490 |\n"));
    assert!(md.contains("![Radius evolution](radius.png)"));
    assert!(!md.contains("NaN"));
}
