//! Reads CARMEN logs (`.clf`), the format of the classic SLAM benchmark
//! datasets: `FLASER`, `ROBOTLASER1` and `ODOM` lines; other lines are skipped.
//! The stamp of every record is its `ipc_timestamp`. A record must be
//! complete up to its `logger_timestamp`, so that a line cut inside a number
//! is never read as a shorter number, and no longer than its counts say (a
//! `FLASER n` line holds exactly n + 10 values after its keyword). A log cut
//! short (its last line without a newline and incomplete) is refused as
//! truncated, naming the line; so is a line longer than [`MAX_LINE_BYTES`].

use std::f64::consts::PI;
use std::path::Path;

use super::options::ReadOptions;
use crate::assumptions::Origin;
use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::recording::{Recording, StampedPose};
use crate::scan::LaserScan;

/// Smallest valid range (m) of `FLASER` scans, which carry no limits: the
/// value the benchmark's ROS conversion (carmen_to_rosbag) uses.
pub const FLASER_RANGE_MIN: f64 = 0.1;
/// Largest valid range (m) of `FLASER` scans; readings of 81.83/81.91 m mark
/// "no return" and fall outside it.
pub const FLASER_RANGE_MAX: f64 = 80.0;

/// Longest line (bytes) read as a record: a `FLASER` line of the largest
/// beam count taken (10⁶ readings of up to 10 characters) fits well within it.
pub const MAX_LINE_BYTES: usize = 16 << 20;

/// Most readings a record may announce.
const MAX_READINGS: f64 = 1e6;

/// Reads a CARMEN log file.
pub fn read_carmen(path: &Path, opts: &ReadOptions) -> Result<Recording, InputError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    read_carmen_bytes(&bytes, &file, opts)
}

/// Beam increment (rad) of an `n`-beam FLASER scan starting at −π/2:
/// CARMEN uses π/n for even counts (180, 360: the last beam stops short of
/// +π/2) and π/(n−1) for odd counts (181, 361: −90°…+90° inclusive).
pub fn flaser_increment(n: usize) -> f64 {
    if n.is_multiple_of(2) {
        PI / n as f64
    } else {
        PI / (n.max(2) - 1) as f64
    }
}

/// Like [`read_carmen`] for a log in memory; `file` names it in errors.
pub fn read_carmen_bytes(
    bytes: &[u8],
    file: &str,
    opts: &ReadOptions,
) -> Result<Recording, InputError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| InputError::new(file, format!("not a CARMEN log (not UTF-8 text: {e})")))?;
    let source = opts.wheels.source;
    if source != crate::robot::WheelSourceKind::JointStates {
        return Err(InputError::new(
            file,
            format!(
                "a CARMEN log has no wheel topic, and the robot file's [wheels] source = \"{}\" \
                 asks for one; its ODOM lines are read as the robot's odometry poses. Use a robot \
                 file without [wheels] for this log",
                source.word()
            ),
        ));
    }
    let mut rec = Recording {
        source: file.to_string(),
        ..Default::default()
    };
    let mut known = 0usize;
    let mut mount = MountFromLog::default();
    let mut latest_scan = f64::NEG_INFINITY;
    let mut latest_odom = f64::NEG_INFINITY;
    // The last line, when the log does not end with a newline, may be cut.
    let cut_tail = if text.ends_with('\n') {
        usize::MAX
    } else {
        text.lines().count().saturating_sub(1)
    };
    for (i, line) in text.lines().enumerate() {
        if line.len() > MAX_LINE_BYTES {
            return Err(InputError::new(
                file,
                format!(
                    "line of {} bytes, over the cap of {} MiB for one CARMEN record",
                    line.len(),
                    MAX_LINE_BYTES >> 20
                ),
            )
            .at(format!("line {}", i + 1)));
        }
        let mut tok = line.split_ascii_whitespace();
        let Some(kind) = tok.next() else { continue };
        let err = |m: String| {
            InputError::new(file, m)
                .topic(kind)
                .at(format!("line {}", i + 1))
        };
        let fields: Vec<&str> = tok.collect();
        let parsed = match kind {
            "FLASER" => parse_flaser(&fields).map(|(scan, odom, laser)| {
                mount.see(&odom.pose, &laser, i + 1);
                (Some(scan), odom)
            }),
            "ROBOTLASER1" => parse_robotlaser(&fields).map(|(scan, odom, laser)| {
                mount.see(&odom.pose, &laser, i + 1);
                (Some(scan), odom)
            }),
            "ODOM" => parse_odom(&fields).map(|o| (None, o)),
            _ => continue,
        };
        let (scan, odom) = match parsed {
            Ok(p) => p,
            Err(m) if i == cut_tail => {
                return Err(err(format!(
                    "the log is truncated: its last line ends without a newline inside the \
                     record ({m})"
                )))
            }
            Err(m) => return Err(err(m)),
        };
        known += 1;
        let tolerance = opts.reorder_tolerance;
        if let Some(s) = scan {
            in_order("time", s.stamp, &mut latest_scan, tolerance).map_err(err)?;
            rec.scans.push(s);
        }
        in_order("odometry time", odom.stamp, &mut latest_odom, tolerance).map_err(err)?;
        rec.odom.push(odom);
    }
    if known == 0 {
        return Err(InputError::new(
            file,
            "neither an MCAP file nor a CARMEN log (no FLASER, ROBOTLASER1 or ODOM line)",
        ));
    }
    mount.finish(&mut rec);
    rec.sort_streams();
    Ok(rec)
}

