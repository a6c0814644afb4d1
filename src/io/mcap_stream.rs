//! Reads a ROS 2 bag (MCAP) message by message, with memory bounded by the
//! chunk size and a short reorder window instead of the recording's length.
//!
//! The file is read through `mcap`'s sans-io [`LinearReader`] from a plain
//! `File` (no mmap). A first pass counts the messages of each stream and
//! resolves `base_from_laser` (static transforms, laser frame); the second
//! pass decodes every message as [`read_mcap`](super::read_mcap) does and
//! yields each stream in stamp order: an item is released once its stream has
//! seen a stamp more than `reorder_tolerance` later, which the reader's
//! time-order check guarantees no later message can undercut. The streams are
//! therefore exactly what the in-memory reader's stable sort produces. Any
//! error is reported as the in-memory reader reports it.

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::mcap_streams::{channel_roles, RateIntegrator, Role, State};
use super::options::ReadOptions;
use super::source::{Item, SampleSource, StreamInfo};
use crate::error::InputError;

/// Raw message source over one file: channels, roles and per-topic counters.
struct Messages<'o> {
    file: File,
    reader: LinearReader,
    /// The records of the chunk being read (decompressed and checked) and
    /// the offset of the next one.
    chunk: Vec<u8>,
    chunk_pos: usize,
    catalog: Catalog<'o>,
}

/// Schemas and channels seen so far, and what each message is for.
struct Catalog<'o> {
    opts: &'o ReadOptions,
    name: String,
    schemas: HashMap<u16, Arc<mcap::Schema<'static>>>,
    /// Per channel: topic, roles, messages seen so far.
    channels: HashMap<u16, (String, Vec<Role>, usize)>,
    total: usize,
}

/// A message to decode: its roles, topic, per-topic index, payload, log time.
struct Raw {
    roles: Vec<Role>,
    topic: String,
    index: usize,
    data: Vec<u8>,
    log_time: u64,
}

/// Largest record (or decompressed chunk) the streaming reader accepts (bytes).
const MAX_RECORD_BYTES: usize = 1 << 30;

/// A failure while streaming: an MCAP-level problem or a decoding one.
enum Fail {
    Mcap(String),
    Input(InputError),
}

impl<'o> Messages<'o> {
    fn open(path: &Path, opts: &'o ReadOptions) -> Result<Self, Fail> {
        let name = path.display().to_string();
        let mut file = File::open(path)
            .map_err(|e| Fail::Input(InputError::new(&name, format!("cannot read: {e}"))))?;
        check_footer(&mut file).map_err(Fail::Mcap)?;
        Ok(Self {
            file,
            // A corrupt length field must be an error, not an allocation of
            // petabytes: no record or chunk of a real bag comes near this.
            // Chunks come whole and are opened by `mcap_guard`, which checks
            // every length in them before anything is parsed.
            reader: LinearReader::new_with_options(
                LinearReaderOptions::default()
                    .with_record_length_limit(MAX_RECORD_BYTES)
                    .with_emit_chunks(true),
            ),
            chunk: Vec::new(),
            chunk_pos: 0,
            catalog: Catalog {
                opts,
                name,
                schemas: HashMap::new(),
                channels: HashMap::new(),
                total: 0,
            },
        })
    }

    /// The next message of a channel that plays a role (others are skipped).
    fn next(&mut self) -> Result<Option<Raw>, Fail> {
        loop {
            if self.chunk_pos < self.chunk.len() {
                let (opcode, body) =
                    super::mcap_guard::chunk_records(&self.chunk[self.chunk_pos..])
                        .next()
                        .expect("open_chunk checked every record of the chunk");
                self.chunk_pos += 9 + body.len();
                match self.catalog.handle(opcode, body)? {
                    Some(raw) => return Ok(Some(raw)),
                    None => continue,
                }
            }
            let event = match self.reader.next_event() {
                None => return Ok(None),
                Some(e) => e.map_err(|e| Fail::Mcap(e.to_string()))?,
            };
            let (opcode, data) = match event {
                LinearReadEvent::ReadRequest(n) => {
                    let buf = self.reader.insert(n);
                    let got = self.file.read(buf).map_err(|e| Fail::Mcap(e.to_string()))?;
                    self.reader.notify_read(got);
                    continue;
                }
                LinearReadEvent::Record { opcode, data } => (opcode, data),
            };
            if opcode == CHUNK {
                let inner = super::mcap_guard::open_chunk(data).map_err(Fail::Mcap)?;
                let inner = inner
                    .ok_or_else(|| Fail::Mcap("chunk with an unsupported compression".into()))?;
                self.chunk = inner.into_owned();
                self.chunk_pos = 0;
                continue;
            }
            if let Some(raw) = self.catalog.handle(opcode, data)? {
                return Ok(Some(raw));
            }
        }
    }
}

/// MCAP opcode of a chunk.
const CHUNK: u8 = 0x06;

