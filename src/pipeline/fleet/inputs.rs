//! Which recordings a fleet run takes: a directory laid out `ROBOT/…/REC`
//! (any recording odocal reads, in any sub-folder; a rosbag2 folder counts as
//! one recording), each placed in time by its own first stamp, or by the
//! first date in its path when its clock is not a date; or a manifest CSV
//! `robot,path,start`. And each recording's content hash (the result cache's
//! key).

use crate::error::InputError;
use crate::pipeline::PipelineError;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::{Path, PathBuf};

/// One recording to calibrate.
#[derive(Debug, Clone, PartialEq)]
pub struct Listed {
    /// The robot it belongs to.
    pub robot: String,
    /// Its path (as found or as the manifest resolves it).
    pub path: PathBuf,
    /// When it started (days since 1970-01-01, UTC).
    pub unix_day: f64,
    /// Where that time was taken from.
    pub start_from: StartFrom,
}

/// Where a recording's start time was taken from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StartFrom {
    /// The recording's own first stamp.
    #[default]
    Recording,
    /// The first date in its path (its clock is not a date).
    Path,
    /// The manifest's `start` column.
    Manifest,
}

/// The first second of 2000-01-01 (UTC), s since 1970: a recording whose
/// first stamp is earlier runs on a clock that counts from 0 or from boot
/// (a simulator, a robot without time sync), not on a date.
pub const FIRST_DATE_UNIX_S: f64 = 946_684_800.0;

/// The start of a recording from its own clock (days since 1970-01-01), when
/// that clock is a date.
fn stamped_day(path: &Path) -> Result<Option<f64>, PipelineError> {
    let first = crate::io::survey::first_stamp(path)?;
    Ok(first
        .filter(|&s| s >= FIRST_DATE_UNIX_S)
        .map(|s| s / 86_400.0))
}

/// Days since 1970-01-01 of a civil date (Hinnant's `days_from_civil` \[Hinnant\]).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146097 + doe - 719468
}

