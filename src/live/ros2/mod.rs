//! The ROS 2 side of a live run: a node on a DDS domain through
//! ros2-client and RustDDS (no ROS installation), raw readers of the
//! robot's topics feeding the [`super::inlet`], publishers of the
//! calibrated odometry and the diagnostics, the multipliers as node
//! parameters, and `odocal play`'s writers.

mod listen;
pub mod msgs;
mod node;
pub mod play;
mod raw;

pub use listen::Listener;
pub use node::{Ros2Node, PARAMETERS};
pub use raw::RawCdr;

/// A failure of the network side.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// DDS refused to create something (participant, topic, reader, writer).
    #[error("DDS: {0}")]
    Dds(String),
    /// A name ROS 2 does not accept.
    #[error("ROS 2 name {name:?}: {why}")]
    Name {
        /// The name.
        name: String,
        /// Why it is refused.
        why: String,
    },
}

impl Ros2Error {
    fn dds(e: impl std::fmt::Display) -> Self {
        Ros2Error::Dds(e.to_string())
    }
}

/// The DDS type of a ROS 2 message type: `sensor_msgs/msg/LaserScan` →
/// `sensor_msgs::msg::dds_::LaserScan_` (a ROS 1 style `pkg/Type` gets the
/// `msg` namespace).
pub fn dds_type(ros_type: &str) -> String {
    let parts: Vec<&str> = ros_type.split('/').filter(|p| !p.is_empty()).collect();
    match parts.as_slice() {
        [pkg, kind, name] => format!("{pkg}::{kind}::dds_::{name}_"),
        [pkg, name] => format!("{pkg}::msg::dds_::{name}_"),
        _ => ros_type.replace('/', "::"),
    }
}

/// The DDS topic of a ROS 2 topic: `/scan` → `rt/scan`; a relative name is
/// taken from the root namespace.
pub fn dds_topic(ros_topic: &str) -> Result<String, Ros2Error> {
    let name = ros_topic.trim_start_matches('/');
    let bad = |why: &str| Ros2Error::Name {
        name: ros_topic.to_string(),
        why: why.to_string(),
    };
    if name.is_empty() {
        return Err(bad("empty"));
    }
    if name.contains("//") || name.ends_with('/') {
        return Err(bad("empty segment"));
    }
    if !name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/')
    {
        return Err(bad("only letters, digits, '_' and '/' are allowed"));
    }
    Ok(format!("rt/{name}"))
}

/// Nanoseconds since the epoch of a DDS timestamp (seconds and 2⁻³² s).
fn timestamp_ns(t: ros2_client::dds::rustdds::Timestamp) -> u64 {
    let ticks = t.to_ticks();
    (ticks >> 32) * 1_000_000_000 + (((ticks & 0xffff_ffff) * 1_000_000_000) >> 32)
}

/// The DDS timestamp of `ns` nanoseconds since the epoch.
fn timestamp_of(ns: u64) -> ros2_client::dds::rustdds::Timestamp {
    let secs = ns / 1_000_000_000;
    let frac = ((ns % 1_000_000_000) << 32) / 1_000_000_000;
    ros2_client::dds::rustdds::Timestamp::from_ticks((secs << 32) | frac)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros_names_become_dds_names() {
        assert_eq!(
            dds_type("sensor_msgs/msg/LaserScan"),
            "sensor_msgs::msg::dds_::LaserScan_"
        );
        assert_eq!(
            dds_type("std_msgs/Int32MultiArray"),
            "std_msgs::msg::dds_::Int32MultiArray_"
        );
        assert_eq!(dds_topic("/scan").unwrap(), "rt/scan");
        assert_eq!(dds_topic("odocal/odometry").unwrap(), "rt/odocal/odometry");
        assert!(dds_topic("/").is_err());
        assert!(dds_topic("/a b").is_err());
    }

    #[test]
    fn timestamps_round_trip_to_the_nanosecond_floor() {
        for ns in [0u64, 1, 999_999_999, 1_700_000_000_123_456_789] {
            let back = timestamp_ns(timestamp_of(ns));
            assert!(ns - back <= 1, "{ns} → {back}");
        }
    }
}
