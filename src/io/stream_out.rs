//! Output files written row by row while a long run goes on, still atomically:
//! rows go to the temporary sibling `.NAME.tmp-PID` (see [`super::atomic`]),
//! which is synced and renamed over `NAME` only by [`AtomicWriter::commit`].
//! Dropped without commit (error, panic), the temporary file is removed; a
//! killed process may leave it behind, and the next write of the same
//! output removes such leftovers (their names never match an output's).

use std::fs::{self, File};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use super::atomic;

/// A file being written: rows go to its temporary sibling until [`commit`](Self::commit).
pub struct AtomicWriter {
    path: PathBuf,
    tmp: PathBuf,
    w: Option<BufWriter<File>>,
}

impl AtomicWriter {
    /// Starts writing `path` (creating its directory); removes stale
    /// temporary siblings of `path` left by killed runs.
    pub fn create(path: &Path) -> io::Result<Self> {
        let (tmp, target) = atomic::begin(path)?;
        // Readable too, so that a writer may patch what it wrote (an MCAP summary).
        let f = fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        let w = BufWriter::with_capacity(1 << 16, f);
        Ok(Self {
            path: target,
            tmp,
            w: Some(w),
        })
    }

    /// The writer of the temporary file.
    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.w.as_mut().expect("writer is present until commit")
    }

    /// Flushes, syncs and renames the temporary file over the target.
    pub fn commit(mut self) -> io::Result<()> {
        let w = self.w.take().expect("commit runs once");
        let result = w
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|f| atomic::finish(f, &self.tmp, &self.path));
        if result.is_err() {
            let _ = fs::remove_file(&self.tmp);
        }
        result
    }
}

impl Drop for AtomicWriter {
    fn drop(&mut self) {
        if self.w.take().is_some() {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn rows_appear_only_on_commit_and_drop_cleans_up() {
        let dir = std::env::temp_dir().join(format!("odocal-stream-out-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.csv");
        fs::write(&p, b"old\n").unwrap();
        // A leftover of a run that no longer exists (PID beyond pid_max).
        let stale = dir.join(".out.csv.tmp-4294967295");
        fs::write(&stale, b"torn").unwrap();
        {
            let mut w = AtomicWriter::create(&p).unwrap();
            assert!(!stale.exists(), "stale temp removed");
            writeln!(w.writer(), "half").unwrap();
            assert_eq!(fs::read(&p).unwrap(), b"old\n");
        }
        assert_eq!(fs::read(&p).unwrap(), b"old\n");
        assert_eq!(
            fs::read_dir(&dir).unwrap().count(),
            1,
            "dropped temp removed"
        );
        let mut w = AtomicWriter::create(&p).unwrap();
        writeln!(w.writer(), "new").unwrap();
        w.commit().unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new\n");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }
}
