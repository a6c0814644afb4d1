//! A robot's live topics as the driver's [`SampleSource`]: messages from the
//! [`super::inlet`] decoded by [`MessageDecoder`], after a start that waits
//! for scans and wheels (and gives the static transforms and the gyro a
//! moment), until the stop flag is raised. A message the decoder refuses is
//! logged and counted, never fatal. Streams that go silent are bounded:
//! scans beyond the wheels' last sample by more than `silence_s` are dropped
//! (nothing to compare their motion with, and they would wait for wheel data
//! without end), and a silent gyro is left out of the rest of the run.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::inlet::{Incoming, InletStats};
use super::params::LiveParams;
use crate::error::InputError;
use crate::io::{Item, MessageDecoder, ReadOptions, SampleSource, StreamInfo};

/// How long one wait on the inlet lasts before the stop flag is looked at.
const POLL: Duration = Duration::from_millis(50);

/// Scan arrivals remembered for the latency measurement.
const ARRIVALS: usize = 256;

/// What the source saw of the traffic, shared with the status.
#[derive(Debug, Default)]
pub struct Traffic {
    /// When each stream (scans, wheels, gyro, odometry, reference) last
    /// gave a sample.
    pub heard: [Option<Instant>; 5],
    /// The latest stamp (s) of each stream.
    pub stamp: [Option<f64>; 5],
    /// Samples handed to the driver per stream.
    pub counts: [u64; 5],
    /// (stamp (s), arrival) of the latest scans.
    pub scan_arrivals: VecDeque<(f64, Instant)>,
    /// The arrival of the latest wheel message released.
    pub wheel_arrival: Option<Instant>,
    /// Scans dropped because the wheels were silent.
    pub scans_dropped: u64,
    /// Whether the gyro was left out after going silent.
    pub gyro_dropped: bool,
    /// The last message refused, with its topic.
    pub last_refusal: Option<String>,
}

impl Traffic {
    /// The arrival of the scan stamped `t` (s), if remembered.
    pub fn scan_arrival(&self, t: f64) -> Option<Instant> {
        self.scan_arrivals
            .iter()
            .rev()
            .find(|(s, _)| (s - t).abs() < 1e-6)
            .map(|(_, a)| *a)
    }
}

/// Shared traffic record.
pub type SharedTraffic = Arc<Mutex<Traffic>>;

/// Logs refusals: the first few of each topic, then every hundredth.
#[derive(Default)]
struct Refusals(HashMap<String, u64>);

impl Refusals {
    fn note(&mut self, topic: &str) -> Option<u64> {
        let n = self.0.entry(topic.to_string()).or_insert(0);
        *n += 1;
        (*n <= 5 || n.is_multiple_of(100)).then_some(*n)
    }
}

/// What the source is told to log.
pub type Log = Box<dyn FnMut(&str) + Send>;

/// A robot's live topics as a sample source.
pub struct LiveSource<'o> {
    name: String,
    rx: Receiver<Incoming>,
    decoder: MessageDecoder<'o>,
    opts: &'o ReadOptions,
    info: StreamInfo,
    stop: Arc<AtomicBool>,
    stats: Arc<InletStats>,
    params: LiveParams,
    log: Log,
    traffic: SharedTraffic,
    refusals: Refusals,
    /// Samples decoded and not yet handed out.
    ready: VecDeque<Item>,
    /// Whether gyro samples are handed out (the gyro was heard at the start
    /// and has not gone silent).
    gyro_on: bool,
    /// The gyro went silent and the driver has not been told yet.
    gyro_just_ended: bool,
    /// Whether scans are being dropped for silent wheels (to log once per
    /// silence).
    dropping: bool,
    arrival: Instant,
    ended: bool,
}