impl Catalog<'_> {
    /// Takes in one record: schemas and channels are remembered, a message
    /// of a channel with a role is returned, anything else is passed over.
    fn handle(&mut self, opcode: u8, data: &[u8]) -> Result<Option<Raw>, Fail> {
        super::mcap_guard::check_record(opcode, data).map_err(Fail::Mcap)?;
        let record = mcap::parse_record(opcode, data).map_err(|e| Fail::Mcap(e.to_string()))?;
        match record {
            mcap::records::Record::Schema { header, data } => {
                self.schemas.insert(
                    header.id,
                    Arc::new(mcap::Schema {
                        id: header.id,
                        name: header.name,
                        encoding: header.encoding,
                        data: std::borrow::Cow::Owned(data.into_owned()),
                    }),
                );
            }
            mcap::records::Record::Channel(ch) => {
                if self.channels.contains_key(&ch.id) {
                    return Ok(None);
                }
                let channel = mcap::Channel {
                    id: ch.id,
                    topic: ch.topic,
                    schema: self.schemas.get(&ch.schema_id).cloned(),
                    message_encoding: ch.message_encoding,
                    metadata: ch.metadata,
                };
                let roles = channel_roles(&channel, self.opts).map_err(|m| {
                    Fail::Input(InputError::new(&self.name, m).topic(&channel.topic))
                })?;
                self.channels.insert(ch.id, (channel.topic, roles, 0));
            }
            mcap::records::Record::Message { header, data } => {
                self.total += 1;
                let Some((topic, roles, count)) = self.channels.get_mut(&header.channel_id) else {
                    return Err(Fail::Mcap(format!(
                        "message refers to unknown channel {}",
                        header.channel_id
                    )));
                };
                let index = *count;
                *count += 1;
                if roles.is_empty() {
                    return Ok(None);
                }
                return Ok(Some(Raw {
                    roles: roles.clone(),
                    topic: topic.clone(),
                    index,
                    data: data.into_owned(),
                    log_time: header.log_time,
                }));
            }
            _ => {}
        }
        Ok(None)
    }
}

/// Checks the start magic and the footer from the file's two ends.
fn check_footer(file: &mut File) -> Result<(), String> {
    let len = file.seek(SeekFrom::End(0)).map_err(|e| e.to_string())?;
    let tail = len.min(64);
    let mut buf = vec![0u8; 8.min(len as usize)];
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    file.read_exact(&mut buf).map_err(|e| e.to_string())?;
    if len > 8 {
        let mut end = vec![0u8; tail.min(len - 8) as usize];
        file.seek(SeekFrom::Start(len - end.len() as u64))
            .map_err(|e| e.to_string())?;
        file.read_exact(&mut end).map_err(|e| e.to_string())?;
        buf.extend_from_slice(&end);
    }
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    mcap::read::footer(&buf)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// A stream's reorder buffer: sorted by stamp (ties in arrival order).
#[derive(Default)]
struct Reorder {
    items: VecDeque<Item>,
    latest: Option<f64>,
}

impl Reorder {
    fn insert(&mut self, item: Item) {
        let t = item.stamp();
        let at = self.items.partition_point(|i| i.stamp() <= t);
        self.items.insert(at, item);
        self.latest = Some(self.latest.map_or(t, |l: f64| l.max(t)));
    }

    /// The front item, if no message still to come can be earlier.
    fn pop_ready(&mut self, tolerance: f64) -> Option<Item> {
        let bound = self.latest? - tolerance;
        if self.items.front()?.stamp() < bound {
            self.items.pop_front()
        } else {
            None
        }
    }
}

/// Yields a bag's samples stream by stream in stamp order, in bounded memory.
pub struct McapStream<'o> {
    path: std::path::PathBuf,
    messages: Messages<'o>,
    state: State<'o>,
    info: StreamInfo,
    buffers: [Reorder; 5],
    rates: Option<RateIntegrator>,
    ready: VecDeque<Item>,
    done: bool,
    /// Items decoded per stream, and how many the first pass counted.
    decoded: [usize; 5],
    expected: [usize; 5],
    /// The configured scan topic.
    scan_topic: String,
}

impl<'o> McapStream<'o> {
    /// Opens `path`: runs the first pass (counts, laser mount), then is ready
    /// to yield items. Errors are those [`read_mcap`](super::read_mcap) gives.
    pub fn open(path: &Path, opts: &'o ReadOptions) -> Result<Self, InputError> {
        let info = first_pass(path, opts).map_err(|f| canonical(path, opts, f))?;
        let messages = Messages::open(path, opts).map_err(|f| canonical(path, opts, f))?;
        let state = State::new(&messages.catalog.name, opts);
        Ok(Self {
            path: path.to_path_buf(),
            messages,
            state,
            info: info.clone(),
            buffers: Default::default(),
            rates: None,
            ready: VecDeque::new(),
            done: false,
            decoded: [0; 5],
            expected: [
                info.scans,
                info.wheels,
                info.gyro,
                info.odom,
                info.reference,
            ],
            scan_topic: opts.topics.scan.clone(),
        })
    }

