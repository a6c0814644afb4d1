//! KITTI pose text and timestamp text (split at the first NUL byte): an error
//! value or a trajectory of finite poses with unit quaternions.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::kitti::parse_kitti;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (poses, times) = text.split_once('\0').unwrap_or((text, ""));
    if let Ok(t) = parse_kitti(poses, "fuzz.txt", times, "fuzz.times") {
        assert!(t.stamps.len() >= 2 && t.stamps.len() == t.poses.len());
        assert!(t.stamps.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(t.first_non_finite(), None);
        for p in &t.poses {
            let q = p.rotation.coords;
            assert!((q.norm() - 1.0).abs() < 1e-6, "non-unit quaternion {q:?}");
        }
    }
});
