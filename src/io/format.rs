//! What kind of file an input is, decided in one place: by the MCAP magic
//! bytes, by the `.tuple` extension of Censi et al.'s calibration tuples, and
//! otherwise text, which a reader then parses as the format it expects (a
//! CARMEN log for recordings, TUM for trajectories). ROS 1 bags and rosbag2
//! SQLite files are known by their first bytes, a rosbag2 folder by its
//! `metadata.yaml`.

use std::io::Read;
use std::path::Path;

use crate::error::InputError;

/// The format of an input file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A ROS 2 bag (MCAP, starts with its magic bytes).
    Mcap,
    /// Censi et al.'s calibration tuples (`.tuple`).
    CensiTuples,
    /// Any other file: a text format (CARMEN log, TUM trajectory).
    Text,
    /// A ROS 1 bag, format 2.0 (starts with `#ROSBAG V2.0`).
    Ros1Bag,
    /// A rosbag2 SQLite file (`.db3`, starts with `SQLite format 3`).
    Rosbag2Sqlite,
    /// A rosbag2 folder: `metadata.yaml` and the files it lists.
    Rosbag2Dir,
}

impl Format {
    /// Whether this is a recording of ROS messages (a bag of any kind).
    pub fn is_bag(self) -> bool {
        matches!(
            self,
            Format::Mcap | Format::Ros1Bag | Format::Rosbag2Sqlite | Format::Rosbag2Dir
        )
    }
}

/// Sniffs the format of `path`; an error when the file cannot be opened.
pub fn sniff(path: &Path) -> Result<Format, InputError> {
    if path.is_dir() {
        return sniff_dir(path);
    }
    let mut file = std::fs::File::open(path)
        .map_err(|e| InputError::new(path.display().to_string(), format!("cannot read: {e}")))?;
    let mut head = [0u8; 16];
    let n = read_up_to(&mut file, &mut head);
    if head[..n].starts_with(mcap::MAGIC) {
        return Ok(Format::Mcap);
    }
    if head[..n].starts_with(super::ros1_records::MAGIC) {
        return Ok(Format::Ros1Bag);
    }
    if head[..n].starts_with(super::rosbag2_db3::MAGIC) {
        return Ok(Format::Rosbag2Sqlite);
    }
    if let Some(byte) = damaged_magic(&head[..n]) {
        return Err(InputError::new(
            path.display().to_string(),
            format!(
                "not an MCAP (bad magic at byte {byte}: {:02x?} instead of {:02x?}); the file \
                 starts like one but is damaged",
                &head[..n.min(mcap::MAGIC.len())],
                mcap::MAGIC
            ),
        ));
    }
    if path.extension().is_some_and(|e| e == "tuple") {
        return Ok(Format::CensiTuples);
    }
    Ok(Format::Text)
}

/// Most flipped bits for which a start that differs from the MCAP magic is
/// still taken for a damaged MCAP rather than another format (no text
/// format starts within 3 bits of `\x89MCAP0\r\n`).
const MAGIC_BIT_SLACK: u32 = 3;

/// The first byte at which `head` (8 bytes read) departs from the MCAP magic,
/// when it departs by at most [`MAGIC_BIT_SLACK`] bits in all.
fn damaged_magic(head: &[u8]) -> Option<usize> {
    if head.len() < mcap::MAGIC.len() {
        return None;
    }
    let bits: u32 = head
        .iter()
        .zip(mcap::MAGIC)
        .map(|(a, b)| (a ^ b).count_ones())
        .sum();
    if bits > MAGIC_BIT_SLACK {
        return None;
    }
    head.iter().zip(mcap::MAGIC).position(|(a, b)| a != b)
}

/// A folder is a recording when it holds a rosbag2 `metadata.yaml`.
fn sniff_dir(path: &Path) -> Result<Format, InputError> {
    if path.join("metadata.yaml").is_file() {
        Ok(Format::Rosbag2Dir)
    } else {
        Err(InputError::new(
            path.display().to_string(),
            "a folder without metadata.yaml: a rosbag2 folder (what `ros2 bag record` \
             writes) has one; otherwise name the bag file itself",
        ))
    }
}

/// Reads as many bytes as the file has, up to `buf.len()`.
fn read_up_to(file: &mut std::fs::File, buf: &mut [u8]) -> usize {
    let mut n = 0;
    while n < buf.len() {
        match file.read(&mut buf[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    n
}