/// The laser mounting a CARMEN log states: each laser line carries the
/// laser's pose and the robot's odometry pose, so `odom⁻¹ ⊕ laser` is
/// `base_from_laser` — when it is the same on every line. Logs whose laser
/// pose was corrected (by SLAM) give no fixed offset and state no mounting.
#[derive(Debug, Default)]
struct MountFromLog {
    first: Option<Pose2>,
    /// The first line whose offset departs from the first one's.
    departs: Option<usize>,
}

impl MountFromLog {
    /// Largest departure from the first line's offset still taken as the
    /// same mounting: the logs' 4–6 decimals.
    const TOL_M: f64 = 1e-3;
    const TOL_RAD: f64 = 1e-3;

    fn see(&mut self, odom: &Pose2, laser: &Pose2, line: usize) {
        let b = geom::between(odom, laser);
        match &self.first {
            None => self.first = Some(b),
            Some(f) if self.departs.is_none() => {
                let d = geom::between(f, &b);
                if d.translation.vector.norm() > Self::TOL_M
                    || d.rotation.angle().abs() > Self::TOL_RAD
                {
                    self.departs = Some(line);
                }
            }
            Some(_) => {}
        }
    }

    fn finish(self, rec: &mut Recording) {
        match (self.first, self.departs) {
            (Some(b), None) => {
                rec.base_from_laser = Some(b);
                rec.mount_origin = Some(Origin::Log);
            }
            (Some(_), Some(line)) => {
                rec.mount_note = Some(format!(
                    "the log's laser poses are not at a fixed offset from its odometry poses \
                     (from line {line} on), so they state no mounting"
                ));
            }
            (None, _) => {}
        }
    }
}

/// Checks that a stream's `stamp` goes back at most `tolerance` s behind the
/// `latest` stamp it has seen (the time policy in [`super`]), then advances
/// `latest`; `what` names the stream's time in the error.
fn in_order(what: &str, stamp: f64, latest: &mut f64, tolerance: f64) -> Result<(), String> {
    if stamp < *latest - tolerance {
        return Err(format!(
            "{what} goes backwards by {:.3} s, more than the {tolerance} s tolerance",
            *latest - stamp
        ));
    }
    *latest = latest.max(stamp);
    Ok(())
}

fn num(fields: &[&str], i: usize, what: &str) -> Result<f64, String> {
    let s = fields
        .get(i)
        .ok_or_else(|| format!("line ends before {what} (field {})", i + 2))?;
    let v: f64 = s
        .parse()
        .map_err(|_| format!("{what} '{s}' is not a number (field {})", i + 2))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{what} is {v} (field {})", i + 2))
    }
}

/// An `ipc_timestamp` (s): a finite number ≥ 0.
fn stamp(fields: &[&str], i: usize) -> Result<f64, String> {
    let t = num(fields, i, "ipc_timestamp")?;
    if t < 0.0 {
        return Err(format!("ipc_timestamp {t} is negative (field {})", i + 2));
    }
    Ok(t)
}

