//! The thread that takes the robot's messages off the network: one raw
//! reader per topic, woken by the readers' own events (no busy loop), each
//! sample put into the [`Inlet`] with its source timestamp. It never waits
//! on the calibration: a full inlet drops and counts.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};

use super::node::{latched_qos, sensor_qos, RawReader, Ros2Node};
use super::{timestamp_ns, Ros2Error};
use crate::live::inlet::{Incoming, Inlet};

/// How long one wait for network events lasts before the stop flag is
/// looked at.
const WAKE: Duration = Duration::from_millis(100);

/// Samples a sensor reader keeps between two takes.
const DEPTH: i32 = 256;

/// The listening thread.
pub struct Listener {
    handle: Option<std::thread::JoinHandle<()>>,
    stop: Arc<AtomicBool>,
}

impl Listener {
    /// Subscribes to `topics` (ROS topic, ROS type) on `node` (`latched`
    /// topics with `/tf_static`'s QoS, the others as sensor streams) and
    /// starts feeding `inlet` until `stop` or [`Listener::finish`].
    pub fn start(
        node: &Ros2Node,
        topics: &[(String, String)],
        latched: &[String],
        inlet: Inlet,
        stop: Arc<AtomicBool>,
    ) -> Result<Self, Ros2Error> {
        let mut readers = Vec::new();
        for (topic, ty) in topics {
            let qos = if latched.contains(topic) {
                latched_qos()
            } else {
                sensor_qos(DEPTH)
            };
            readers.push((topic.clone(), node.raw_reader(topic, ty, qos)?));
        }
        let poll = Poll::new().map_err(Ros2Error::dds)?;
        for (i, (_, r)) in readers.iter_mut().enumerate() {
            poll.registry()
                .register(r, Token(i), Interest::READABLE)
                .map_err(Ros2Error::dds)?;
        }
        let flag = stop.clone();
        let handle = std::thread::Builder::new()
            .name("ros2-listener".into())
            .spawn(move || listen(poll, readers, inlet, flag))
            .map_err(Ros2Error::dds)?;
        Ok(Self {
            handle: Some(handle),
            stop,
        })
    }

    /// Stops the thread and waits for it.
    pub fn finish(mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn listen(
    mut poll: Poll,
    mut readers: Vec<(String, RawReader)>,
    inlet: Inlet,
    stop: Arc<AtomicBool>,
) {
    let mut events = Events::with_capacity(64);
    // A first sweep: samples may have come before registration.
    let mut ready: Vec<usize> = (0..readers.len()).collect();
    while !stop.load(Ordering::Relaxed) {
        for &i in &ready {
            let (topic, reader) = &mut readers[i];
            if !drain(topic, reader, &inlet) {
                return;
            }
        }
        if poll.poll(&mut events, Some(WAKE)).is_err() {
            std::thread::sleep(WAKE);
        }
        ready = events.iter().map(|e| e.token().0).collect();
    }
}

/// Takes every sample `reader` holds into `inlet`; `false` once the inlet's
/// other end is gone.
fn drain(topic: &str, reader: &mut RawReader, inlet: &Inlet) -> bool {
    loop {
        let sample = match reader.take_next_sample() {
            Ok(Some(s)) => s,
            // A sample RustDDS could not hand over is lost here; the stream
            // goes on.
            Ok(None) | Err(_) => return true,
        };
        let arrived = Instant::now();
        let log_time_ns = sample
            .sample_info()
            .source_timestamp()
            .map(timestamp_ns)
            .unwrap_or_else(now_ns);
        let m = Incoming {
            topic: topic.to_string(),
            data: sample.into_value().0,
            log_time_ns,
            arrived,
        };
        if !inlet.offer(m) {
            return false;
        }
    }
}

/// Nanoseconds since the epoch now.
fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}
