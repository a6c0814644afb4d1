//! `odocal play`: a recording's messages put on the DDS domain as the robot
//! published them: the same topics, types and payloads, `/tf_static`
//! latched (reliable, transient-local), the others reliable (which both
//! reliable and best-effort subscribers receive), each message at its log
//! time scaled by the rate, its source timestamp the log time. Looping
//! moves every header stamp (and source timestamp) on by the recording's
//! length each time round, so a subscriber sees time go on; the latched
//! transforms are sent once.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::node::{latched_qos, reliable_qos, RawWriter, Ros2Node};
use super::raw::RawCdr;
use super::{timestamp_of, Ros2Error};
use crate::error::InputError;
use crate::io::stored::{StoredMessage, StoredMessages};

/// How to play.
#[derive(Debug, Clone)]
pub struct PlayOptions {
    /// Speed against the log times (2.0: twice as fast).
    pub rate: f64,
    /// Start again at the end, until stopped.
    pub looped: bool,
    /// Topics sent latched (`/tf_static`).
    pub latched: Vec<String>,
    /// Wait before the first message (s), for subscribers to discover the
    /// writers.
    pub delay_s: f64,
}

/// What was played.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Played {
    /// Messages sent.
    pub messages: u64,
    /// Times through the recording (the last one maybe partly).
    pub rounds: u32,
    /// Length of one round in log time (s).
    pub round_s: f64,
    /// Wall time from the first message to the last (s).
    pub wall_s: f64,
    /// How far behind its schedule the latest message was sent, at most (s):
    /// above a period or two, this machine cannot keep up with the rate.
    pub max_behind_s: f64,
}

/// Why playing stopped early.
#[derive(Debug, thiserror::Error)]
pub enum PlayError {
    /// The recording could not be read.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The network refused.
    #[error(transparent)]
    Network(#[from] Ros2Error),
}

/// Whether messages of `type_name` start with a `std_msgs/Header` (whose
/// stamp a loop moves on); transforms and tick arrays do not.
fn has_header(type_name: &str) -> bool {
    !(type_name.ends_with("TFMessage") || type_name.contains("MultiArray"))
}

/// Moves the header stamp of the CDR message `data` on by `shift_ns`
/// (the stamp follows the 4-byte encapsulation header: seconds i32,
/// nanoseconds u32, little endian). A message too short keeps its bytes.
fn shift_stamp(data: &mut [u8], shift_ns: u64) {
    let Some(head) = data.get_mut(4..12) else {
        return;
    };
    let sec = i32::from_le_bytes(head[0..4].try_into().expect("4 bytes")) as i64;
    let nsec = u32::from_le_bytes(head[4..8].try_into().expect("4 bytes")) as i64;
    let total = sec * 1_000_000_000 + nsec + shift_ns as i64;
    let (s, n) = (
        total.div_euclid(1_000_000_000),
        total.rem_euclid(1_000_000_000),
    );
    head[0..4].copy_from_slice(&(s as i32).to_le_bytes());
    head[4..8].copy_from_slice(&(n as u32).to_le_bytes());
}

/// Plays what `open` gives (called again for each loop) on `node` until
/// the end, or `stop`.
pub fn play<'o>(
    node: &Ros2Node,
    open: &mut dyn FnMut() -> Result<StoredMessages<'o>, InputError>,
    opts: &PlayOptions,
    stop: &AtomicBool,
) -> Result<Played, PlayError> {
    let mut writers: HashMap<String, RawWriter> = HashMap::new();
    let mut played = Played::default();
    std::thread::sleep(Duration::from_secs_f64(opts.delay_s.max(0.0)));
    let rate = opts.rate.max(1e-6);
    let mut clock: Option<(u64, Instant)> = None;
    let mut last_ns = 0u64;
    let mut shift_ns = 0u64;
    loop {
        let mut messages = open()?;
        played.rounds += 1;
        let mut first_ns = None;
        while let Some(mut m) = messages.next_message()? {
            if stop.load(Ordering::Relaxed) {
                return Ok(finish(played, clock));
            }
            let latched = opts.latched.contains(&m.topic);
            if latched && played.rounds > 1 {
                continue;
            }
            first_ns.get_or_insert(m.log_time_ns);
            let at_ns = m.log_time_ns + shift_ns;
            let (t0, w0) = *clock.get_or_insert((at_ns, Instant::now()));
            let due = w0 + Duration::from_secs_f64(at_ns.saturating_sub(t0) as f64 * 1e-9 / rate);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            } else {
                played.max_behind_s = played.max_behind_s.max((now - due).as_secs_f64());
            }
            if shift_ns > 0 && has_header(&m.type_name) {
                shift_stamp(&mut m.data, shift_ns);
            }
            send(node, &mut writers, m, at_ns, latched)?;
            played.messages += 1;
            last_ns = last_ns.max(at_ns);
        }
        let round = last_ns.saturating_sub(first_ns.unwrap_or(last_ns) + shift_ns);
        played.round_s = round as f64 * 1e-9;
        if !opts.looped || played.messages == 0 {
            return Ok(finish(played, clock));
        }
        // The next round starts 1 ms after this one ended (stamps stay increasing).
        shift_ns += round + 1_000_000;
    }
}

fn finish(mut played: Played, clock: Option<(u64, Instant)>) -> Played {
    played.wall_s = clock.map_or(0.0, |(_, w)| w.elapsed().as_secs_f64());
    played
}

/// Sends `m` on its topic's writer (made on first use).
fn send(
    node: &Ros2Node,
    writers: &mut HashMap<String, RawWriter>,
    m: StoredMessage,
    at_ns: u64,
    latched: bool,
) -> Result<(), Ros2Error> {
    if !writers.contains_key(&m.topic) {
        let qos = if latched {
            latched_qos()
        } else {
            reliable_qos(100)
        };
        let w = node.raw_writer(&m.topic, &m.type_name, qos)?;
        writers.insert(m.topic.clone(), w);
    }
    let w = &writers[&m.topic];
    // A payload that is not little-endian CDR is refused by the writer's
    // adapter; the message is skipped, as a robot's driver would drop it.
    let _ = w.write(RawCdr(m.data), Some(timestamp_of(at_ns)));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loop_moves_the_header_stamp_with_carry() {
        let mut d = vec![0u8, 1, 0, 0];
        d.extend_from_slice(&5i32.to_le_bytes());
        d.extend_from_slice(&900_000_000u32.to_le_bytes());
        d.extend_from_slice(&[7, 7]);
        shift_stamp(&mut d, 1_200_000_000);
        assert_eq!(i32::from_le_bytes(d[4..8].try_into().unwrap()), 7);
        assert_eq!(
            u32::from_le_bytes(d[8..12].try_into().unwrap()),
            100_000_000
        );
        assert_eq!(&d[12..], &[7, 7]);
        let mut short = vec![0u8, 1, 0, 0, 1];
        shift_stamp(&mut short, 5);
        assert_eq!(short, [0, 1, 0, 0, 1]);
        assert!(has_header("sensor_msgs/msg/LaserScan"));
        assert!(!has_header("tf2_msgs/msg/TFMessage"));
        assert!(!has_header("std_msgs/msg/Int32MultiArray"));
    }
}
