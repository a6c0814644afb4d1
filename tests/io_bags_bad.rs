//! Damaged ROS 1 bags, rosbag2 SQLite files and rosbag2 folders: each is an
//! `InputError` naming the file and the position (byte offset, row id) or a
//! sound partial read, never a panic; the command line exits with code 2.
//! The bags come from the `rosbags` package (`tools/bag_convert.py`) on the
//! first 3 s of the bundled recording.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use odocal::io::{collect, open, read_recording, write_mcap, ReadOptions, WriteOptions};
use odocal::recording::Recording;
use odocal::InputError;
use proptest::prelude::*;

use crate::io_props::assert_sound;
use crate::support::{python_with, scratch};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// Small bags: `none/bag.bag`, `bz2/bag.bag`, `lz4/bag.bag` (lz4 topic after
/// topic), `none/db3/db3.db3`, and the recording they hold.
fn small() -> Option<&'static (PathBuf, Recording)> {
    static S: OnceLock<Option<(PathBuf, Recording)>> = OnceLock::new();
    S.get_or_init(|| {
        let py = python_with("io_bags_bad (small bags)", &["rosbags", "mcap"])?;
        let dir = scratch("io_bags_bad_small");
        let mut rec = read_recording(Path::new(BUNDLED), &ReadOptions::default()).unwrap();
        let end = rec.scans[0].stamp + 3.0;
        rec.scans.retain(|s| s.stamp < end);
        rec.wheels.retain(|s| s.stamp < end);
        rec.gyro.retain(|s| s.stamp < end);
        rec.odom.retain(|s| s.stamp < end);
        rec.reference.retain(|s| s.stamp < end);
        let src = dir.join("small.mcap");
        write_mcap(&src, &rec, &WriteOptions::default()).unwrap();
        let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/bag_convert.py");
        for (sub, args) in [
            ("none", &["--only", "bag,db3"][..]),
            ("bz2", &["--ros1-compression", "bz2", "--only", "bag"][..]),
            (
                "lz4",
                &["--ros1-compression", "lz4", "--by-topic", "--only", "bag"][..],
            ),
        ] {
            let o = Command::new(&py)
                .arg(&tool)
                .arg(&src)
                .arg(dir.join(sub))
                .args(args)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        let read = read_recording(&src, &ReadOptions::default()).unwrap();
        Some((dir, read))
    })
    .as_ref()
}

/// Reads `path` through `io::open` as every command does.
fn read(path: &Path) -> Result<Recording, InputError> {
    let opts = ReadOptions::default();
    let mut source = open(path, &opts)?;
    collect(&mut *source)
}

/// Writes `bytes` as `name` in a fresh scratch folder and reads it.
fn read_bytes(test: &str, name: &str, bytes: &[u8]) -> Result<Recording, InputError> {
    let path = scratch(test).join(name);
    std::fs::write(&path, bytes).unwrap();
    read(&path)
}

