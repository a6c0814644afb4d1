//! `sensor_msgs`: LaserScan, JointState, Imu.

use super::{fields_in_order, Field, Header, Quat, RosMsg, Vec3};
use crate::io::cdr::{CdrError, CdrReader, CdrWriter};

/// `sensor_msgs/msg/LaserScan`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaserScanMsg {
    /// Stamp of the first beam, laser frame.
    pub header: Header,
    /// First beam angle (rad).
    pub angle_min: f32,
    /// Last beam angle (rad).
    pub angle_max: f32,
    /// Angle between beams (rad).
    pub angle_increment: f32,
    /// Time between beams (s).
    pub time_increment: f32,
    /// Time between scans (s).
    pub scan_time: f32,
    /// Smallest valid range (m).
    pub range_min: f32,
    /// Largest valid range (m).
    pub range_max: f32,
    /// Ranges (m).
    pub ranges: Vec<f32>,
    /// Intensities (device units), often empty.
    pub intensities: Vec<f32>,
}

impl RosMsg for LaserScanMsg {
    const TYPE: &'static str = "sensor_msgs/msg/LaserScan";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        let header = Header::read(r)?;
        let mut m = Self {
            header,
            angle_min: r.f32()?,
            angle_max: r.f32()?,
            angle_increment: r.f32()?,
            time_increment: r.f32()?,
            scan_time: r.f32()?,
            range_min: r.f32()?,
            range_max: r.f32()?,
            ..Default::default()
        };
        r.f32_seq_into(&mut m.ranges)?;
        r.f32_seq_into(&mut m.intensities)?;
        Ok(m)
    }

    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        self.header.read_into(r)?;
        for v in [
            &mut self.angle_min,
            &mut self.angle_max,
            &mut self.angle_increment,
            &mut self.time_increment,
            &mut self.scan_time,
            &mut self.range_min,
            &mut self.range_max,
        ] {
            *v = r.f32()?;
        }
        r.f32_seq_into(&mut self.ranges)?;
        r.f32_seq_into(&mut self.intensities)
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        w.f32_seq(&self.ranges);
        w.f32_seq(&self.intensities);
    }
}

/// `sensor_msgs/msg/JointState`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointStateMsg {
    /// Stamp.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad), empty or one per name.
    pub position: Vec<f64>,
    /// Velocities (rad/s), empty or one per name.
    pub velocity: Vec<f64>,
    /// Efforts (N·m), empty or one per name.
    pub effort: Vec<f64>,
}

impl RosMsg for JointStateMsg {
    const TYPE: &'static str = "sensor_msgs/msg/JointState";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        let header = Header::read(r)?;
        let n = r.seq_len(5)?;
        let mut name = Vec::with_capacity(n);
        for _ in 0..n {
            name.push(r.string()?.to_string());
        }
        Ok(Self {
            header,
            name,
            position: r.f64_seq()?,
            velocity: r.f64_seq()?,
            effort: r.f64_seq()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.seq_len(self.name.len());
        for n in &self.name {
            w.string(n);
        }
        w.f64_seq(&self.position);
        w.f64_seq(&self.velocity);
        w.f64_seq(&self.effort);
    }
}

/// `sensor_msgs/msg/Imu`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuMsg {
    /// Stamp, IMU frame.
    pub header: Header,
    /// Orientation estimate.
    pub orientation: Quat,
    /// Its covariance (row-major 3×3; element 0 = −1 means no estimate).
    pub orientation_covariance: [f64; 9],
    /// Angular velocity (rad/s).
    pub angular_velocity: Vec3,
    /// Its covariance.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration (m/s²).
    pub linear_acceleration: Vec3,
    /// Its covariance.
    pub linear_acceleration_covariance: [f64; 9],
}

impl RosMsg for ImuMsg {
    const TYPE: &'static str = "sensor_msgs/msg/Imu";

    fields_in_order!(
        header,
        orientation,
        orientation_covariance,
        angular_velocity,
        angular_velocity_covariance,
        linear_acceleration,
        linear_acceleration_covariance
    );
}
