//! Where a robot reports its wheels (the robot file's optional `[wheels]`
//! table): `sensor_msgs/JointState` angles or rates (the default), the twist
//! of its own `nav_msgs/Odometry`, or raw encoder tick counts in a
//! `std_msgs` integer array. Plain configuration: the readers decode it.

use serde::{Deserialize, Serialize};

/// Which stream carries the wheel motion (defined with the recording's
/// wheel source, which names it).
pub use crate::recording::WheelSourceKind;

/// The message type of a tick topic: a `std_msgs` array whose elements
/// `data[left_index]` and `data[right_index]` are the counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TicksType {
    /// `int16[] data`.
    #[serde(
        rename = "std_msgs/msg/Int16MultiArray",
        alias = "std_msgs/Int16MultiArray"
    )]
    Int16MultiArray,
    /// `uint16[] data`.
    #[serde(
        rename = "std_msgs/msg/UInt16MultiArray",
        alias = "std_msgs/UInt16MultiArray"
    )]
    UInt16MultiArray,
    /// `int32[] data`.
    #[serde(
        rename = "std_msgs/msg/Int32MultiArray",
        alias = "std_msgs/Int32MultiArray"
    )]
    Int32MultiArray,
    /// `uint32[] data`.
    #[serde(
        rename = "std_msgs/msg/UInt32MultiArray",
        alias = "std_msgs/UInt32MultiArray"
    )]
    UInt32MultiArray,
    /// `int64[] data`.
    #[serde(
        rename = "std_msgs/msg/Int64MultiArray",
        alias = "std_msgs/Int64MultiArray"
    )]
    Int64MultiArray,
    /// `uint64[] data`.
    #[serde(
        rename = "std_msgs/msg/UInt64MultiArray",
        alias = "std_msgs/UInt64MultiArray"
    )]
    UInt64MultiArray,
}

impl TicksType {
    /// The ROS 2 type name (`std_msgs/msg/Int32MultiArray`).
    pub fn type_name(self) -> &'static str {
        match self {
            TicksType::Int16MultiArray => "std_msgs/msg/Int16MultiArray",
            TicksType::UInt16MultiArray => "std_msgs/msg/UInt16MultiArray",
            TicksType::Int32MultiArray => "std_msgs/msg/Int32MultiArray",
            TicksType::UInt32MultiArray => "std_msgs/msg/UInt32MultiArray",
            TicksType::Int64MultiArray => "std_msgs/msg/Int64MultiArray",
            TicksType::UInt64MultiArray => "std_msgs/msg/UInt64MultiArray",
        }
    }

    /// Bits of one element (16, 32 or 64).
    pub fn bits(self) -> u32 {
        match self {
            TicksType::Int16MultiArray | TicksType::UInt16MultiArray => 16,
            TicksType::Int32MultiArray | TicksType::UInt32MultiArray => 32,
            TicksType::Int64MultiArray | TicksType::UInt64MultiArray => 64,
        }
    }

    /// Whether the elements are signed.
    pub fn signed(self) -> bool {
        matches!(
            self,
            TicksType::Int16MultiArray | TicksType::Int32MultiArray | TicksType::Int64MultiArray
        )
    }
}

/// The robot file's `[wheels]` table. Absent: JointState on `[topics]
/// joint_states`. The tick keys are refused for the other sources, so that a
/// key that would do nothing is never silently ignored.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WheelsConfig {
    /// Which stream carries the wheels.
    pub source: WheelSourceKind,
    /// Its topic; default `[topics] joint_states` (JointState) or `[topics]
    /// odom` (Odometry); required for ticks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub topic: Option<String>,
    /// Ticks only: the message type.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ticks_type: Option<TicksType>,
    /// Ticks only: index of the left counter in `data` (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left_index: Option<usize>,
    /// Ticks only: index of the right counter in `data` (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub right_index: Option<usize>,
    /// Ticks only: the counters' width in bits, where they wrap around
    /// (default the element width; e.g. 16 for a 16-bit hardware counter
    /// published in an `Int32MultiArray`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ticks_wrap_bits: Option<u32>,
}