/// The civil date `YYYY-MM-DD` of a day number (Hinnant's `civil_from_days`).
pub fn date_of(day: i64) -> String {
    let z = day + 719468;
    let era = z.div_euclid(146097);
    let doe = z - era * 146097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// `YYYY-MM-DDTHH:MM:SSZ` of a time in days since 1970-01-01 (UTC),
/// rounded to the second.
pub fn datetime_of(unix_day: f64) -> String {
    let secs = (unix_day * 86_400.0).round() as i64;
    let (day, s) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    format!(
        "{}T{:02}:{:02}:{:02}Z",
        date_of(day),
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

/// The first `YYYY-MM-DD[(T| |_)HH(:|-)MM[(:|-)SS]]` in `text`, as days
/// since 1970-01-01 (UTC); `None` when there is none or it is not a date.
pub fn find_date(text: &str) -> Option<f64> {
    let b = text.as_bytes();
    let digits = |i: usize, n: usize| -> Option<i64> {
        let s = b.get(i..i + n)?;
        s.iter()
            .all(u8::is_ascii_digit)
            .then(|| std::str::from_utf8(s).ok()?.parse().ok())?
    };
    (0..b.len()).find_map(|i| {
        if i > 0 && b[i - 1].is_ascii_digit() {
            return None;
        }
        let (y, m, d) = (digits(i, 4)?, digits(i + 5, 2)?, digits(i + 8, 2)?);
        if b[i + 4] != b'-' || b[i + 7] != b'-' || !(1..=12).contains(&m) || !(1..=31).contains(&d)
        {
            return None;
        }
        let mut day = days_from_civil(y, m, d) as f64;
        let sep = |k: usize, set: &[u8]| b.get(k).is_some_and(|c| set.contains(c));
        if sep(i + 10, b"T _") && sep(i + 13, b":-") {
            if let (Some(h), Some(mi)) = (digits(i + 11, 2), digits(i + 14, 2)) {
                let s = if sep(i + 16, b":-") {
                    digits(i + 17, 2).unwrap_or(0)
                } else {
                    0
                };
                if h < 24 && mi < 60 && s < 61 {
                    day += (h * 3600 + mi * 60 + s) as f64 / 86400.0;
                }
            }
        }
        Some(day)
    })
}

/// File extensions of recordings: bags, CARMEN logs, Censi et al.'s tuples.
const RECORDING_EXTENSIONS: [&str; 6] = ["mcap", "bag", "db3", "log", "clf", "tuple"];

fn is_recording_file(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| RECORDING_EXTENSIONS.contains(&e))
}

/// The entries of `dir`, sorted.
fn children(dir: &Path) -> Result<Vec<PathBuf>, PipelineError> {
    let read = std::fs::read_dir(dir)
        .map_err(|e| InputError::new(dir.display().to_string(), format!("cannot list: {e}")))?;
    let mut paths: Vec<PathBuf> = read.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    Ok(paths)
}

/// Every recording under `dir` (sorted), a rosbag2 folder as one.
fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), PipelineError> {
    for p in children(dir)? {
        if p.is_dir() {
            if p.join("metadata.yaml").is_file() {
                out.push(p);
            } else {
                walk(&p, out)?;
            }
        } else if is_recording_file(&p) {
            out.push(p);
        }
    }
    Ok(())
}

/// The recordings of a directory laid out `ROBOT/…/REC`, each placed by its
/// first stamp, or by the first date in its path below `ROBOT/` when its
/// clock is not a date.
fn from_dir(dir: &Path) -> Result<Vec<Listed>, PipelineError> {
    let mut found = Vec::new();
    walk(dir, &mut found)?;
    let mut listed = Vec::new();
    for path in found {
        let rel = path.strip_prefix(dir).unwrap_or(&path);
        let mut parts = rel.components();
        let robot = parts
            .next()
            .map(|c| c.as_os_str().to_string_lossy().to_string());
        let below: PathBuf = parts.collect();
        let (Some(robot), false) = (robot, below.as_os_str().is_empty()) else {
            return Err(InputError::new(
                path.display().to_string(),
                "a recording directly in the fleet folder: lay it out as ROBOT/DATE/recording \
                 or give a manifest CSV (robot,path,start)",
            )
            .into());
        };
        // A recording that cannot be read is still placed by its path when
        // it can be: its calibration then reports what is wrong with it.
        let (unix_day, start_from) = match (stamped_day(&path), find_date(&below.to_string_lossy()))
        {
            (Ok(Some(day)), _) => (day, StartFrom::Recording),
            (_, Some(day)) => (day, StartFrom::Path),
            (Err(e), None) => {
                return Err(InputError::new(
                    path.display().to_string(),
                    format!(
                        "its first stamp cannot be read ({e}) and its path below the robot's \
                         folder holds no date YYYY-MM-DD: put it under ROBOT/YYYY-MM-DD/ or \
                         give a manifest CSV (robot,path,start)"
                    ),
                )
                .into())
            }
            (Ok(None), None) => {
                return Err(InputError::new(
                    path.display().to_string(),
                    "its clock is not a date (first stamp before 2000-01-01, or none) and \
                     its path below the robot's folder holds no date YYYY-MM-DD: put it \
                     under ROBOT/YYYY-MM-DD/ or give a manifest CSV (robot,path,start)",
                )
                .into())
            }
        };
        listed.push(Listed {
            robot,
            path,
            unix_day,
            start_from,
        });
    }
    Ok(listed)
}

/// The recordings of a manifest CSV: a header `robot,path,start`, then one
/// line per recording, `path` relative to the manifest's folder, `start` a
/// date `YYYY-MM-DD` with an optional time `THH:MM[:SS]` (UTC).
fn from_manifest(csv: &Path) -> Result<Vec<Listed>, PipelineError> {
    let name = csv.display().to_string();
    crate::io::input::check_regular(csv)?;
    let text = std::fs::read_to_string(csv)
        .map_err(|e| InputError::new(&name, format!("cannot read: {e}")))?;
    let base = csv.parent().unwrap_or(Path::new("."));
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let header: Vec<String> = match lines.next() {
        Some((_, h)) => h.split(',').map(|c| c.trim().to_lowercase()).collect(),
        None => {
            return Err(
                InputError::new(&name, "empty manifest: want a header robot,path,start").into(),
            )
        }
    };
    let col = |want: &str| {
        header.iter().position(|c| c == want).ok_or_else(|| {
            InputError::new(
                &name,
                format!("no column '{want}' in the header: want robot,path,start"),
            )
            .at("line 1")
        })
    };
    let (c_robot, c_path, c_start) = (col("robot")?, col("path")?, col("start")?);
    let mut listed = Vec::new();
    for (i, line) in lines {
        let at = format!("line {}", i + 1);
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let cell = |k: usize| {
            cells
                .get(k)
                .copied()
                .filter(|c| !c.is_empty())
                .ok_or_else(|| {
                    InputError::new(
                        &name,
                        format!("{} columns, want robot,path,start", cells.len()),
                    )
                    .at(at.clone())
                })
        };
        let (robot, path, start) = (cell(c_robot)?, cell(c_path)?, cell(c_start)?);
        let unix_day = find_date(start)
            .filter(|_| start.len() <= 25)
            .ok_or_else(|| {
                InputError::new(
                    &name,
                    format!("start '{start}' is not a date YYYY-MM-DD[THH:MM[:SS]]"),
                )
                .at(at.clone())
            })?;
        let path = base.join(path);
        if !path.exists() {
            return Err(
                InputError::new(&name, format!("{} does not exist", path.display()))
                    .at(at)
                    .into(),
            );
        }
        listed.push(Listed {
            robot: robot.to_string(),
            path,
            unix_day,
            start_from: StartFrom::Manifest,
        });
    }
    Ok(listed)
}

/// The recordings of `source`: a manifest CSV (a file) or a fleet folder;
/// at least one.
pub fn list(source: &Path) -> Result<Vec<Listed>, PipelineError> {
    let listed = if source.is_dir() {
        from_dir(source)?
    } else {
        from_manifest(source)?
    };
    if listed.is_empty() {
        return Err(InputError::new(
            source.display().to_string(),
            "no recording found (*.mcap, *.bag, *.db3, *.log, *.clf, *.tuple or rosbag2 \
             folders under ROBOT/…)",
        )
        .into());
    }
    Ok(listed)
}

/// SHA-256 of a recording's bytes (a folder: of its files' names and bytes,
/// in name order), in hex.
pub fn content_hash(path: &Path) -> Result<String, PipelineError> {
    let mut h = Sha256::new();
    let mut files = Vec::new();
    if path.is_dir() {
        walk_all(path, &mut files)?;
    } else {
        files.push(path.to_path_buf());
    }
    let mut buf = vec![0u8; 1 << 16];
    for f in files {
        let name = f
            .strip_prefix(path)
            .unwrap_or(&f)
            .to_string_lossy()
            .to_string();
        h.update(name.as_bytes());
        let mut file = std::fs::File::open(&f)
            .map_err(|e| InputError::new(f.display().to_string(), format!("cannot read: {e}")))?;
        loop {
            let n = file.read(&mut buf).map_err(|e| {
                InputError::new(f.display().to_string(), format!("cannot read: {e}"))
            })?;
            if n == 0 {
                break;
            }
            h.update(&buf[..n]);
        }
    }
    Ok(hex(&h.finalize()))
}

/// Every file under `dir`, sorted.
fn walk_all(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), PipelineError> {
    for p in children(dir)? {
        if p.is_dir() {
            walk_all(&p, out)?;
        } else {
            out.push(p);
        }
    }
    Ok(())
}

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_round_trip_and_times_add_fractions_of_a_day() {
        // 2000-03-01 is day 11017 (e.g. `date -d 2000-03-01 +%s` / 86400).
        assert_eq!(find_date("chair/2000-03-01/run.mcap"), Some(11017.0));
        assert_eq!(date_of(11017), "2000-03-01");
        assert_eq!(date_of(0), "1970-01-01");
        assert_eq!(find_date("2024-02-29T12:00:00Z"), Some(19782.5));
        assert_eq!(date_of(19782), "2024-02-29");
        assert_eq!(find_date("run-2024-13-01.mcap"), None);
        assert_eq!(find_date("12024-01-01"), None);
        // 1700000000 s is 2023-11-14 22:13:20 UTC (`date -u -d @1700000000`).
        assert_eq!(datetime_of(1.7e9 / 86_400.0), "2023-11-14T22:13:20Z");
    }
}
