//! A ROS 2 bag's messages exactly as stored (topic, type, CDR payload, log
//! time), in the bag's order, for the streams a reader with these options
//! would read: what `odocal play` puts back on the network. Formats that
//! do not store ROS 2 CDR (ROS 1 bags, CARMEN, text) have none; they are
//! converted to MCAP first.

use std::path::Path;

use super::bag_stream::{Fail, RawMessages};
use super::format::Format;
use super::options::ReadOptions;
use crate::error::InputError;

/// One stored message.
#[derive(Debug, Clone)]
pub struct StoredMessage {
    /// Its topic.
    pub topic: String,
    /// Its type as the bag names it (`pkg/msg/Type`).
    pub type_name: String,
    /// The CDR payload with its encapsulation header.
    pub data: Vec<u8>,
    /// The log time (ns since the epoch).
    pub log_time_ns: u64,
}

/// A bag's stored messages, one at a time.
pub struct StoredMessages<'o> {
    raw: Box<dyn RawMessages + 'o>,
}

impl StoredMessages<'_> {
    /// The next message; `None` at the end; errors name the file, topic and
    /// position as the readers do.
    pub fn next_message(&mut self) -> Result<Option<StoredMessage>, InputError> {
        let name = self.raw.name().to_string();
        let raw = self.raw.next_raw().map_err(|f: Fail| f.into_input(&name))?;
        Ok(raw.map(|r| StoredMessage {
            topic: r.topic,
            type_name: r.type_name.to_string(),
            data: r.data,
            log_time_ns: r.log_time,
        }))
    }
}

/// The stored messages of the bag at `path` on the topics `opts` reads;
/// `None` when its format stores no ROS 2 CDR.
pub fn stored_messages<'o>(
    path: &Path,
    opts: &'o ReadOptions,
) -> Result<Option<StoredMessages<'o>>, InputError> {
    let raw: Box<dyn RawMessages + 'o> = match super::sniff(path)? {
        Format::Mcap => Box::new(super::mcap_stream::raw_messages(path, opts)?),
        Format::Rosbag2Sqlite => Box::new(super::rosbag2_db3::Db3Messages::open(path, opts)?),
        Format::Rosbag2Dir => Box::new(super::rosbag2_dir::DirMessages::open(path, opts)?),
        _ => return Ok(None),
    };
    Ok(Some(StoredMessages { raw }))
}
