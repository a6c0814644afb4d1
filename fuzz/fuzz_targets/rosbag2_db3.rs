//! Any bytes as a rosbag2 SQLite file (`.db3`: its tables, topics, types and
//! CDR rows), streamed by the reader the CLI uses: an error value or a
//! finite, sorted recording.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::{collect, rosbag2_db3, ReadOptions};
use odocal_fuzz::{check_recording, scratch_file, with_reference};

fuzz_target!(|data: &[u8]| {
    let path = scratch_file("db3", data);
    for opts in [ReadOptions::default(), with_reference()] {
        let read = rosbag2_db3::open(&path, &opts).and_then(|mut src| collect(&mut *src));
        if let Ok(r) = read {
            check_recording(&r);
        }
    }
});