    /// The next item (each stream in stamp order; streams interleaved roughly
    /// by time), `None` at the end. A stream's items are all out once as many
    /// have come as [`StreamInfo`] counts.
    fn next_decoded(&mut self) -> Result<Option<Item>, InputError> {
        loop {
            if let Some(i) = self.ready.pop_front() {
                return Ok(Some(i));
            }
            if self.done {
                return Ok(None);
            }
            match self.messages.next() {
                Err(f) => return Err(canonical(&self.path, self.messages.catalog.opts, f)),
                Ok(None) => {
                    self.done = true;
                    for b in 0..self.buffers.len() {
                        while let Some(item) = self.buffers[b].items.pop_front() {
                            self.release(item);
                        }
                    }
                }
                Ok(Some(raw)) => {
                    self.decode(raw)
                        .map_err(|f| canonical(&self.path, self.messages.catalog.opts, f))?;
                }
            }
        }
    }

    fn decode(&mut self, raw: Raw) -> Result<(), Fail> {
        // Transforms were resolved in the first pass.
        for role in raw
            .roles
            .iter()
            .filter(|r| !matches!(r, Role::Tf | Role::TfStatic))
        {
            self.state
                .handle(*role, &raw.data, raw.log_time)
                .map_err(|m| {
                    Fail::Input(
                        InputError::new(&self.messages.catalog.name, m)
                            .topic(raw.topic.as_str())
                            .at(format!("message {}", raw.index)),
                    )
                })?;
        }
        let rec = self.state.decoded();
        let mut fresh: Vec<Item> = Vec::new();
        fresh.extend(rec.scans.drain(..).map(Item::Scan));
        fresh.extend(rec.wheels.drain(..).map(Item::Wheel));
        fresh.extend(rec.gyro.drain(..).map(Item::Gyro));
        fresh.extend(rec.odom.drain(..).map(Item::Odom));
        fresh.extend(rec.reference.drain(..).map(Item::Reference));
        let tol = self.messages.catalog.opts.reorder_tolerance;
        for item in fresh {
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
        Ok(())
    }

    fn release(&mut self, item: Item) {
        let item = match item {
            Item::Wheel(w) if self.state.wheel_rates() => {
                Item::Wheel(self.rates.get_or_insert_with(Default::default).angles(w))
            }
            other => other,
        };
        self.ready.push_back(item);
    }
}

/// Counts the messages of each stream and resolves the laser mount.
fn first_pass(path: &Path, opts: &ReadOptions) -> Result<StreamInfo, Fail> {
    let mut m = Messages::open(path, opts)?;
    let name = m.catalog.name.clone();
    let mut state = State::new(&name, opts);
    let mut info = StreamInfo::default();
    while let Some(raw) = m.next()? {
        for role in &raw.roles {
            match role {
                Role::Scan => {
                    if info.scans == 0 {
                        state.handle(*role, &raw.data, raw.log_time).map_err(|e| {
                            Fail::Input(InputError::new(&name, e).topic(raw.topic.as_str()))
                        })?;
                    }
                    info.scans += 1;
                }
                Role::Joints => info.wheels += 1,
                Role::Imu => info.gyro += 1,
                Role::Odom => info.odom += 1,
                Role::RefOdometry | Role::RefPose | Role::RefPoint => info.reference += 1,
                Role::TfStatic | Role::Tf => {
                    state.handle(*role, &raw.data, raw.log_time).map_err(|e| {
                        Fail::Input(InputError::new(&name, e).topic(raw.topic.as_str()))
                    })?
                }
            }
        }
    }
    let rec = state.finish().map_err(Fail::Input)?;
    info.base_from_laser = rec.base_from_laser;
    info.mount_origin = rec.mount_origin;
    info.mount_note = rec.mount_note;
    Ok(info)
}

/// The error the in-memory reader gives for this file (so both paths report
/// a bad file alike); the streaming error if that reader accepts it.
fn canonical(path: &Path, opts: &ReadOptions, f: Fail) -> InputError {
    let name = path.display().to_string();
    match super::mcap_read::read_mcap(path, opts) {
        Err(e) => e,
        Ok(_) => match f {
            Fail::Input(e) => e,
            Fail::Mcap(m) => InputError::new(name, format!("corrupt or truncated MCAP: {m}")),
        },
    }
}

impl SampleSource for McapStream<'_> {
    fn name(&self) -> &str {
        &self.messages.catalog.name
    }

    fn info(&self) -> &StreamInfo {
        &self.info
    }

    fn next_item(&mut self) -> Result<Option<Item>, InputError> {
        self.next_decoded()
    }

    fn scan_topic(&self) -> &str {
        &self.scan_topic
    }
}
