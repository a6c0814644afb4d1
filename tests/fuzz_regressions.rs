//! Inputs that once crashed a fuzz target (or made a reader return a
//! non-finite number), kept in `tests/fuzz-regressions/<target>/` and fed to
//! the same entry point as the fuzz target. Each must now give an error value;
//! a file named `ok-*` is valid input and must read soundly instead.

use odocal::io::SampleSource;
use std::path::{Path, PathBuf};

use odocal::effects::Effect;
use odocal::io::carmen::read_carmen_bytes;
use odocal::io::kitti::parse_kitti;
use odocal::io::relations::parse_relations;
use odocal::io::ros_msgs::{
    DiagnosticArrayMsg, ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg,
    PoseStampedMsg, RosMsg, TfMessage,
};
use odocal::io::tum::parse_tum;
use odocal::io::{read_mcap_bytes, ReadOptions, TopicConfig};
use odocal::pipeline::Config;
use odocal::robot::RobotConfig;

use crate::io_props::assert_sound;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions")
}

/// Decodes with the message type and wire the fuzz target picks from the
/// first byte (bit 3: ROS 1; type 7: the tick arrays); `Ok(())` when it
/// decodes (and a CDR message re-encodes to something that decodes).
fn cdr(data: &[u8]) -> Result<(), String> {
    fn round<M: RosMsg>(d: &[u8], ros1: bool) -> Result<(), String> {
        if ros1 {
            return M::decode_ros1(d).map(|_| ()).map_err(|e| e.to_string());
        }
        let m = M::decode(d).map_err(|e| e.to_string())?;
        M::decode(&m.encode())
            .map(|_| ())
            .map_err(|e| e.to_string())
    }
    fn ticks(d: &[u8], ros1: bool, pick: u8) -> Result<(), String> {
        use odocal::robot::TicksType::*;
        let types = [
            Int16MultiArray,
            UInt16MultiArray,
            Int32MultiArray,
            UInt32MultiArray,
            Int64MultiArray,
            UInt64MultiArray,
        ];
        let ty = types[usize::from(pick) % types.len()];
        let mut r = if ros1 {
            odocal::io::cdr::CdrReader::ros1(d)
        } else {
            odocal::io::cdr::CdrReader::new(d).map_err(|e| e.to_string())?
        };
        odocal::io::ros_msgs::read_int_array(&mut r, ty)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }
    let (&kind, msg) = data.split_first().ok_or("empty")?;
    let ros1 = kind & 8 != 0;
    match (kind & 7, kind >> 4) {
        (0, _) => round::<LaserScanMsg>(msg, ros1),
        (1, _) => round::<JointStateMsg>(msg, ros1),
        (2, _) => round::<ImuMsg>(msg, ros1),
        (3, _) => round::<OdometryMsg>(msg, ros1),
        (4, _) => round::<PoseStampedMsg>(msg, ros1),
        (5, _) => round::<PointStampedMsg>(msg, ros1),
        (6, _) => round::<TfMessage>(msg, ros1),
        (_, 15) => round::<DiagnosticArrayMsg>(msg, ros1),
        (_, pick) => ticks(msg, ros1, pick),
    }
}

