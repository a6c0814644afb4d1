//! Reading and writing files, and nothing else: recordings (MCAP, rosbag2
//! SQLite and folders, ROS 1 bags, CARMEN) as
//! a stream of samples ([`source`]), trajectories, CSV outputs. The format of
//! an input is decided in [`format::sniff`]. Every write goes through
//! [`atomic`].
//!
//! # Time policy
//! How the readers turn stamps into the times of a [`Recording`] (seconds as
//! `f64`), and what the later stages do with what they get:
//! - **Source.** A bag message's time is its `header.stamp`; a stamp of
//!   exactly zero means "unset" and the message's receive time is used
//!   instead (MCAP log time, ROS 1 record `time`, rosbag2 SQLite
//!   `timestamp`). Messages without a header (the `std_msgs` tick arrays
//!   of a `[wheels] source = "ticks"`) always take their receive time. A
//!   CARMEN record's time is its `ipc_timestamp`.
//! - **Invalid stamps** are errors naming the message (bag) or line (CARMEN):
//!   a negative time, or nanoseconds ≥ 10⁹.
//! - **Going backwards.** Each stream (scans, joint states, IMU, odometry,
//!   reference) is checked on its own against the latest stamp it has seen:
//!   a step back of up to [`ReadOptions::reorder_tolerance`] (default 2 s) is
//!   normal jitter and fixed by a stable sort; a larger one is an error naming
//!   the message. When a log time stood in for an unset stamp, the error says
//!   so (header and log clocks differ).
//! - **Duplicate stamps** are kept, in file order. Downstream every step of
//!   zero length is skipped: wheel rates ([`crate::robot::wheel_rates`]) and
//!   wheel odometry step over it, ICP marks the pair `bad_time` and keeps the
//!   earlier scan as its reference, the calibration steps have `t1 > t0`.
//! - **Gaps** of any length are kept as recorded. ICP matches across them
//!   with its plausibility gates widened by the gap (max speed × dt); the
//!   calibration fills time without observations with predict-only steps of
//!   at most 0.1 s (`calib::MAX_GAP_STEP`), wheel angles interpolated
//!   linearly; wheel *rates* (joint states without positions, or an odometry
//!   twist turned into wheel rates) are integrated across a gap by the
//!   trapezoid rule, i.e. at the mean of the two rates.
//! - **Clocks at 0 or at Unix time.** Both read as they are. Unix stamps
//!   (≈ 1.7·10⁹ s) keep a resolution of about 0.24 µs in `f64`. A header clock
//!   that starts at exactly 0 is read through the log time of that first
//!   message (indistinguishable from an unset stamp): our own bags write log
//!   time = stamp, so this is 0; a bag whose headers run on simulated time
//!   from 0 while its log times are wall-clock fails with the error above.

pub mod atomic;
mod bag_stream;
pub mod carmen;
pub mod cdr;
pub mod censi;
mod columns;
pub mod csv;
pub mod format;
pub mod input;
pub mod kitti;
pub mod mcap_canon;
mod mcap_guard;
pub mod mcap_read;
pub mod mcap_stream;
mod mcap_streams;
pub mod mcap_topics;
pub mod mcap_write;
pub mod messages;
mod options;
pub mod out_lock;
pub mod relations;
mod reorder;
pub mod ros1_bag;
mod ros1_records;
pub mod ros_msgs;
pub mod ros_schema;
pub mod rosbag2_db3;
pub mod rosbag2_dir;
pub mod seed_tables;
pub mod source;
pub mod stored;
pub mod stream_out;
pub mod survey;
pub mod tum;
mod wheel_msgs;

pub use carmen::read_carmen;
pub use format::{sniff, Format};
pub use mcap_read::{read_mcap, read_mcap_bytes};
pub use mcap_stream::McapStream;
pub use mcap_write::{
    encode_mcap, write_mcap, write_mcap_streaming, BagSource, BagStream, WheelRates, WriteError,
    WriteOptions,
};
pub use messages::MessageDecoder;
pub use options::{ReadOptions, TopicConfig};
pub use source::{Item, RecordingSource, SampleSource, StreamInfo};

use crate::error::InputError;
use crate::recording::Recording;
use std::path::Path;

/// Reads a whole recording by its sniffed format ([`sniff`]): a ROS 2 bag
/// (MCAP, rosbag2 SQLite or folder), a ROS 1 bag, or a text file read as a
/// CARMEN log; the result's streams are sorted by stamp. Censi et al.'s
/// tuples are not a recording and are refused.
pub fn read_recording(path: &Path, opts: &ReadOptions) -> Result<Recording, InputError> {
    match sniff(path)? {
        Format::Mcap => read_mcap(path, opts),
        Format::Ros1Bag | Format::Rosbag2Sqlite | Format::Rosbag2Dir => {
            collect(&mut *open(path, opts)?)
        }
        Format::Text => read_carmen(path, opts),
        Format::CensiTuples => Err(InputError::new(
            path.display().to_string(),
            "Censi et al.'s calibration tuples hold no scans or wheel encoder samples, and \
             no laser mounting ([laser]) for the online filters: `odocal calibrate --method \
             batch` (which estimates the mounting) and `odocal diagnose --measured` read them",
        )),
    }
}

/// Opens a recording file (or rosbag2 folder) as a sample source, by its
/// sniffed format: bags stream from disk, CARMEN logs are read whole and
/// then streamed.
pub fn open<'o>(
    path: &Path,
    opts: &'o ReadOptions,
) -> Result<Box<dyn SampleSource + 'o>, InputError> {
    match sniff(path)? {
        Format::Mcap => Ok(Box::new(McapStream::open(path, opts)?)),
        Format::Ros1Bag => ros1_bag::open(path, opts),
        Format::Rosbag2Sqlite => rosbag2_db3::open(path, opts),
        Format::Rosbag2Dir => rosbag2_dir::open(path, opts),
        Format::Text | Format::CensiTuples => Ok(Box::new(RecordingSource::owned(read_recording(
            path, opts,
        )?))),
    }
}

/// Reads a whole source into a [`Recording`] (streams sorted by stamp).
pub fn collect(source: &mut dyn SampleSource) -> Result<Recording, InputError> {
    let info = source.info().clone();
    let mut rec = Recording {
        source: source.name().to_string(),
        base_from_laser: info.base_from_laser,
        mount_origin: info.mount_origin,
        mount_note: info.mount_note.clone(),
        wheel_values: info.wheel_values,
        ..Default::default()
    };
    while let Some(item) = source.next_item()? {
        match item {
            Item::Scan(s) => rec.scans.push(s),
            Item::Wheel(w) => rec.wheels.push(w),
            Item::Gyro(g) => rec.gyro.push(g),
            Item::Odom(p) => rec.odom.push(p),
            Item::Reference(p) => rec.reference.push(p),
        }
    }
    Ok(rec)
}
