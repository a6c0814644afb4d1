//! What kind of file an input is, decided in one place: by the MCAP magic
//! bytes, by the `.tuple` extension of Censi et al.'s calibration tuples, and
//! otherwise text, which a reader then parses as the format it expects (a
//! CARMEN log for recordings, TUM for trajectories).

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
}

/// Sniffs the format of `path`; an error when the file cannot be opened.
pub fn sniff(path: &Path) -> Result<Format, InputError> {
    let mut file = std::fs::File::open(path)
        .map_err(|e| InputError::new(path.display().to_string(), format!("cannot read: {e}")))?;
    let mut head = [0u8; 8];
    let n = read_up_to(&mut file, &mut head);
    if head[..n].starts_with(mcap::MAGIC) {
        return Ok(Format::Mcap);
    }
    if let Some(byte) = damaged_magic(&head[..n]) {
        return Err(InputError::new(
            path.display().to_string(),
            format!(
                "not an MCAP (bad magic at byte {byte}: {:02x?} instead of {:02x?}); the file \
                 starts like one but is damaged",
                &head[..n],
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
