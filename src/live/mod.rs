//! `odocal live` and `odocal play`: odocal on a robot's topics instead of a
//! recording. Messages come off the network into a bounded inlet
//! ([`inlet`]), are decoded by the bag readers' own code
//! ([`crate::io::MessageDecoder`]) into the one driver's sample stream
//! ([`source::LiveSource`]), and what the calibration knows goes back out as
//! a status ([`status`]). The ROS 2 side (DDS through RustDDS, no ROS
//! installation) is [`ros2`], with the `live` feature.

pub mod inlet;
pub mod params;
pub mod source;
pub mod status;

#[cfg(feature = "dds")]
pub mod ros2;

pub use inlet::{Incoming, Inlet, InletStats};
pub use params::LiveParams;
pub use source::LiveSource;
pub use status::{Level, Status, StatusBoard};
