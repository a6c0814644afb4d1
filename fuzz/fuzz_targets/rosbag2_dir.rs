//! A rosbag2 folder: the bytes up to the first NUL are its `metadata.yaml`,
//! the rest the storage file it may name (`bag_0.db3` or `bag_0.mcap`, both
//! written). Read by the folder reader the CLI uses: an error value or a
//! finite, sorted recording.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::{collect, rosbag2_dir, ReadOptions};
use odocal_fuzz::{check_recording, scratch_dir};

fuzz_target!(|data: &[u8]| {
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let (yaml, rest) = data.split_at(split);
    let storage = rest.get(1..).unwrap_or(&[]);
    let dir = scratch_dir(&[
        ("metadata.yaml", yaml),
        ("bag_0.db3", storage),
        ("bag_0.mcap", storage),
    ]);
    let opts = ReadOptions::default();
    let read = rosbag2_dir::open(&dir, &opts).and_then(|mut src| collect(&mut *src));
    if let Ok(r) = read {
        check_recording(&r);
    }
});
