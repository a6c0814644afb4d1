//! Reading and writing files: recordings (MCAP, CARMEN), trajectories, CSV
//! outputs. Every write goes through [`atomic`].

pub mod atomic;
pub mod carmen;
pub mod cdr;
pub mod censi;
mod columns;
pub mod csv;
pub mod kitti;
pub mod mcap_canon;
pub mod mcap_read;
mod mcap_streams;
pub mod mcap_write;
pub mod relations;
pub mod ros_msgs;
pub mod ros_schema;
pub mod seed_tables;
pub mod stream;
pub mod stream_icp;
pub mod stream_out;
pub mod stream_run;
pub mod stream_steps;
pub mod tum;

pub use carmen::read_carmen;
pub use mcap_read::{read_mcap, read_mcap_bytes, ReadOptions, TopicConfig};
pub use mcap_write::{encode_mcap, write_mcap, WriteError, WriteOptions};

use crate::error::InputError;
use crate::recording::Recording;
use std::path::Path;

/// Reads a recording, MCAP (recognised by its magic bytes) or else a CARMEN
/// log; the result's streams are sorted by stamp.
pub fn read_recording(path: &Path, opts: &ReadOptions) -> Result<Recording, InputError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    if bytes.starts_with(mcap::MAGIC) {
        mcap_read::read_mcap_bytes(&bytes, &file, opts)
    } else {
        carmen::read_carmen_bytes(&bytes, &file, opts)
    }
}
