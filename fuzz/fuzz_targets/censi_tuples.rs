//! Censi et al.'s calibration tuples as text: an error value, or tuples with
//! T > 0 and finite values whose streams (wheel angles, motions) are finite
//! and in time order.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::censi;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(tuples) = censi::parse(text, "fuzz.tuple") else {
        return;
    };
    for t in &tuples {
        assert!(t.t > 0.0 && t.t.is_finite(), "interval {}", t.t);
        assert!(
            t.phi_l.is_finite() && t.phi_r.is_finite() && t.sm.iter().all(|v| v.is_finite()),
            "non-finite tuple {t:?}"
        );
    }
    let mount = odocal::geom::pose(0.1, -0.02, 0.3);
    let (wheels, motions) = censi::to_streams(&tuples, &mount, 0.005, 0.002);
    assert_eq!(wheels.len(), tuples.len() + 1);
    assert_eq!(motions.len(), tuples.len());
    assert!(wheels.windows(2).all(|w| w[0].stamp <= w[1].stamp));
    for w in &wheels {
        assert!(w.left.is_finite() && w.right.is_finite() && w.stamp.is_finite());
    }
    for m in &motions {
        assert!(
            [m.t0, m.t1, m.dx, m.dy, m.dtheta]
                .iter()
                .all(|v| v.is_finite())
                && m.t1 > m.t0,
            "motion {m:?}"
        );
        assert!(m.cov.iter().all(|v| v.is_finite()), "covariance {m:?}");
        assert!(
            m.dtheta.abs() <= std::f64::consts::PI + 1e-9,
            "unwrapped {m:?}"
        );
    }
});
