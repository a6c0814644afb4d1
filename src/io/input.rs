//! What odocal accepts as an input file: a regular file (or a symbolic link
//! to one). A device such as `/dev/zero` never ends and a pipe cannot be
//! read twice (the bag reader makes two passes), so both are refused at
//! once, before anything reads them.

use crate::error::InputError;
use std::path::Path;

/// Refuses `path` when it exists and is neither a regular file nor a
/// directory, naming what it is. A missing file passes (the reader reports
/// it as unreadable), and so does a directory: a rosbag2 folder is a
/// recording, and the format sniffer refuses any other folder by name.
pub fn check_regular(path: &Path) -> Result<(), InputError> {
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    if meta.is_file() || meta.is_dir() {
        return Ok(());
    }
    let what = kind(&meta);
    Err(InputError::new(
        path.display().to_string(),
        format!(
            "is {what}, not a regular file: odocal reads only regular files (save a stream to \
             a file first)"
        ),
    ))
}

/// What kind of file `meta` describes, in words.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a pipe (FIFO)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}
