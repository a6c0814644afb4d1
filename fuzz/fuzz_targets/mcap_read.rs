//! Any bytes through the public MCAP reader (footer, chunks, records, CDR of
//! every message type we read): an error value or a finite, sorted recording.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::{read_mcap_bytes, ReadOptions, TopicConfig};
use odocal_fuzz::check_recording;

fuzz_target!(|data: &[u8]| {
    let default = ReadOptions::default();
    // The LEGO and Mines bags publish their reference on /reference.
    let reference = ReadOptions {
        topics: TopicConfig {
            reference: "/reference".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    for opts in [&default, &reference] {
        if let Ok(r) = read_mcap_bytes(data, "fuzz.mcap", opts) {
            check_recording(&r);
        }
    }
});
