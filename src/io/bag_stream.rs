//! What every bag reader shares once it can hand out raw messages one by
//! one (MCAP, ROS 1 bags, rosbag2 SQLite, rosbag2 folders): a first pass that
//! counts the messages of each stream and resolves `base_from_laser` (static
//! transforms, laser frame), and a second pass that decodes every message and
//! yields each stream in stamp order. An item is released once its stream
//! has seen a stamp more than `reorder_tolerance` later, which the time-order
//! check of [`State`] guarantees no later message can undercut, so the streams
//! are exactly what a stable sort of the whole recording gives.

use std::collections::VecDeque;

use super::mcap_streams::{released, RateIntegrator, Role, State, Wire};
use super::options::ReadOptions;
use super::reorder::Reorder;
use super::source::{Item, SampleSource, StreamInfo};
use crate::error::InputError;

/// A message to decode: its roles, topic, where it is, payload, log time.
pub(crate) struct Raw {
    pub roles: Vec<Role>,
    pub topic: String,
    /// The topic's message type as the bag names it (`pkg/msg/Type` or
    /// ROS 1's `pkg/Type`).
    pub type_name: std::sync::Arc<str>,
    /// Where the message is, for errors (e.g. "message 12", "row id 40").
    pub at: At,
    pub data: Vec<u8>,
    /// Receive (log) time (ns), the stand-in for an unset header stamp.
    pub log_time: u64,
}

/// Where a message sits in its file.
#[derive(Debug, Clone, Copy)]
pub(crate) enum At {
    /// The n-th message of its topic (0-based).
    Message(usize),
    /// The n-th message of its topic, in the chunk record at a byte offset.
    InChunk { index: usize, chunk: u64 },
    /// A row of an SQLite table (its `id`).
    Row(i64),
}

impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            At::Message(i) => write!(f, "message {i}"),
            At::InChunk { index, chunk } => {
                write!(f, "message {index} (chunk at byte {chunk})")
            }
            At::Row(id) => write!(f, "row id {id}"),
        }
    }
}

/// A failure while streaming: a format-level problem (a reader may turn it
/// into its own canonical message) or a decoding one.
pub(crate) enum Fail {
    Format(String),
    Input(InputError),
}

impl Fail {
    /// As an input error about `file` (a format problem names just the file).
    pub(crate) fn into_input(self, file: &str) -> InputError {
        match self {
            Fail::Input(e) => e,
            Fail::Format(m) => InputError::new(file, m),
        }
    }
}

impl From<InputError> for Fail {
    fn from(e: InputError) -> Self {
        Fail::Input(e)
    }
}

/// A bag's raw messages, in the order the bag defines (file or time order).
pub(crate) trait RawMessages {
    /// The file being read (for a folder: the file of the latest message).
    fn name(&self) -> &str;
    /// How the messages are serialised.
    fn wire(&self) -> Wire;
    /// The next message of a topic that plays a role (others are skipped).
    fn next_raw(&mut self) -> Result<Option<Raw>, Fail>;
}

/// A bag's samples, stream by stream in stamp order, in bounded memory.
pub(crate) struct BagStream<'o, M> {
    messages: M,
    opts: &'o ReadOptions,
    state: State<'o>,
    info: StreamInfo,
    buffers: [Reorder; 5],
    rates: Option<RateIntegrator>,
    ready: VecDeque<Item>,
    done: bool,
    /// Items decoded per stream, and how many the first pass counted.
    decoded: [usize; 5],
    expected: [usize; 5],
    /// The items of the message being decoded (kept to reuse its allocation).
    fresh: Vec<Item>,
}

impl<'o, M: RawMessages> BagStream<'o, M> {
    /// Runs the first pass over `first` (counts, laser mount) and gets ready
    /// to decode `second`, a fresh reader of the same bag.
    pub(crate) fn new(first: M, second: M, opts: &'o ReadOptions) -> Result<Self, Fail> {
        let info = first_pass(first, opts)?;
        let state = State::with_wire(second.name(), opts, second.wire());
        Ok(Self {
            messages: second,
            opts,
            state,
            expected: [
                info.scans,
                info.wheels,
                info.gyro,
                info.odom,
                info.reference,
            ],
            info,
            buffers: Default::default(),
            rates: None,
            ready: VecDeque::new(),
            done: false,
            decoded: [0; 5],
            fresh: Vec::new(),
        })
    }

    /// Counts and laser mount, known before the first item.
    pub(crate) fn info(&self) -> &StreamInfo {
        &self.info
    }

    /// The raw message reader.
    pub(crate) fn messages(&self) -> &M {
        &self.messages
    }

