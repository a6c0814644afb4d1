//! Reads a ROS 2 bag (MCAP) message by message, with memory bounded by the
//! chunk size and a short reorder window instead of the recording's length.
//!
//! The file is read through `mcap`'s sans-io [`LinearReader`] from a plain
//! `File` (no mmap), in file order; `BagStream` makes the two passes and
//! yields each stream in stamp order, exactly what the in-memory reader's
//! stable sort produces. Any error is reported as the in-memory reader
//! reports it.

use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::bag_stream::{At, BagStream, Fail, Raw, RawMessages};
use super::mcap_streams::{channel_roles, Role, Wire};
use super::options::ReadOptions;
use super::source::{Item, SampleSource, StreamInfo};
use crate::error::InputError;

/// Raw message source over one file: channels, roles and per-topic counters.
pub(crate) struct Messages<'o> {
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
    /// Per channel: topic, type, roles, messages seen so far.
    channels: HashMap<u16, (String, Arc<str>, Vec<Role>, usize)>,
    total: usize,
}

/// Largest record (or decompressed chunk) the streaming reader accepts (bytes).
const MAX_RECORD_BYTES: usize = 1 << 30;

/// The record length limit for a file of `file_len` bytes: no record is
/// longer than the file that holds it.
fn record_limit(file_len: u64) -> usize {
    usize::try_from(file_len).map_or(MAX_RECORD_BYTES, |n| n.min(MAX_RECORD_BYTES))
}

impl<'o> Messages<'o> {
    fn open(path: &Path, opts: &'o ReadOptions) -> Result<Self, Fail> {
        let name = path.display().to_string();
        let mut file = File::open(path)
            .map_err(|e| Fail::Input(InputError::new(&name, format!("cannot read: {e}"))))?;
        check_footer(&mut file).map_err(Fail::Format)?;
        let file_len = file
            .metadata()
            .map_err(|e| Fail::Input(InputError::new(&name, format!("cannot read: {e}"))))?
            .len();
        Ok(Self {
            file,
            // A corrupt length field must be an error, not an allocation of
            // petabytes: no record of a real bag comes near this, and none
            // is longer than its file (the reader allocates a record's
            // claimed length before reading it). Chunks come whole and are
            // opened by `mcap_guard`, which checks every length in them
            // before anything is parsed.
            reader: LinearReader::new_with_options(
                LinearReaderOptions::default()
                    .with_record_length_limit(record_limit(file_len))
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
                match self.catalog.handle(opcode, body, true)? {
                    Some(raw) => return Ok(Some(raw)),
                    None => continue,
                }
            }
            let event = match self.reader.next_event() {
                None => return Ok(None),
                Some(e) => e.map_err(|e| Fail::Format(e.to_string()))?,
            };
            let (opcode, data) = match event {
                LinearReadEvent::ReadRequest(n) => {
                    let buf = self.reader.insert(n);
                    let got = self
                        .file
                        .read(buf)
                        .map_err(|e| Fail::Format(e.to_string()))?;
                    self.reader.notify_read(got);
                    continue;
                }
                LinearReadEvent::Record { opcode, data } => (opcode, data),
            };
            if opcode == CHUNK {
                let inner = super::mcap_guard::open_chunk(data).map_err(Fail::Format)?;
                let inner = inner
                    .ok_or_else(|| Fail::Format("chunk with an unsupported compression".into()))?;
                self.chunk = inner.into_owned();
                self.chunk_pos = 0;
                continue;
            }
            if let Some(raw) = self.catalog.handle(opcode, data, false)? {
                return Ok(Some(raw));
            }
        }
    }
}

/// MCAP opcode of a chunk.
const CHUNK: u8 = 0x06;
/// MCAP opcode of a message.
const MESSAGE: u8 = 0x05;

impl Catalog<'_> {
    /// Takes in one record: schemas and channels are remembered, a message
    /// of a channel with a role is returned, anything else is passed over.
    /// `checked`: the record comes from a chunk that
    /// [`open_chunk`](super::mcap_guard::open_chunk) has checked whole.
    fn handle(&mut self, opcode: u8, data: &[u8], checked: bool) -> Result<Option<Raw>, Fail> {
        if !checked {
            super::mcap_guard::check_record(opcode, data).map_err(Fail::Format)?;
        }
        if opcode == MESSAGE {
            return self.message(data);
        }
        let record = mcap::parse_record(opcode, data).map_err(|e| Fail::Format(e.to_string()))?;
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
                let ty: Arc<str> = channel
                    .schema
                    .as_ref()
                    .map_or("", |s| s.name.as_str())
                    .into();
                self.channels.insert(ch.id, (channel.topic, ty, roles, 0));
            }
            _ => {}
        }
        Ok(None)
    }
}

