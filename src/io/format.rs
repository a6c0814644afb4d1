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
    if path.extension().is_some_and(|e| e == "tuple") {
        return Ok(Format::CensiTuples);
    }
    Ok(Format::Text)
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