/// Checks that the record goes on past its `ipc_timestamp` at `i` to the
/// host and a `logger_timestamp` number: the line was not cut.
fn complete(fields: &[&str], i: usize) -> Result<(), String> {
    if fields.get(i + 1).is_none() {
        return Err(format!("line ends before the host name (field {})", i + 3));
    }
    num(fields, i + 2, "logger_timestamp")?;
    if fields.len() > i + 3 {
        return Err(format!(
            "{} values after the logger_timestamp (field {}): the line is longer than its \
             counts say",
            fields.len() - i - 3,
            i + 4
        ));
    }
    Ok(())
}

fn count(fields: &[&str], i: usize, what: &str) -> Result<usize, String> {
    let v = num(fields, i, what)?;
    if v < 0.0 || v.fract() != 0.0 {
        return Err(format!("{what} {v} is not a count"));
    }
    if v > MAX_READINGS {
        return Err(format!(
            "{what} {v} is over the cap of {MAX_READINGS:e} readings per record"
        ));
    }
    Ok(v as usize)
}

fn ranges(fields: &[&str], start: usize, n: usize) -> Result<Vec<f32>, String> {
    (start..start + n)
        .map(|i| num(fields, i, "range").map(|r| r as f32))
        .collect()
}

fn pose_at(fields: &[&str], i: usize, what: &str) -> Result<Pose2, String> {
    Ok(geom::pose(
        num(fields, i, what)?,
        num(fields, i + 1, what)?,
        num(fields, i + 2, what)?,
    ))
}

/// `FLASER n r… x y θ odom_x odom_y odom_θ ipc_timestamp host logger_timestamp`.
fn parse_flaser(f: &[&str]) -> Result<(LaserScan, StampedPose, Pose2), String> {
    let n = count(f, 0, "number of readings")?;
    if n == 0 {
        return Err("FLASER with zero beams".into());
    }
    if f.len() > n + 10 {
        return Err(format!(
            "FLASER {n} makes {} values after the keyword (n readings, two poses, three \
             stamps and host), but the line has {}",
            n + 10,
            f.len()
        ));
    }
    let r = ranges(f, 1, n)?;
    let laser = pose_at(f, n + 1, "laser pose")?;
    let odom = pose_at(f, n + 4, "odometry pose")?;
    let stamp = stamp(f, n + 7)?;
    complete(f, n + 7)?;
    let scan = LaserScan {
        stamp,
        angle_min: -PI / 2.0,
        angle_increment: flaser_increment(n),
        range_min: FLASER_RANGE_MIN,
        range_max: FLASER_RANGE_MAX,
        ranges: r,
        ..Default::default()
    };
    scan.check_geometry(None)?;
    Ok((
        scan,
        StampedPose {
            stamp,
            pose: odom,
            has_heading: true,
        },
        laser,
    ))
}

/// `ROBOTLASER1 type start_angle fov resolution max_range accuracy
/// remission_mode n r… m rem… laser_x laser_y laser_θ robot_x robot_y robot_θ
/// tv rv forward_safety side_safety turn_axis ipc_timestamp host logger_timestamp`.
/// Returns the scan, the robot's odometry pose and the laser's pose.
fn parse_robotlaser(f: &[&str]) -> Result<(LaserScan, StampedPose, Pose2), String> {
    let start = num(f, 1, "start_angle")?;
    let fov = num(f, 2, "fov")?;
    let res = num(f, 3, "angular_resolution")?;
    let max_range = num(f, 4, "maximum_range")?;
    let n = count(f, 7, "number of readings")?;
    if n == 0 {
        return Err("ROBOTLASER1 with zero beams".into());
    }
    if res == 0.0 && n > 1 {
        return Err("ROBOTLASER1 angular_resolution is 0 with several beams".into());
    }
    let r = ranges(f, 8, n)?;
    let m = count(f, 8 + n, "number of remissions")?;
    let p = 9 + n + m;
    let laser = pose_at(f, p, "laser pose")?;
    let robot = pose_at(f, p + 3, "robot pose")?;
    let stamp = stamp(f, p + 11)?;
    complete(f, p + 11)?;
    let scan = LaserScan {
        stamp,
        angle_min: start,
        angle_increment: res,
        range_min: 0.0,
        range_max: max_range,
        ranges: r,
        ..Default::default()
    };
    scan.check_geometry(Some(start + fov))?;
    let odom = StampedPose {
        stamp,
        pose: robot,
        has_heading: true,
    };
    Ok((scan, odom, laser))
}