/// The tick layout of a `ticks` source, with its defaults filled in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TicksLayout {
    /// The message type.
    pub ticks_type: TicksType,
    /// Index of the left counter in `data`.
    pub left_index: usize,
    /// Index of the right counter in `data`.
    pub right_index: usize,
    /// Counter width (bits): consecutive readings are unwrapped modulo 2^bits.
    pub wrap_bits: u32,
}

impl WheelsConfig {
    /// Whether this is the absent table's meaning (JointState, default topic).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The tick layout, for a `ticks` source with a `ticks_type`.
    pub fn ticks_layout(&self) -> Option<TicksLayout> {
        let ticks_type = self.ticks_type?;
        (self.source == WheelSourceKind::Ticks).then(|| TicksLayout {
            ticks_type,
            left_index: self.left_index.unwrap_or(0),
            right_index: self.right_index.unwrap_or(1),
            wrap_bits: self.ticks_wrap_bits.unwrap_or(ticks_type.bits()),
        })
    }

    /// Checks the keys against the source; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        if self.topic.as_deref().is_some_and(|t| t.trim().is_empty()) {
            return Err("[wheels] topic is empty".into());
        }
        if self.source != WheelSourceKind::Ticks {
            let given = [
                ("ticks_type", self.ticks_type.is_some()),
                ("left_index", self.left_index.is_some()),
                ("right_index", self.right_index.is_some()),
                ("ticks_wrap_bits", self.ticks_wrap_bits.is_some()),
            ];
            if let Some((key, _)) = given.iter().find(|(_, g)| *g) {
                return Err(format!(
                    "[wheels] {key} applies only to source = \"ticks\" (source is \"{}\")",
                    self.source.word()
                ));
            }
            return Ok(());
        }
        if self.topic.is_none() {
            return Err(
                "[wheels] source = \"ticks\" needs topic (the topic of the tick \
                        counters)"
                    .into(),
            );
        }
        let Some(layout) = self.ticks_layout() else {
            return Err("[wheels] source = \"ticks\" needs ticks_type (e.g. \
                 \"std_msgs/msg/Int32MultiArray\")"
                .into());
        };
        if layout.left_index == layout.right_index {
            return Err(format!(
                "[wheels] left_index and right_index are both {}",
                layout.left_index
            ));
        }
        let width = layout.ticks_type.bits();
        if !(2..=width).contains(&layout.wrap_bits) {
            return Err(format!(
                "[wheels] ticks_wrap_bits = {} is outside 2..={width} (the bits of {})",
                layout.wrap_bits,
                layout.ticks_type.type_name()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absent_table_is_joint_states_and_tick_keys_need_ticks() {
        let w: WheelsConfig = toml::from_str("").unwrap();
        assert!(w.is_default() && w.validate().is_ok());
        let w: WheelsConfig = toml::from_str("source = \"odometry\"\nleft_index = 2").unwrap();
        let e = w.validate().unwrap_err();
        assert!(e.contains("left_index") && e.contains("ticks"), "{e}");
        let w: WheelsConfig = toml::from_str("source = \"ticks\"\ntopic = \"/t\"").unwrap();
        assert!(w.validate().unwrap_err().contains("ticks_type"));
        let w: WheelsConfig = toml::from_str(
            "source = \"ticks\"\ntopic = \"/t\"\nticks_type = \"std_msgs/Int32MultiArray\"\n\
             ticks_wrap_bits = 16",
        )
        .unwrap();
        w.validate().unwrap();
        let l = w.ticks_layout().unwrap();
        assert_eq!((l.left_index, l.right_index, l.wrap_bits), (0, 1, 16));
        assert_eq!(l.ticks_type, TicksType::Int32MultiArray);
        let wide = WheelsConfig {
            ticks_wrap_bits: Some(33),
            ..w.clone()
        };
        assert!(wide.validate().unwrap_err().contains("ticks_wrap_bits"));
        assert!(toml::from_str::<WheelsConfig>("source = \"encoders\"").is_err());
        assert!(toml::from_str::<WheelsConfig>("ticks_type = \"std_msgs/msg/Float32\"").is_err());
    }
}
