//! Any bytes as a ROS 1 bag (format 2.0: records, connections, chunks in
//! every compression, index data), streamed from disk by the reader the CLI
//! uses: an error value or a finite, sorted recording.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::{collect, ros1_bag, ReadOptions};
use odocal_fuzz::{check_recording, scratch_file, with_reference};

fuzz_target!(|data: &[u8]| {
    let path = scratch_file("bag", data);
    for opts in [ReadOptions::default(), with_reference()] {
        let read = ros1_bag::open(&path, &opts).and_then(|mut src| collect(&mut *src));
        if let Ok(r) = read {
            check_recording(&r);
        }
    }
});
