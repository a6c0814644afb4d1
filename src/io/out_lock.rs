//! One writer per output at a time: before a run writes an output (a file or
//! a directory of files), it takes an exclusive advisory lock (`flock`) on the
//! sibling `.NAME.lock`, so that two concurrent runs on the same output can
//! never leave files of both side by side: the second is refused at once,
//! told which lock and which process holds it. The kernel drops the lock
//! when its process ends however it ends (a kill included), so a lock file
//! left by a killed run never blocks the next one; a run that ends normally
//! removes its lock file.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// Why an output could not be locked.
#[derive(Debug)]
pub enum LockError {
    /// Another process holds the lock.
    Busy {
        /// The lock file.
        lock: PathBuf,
        /// The process id written in it, when readable.
        holder: Option<u32>,
    },
    /// The lock file could not be created or locked.
    Io(PathBuf, io::Error),
}

impl std::fmt::Display for LockError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Busy { lock, holder } => {
                let who = holder.map_or("another odocal run".to_string(), |p| {
                    format!("another odocal run (process {p})")
                });
                write!(f, "{who} holds the lock {}", lock.display())
            }
            Self::Io(lock, e) => write!(f, "cannot lock {}: {e}", lock.display()),
        }
    }
}

/// The lock file of an output path: `.NAME.lock` beside it.
pub fn lock_path(output: &Path) -> PathBuf {
    let name = output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    output.with_file_name(format!(".{name}.lock"))
}

/// A held lock; dropping it removes the lock file and releases the lock.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    file: Option<File>,
}

/// Attempts after which a lock file that keeps being replaced under us is an error.
const MAX_ATTEMPTS: usize = 8;

impl OutputLock {
    /// Locks `output` (a file or directory path, existing or not), creating
    /// its parent directory; refused with [`LockError::Busy`] when another
    /// process holds the lock.
    pub fn acquire(output: &Path) -> Result<Self, LockError> {
        let path = lock_path(output);
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir).map_err(|e| LockError::Io(path.clone(), e))?;
        }
        for _ in 0..MAX_ATTEMPTS {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(|e| LockError::Io(path.clone(), e))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    let mut text = String::new();
                    let _ = file.read_to_string(&mut text);
                    return Err(LockError::Busy {
                        lock: path,
                        holder: text.trim().parse().ok(),
                    });
                }
                Err(fs::TryLockError::Error(e)) => return Err(LockError::Io(path, e)),
            }
            // The holder before us removes the file before it unlocks: the
            // lock is ours only if the path still names the file we locked.
            if same_file(&file, &path) {
                file.set_len(0)
                    .map_err(|e| LockError::Io(path.clone(), e))?;
                write!(file, "{}", std::process::id())
                    .map_err(|e| LockError::Io(path.clone(), e))?;
                return Ok(Self {
                    path,
                    file: Some(file),
                });
            }
        }
        Err(LockError::Io(
            path,
            io::Error::other("the lock file keeps being replaced"),
        ))
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Whether the open `file` is the file `path` names now.
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Remove first, unlock second (see `acquire`'s check).
        let _ = fs::remove_file(&self.path);
        drop(self.file.take());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_until_the_first_is_dropped() {
        let dir = std::env::temp_dir().join(format!("odocal-lock-{}", std::process::id()));
        let out = dir.join("cal");
        let first = OutputLock::acquire(&out).unwrap();
        assert!(lock_path(&out).is_file());
        match OutputLock::acquire(&out) {
            Err(LockError::Busy { lock, holder }) => {
                assert_eq!(lock, dir.join(".cal.lock"));
                assert_eq!(holder, Some(std::process::id()));
            }
            other => panic!("expected Busy, got {other:?}"),
        }
        drop(first);
        assert!(!lock_path(&out).exists(), "lock file removed");
        let again = OutputLock::acquire(&out).unwrap();
        drop(again);
        fs::remove_dir_all(&dir).unwrap();
    }
}