/// `odocal icp` on `input`: exit code and stderr.
fn icp(input: &Path) -> (i32, String) {
    let out = std::env::temp_dir().join(format!("odocal-bags-bad-{}.tum", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["icp", "--input"])
        .arg(input)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Byte offset of the first occurrence of `needle` at or after `from`.
fn find(hay: &[u8], needle: &[u8], from: usize) -> usize {
    from + hay[from..]
        .windows(needle.len())
        .position(|w| w == needle)
        .unwrap_or_else(|| panic!("{:?} not found", String::from_utf8_lossy(needle)))
}

#[test]
fn folder_without_metadata_or_with_a_missing_file_is_refused_with_exit_code_2() {
    let dir = scratch("bags_bad_folder");
    let (code, err) = icp(&dir);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("metadata.yaml") && err.contains("odocal-test"),
        "{err}"
    );
    let meta = "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: sqlite3\n  \
                relative_file_paths:\n  - gone_0.db3\n";
    std::fs::write(dir.join("metadata.yaml"), meta).unwrap();
    let e = read(&dir).unwrap_err();
    assert!(e.file.ends_with("metadata.yaml"), "{e}");
    assert!(e.message.contains("gone_0.db3"), "{e}");
    let zstd = meta.replace(
        "version: 9",
        "version: 9\n  compression_format: zstd\n  compression_mode: file",
    );
    std::fs::write(dir.join("metadata.yaml"), zstd).unwrap();
    let e = read(&dir).unwrap_err();
    assert!(
        e.message.contains("compressed") && e.message.contains("zstd"),
        "{e}"
    );
    std::fs::write(
        dir.join("metadata.yaml"),
        "rosbag2_bagfile_information: [1, 2]\n",
    )
    .unwrap();
    let e = read(&dir).unwrap_err();
    assert!(e.message.contains("not a rosbag2 metadata file"), "{e}");
}

#[test]
fn sqlite_file_without_the_rosbag2_tables_is_refused_with_exit_code_2() {
    let path = scratch("bags_bad_sqlite").join("other.db3");
    let db = rusqlite::Connection::open(&path).unwrap();
    db.execute_batch("CREATE TABLE topics(id INTEGER, name TEXT);")
        .unwrap();
    drop(db);
    let e = read(&path).unwrap_err();
    assert!(e.message.contains("no table 'messages'"), "{e}");
    assert_eq!(e.file, path.display().to_string());
    let (code, err) = icp(&path);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no table 'messages'"), "{err}");
}

#[test]
fn sqlite_message_with_a_bad_timestamp_names_its_row() {
    let Some((dir, _)) = small() else { return };
    let path = scratch("bags_bad_sqlite_row").join("bag.db3");
    std::fs::copy(dir.join("none/db3/db3.db3"), &path).unwrap();
    let db = rusqlite::Connection::open(&path).unwrap();
    db.execute("UPDATE messages SET timestamp = -5 WHERE id = 7", [])
        .unwrap();
    drop(db);
    let e = read(&path).unwrap_err();
    assert_eq!(e.position.as_deref(), Some("row id 7"), "{e}");
    assert!(e.message.contains("negative timestamp"), "{e}");
    assert!(e.topic.is_some(), "{e}");
}

#[test]
fn ros1_bag_with_unknown_compression_missing_connection_or_no_index_is_refused() {
    let Some((dir, truth)) = small() else { return };
    let bag = std::fs::read(dir.join("none/bag.bag")).unwrap();
    assert_eq!(
        read_bytes("bags_bad_ok", "ok.bag", &bag)
            .unwrap()
            .scans
            .len(),
        truth.scans.len()
    );
    // Unknown compression in the first chunk's header.
    let mut b = bag.clone();
    let at = find(&b, b"compression=none", 0);
    b[at + 12..at + 16].copy_from_slice(b"zzzz");
    let e = read_bytes("bags_bad_compression", "c.bag", &b).unwrap_err();
    assert!(e.message.contains("'zzzz'"), "{e}");
    assert!(
        e.position
            .as_deref()
            .is_some_and(|p| p.starts_with("byte ")),
        "{e}"
    );
    // The index lists the connections under other ids than the chunks use.
    let mut b = bag.clone();
    let index = find(&b, b"index_pos=", 0) + 10;
    let index = u64::from_le_bytes(b[index..index + 8].try_into().unwrap()) as usize;
    let mut from = index;
    while let Some(p) = b[from..].windows(5).position(|w| w == b"conn=") {
        let at = from + p + 5;
        b[at..at + 4].copy_from_slice(&(1000 + at as u32).to_le_bytes());
        from = at;
    }
    let e = read_bytes("bags_bad_connection", "k.bag", &b).unwrap_err();
    assert!(e.message.contains("does not list"), "{e}");
    // The first JointState's name count made huge: the message is named.
    let mut b = bag.clone();
    let robot = odocal::robot::RobotConfig::default();
    let name_at = |n: &str| {
        let mut pat = (n.len() as u32).to_le_bytes().to_vec();
        pat.extend_from_slice(n.as_bytes());
        find(&b, &pat, 0)
    };
    let first = name_at(&robot.left_joint).min(name_at(&robot.right_joint));
    b[first - 4..first].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = read_bytes("bags_bad_message", "m.bag", &b).unwrap_err();
    assert_eq!(e.topic.as_deref(), Some("/joint_states"), "{e}");
    let at = e.position.clone().unwrap_or_default();
    assert!(at.starts_with("message 0 (chunk at byte "), "{e}");
    assert!(e.message.contains("sequence of 4294967295"), "{e}");
    // A configured topic of another type names the topic.
    let mut opts = ReadOptions::default();
    opts.topics.scan = "/joint_states".into();
    let path = scratch("bags_bad_type").join("t.bag");
    std::fs::write(&path, &bag).unwrap();
    let e = open(&path, &opts)
        .err()
        .expect("a JointState topic is no scan topic");
    assert_eq!(e.topic.as_deref(), Some("/joint_states"), "{e}");
    assert!(e.message.contains("sensor_msgs/JointState"), "{e}");
    // A bag whose recording was not closed has index_pos 0.
    let mut b = bag.clone();
    let at = find(&b, b"index_pos=", 0) + 10;
    b[at..at + 8].copy_from_slice(&0u64.to_le_bytes());
    let path = scratch("bags_bad_unindexed").join("u.bag");
    std::fs::write(&path, &b).unwrap();
    let (code, err) = icp(&path);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("reindex") && err.contains("u.bag"), "{err}");
}

