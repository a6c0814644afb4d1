//! Reads a rosbag2 folder, what `ros2 bag record` writes: `metadata.yaml`
//! (key `rosbag2_bagfile_information`: `storage_identifier`, `mcap` or
//! `sqlite3`, and `relative_file_paths`, the files in recording order) and
//! the files it lists, each an MCAP or SQLite file (recognised by content).
//! The files are streamed one after the other as one recording. Files that
//! rosbag2 compressed whole or message by message (`compression_format`)
//! are refused with what to run.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::bag_stream::{Fail, Raw, RawMessages};
use super::format::{sniff, Format};
use super::mcap_streams::Wire;
use super::options::ReadOptions;
use super::source::SampleSource;
use crate::error::InputError;

/// The part of `metadata.yaml` the reader needs.
#[derive(Debug, Deserialize)]
struct Metadata {
    rosbag2_bagfile_information: Info,
}

#[derive(Debug, Deserialize)]
struct Info {
    #[serde(default)]
    storage_identifier: String,
    relative_file_paths: Vec<String>,
    #[serde(default)]
    compression_format: String,
    #[serde(default)]
    compression_mode: String,
}

/// The files of a rosbag2 folder, in recording order, checked to exist.
fn bag_files(dir: &Path) -> Result<Vec<PathBuf>, InputError> {
    let meta = dir.join("metadata.yaml");
    let name = meta.display().to_string();
    let text = std::fs::read_to_string(&meta)
        .map_err(|e| InputError::new(&name, format!("cannot read: {e}")))?;
    let m: Metadata = serde_yaml_ng::from_str(&text).map_err(|e| {
        InputError::new(&name, format!("not a rosbag2 metadata file: {e}"))
            .topic("rosbag2_bagfile_information")
    })?;
    let info = m.rosbag2_bagfile_information;
    if !info.compression_format.is_empty() {
        return Err(InputError::new(
            &name,
            format!(
                "the bag is compressed (compression_format {}, compression_mode {}), which \
                 odocal does not read: `ros2 bag convert` writes an uncompressed copy",
                info.compression_format, info.compression_mode
            ),
        )
        .topic("rosbag2_bagfile_information"));
    }
    if info.relative_file_paths.is_empty() {
        return Err(InputError::new(&name, "relative_file_paths lists no file")
            .topic("rosbag2_bagfile_information"));
    }
    let files: Vec<PathBuf> = info
        .relative_file_paths
        .iter()
        .map(|f| dir.join(f))
        .collect();
    for f in &files {
        if !f.is_file() {
            return Err(InputError::new(
                &name,
                format!(
                    "relative_file_paths lists {}, which is not a file (storage {})",
                    f.display(),
                    info.storage_identifier
                ),
            )
            .topic("rosbag2_bagfile_information"));
        }
    }
    Ok(files)
}

/// One file of the folder, opened for reading.
type Part<'o> = Box<dyn RawMessages + 'o>;

/// Opens one listed file by its content: MCAP or SQLite.
fn open_part<'o>(path: &Path, opts: &'o ReadOptions) -> Result<Part<'o>, InputError> {
    match sniff(path)? {
        Format::Mcap => Ok(Box::new(super::mcap_stream::raw_messages(path, opts)?)),
        Format::Rosbag2Sqlite => Ok(Box::new(super::rosbag2_db3::Db3Messages::open(path, opts)?)),
        _ => Err(InputError::new(
            path.display().to_string(),
            "listed in metadata.yaml but neither an MCAP nor an SQLite file",
        )),
    }
}

/// The raw messages of every file of a folder, one file after the other.
pub(crate) struct DirMessages<'o> {
    opts: &'o ReadOptions,
    /// Files not opened yet, last first.
    files: Vec<PathBuf>,
    current: Part<'o>,
}

impl<'o> DirMessages<'o> {
    /// Opens the folder `dir` and its first file.
    pub(crate) fn open(dir: &Path, opts: &'o ReadOptions) -> Result<Self, InputError> {
        let mut files = bag_files(dir)?;
        files.reverse();
        let first = files.pop().expect("bag_files lists at least one file");
        Ok(Self {
            opts,
            current: open_part(&first, opts)?,
            files,
        })
    }
}

impl RawMessages for DirMessages<'_> {
    fn name(&self) -> &str {
        self.current.name()
    }

    fn wire(&self) -> Wire {
        Wire::Cdr
    }

    fn next_raw(&mut self) -> Result<Option<Raw>, Fail> {
        loop {
            match self.current.next_raw() {
                Ok(Some(raw)) => return Ok(Some(raw)),
                Ok(None) => {}
                Err(Fail::Format(m)) => {
                    return Err(Fail::Input(InputError::new(
                        self.current.name(),
                        format!("corrupt or truncated: {m}"),
                    )))
                }
                Err(e) => return Err(e),
            }
            match self.files.pop() {
                None => return Ok(None),
                Some(f) => self.current = open_part(&f, self.opts)?,
            }
        }
    }
}

/// Opens a rosbag2 folder as one sample source over all its files.
pub fn open<'o>(
    dir: &Path,
    opts: &'o ReadOptions,
) -> Result<Box<dyn SampleSource + 'o>, InputError> {
    super::bag_stream::open_with(dir, opts, || DirMessages::open(dir, opts))
}
