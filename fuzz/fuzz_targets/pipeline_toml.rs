//! The pipeline configuration TOML: an error value (with a position) or a
//! configuration that survives a TOML round trip.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::pipeline::Config;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(c) = Config::parse(text, "fuzz.toml") {
        if let Ok(back) = toml::to_string(&c) {
            let again = Config::parse(&back, "back.toml").expect("a printed config reads back");
            // Compared as text: a NaN setting is not equal to itself.
            assert_eq!(toml::to_string(&again).unwrap(), back);
        }
    }
});