#[test]
fn ros1_bag_cut_anywhere_in_its_index_is_an_error() {
    let Some((dir, _)) = small() else { return };
    let bag = std::fs::read(dir.join("lz4/bag.bag")).unwrap();
    let at = find(&bag, b"index_pos=", 0) + 10;
    let index = u64::from_le_bytes(bag[at..at + 8].try_into().unwrap()) as usize;
    assert!(bag.len() - index > 1000, "an index of many chunks");
    let path = scratch("bags_bad_index_cut").join("i.bag");
    // Every cut loses part of the index: every 13th byte, and every byte
    // where a record may start (a plausible u32 header length follows), so
    // that cuts between whole records are among them.
    let boundary = |c: usize| {
        bag.get(c..c + 4)
            .is_some_and(|b| (8..512).contains(&u32::from_le_bytes(b.try_into().unwrap())))
    };
    for cut in (index..bag.len()).filter(|&c| c % 13 == 0 || boundary(c)) {
        std::fs::write(&path, &bag[..cut]).unwrap();
        let e = read(&path).expect_err("a cut index is an error");
        assert!(e.position.is_some(), "cut at {cut}: {e}");
    }
}

/// The small bags' bytes: plain, bz2 and lz4 ROS 1 bags, and the SQLite file.
fn small_files() -> Option<Vec<(&'static str, Vec<u8>)>> {
    let (dir, _) = small()?;
    Some(
        [
            ("none.bag", "none/bag.bag"),
            ("bz2.bag", "bz2/bag.bag"),
            ("lz4.bag", "lz4/bag.bag"),
            ("small.db3", "none/db3/db3.db3"),
        ]
        .into_iter()
        .map(|(name, f)| (name, std::fs::read(dir.join(f)).unwrap()))
        .collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A ROS 1 bag cut anywhere loses its index: always an error naming the
    /// file. A cut SQLite file is an error or a sound partial read.
    #[test]
    fn truncated_bag_or_db3_is_an_error(which in 0usize..4, f in 0.0f64..1.0) {
        let Some(files) = small_files() else { return Ok(()) };
        let (name, bytes) = &files[which];
        let cut = ((bytes.len() as f64 * f) as usize).min(bytes.len() - 1);
        match read_bytes("bags_props_cut", name, &bytes[..cut]) {
            Err(e) => prop_assert!(e.file.ends_with(name), "{e}"),
            Ok(r) => {
                prop_assert!(name.ends_with(".db3"), "{name} cut at {cut} read");
                assert_sound(&r);
            }
        }
    }

    /// Flipped bits anywhere: an error naming the file, or a sound read.
    #[test]
    fn bit_flipped_bag_or_db3_never_panics(which in 0usize..4, f in 0.0f64..1.0, bit in 0u8..8) {
        let Some(files) = small_files() else { return Ok(()) };
        let (name, bytes) = &files[which];
        let mut b = bytes.clone();
        let at = ((b.len() as f64 * f) as usize).min(b.len() - 1);
        b[at] ^= 1 << bit;
        match read_bytes("bags_props_flip", name, &b) {
            Err(e) => prop_assert!(e.file.ends_with(name), "{e}"),
            Ok(r) => assert_sound(&r),
        }
    }
}