impl<'o> LiveSource<'o> {
    /// Waits for the first scans and wheel samples on `rx` (up to
    /// `params.wait_s`, or until `stop`), then `settle_s` for the static
    /// transforms and the gyro; `topics` are the topics subscribed to with
    /// their types (`pkg/msg/Type`). Refuses a configured topic of another
    /// type, no scans or wheels in time, or a stop before the start.
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        name: &str,
        rx: Receiver<Incoming>,
        topics: &[(String, String)],
        opts: &'o ReadOptions,
        params: &LiveParams,
        stop: Arc<AtomicBool>,
        stats: Arc<InletStats>,
        log: Log,
    ) -> Result<Self, InputError> {
        let mut decoder = MessageDecoder::new(name, opts);
        for (topic, ty) in topics {
            decoder
                .declare(topic, ty)
                .map_err(|m| InputError::new(name, m).topic(topic.as_str()))?;
        }
        let mut s = Self {
            name: name.to_string(),
            rx,
            decoder,
            opts,
            info: StreamInfo::default(),
            stop,
            stats,
            params: params.clone(),
            log,
            traffic: Arc::default(),
            refusals: Refusals::default(),
            ready: VecDeque::new(),
            gyro_on: true,
            gyro_just_ended: false,
            dropping: false,
            arrival: Instant::now(),
            ended: false,
        };
        s.wait_for_streams()?;
        s.info = s.announce()?;
        Ok(s)
    }

    /// The traffic record (for the status and the latency measurement).
    pub fn traffic(&self) -> SharedTraffic {
        self.traffic.clone()
    }

    /// Receives until scans and wheels both flow and `settle_s` has passed.
    fn wait_for_streams(&mut self) -> Result<(), InputError> {
        let begun = Instant::now();
        let mut flowing: Option<Instant> = None;
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return Err(self.not_started("stopped before the run could start"));
            }
            if let Some(f) = flowing {
                if f.elapsed().as_secs_f64() >= self.params.settle_s {
                    return Ok(());
                }
            } else if self.params.wait_s > 0.0 && begun.elapsed().as_secs_f64() > self.params.wait_s
            {
                return Err(self.not_started(&format!(
                    "no scans and wheel data within {} s ([live] wait_s)",
                    self.params.wait_s
                )));
            }
            if !self.receive_one() {
                return Err(self.not_started("the network side closed"));
            }
            let [scans, wheels, ..] = self.decoder.decoded();
            if flowing.is_none() && scans >= 2 && wheels >= 2 {
                flowing = Some(Instant::now());
            }
        }
    }

    /// The error of a run that never started: what came on each topic.
    fn not_started(&self, why: &str) -> InputError {
        let [scans, wheels, gyro, odom, _] = self.decoder.decoded();
        let [queued, full, big, refused] = self.stats.counts();
        InputError::new(
            &self.name,
            format!(
                "{why}: {scans} scans on {}, {wheels} wheel samples on {}, {gyro} gyro, {odom} \
                 odometry decoded ({queued} messages received, {refused} refused, {full} dropped \
                 on a full queue, {big} too large); check the domain (ROS_DOMAIN_ID), the \
                 [topics] names and the robot file's [wheels] source (`ros2 topic list` on the \
                 robot shows what it publishes)",
                self.opts.topics.scan,
                self.opts.wheel_topic()
            ),
        )
    }

    /// The streams as announced to the driver: the live streams have no
    /// count (they end when the run stops); the gyro and the robot's
    /// odometry are used when heard during the start.
    fn announce(&mut self) -> Result<StreamInfo, InputError> {
        let [_, _, gyro, odom, _] = self.decoder.decoded();
        let (base_from_laser, mount_origin, mount_note) = self.decoder.mount()?;
        self.gyro_on = gyro > 0;
        if !self.gyro_on {
            (self.log)(&format!(
                "no gyro on {} within the start: calibrating without it",
                self.opts.topics.imu
            ));
        }
        Ok(StreamInfo {
            scans: usize::MAX,
            wheels: usize::MAX,
            gyro: if self.gyro_on { usize::MAX } else { 0 },
            odom: if odom > 0 { usize::MAX } else { 0 },
            reference: 0,
            base_from_laser,
            mount_origin,
            mount_note,
            wheel_values: self.decoder.wheel_values(),
        })
    }

    /// Waits for one message (at most [`POLL`]) and decodes it; `false`
    /// when the network side has gone.
    fn receive_one(&mut self) -> bool {
        match self.rx.recv_timeout(POLL) {
            Ok(m) => {
                self.decode(m);
                true
            }
            Err(RecvTimeoutError::Timeout) => true,
            Err(RecvTimeoutError::Disconnected) => false,
        }
    }

    fn decode(&mut self, m: Incoming) {
        self.arrival = m.arrived;
        if let Err(why) = self.decoder.push(&m.topic, &m.data, m.log_time_ns) {
            self.stats.refuse();
            let line = format!("{}: message refused: {why}", m.topic);
            if let Some(n) = self.refusals.note(&m.topic) {
                (self.log)(&format!("{line} ({n} refused on this topic)"));
            }
            self.traffic
                .lock()
                .map(|mut t| t.last_refusal = Some(line))
                .ok();
        }
        while let Some(item) = self.decoder.pop() {
            self.ready.push_back(item);
        }
    }

    /// Whether `item` goes to the driver: no gyro once it is left out; no
    /// scan beyond the wheels' last sample by more than `silence_s`.
    fn admit(&mut self, item: &Item, t: &mut Traffic) -> bool {
        match item {
            Item::Gyro(_) => self.gyro_on,
            Item::Scan(s) => {
                // Before any wheel sample there is no silence to judge.
                let Some(wheels) = t.stamp[1] else {
                    return true;
                };
                let silent = s.stamp > wheels + self.params.silence_s;
                if silent {
                    t.scans_dropped += 1;
                    if !self.dropping {
                        (self.log)(&format!(
                            "no wheel data since {wheels:.3} s: scans dropped until it returns"
                        ));
                    }
                } else if self.dropping {
                    (self.log)("wheel data back: scans used again");
                }
                self.dropping = silent;
                !silent
            }
            _ => true,
        }
    }

    /// Leaves the gyro out once it has been silent for `silence_s` while the
    /// scans went on.
    fn check_gyro(&mut self, t: &mut Traffic) {
        if !self.gyro_on {
            return;
        }
        let (Some(scan), Some(gyro)) = (t.stamp[0], t.stamp[2]) else {
            return;
        };
        if scan - gyro > self.params.silence_s {
            self.gyro_on = false;
            self.gyro_just_ended = true;
            t.gyro_dropped = true;
            (self.log)(&format!(
                "no gyro since {gyro:.3} s while scans go on: the rest of the run goes without it"
            ));
        }
    }

    /// Records `item` in the traffic; `false` when it is not handed out.
    fn note(&mut self, item: &Item) -> bool {
        let traffic = self.traffic.clone();
        let Ok(mut t) = traffic.lock() else {
            return true;
        };
        let k = item.stream();
        t.heard[k] = Some(Instant::now());
        t.stamp[k] = Some(t.stamp[k].map_or(item.stamp(), |s| s.max(item.stamp())));
        if k == 0 {
            if t.scan_arrivals.len() == ARRIVALS {
                t.scan_arrivals.pop_front();
            }
            t.scan_arrivals.push_back((item.stamp(), self.arrival));
            self.check_gyro(&mut t);
        } else if k == 1 {
            t.wheel_arrival = Some(self.arrival);
        }
        let admitted = self.admit(item, &mut t);
        if admitted {
            t.counts[k] += 1;
        }
        admitted
    }
}

impl SampleSource for LiveSource<'_> {
    fn name(&self) -> &str {
        &self.name
    }

    fn info(&self) -> &StreamInfo {
        &self.info
    }

    fn next_item(&mut self) -> Result<Option<Item>, InputError> {
        loop {
            if let Some(item) = self.ready.pop_front() {
                if self.note(&item) {
                    return Ok(Some(item));
                }
                continue;
            }
            if self.ended {
                return Ok(None);
            }
            if self.stop.load(Ordering::Relaxed) || !self.receive_one() {
                self.ended = true;
                self.decoder.flush();
                while let Some(item) = self.decoder.pop() {
                    self.ready.push_back(item);
                }
            }
        }
    }

    fn scan_topic(&self) -> &str {
        &self.opts.topics.scan
    }

    fn gyro_ended(&mut self) -> bool {
        std::mem::take(&mut self.gyro_just_ended)
    }
}
