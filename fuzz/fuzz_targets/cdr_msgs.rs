//! The CDR decoders directly: the first byte picks the message type, the rest
//! is the message. A decoded message must encode and decode again.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::ros_msgs::{
    ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg, PoseStampedMsg, RosMsg,
    TfMessage,
};

fn round<M: RosMsg>(data: &[u8]) {
    if let Ok(m) = M::decode(data) {
        let again = m.encode();
        assert!(
            M::decode(&again).is_ok(),
            "{}: re-encoded message does not decode",
            M::TYPE
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, msg)) = data.split_first() else {
        return;
    };
    match kind % 7 {
        0 => round::<LaserScanMsg>(msg),
        1 => round::<JointStateMsg>(msg),
        2 => round::<ImuMsg>(msg),
        3 => round::<OdometryMsg>(msg),
        4 => round::<PoseStampedMsg>(msg),
        5 => round::<PointStampedMsg>(msg),
        _ => round::<TfMessage>(msg),
    }
});
