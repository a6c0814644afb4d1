//! Every recording format as one stream of samples: a [`SampleSource`] yields
//! each stream (scans, wheels, gyro, odometry, reference) in stamp order,
//! after saying how many samples each stream has and where the laser sits.
//! Bags (MCAP, ROS 1, rosbag2 SQLite and folders) stream from disk in bounded
//! memory ([`super::McapStream`] and the readers beside it);
//! a recording already in memory, or a format read whole, is streamed by
//! [`RecordingSource`]. The stages downstream see only the source, so every
//! format gets the same streaming pipeline.

use std::borrow::Cow;

use crate::error::InputError;
use crate::geom::Pose2;
use crate::recording::{GyroSample, Recording, StampedPose, WheelSample};
use crate::scan::LaserScan;

/// One decoded sample of a recording stream.
#[derive(Debug, Clone)]
pub enum Item {
    /// A laser scan.
    Scan(LaserScan),
    /// Wheel angles (rad), integrated from rates when the bag has only rates.
    Wheel(WheelSample),
    /// A gyro yaw rate (rad/s).
    Gyro(GyroSample),
    /// The robot's own odometry pose.
    Odom(StampedPose),
    /// A reference pose.
    Reference(StampedPose),
}

impl Item {
    /// Stamp (s).
    pub fn stamp(&self) -> f64 {
        match self {
            Item::Scan(s) => s.stamp,
            Item::Wheel(w) => w.stamp,
            Item::Gyro(g) => g.stamp,
            Item::Odom(p) | Item::Reference(p) => p.stamp,
        }
    }

    /// The stream's index: scans 0, wheels 1, gyro 2, odometry 3, reference 4.
    pub(crate) fn stream(&self) -> usize {
        match self {
            Item::Scan(_) => 0,
            Item::Wheel(_) => 1,
            Item::Gyro(_) => 2,
            Item::Odom(_) => 3,
            Item::Reference(_) => 4,
        }
    }
}

/// What the first pass learns: message counts per stream and the laser mount.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StreamInfo {
    /// LaserScan messages.
    pub scans: usize,
    /// Wheel messages (one wheel sample each).
    pub wheels: usize,
    /// Imu messages.
    pub gyro: usize,
    /// Odometry messages of the robot's own odometry.
    pub odom: usize,
    /// Reference messages.
    pub reference: usize,
    /// `base_from_laser` from /tf_static, when the bag states it.
    pub base_from_laser: Option<Pose2>,
    /// Where `base_from_laser` came from.
    pub mount_origin: Option<crate::assumptions::Origin>,
    /// Why the recording states no mounting, when it could have.
    pub mount_note: Option<String>,
    /// How the wheel angles are obtained (`None`: no wheel samples).
    pub wheel_values: Option<crate::recording::WheelValues>,
}

impl StreamInfo {
    /// What a recording in memory holds, as a stream announces it.
    pub fn of(rec: &Recording) -> Self {
        Self {
            scans: rec.scans.len(),
            wheels: rec.wheels.len(),
            gyro: rec.gyro.len(),
            odom: rec.odom.len(),
            reference: rec.reference.len(),
            base_from_laser: rec.base_from_laser,
            mount_origin: rec.mount_origin,
            mount_note: rec.mount_note.clone(),
            wheel_values: rec.wheel_values,
        }
    }
}

/// A recording as a stream of samples, each stream in stamp order.
pub trait SampleSource {
    /// Where the samples come from (the file), for messages.
    fn name(&self) -> &str;
    /// The number of samples of each stream and the laser mount, known
    /// before the first sample.
    fn info(&self) -> &StreamInfo;
    /// The next sample; `None` at the end. Each stream's samples come in
    /// stamp order; streams are interleaved roughly by time.
    fn next_item(&mut self) -> Result<Option<Item>, InputError>;
    /// The topic (or record kind) the scans come from, for messages.
    fn scan_topic(&self) -> &str {
        "laser scans"
    }
    /// Whether the gyro stream has ended before its announced count (a live
    /// source whose gyro went silent): the run then goes on without it.
    /// Asked after each sample.
    fn gyro_ended(&mut self) -> bool {
        false
    }
}

/// A recording in memory (borrowed or owned) as a [`SampleSource`]: the
/// streams merged by stamp (on equal stamps: scans, wheels, gyro, odometry,
/// reference).
pub struct RecordingSource<'r> {
    rec: Cow<'r, Recording>,
    info: StreamInfo,
    next: [usize; 5],
}

impl<'r> RecordingSource<'r> {
    /// Streams `rec`, whose streams are sorted by stamp.
    pub fn new(rec: &'r Recording) -> Self {
        Self::of(Cow::Borrowed(rec))
    }

    /// Streams `rec`, taking it.
    pub fn owned(rec: Recording) -> RecordingSource<'static> {
        RecordingSource::of(Cow::Owned(rec))
    }

    fn of(rec: Cow<'r, Recording>) -> Self {
        let info = StreamInfo::of(&rec);
        Self {
            rec,
            info,
            next: [0; 5],
        }
    }

    /// The stamp of stream `k`'s next sample.
    fn head(&self, k: usize) -> Option<f64> {
        let i = self.next[k];
        let r = &self.rec;
        match k {
            0 => r.scans.get(i).map(|s| s.stamp),
            1 => r.wheels.get(i).map(|s| s.stamp),
            2 => r.gyro.get(i).map(|s| s.stamp),
            3 => r.odom.get(i).map(|s| s.stamp),
            _ => r.reference.get(i).map(|s| s.stamp),
        }
    }

    /// Takes stream `k`'s next sample.
    fn take(&mut self, k: usize) -> Item {
        let i = self.next[k];
        self.next[k] += 1;
        let r = &self.rec;
        match k {
            0 => Item::Scan(r.scans[i].clone()),
            1 => Item::Wheel(r.wheels[i]),
            2 => Item::Gyro(r.gyro[i]),
            3 => Item::Odom(r.odom[i]),
            _ => Item::Reference(r.reference[i]),
        }
    }
}

impl SampleSource for RecordingSource<'_> {
    fn name(&self) -> &str {
        &self.rec.source
    }

    fn info(&self) -> &StreamInfo {
        &self.info
    }

    fn next_item(&mut self) -> Result<Option<Item>, InputError> {
        let earliest = (0..5)
            .filter_map(|k| self.head(k).map(|t| (k, t)))
            .reduce(|a, b| if b.1 < a.1 { b } else { a });
        Ok(earliest.map(|(k, _)| self.take(k)))
    }
}
