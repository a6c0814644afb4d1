//! Robot TOML: an error value or a valid robot whose derived numbers are
//! finite and which survives a TOML round trip.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::robot::RobotConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(c) = RobotConfig::from_toml(text) {
        assert!(c.validate().is_ok());
        let d = c.diff_drive();
        assert!(d.r_right.is_finite() && d.r_left.is_finite() && d.wheel_base.is_finite());
        assert!(
            c.rad_per_tick().is_finite() && c.rad_per_tick() > 0.0,
            "{c:?}"
        );
        let back = toml::to_string(&c).expect("a valid robot serialises");
        assert_eq!(RobotConfig::from_toml(&back).expect("and reads back"), c);
    }
});
