//! ROS 1 bags, rosbag2 SQLite files and rosbag2 folders written by an
//! independent writer (the Python `rosbags` package, `tools/bag_convert.py`)
//! from ROS 2 MCAPs: read through `io::open`, every sample equals, value for
//! value, what the source MCAP gives; `odocal icp` writes byte-identical
//! trajectories from every form of two benchmark logs; damaged bags give an
//! error naming file and position, never a panic.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use odocal::io::{collect, open, read_recording, sniff, Format, ReadOptions};
use odocal::recording::Recording;

use crate::support::{python_tool, python_with, scratch, shared_data};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// Runs `tools/bag_convert.py SRC OUT ARGS...`; `None` (skip) without
/// Python and rosbags outside CI.
fn convert(test: &str, src: &Path, out: &Path, args: &[&str]) -> Option<()> {
    let py = python_with(test, &["rosbags", "mcap"])?;
    let mut all = vec![src.as_os_str(), out.as_os_str()];
    all.extend(args.iter().map(std::ffi::OsStr::new));
    python_tool(&py, "bag_convert.py", &all);
    Some(())
}

fn read(path: &Path) -> Recording {
    let opts = ReadOptions::default();
    let mut source = open(path, &opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    collect(&mut *source).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Asserts two recordings hold the same samples, bit for bit (NaN ranges too).
fn assert_same(a: &Recording, b: &Recording, what: &str) {
    assert_eq!(a.scans.len(), b.scans.len(), "{what}: scans");
    for (i, (x, y)) in a.scans.iter().zip(&b.scans).enumerate() {
        let head = |s: &odocal::scan::LaserScan| {
            [
                s.stamp,
                s.angle_min,
                s.angle_increment,
                s.time_increment,
                s.scan_time,
                s.range_min,
                s.range_max,
            ]
            .map(f64::to_bits)
        };
        assert_eq!(head(x), head(y), "{what}: scan {i}");
        let bits = |s: &odocal::scan::LaserScan| s.ranges.iter().map(|r| r.to_bits()).collect();
        let (bx, by): (Vec<u32>, Vec<u32>) = (bits(x), bits(y));
        assert_eq!(bx, by, "{what}: scan {i} ranges");
    }
    assert_eq!(a.wheels, b.wheels, "{what}: wheels");
    assert_eq!(a.gyro, b.gyro, "{what}: gyro");
    assert_eq!(a.odom, b.odom, "{what}: odometry");
    assert_eq!(a.reference, b.reference, "{what}: reference");
    assert_eq!(a.base_from_laser, b.base_from_laser, "{what}: laser mount");
}

/// The bundled recording converted once (bz2 ROS 1 bag, SQLite and MCAP
/// folders) and read from its MCAP.
fn bundled(test: &str) -> Option<&'static (PathBuf, Recording)> {
    static B: OnceLock<Option<(PathBuf, Recording)>> = OnceLock::new();
    B.get_or_init(|| {
        let dir = scratch("io_bags_bundled");
        convert(
            test,
            Path::new(BUNDLED),
            &dir,
            &["--ros1-compression", "bz2"],
        )?;
        let rec = read_recording(Path::new(BUNDLED), &ReadOptions::default()).unwrap();
        Some((dir, rec))
    })
    .as_ref()
}

#[test]
fn rosbags_bag_db3_and_folders_read_as_the_source_mcap() {
    let Some((dir, truth)) = bundled("rosbags_bag_db3_and_folders_read_as_the_source_mcap") else {
        return;
    };
    assert!(truth.scans.len() > 1000 && !truth.wheels.is_empty() && !truth.gyro.is_empty());
    assert!(!truth.reference.is_empty() && truth.base_from_laser.is_some());
    let db3 = dir.join("db3/db3.db3");
    for (path, format) in [
        (dir.join("bag.bag"), Format::Ros1Bag),
        (db3.clone(), Format::Rosbag2Sqlite),
        (dir.join("db3"), Format::Rosbag2Dir),
        (dir.join("mcap"), Format::Rosbag2Dir),
    ] {
        assert_eq!(sniff(&path).unwrap(), format, "{}", path.display());
        assert_same(&read(&path), truth, &path.display().to_string());
        // The whole-recording reader gives the same.
        let whole = read_recording(&path, &ReadOptions::default()).unwrap();
        assert_same(&whole, truth, "read_recording");
    }
}

#[test]
fn ros1_bags_with_lz4_or_plain_chunks_overlapping_in_time_read_in_time_order() {
    let test = "ros1_bags_with_lz4_or_plain_chunks_overlapping_in_time_read_in_time_order";
    let Some((_, truth)) = bundled(test) else {
        return;
    };
    let dir = scratch("io_bags_overlap");
    for compression in ["lz4", "none"] {
        let out = dir.join(compression);
        // Topic after topic in 16 KiB chunks: the chunks of /scan span the
        // whole recording, and so do those of every other topic.
        let args = [
            "--ros1-compression",
            compression,
            "--by-topic",
            "--only",
            "bag",
        ];
        convert(test, Path::new(BUNDLED), &out, &args).unwrap();
        let bag = out.join("bag.bag");
        assert_same(&read(&bag), truth, compression);
    }
}

/// Runs `odocal icp` on `input`; the TUM text written.
fn icp_tum(input: &Path, out: &Path) -> Vec<u8> {
    let o = Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["icp", "--input"])
        .arg(input)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "odocal icp {}: {}",
        input.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(out).unwrap()
}

/// Two of the four benchmark logs (all four: `tools/bag_formats_check.sh`).
#[test]
fn benchmark_logs_as_ros1_bag_and_db3_give_identical_icp_trajectories() {
    let test = "benchmark_logs_as_ros1_bag_and_db3_give_identical_icp_trajectories";
    let Some(data) = shared_data(test) else {
        return;
    };
    let dir = scratch("io_bags_benchmark");
    for log in ["mit-csail", "aces"] {
        let src = data.join(format!("slam-benchmark/{log}.mcap"));
        let out = dir.join(log);
        let args = ["--ros1-compression", "lz4", "--only", "bag,db3"];
        let Some(()) = convert(test, &src, &out, &args) else {
            return;
        };
        let want = icp_tum(&src, &dir.join(format!("{log}-mcap.tum")));
        assert!(want.len() > 100_000, "{log}: a real trajectory");
        let bag = icp_tum(&out.join("bag.bag"), &dir.join(format!("{log}-bag.tum")));
        assert!(bag == want, "{log}: .bag trajectory differs");
        let db3 = icp_tum(&out.join("db3"), &dir.join(format!("{log}-db3.tum")));
        assert!(db3 == want, "{log}: .db3 folder trajectory differs");
    }
}