    /// The next item (each stream in stamp order; streams interleaved roughly
    /// by time), `None` at the end. A stream's items are all out once as many
    /// have come as [`StreamInfo`] counts.
    pub(crate) fn next_decoded(&mut self) -> Result<Option<Item>, Fail> {
        loop {
            if let Some(i) = self.ready.pop_front() {
                return Ok(Some(i));
            }
            if self.done {
                return Ok(None);
            }
            match self.messages.next_raw()? {
                None => {
                    self.done = true;
                    for b in 0..self.buffers.len() {
                        while let Some(item) = self.buffers[b].items.pop_front() {
                            self.release(item);
                        }
                    }
                }
                Some(raw) => self.decode(raw)?,
            }
        }
    }

    fn decode(&mut self, raw: Raw) -> Result<(), Fail> {
        // Transforms were resolved in the first pass.
        let roles = raw
            .roles
            .iter()
            .filter(|r| !matches!(r, Role::Tf | Role::TfStatic | Role::Survey));
        for role in roles {
            self.state
                .handle(*role, &raw.data, raw.log_time)
                .map_err(|m| {
                    Fail::Input(
                        InputError::new(self.messages.name(), m)
                            .topic(raw.topic.as_str())
                            .at(raw.at.to_string()),
                    )
                })?;
        }
        let rec = self.state.decoded();
        let mut fresh = std::mem::take(&mut self.fresh);
        fresh.extend(rec.scans.drain(..).map(Item::Scan));
        fresh.extend(rec.wheels.drain(..).map(Item::Wheel));
        fresh.extend(rec.gyro.drain(..).map(Item::Gyro));
        fresh.extend(rec.odom.drain(..).map(Item::Odom));
        fresh.extend(rec.reference.drain(..).map(Item::Reference));
        let tol = self.opts.reorder_tolerance;
        for item in fresh.drain(..) {
            let s = item.stream();
            self.decoded[s] += 1;
            self.buffers[s].insert(item);
            while let Some(i) = self.buffers[s].pop_ready(tol) {
                self.release(i);
            }
            // The stream's last message: nothing can come before its tail.
            if self.decoded[s] == self.expected[s] {
                while let Some(i) = self.buffers[s].items.pop_front() {
                    self.release(i);
                }
            }
        }
        self.fresh = fresh;
        Ok(())
    }

    fn release(&mut self, item: Item) {
        let item = released(item, self.state.wheel_rates(), &mut self.rates);
        self.ready.push_back(item);
    }
}

impl<M: RawMessages> SampleSource for BagStream<'_, M> {
    fn name(&self) -> &str {
        self.messages.name()
    }

    fn info(&self) -> &StreamInfo {
        &self.info
    }

    fn next_item(&mut self) -> Result<Option<Item>, InputError> {
        self.next_decoded()
            .map_err(|f| f.into_input(self.messages.name()))
    }

    fn scan_topic(&self) -> &str {
        &self.opts.topics.scan
    }
}

/// A bag as a sample source, from a function that opens a fresh raw reader
/// of it (called twice: one reader per pass).
pub(crate) fn open_with<'o, M: RawMessages + 'o>(
    path: &std::path::Path,
    opts: &'o ReadOptions,
    open: impl Fn() -> Result<M, InputError>,
) -> Result<Box<dyn SampleSource + 'o>, InputError> {
    let stream = BagStream::new(open()?, open()?, opts)
        .map_err(|f| f.into_input(&path.display().to_string()))?;
    Ok(Box::new(stream))
}

/// Counts the messages of each stream and resolves the laser mount.
fn first_pass<M: RawMessages>(mut m: M, opts: &ReadOptions) -> Result<StreamInfo, Fail> {
    let mut state = State::with_wire(m.name(), opts, m.wire());
    let mut info = StreamInfo::default();
    while let Some(raw) = m.next_raw()? {
        for role in &raw.roles {
            let mut handle = || {
                state.handle(*role, &raw.data, raw.log_time).map_err(|e| {
                    Fail::Input(
                        InputError::new(m.name(), e)
                            .topic(raw.topic.as_str())
                            .at(raw.at.to_string()),
                    )
                })
            };
            match role {
                Role::Scan => {
                    if info.scans == 0 {
                        handle()?;
                    }
                    info.scans += 1;
                }
                Role::Wheels => {
                    // Decoded here too, so that the wheel values are known
                    // before the first item and a bad topic fails early.
                    handle()?;
                    state.decoded().wheels.clear();
                    info.wheels += 1;
                }
                Role::Imu => info.gyro += 1,
                Role::Odom => info.odom += 1,
                Role::RefOdometry | Role::RefPose | Role::RefPoint => info.reference += 1,
                Role::TfStatic | Role::Tf => handle()?,
                Role::Survey => {}
            }
        }
    }
    let rec = state.finish().map_err(Fail::Input)?;
    info.base_from_laser = rec.base_from_laser;
    info.mount_origin = rec.mount_origin;
    info.mount_note = rec.mount_note;
    info.wheel_values = rec.wheel_values;
    Ok(info)
}
