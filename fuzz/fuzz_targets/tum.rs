//! TUM text: an error value or a trajectory of finite poses with unit
//! quaternions and strictly increasing stamps.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::tum::parse_tum;
use odocal_fuzz::check_pose;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(t) = parse_tum(text, "fuzz.tum") {
        assert!(t.stamps.len() >= 2 && t.stamps.len() == t.poses.len());
        assert!(t.stamps.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(t.first_non_finite(), None);
        for p in &t.poses {
            let q = p.rotation.coords;
            assert!((q.norm() - 1.0).abs() < 1e-6, "non-unit quaternion {q:?}");
        }
        for p in &t.to_2d().poses {
            check_pose("tum 2d", p);
        }
    }
});
