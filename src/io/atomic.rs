//! The one way odocal writes files: into a temporary file in the same
//! directory, fsync, then rename over the target, so a failed or killed run
//! leaves either the previous file or none, never a torn one. A killed run
//! may leave its temporary sibling `.NAME.tmp-PID`; the next write of `NAME`
//! removes it. [`write_atomic`] fills a file in one go; a file written row by
//! row goes through the same two steps, `begin` and `finish`, with its
//! rows in between. A write never replaces anything but a regular file: an
//! output path that is a symbolic link is written through to its target, and
//! one naming a directory, device or pipe is refused.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The temporary sibling `.NAME.tmp-PID` a write goes through before the rename.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let unique = format!(".{name}.tmp-{}", std::process::id());
    path.with_file_name(unique)
}

/// The directory `path` is in, if it names one.
fn parent_dir(path: &Path) -> Option<&Path> {
    path.parent().filter(|d| !d.as_os_str().is_empty())
}

/// Removes `.NAME.tmp-PID` siblings of `path` whose process no longer runs
/// (on Linux, checked through /proc; elsewhere only our own PID is spared).
pub fn remove_stale_temps(path: &Path) {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let dir = match parent_dir(path) {
        Some(d) => d.to_path_buf(),
        None => PathBuf::from("."),
    };
    let prefix = format!(".{name}.tmp-");
    let Ok(entries) = fs::read_dir(&dir) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix) else {
            continue;
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        let alive = pid == std::process::id()
            || (cfg!(target_os = "linux") && Path::new(&format!("/proc/{pid}")).exists());
        if !alive {
            let _ = fs::remove_file(e.path());
        }
    }
}

/// Most symbolic links followed from an output path to the file it names.
const MAX_LINKS: usize = 40;

/// The file a write of `path` replaces: `path` itself, or, when `path` is a
/// symbolic link, the file it points to (written through, so that the link
/// stays a link and its target is the one updated). An existing target that
/// is not a regular file (a directory, a device, a pipe, a socket) is
/// refused: odocal replaces only regular files.
pub fn target_of(path: &Path) -> io::Result<PathBuf> {
    let mut target = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        let meta = match fs::symlink_metadata(&target) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(target),
            other => other?,
        };
        if meta.is_file() {
            return Ok(target);
        }
        if !meta.file_type().is_symlink() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "{} is not a regular file (odocal writes only regular files)",
                    target.display()
                ),
            ));
        }
        let link = fs::read_link(&target)?;
        target = match parent_dir(&target) {
            Some(dir) if link.is_relative() => dir.join(link),
            _ => link,
        };
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{}: too many levels of symbolic links", path.display()),
    ))
}

/// First step of a write of `path`: finds the file it replaces
/// ([`target_of`]), creates its directory, removes stale temporary siblings
/// left by killed runs, and returns the temporary path to write to and the
/// target to rename it over.
pub(crate) fn begin(path: &Path) -> io::Result<(PathBuf, PathBuf)> {
    let target = target_of(path)?;
    if let Some(dir) = parent_dir(&target) {
        fs::create_dir_all(dir)?;
    }
    remove_stale_temps(&target);
    Ok((temp_path(&target), target))
}

/// Last step of a write: syncs the written temporary file `f` at `tmp`,
/// renames it over `path` and syncs the directory, so that the rename itself
/// is durable.
pub(crate) fn finish(f: File, tmp: &Path, path: &Path) -> io::Result<()> {
    f.sync_all()?;
    drop(f);
    fs::rename(tmp, path)?;
    if let Some(dir) = parent_dir(path) {
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// Writes `path` atomically with the bytes `fill` writes. On any error the
/// temporary file is removed and the target is left untouched.
pub fn write_atomic<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let (tmp, target) = begin(path)?;
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        fill(&mut w)?;
        w.flush()?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        finish(f, &tmp, &target)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Atomically writes a whole byte buffer.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failure_leaves_previous_file_and_no_temp() {
        let dir = std::env::temp_dir().join(format!("odocal-atomic-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.txt");
        write_bytes_atomic(&p, b"old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(&p).unwrap(), b"old");
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty());
        write_bytes_atomic(&p, b"new").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        fs::remove_dir_all(&dir).unwrap();
    }
}
