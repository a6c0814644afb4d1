//! Any bytes through the CARMEN log reader: an error value or a finite,
//! sorted recording.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::carmen::read_carmen_bytes;
use odocal::io::ReadOptions;
use odocal_fuzz::check_recording;

fuzz_target!(|data: &[u8]| {
    if let Ok(r) = read_carmen_bytes(data, "fuzz.clf", &ReadOptions::default()) {
        check_recording(&r);
    }
});