impl Catalog<'_> {
    /// A message record (its length checked by `check_record`): channel id,
    /// sequence, log time, publish time, then the payload, as the MCAP
    /// specification lays it out; read here without the general record
    /// parser, which would copy nothing more but costs a fifth of the
    /// reader's own time per message.
    fn message(&mut self, data: &[u8]) -> Result<Option<Raw>, Fail> {
        let short = || Fail::Format(format!("message record of {} bytes", data.len()));
        let channel_id = u16::from_le_bytes(data.get(0..2).ok_or_else(short)?.try_into().unwrap());
        let log_time = u64::from_le_bytes(data.get(6..14).ok_or_else(short)?.try_into().unwrap());
        let payload = data.get(22..).ok_or_else(short)?;
        self.total += 1;
        let Some((topic, ty, roles, count)) = self.channels.get_mut(&channel_id) else {
            return Err(Fail::Format(format!(
                "message refers to unknown channel {channel_id}"
            )));
        };
        let index = *count;
        *count += 1;
        if roles.is_empty() {
            return Ok(None);
        }
        Ok(Some(Raw {
            roles: roles.clone(),
            topic: topic.clone(),
            type_name: ty.clone(),
            at: At::Message(index),
            data: payload.to_vec(),
            log_time,
        }))
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

impl RawMessages for Messages<'_> {
    fn name(&self) -> &str {
        &self.catalog.name
    }

    fn wire(&self) -> Wire {
        Wire::Cdr
    }

    fn next_raw(&mut self) -> Result<Option<Raw>, Fail> {
        self.next()
    }
}

/// The raw messages of one MCAP file in file order (for a rosbag2 folder);
/// errors are those [`read_mcap`](super::read_mcap) gives.
pub(crate) fn raw_messages<'o>(
    path: &Path,
    opts: &'o ReadOptions,
) -> Result<Messages<'o>, InputError> {
    Messages::open(path, opts).map_err(|f| canonical(path, opts, f))
}

/// Yields a bag's samples stream by stream in stamp order, in bounded memory.
pub struct McapStream<'o> {
    path: std::path::PathBuf,
    opts: &'o ReadOptions,
    stream: BagStream<'o, Messages<'o>>,
}

impl<'o> McapStream<'o> {
    /// Opens `path`: runs the first pass (counts, laser mount), then is ready
    /// to yield items. Errors are those [`read_mcap`](super::read_mcap) gives.
    pub fn open(path: &Path, opts: &'o ReadOptions) -> Result<Self, InputError> {
        let open = || Messages::open(path, opts);
        let stream = open()
            .and_then(|first| BagStream::new(first, open()?, opts))
            .map_err(|f| canonical(path, opts, f))?;
        Ok(Self {
            path: path.to_path_buf(),
            opts,
            stream,
        })
    }
}

/// The error the in-memory reader gives for this file (so both paths report
/// a bad file alike); the streaming error if that reader accepts it.
fn canonical(path: &Path, opts: &ReadOptions, f: Fail) -> InputError {
    let name = path.display().to_string();
    match super::mcap_read::read_mcap(path, opts) {
        Err(e) => e,
        Ok(_) => match f {
            Fail::Input(e) => e,
            Fail::Format(m) => InputError::new(name, format!("corrupt or truncated MCAP: {m}")),
        },
    }
}

impl SampleSource for McapStream<'_> {
    fn name(&self) -> &str {
        self.stream.messages().name()
    }

    fn info(&self) -> &StreamInfo {
        self.stream.info()
    }

    fn next_item(&mut self) -> Result<Option<Item>, InputError> {
        self.stream
            .next_decoded()
            .map_err(|f| canonical(&self.path, self.opts, f))
    }

    fn scan_topic(&self) -> &str {
        &self.opts.topics.scan
    }
}