/// `ODOM x y θ tv rv accel ipc_timestamp host logger_timestamp`.
fn parse_odom(f: &[&str]) -> Result<StampedPose, String> {
    complete(f, 6)?;
    Ok(StampedPose {
        pose: pose_at(f, 0, "odometry pose")?,
        stamp: stamp(f, 6)?,
        has_heading: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Recording, InputError> {
        read_carmen_bytes(text.as_bytes(), "t.clf", &ReadOptions::default())
    }

    #[test]
    fn reads_all_three_kinds() {
        let log = "# comment\nPARAM x 1\n\
            FLASER 3 1.0 2.0 3.0 1.699002 2.519967 0.1 1.5 2.5 0.1 10.5 host 10.6\n\
            ODOM 1.6 2.6 0.2 0 0 0 10.7 host 10.8\n\
            ROBOTLASER1 0 -1.0 2.0 0.5 30 0.01 0 5 1 1 1 1 1 0 1.2 2 0 1 2 0 0 0 0 0 0 11.0 host 11.1\n";
        let r = read(log).unwrap();
        assert_eq!(r.scans.len(), 2);
        assert_eq!(r.odom.len(), 3);
        let s = &r.scans[0];
        assert_eq!(s.stamp, 10.5);
        assert_eq!(s.ranges, vec![1.0, 2.0, 3.0]);
        assert!((s.angle_increment - PI / 2.0).abs() < 1e-15);
        assert_eq!(r.odom[0].pose.translation.vector.x, 1.5);
        let rl = &r.scans[1];
        assert_eq!(
            (rl.angle_min, rl.angle_increment, rl.range_max),
            (-1.0, 0.5, 30.0)
        );
        // Both laser lines put the laser 0.2 m ahead of the odometry pose.
        let b = r.base_from_laser.unwrap();
        assert!((b.translation.vector.x - 0.2).abs() < 1e-5);
        assert_eq!(r.mount_origin, Some(Origin::Log));
    }

    #[test]
    fn laser_poses_off_a_fixed_offset_state_no_mounting() {
        let log = "FLASER 3 1 2 3 0 0 0 0 0 0 1 h 1\n\
            FLASER 3 1 2 3 5.0 0 0 0 0 0 2 h 2\n";
        let r = read(log).unwrap();
        assert_eq!((r.base_from_laser, r.mount_origin), (None, None));
        assert!(r.mount_note.unwrap().contains("line 2"));
    }

    #[test]
    fn malformed_lines_name_the_line() {
        let e = read("ODOM 1 2 3 0 0 0 5 h 5\nFLASER 3 1 2 x 0 0 0 0 0 0 1 h 1\n").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 2"));
        assert_eq!(e.topic.as_deref(), Some("FLASER"));
        let e = read("FLASER 4 1 2\n").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 1"));
        let e = read("ODOM 1 2 nan 0 0 0 5 h 5\n").unwrap_err();
        assert!(e.message.contains("NaN"), "{e}");
        assert!(read("hello world\n").is_err());
    }

    #[test]
    fn a_cut_line_is_refused_naming_it() {
        let full = "ODOM 0 0 0 0 0 0 1.25 h 1.3\nODOM 1 0 0 0 0 0 2.125 h 2.2\n";
        // Cut inside the second ipc_timestamp: "2.1" must not become a stamp.
        let cut = &full[..full.find("2.125").unwrap() + 3];
        let e = read(cut).unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 2"));
        assert!(e.message.contains("truncated"), "{e}");
        // Cut after the host: still incomplete.
        let e = read(&full[..full.rfind(" 2.2").unwrap()]).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
        // The same short record inside the log is an error naming its line.
        let e = read("ODOM 0 0 0 0 0 0 1.25\nODOM 1 0 0 0 0 0 2.125 h 2.2\n").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("line 1"));
        // A complete last line without a newline reads in full.
        assert_eq!(read(full.trim_end()).unwrap().odom.len(), 2);
    }

    #[test]
    fn beam_conventions() {
        assert!((flaser_increment(180) - PI / 180.0).abs() < 1e-15);
        assert!((flaser_increment(360) - PI / 360.0).abs() < 1e-15);
        assert!((flaser_increment(361) - PI / 360.0).abs() < 1e-15);
    }
}