/// Reads `data` as the `rosbag2_dir` fuzz target lays it out (metadata.yaml,
/// a NUL, then the storage file's bytes under both names it may give) in a
/// scratch folder named by `tag`, removed afterwards.
fn read_as_rosbag2_dir(
    data: &[u8],
    tag: &str,
) -> Result<odocal::recording::Recording, odocal::InputError> {
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let (yaml, rest) = data.split_at(split);
    let storage = rest.get(1..).unwrap_or(&[]);
    let dir = std::env::temp_dir().join(format!(
        "odocal-fuzz-dir-{tag}-{}-{}",
        std::process::id(),
        data.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("metadata.yaml"), yaml).unwrap();
    std::fs::write(dir.join("bag_0.db3"), storage).unwrap();
    std::fs::write(dir.join("bag_0.mcap"), storage).unwrap();
    let opts = ReadOptions::default();
    let read = odocal::io::rosbag2_dir::open(&dir, &opts)
        .and_then(|mut src| odocal::io::collect(&mut *src));
    std::fs::remove_dir_all(&dir).unwrap();
    read
}

fn text(data: &[u8]) -> Result<&str, String> {
    std::str::from_utf8(data).map_err(|e| e.to_string())
}

/// Runs one regression file through its target's entry point: `Ok` when the
/// input was accepted (after checking what was read), `Err` with the reason.
fn run(target: &str, data: &[u8]) -> Result<(), String> {
    let e = |x: odocal::InputError| x.to_string();
    match target {
        "mcap_read" => {
            let reference = ReadOptions {
                topics: TopicConfig {
                    reference: "/reference".into(),
                    ..Default::default()
                },
                ..Default::default()
            };
            // The streaming reader (icp, calibrate) must refuse it as well.
            let file = std::env::temp_dir().join(format!(
                "odocal-fuzz-{}-{}.mcap",
                std::process::id(),
                data.len()
            ));
            std::fs::write(&file, data).unwrap();
            let streamed =
                odocal::io::McapStream::open(&file, &ReadOptions::default()).and_then(|mut s| {
                    let mut n = 0usize;
                    while s.next_item()?.is_some() {
                        n += 1;
                    }
                    Ok(n)
                });
            std::fs::remove_file(&file).unwrap();
            let mut out = Err(String::new());
            for opts in [ReadOptions::default(), reference] {
                match read_mcap_bytes(data, "fuzz.mcap", &opts) {
                    Ok(r) => {
                        assert_sound(&r);
                        out = Ok(());
                    }
                    Err(x) => {
                        if out.is_err() {
                            out = Err(e(x));
                        }
                    }
                }
            }
            if let Ok(n) = streamed {
                // Accepted by the stream: it must then be accepted whole too.
                assert!(
                    out.is_ok(),
                    "streamed {n} items of a file the reader refuses"
                );
            }
            out
        }
        "cdr_msgs" => cdr(data),
        "carmen" => read_carmen_bytes(data, "fuzz.clf", &ReadOptions::default())
            .map(|r| assert_sound(&r))
            .map_err(e),
        "tum" => parse_tum(text(data)?, "fuzz.tum")
            .map(|t| {
                assert_eq!(t.first_non_finite(), None);
            })
            .map_err(e),
        "kitti" => {
            let t = text(data)?;
            let (p, s) = t.split_once('\0').unwrap_or((t, ""));
            parse_kitti(p, "fuzz.txt", s, "fuzz.times")
                .map(|t| assert_eq!(t.first_non_finite(), None))
                .map_err(e)
        }
        "relations" => parse_relations(text(data)?, "fuzz.relations")
            .map(|_| ())
            .map_err(e),
        "effect_spec" => Effect::parse(text(data)?)
            .map(|_| ())
            .map_err(|x| x.to_string()),
        "robot_toml" => RobotConfig::from_toml(text(data)?)
            .map(|c| assert!(c.rad_per_tick().is_finite()))
            .map_err(|x| x.to_string()),
        "pipeline_toml" => Config::parse(text(data)?, "fuzz.toml")
            .map(|_| ())
            .map_err(|x| x.to_string()),
        "censi_tuples" => odocal::io::censi::parse(text(data)?, "fuzz.tuple")
            .map(|tuples| {
                // As the fuzz target: what is accepted makes motions that
                // move forward in time, with finite values.
                let mount = odocal::geom::pose(0.1, -0.02, 0.3);
                let (_, motions) = odocal::io::censi::to_streams(&tuples, &mount, 0.005, 0.002);
                for m in &motions {
                    assert!(
                        m.t1 > m.t0 && m.dx.is_finite() && m.dtheta.is_finite(),
                        "{m:?}"
                    );
                }
            })
            .map_err(e),
        "rosbag2_dir" => read_as_rosbag2_dir(data, "regression")
            .map(|r| assert_sound(&r))
            .map_err(e),
        other => panic!("unknown fuzz target folder '{other}'"),
    }
}

fn files(target: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(target)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

#[test]
fn every_fuzz_finding_is_now_an_error_value() {
    let mut n = 0;
    for t in std::fs::read_dir(dir()).unwrap() {
        let t = t.unwrap().path();
        if !t.is_dir() {
            continue;
        }
        let target = t.file_name().unwrap().to_string_lossy().to_string();
        for f in files(&t) {
            let data = std::fs::read(&f).unwrap();
            let name = f.file_name().unwrap().to_string_lossy().to_string();
            let got = run(&target, &data);
            if name.starts_with("ok-") {
                assert!(got.is_ok(), "{target}/{name}: {got:?}");
            } else {
                assert!(got.is_err(), "{target}/{name} must be refused");
                eprintln!("{target}/{name}: {}", got.unwrap_err());
            }
            n += 1;
        }
    }
    assert!(n > 0, "no regression inputs found in {}", dir().display());
}

#[test]
fn chunk_header_string_length_is_refused_before_any_allocation() {
    // libFuzzer found a chunk whose compression-name length field claims
    // 2.7 GB: the `mcap` parser would reserve that much before noticing.
    // Both readers must refuse it from the length check itself.
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-regressions/mcap_read/string-length-in-chunk-header");
    let whole = odocal::io::read_recording(&file, &ReadOptions::default()).unwrap_err();
    let streamed = odocal::io::McapStream::open(&file, &ReadOptions::default())
        .and_then(|mut s| {
            while s.next_item()?.is_some() {}
            Ok(())
        })
        .unwrap_err();
    for e in [whole, streamed] {
        let m = e.to_string();
        assert!(m.contains("claims 2734686212 bytes"), "{m}");
        assert!(m.contains("string-length-in-chunk-header"), "{m}");
    }
}

#[test]
fn a_record_longer_than_its_file_is_refused_before_it_is_allocated() {
    // libFuzzer found a 28 kB MCAP (in a rosbag2 folder) whose record claims
    // 678 MB: the streaming reader allocated that much (700 MB resident)
    // before reading. No record is longer than its file, so the limit is the
    // file's length and the claim is refused from its length field.
    let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-regressions/rosbag2_dir/record-longer-than-its-file");
    let data = std::fs::read(&case).unwrap();
    let streamed = read_as_rosbag2_dir(&data, "long-record")
        .unwrap_err()
        .to_string();
    assert!(
        streamed.contains("length exceeds limit") && streamed.contains("678037049"),
        "{streamed}"
    );
}
