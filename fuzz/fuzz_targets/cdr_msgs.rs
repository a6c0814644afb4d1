//! The CDR decoders directly: the first byte picks the message type and the
//! wire (bit 3: the ROS 1 serialisation), the rest is the message; its low
//! three bits 7 pick a tick array by the high four (15: the
//! `DiagnosticArray` `odocal live` publishes and its tests read back). A message
//! decoded from CDR must encode and decode again; every decode returns an
//! error value or a message, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::cdr::CdrReader;
use odocal::io::ros_msgs::{
    read_int_array, DiagnosticArrayMsg, ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg,
    PoseStampedMsg, RosMsg, TfMessage,
};
use odocal::robot::TicksType;

fn round<M: RosMsg>(data: &[u8], ros1: bool) {
    if ros1 {
        let _ = M::decode_ros1(data);
        return;
    }
    if let Ok(m) = M::decode(data) {
        let again = m.encode();
        assert!(
            M::decode(&again).is_ok(),
            "{}: re-encoded message does not decode",
            M::TYPE
        );
    }
}

/// The wheel tick arrays (`std_msgs/*MultiArray`), in every element type.
fn ticks(data: &[u8], ros1: bool, pick: u8) {
    const TYPES: [TicksType; 6] = [
        TicksType::Int16MultiArray,
        TicksType::UInt16MultiArray,
        TicksType::Int32MultiArray,
        TicksType::UInt32MultiArray,
        TicksType::Int64MultiArray,
        TicksType::UInt64MultiArray,
    ];
    let ty = TYPES[usize::from(pick) % TYPES.len()];
    let reader = if ros1 {
        Ok(CdrReader::ros1(data))
    } else {
        CdrReader::new(data)
    };
    if let Ok(mut r) = reader {
        let _ = read_int_array(&mut r, ty);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, msg)) = data.split_first() else {
        return;
    };
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
});
