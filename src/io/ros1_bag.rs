//! Reads a ROS 1 bag (format 2.0, wiki.ros.org/Bags/Format/2.0) message by
//! message in time order, as `rosbag` plays it: the bag header points to the
//! index section (connection records, one chunk-info record per chunk with
//! the chunk's first and last message time); chunks are opened in order of
//! their first time, and their messages merged by receive time (ties in file
//! order), so chunks that overlap in time still give one time-ordered
//! stream, while only the chunks that overlap are held in memory. Messages
//! use the ROS 1 serialisation ([`super::cdr::CdrReader::ros1`]); type
//! names are ROS 1's (`sensor_msgs/LaserScan`); a ROS 1 stamp's `uint32`
//! seconds are read as ROS 2's `int32`, so stamps after 2038 are refused as
//! negative rather than read wrong. Every problem is an
//! [`InputError`] naming the file, the topic when known, and the byte
//! offset of the record.

use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::bag_stream::{At, Fail, Raw, RawMessages};
use super::mcap_streams::{roles_for, Role, Wire};
use super::options::ReadOptions;
use super::ros1_records::{chunk_records, decompress, op, read_record, Fields, MAGIC};
use super::source::SampleSource;
use crate::error::InputError;

/// A connection of the bag (one publisher of a topic): what its messages
/// are for.
struct Connection {
    topic: String,
    type_name: std::sync::Arc<str>,
    roles: Vec<Role>,
}

/// A chunk as the index describes it.
#[derive(Clone, Copy)]
struct ChunkInfo {
    /// Byte offset of the chunk record.
    pos: u64,
    /// Receive time of its first message (ns).
    start: u64,
}

/// A decompressed chunk whose messages are being handed out.
struct OpenChunk {
    pos: u64,
    data: Vec<u8>,
    /// (time ns, offset in `data` of the record, connection id, data range)
    /// sorted by time, ties in file order.
    entries: Vec<(u64, usize, u32, std::ops::Range<usize>)>,
    next: usize,
}

impl OpenChunk {
    /// Sort key of the next message: time, then file position.
    fn key(&self) -> Option<(u64, u64, usize)> {
        let e = self.entries.get(self.next)?;
        Some((e.0, self.pos, e.1))
    }
}

/// The raw messages of a ROS 1 bag, merged by time across chunks.
pub(crate) struct Ros1Messages {
    name: String,
    file: File,
    len: u64,
    connections: HashMap<u32, Connection>,
    /// Messages of each topic handed out so far (all its connections).
    counts: HashMap<String, usize>,
    /// Chunks not opened yet, latest first (popped from the back).
    pending: Vec<ChunkInfo>,
    open: Vec<OpenChunk>,
}

impl Ros1Messages {
    /// Opens `path`: checks the magic, reads the bag header and the index.
    pub(crate) fn open(path: &Path, opts: &ReadOptions) -> Result<Self, InputError> {
        let name = path.display().to_string();
        let err = |m: String| InputError::new(&name, m);
        let mut file = File::open(path).map_err(|e| err(format!("cannot read: {e}")))?;
        let len = file
            .seek(SeekFrom::End(0))
            .map_err(|e| err(format!("cannot read: {e}")))?;
        let mut magic = [0u8; 13];
        file.seek(SeekFrom::Start(0))
            .and_then(|_| file.read_exact(&mut magic))
            .ok()
            .filter(|_| magic == MAGIC)
            .ok_or_else(|| err("not a ROS 1 bag of format 2.0 (no '#ROSBAG V2.0' line)".into()))?;
        let mut bag = Self {
            name: name.clone(),
            file,
            len,
            connections: HashMap::new(),
            counts: HashMap::new(),
            pending: Vec::new(),
            open: Vec::new(),
        };
        let (index_pos, counts) = bag.bag_header()?;
        bag.read_index(index_pos, opts)?;
        let found = [bag.connections.len(), bag.pending.len()];
        if found != counts.map(|n| n as usize) {
            return Err(bag.at(
                index_pos,
                format!(
                    "the index holds {} connections and {} chunks, the bag header says {} and {} \
                     (truncated?)",
                    found[0], found[1], counts[0], counts[1]
                ),
            ));
        }
        Ok(bag)
    }

    fn at(&self, pos: u64, m: impl Into<String>) -> InputError {
        InputError::new(&self.name, m).at(format!("byte {pos}"))
    }

    /// Reads the bag header record (right after the magic): the index
    /// offset and how many connections and chunks the index lists.
    fn bag_header(&mut self) -> Result<(u64, [u32; 2]), InputError> {
        let pos = MAGIC.len() as u64;
        let rec = read_record(&mut self.file, self.len, pos).map_err(|m| self.at(pos, m))?;
        let f = Fields::parse(&rec.header).map_err(|m| self.at(pos, m))?;
        let index_pos = f
            .op()
            .and_then(|o| match o {
                op::BAG_HEADER => f.u64("index_pos"),
                o => Err(format!(
                    "record op {o:#04x} where the bag header (0x03) was expected"
                )),
            })
            .map_err(|m| self.at(pos, m))?;
        let counts = [f.u32("conn_count"), f.u32("chunk_count")];
        let counts = match counts {
            [Ok(a), Ok(b)] => [a, b],
            [Err(m), _] | [_, Err(m)] => return Err(self.at(pos, m)),
        };
        if index_pos == 0 {
            return Err(self.at(
                pos,
                "the bag has no index (its recording was not closed); \
                 `rosbag reindex` writes one",
            ));
        }
        if index_pos < rec.next || index_pos >= self.len {
            return Err(self.at(
                pos,
                format!(
                    "the index is said to start at byte {index_pos}, outside the file's {} bytes \
                     (truncated?)",
                    self.len
                ),
            ));
        }
        Ok((index_pos, counts))
    }

    /// Reads the index section: connections and chunk infos.
    fn read_index(&mut self, index_pos: u64, opts: &ReadOptions) -> Result<(), InputError> {
        let mut pos = index_pos;
        let mut chunks = Vec::new();
        while pos < self.len {
            let rec = read_record(&mut self.file, self.len, pos).map_err(|m| self.at(pos, m))?;
            let f = Fields::parse(&rec.header).map_err(|m| self.at(pos, m))?;
            match f.op().map_err(|m| self.at(pos, m))? {
                op::CONNECTION => self.connection(&f, &rec.data, opts, pos)?,
                op::CHUNK_INFO => {
                    let info = (|| {
                        Ok::<_, String>(ChunkInfo {
                            pos: f.u64("chunk_pos")?,
                            start: f.time("start_time")?,
                        })
                    })()
                    .map_err(|m| self.at(pos, m))?;
                    if info.pos >= index_pos {
                        return Err(self.at(
                            pos,
                            format!("chunk said to be at byte {}, inside the index", info.pos),
                        ));
                    }
                    chunks.push(info);
                }
                _ => {}
            }
            pos = rec.next;
        }
        // A chunk listed twice is read once.
        chunks.sort_by_key(|c| c.pos);
        chunks.dedup_by_key(|c| c.pos);
        chunks.sort_by_key(|c| std::cmp::Reverse((c.start, c.pos)));
        self.pending = chunks;
        Ok(())
    }

    /// Takes in a connection record: topic and type from its data (a header
    /// of `topic`, `type`, `md5sum`, `message_definition`, ... fields).
    fn connection(
        &mut self,
        f: &Fields<'_>,
        data: &[u8],
        opts: &ReadOptions,
        pos: u64,
    ) -> Result<(), InputError> {
        let conn = f.u32("conn").map_err(|m| self.at(pos, m))?;
        let topic = f.text("topic").map_err(|m| self.at(pos, m))?.to_string();
        let c = Fields::parse(data)
            .and_then(|c| c.text("type").map(str::to_string))
            .map_err(|m| {
                self.at(pos, format!("connection {conn}: {m}"))
                    .topic(&topic)
            })?;
        let roles = roles_for(&topic, &c, "ros1", Wire::Ros1, opts)
            .map_err(|m| InputError::new(&self.name, m).topic(&topic))?;
        self.connections.insert(
            conn,
            Connection {
                topic,
                type_name: c.as_str().into(),
                roles,
            },
        );
        Ok(())
    }

    /// Reads and decompresses the chunk record at `info.pos`, listing its
    /// messages by time.
    fn open_chunk(&mut self, info: ChunkInfo) -> Result<OpenChunk, InputError> {
        let pos = info.pos;
        let rec = read_record(&mut self.file, self.len, pos).map_err(|m| self.at(pos, m))?;
        let data = (|| {
            let f = Fields::parse(&rec.header)?;
            if f.op()? != op::CHUNK {
                return Err(format!(
                    "record op {:#04x} where a chunk (0x05) was expected",
                    f.op()?
                ));
            }
            decompress(f.text("compression")?, rec.data, f.u32("size")?)
        })()
        .map_err(|m| self.at(pos, format!("chunk: {m}")))?;
        let mut entries = Vec::new();
        let records = chunk_records(&data).map_err(|m| self.at(pos, format!("chunk: {m}")))?;
        for (offset, header, body) in records {
            let in_chunk =
                |m: String| self.at(pos, format!("chunk, record at chunk byte {offset}: {m}"));
            let f = Fields::parse(header).map_err(in_chunk)?;
            if f.op().map_err(in_chunk)? != op::MSG_DATA {
                continue;
            }
            let conn = f.u32("conn").map_err(in_chunk)?;
            let time = f.time("time").map_err(in_chunk)?;
            let start = body.as_ptr() as usize - data.as_ptr() as usize;
            entries.push((time, offset, conn, start..start + body.len()));
        }
        entries.sort_by_key(|e| (e.0, e.1));
        Ok(OpenChunk {
            pos,
            data,
            entries,
            next: 0,
        })
    }

    /// The open chunk holding the earliest message, after opening every
    /// chunk that may hold an earlier one; `None` at the end of the bag.
    fn earliest(&mut self) -> Result<Option<usize>, InputError> {
        loop {
            self.open.retain(|c| c.next < c.entries.len());
            let best = (0..self.open.len()).min_by_key(|&i| self.open[i].key());
            let best_time = best.and_then(|i| self.open[i].key()).map(|k| k.0);
            match self.pending.last() {
                Some(c) if best_time.is_none_or(|t| c.start <= t) => {
                    let info = self.pending.pop().expect("a pending chunk");
                    let chunk = self.open_chunk(info)?;
                    self.open.push(chunk);
                }
                _ => return Ok(best),
            }
        }
    }
}

impl RawMessages for Ros1Messages {
    fn name(&self) -> &str {
        &self.name
    }

    fn wire(&self) -> Wire {
        Wire::Ros1
    }

    fn next_raw(&mut self) -> Result<Option<Raw>, Fail> {
        while let Some(i) = self.earliest()? {
            let chunk = &mut self.open[i];
            let (time, offset, conn, range) = chunk.entries[chunk.next].clone();
            chunk.next += 1;
            let chunk_pos = chunk.pos;
            let Some(c) = self.connections.get(&conn) else {
                return Err(Fail::Input(self.at(
                    chunk_pos,
                    format!(
                        "chunk, record at chunk byte {offset}: message of connection {conn}, \
                         which the bag's index does not list"
                    ),
                )));
            };
            let count = self.counts.entry(c.topic.clone()).or_insert(0);
            let index = *count;
            *count += 1;
            if c.roles.is_empty() {
                continue;
            }
            return Ok(Some(Raw {
                roles: c.roles.clone(),
                topic: c.topic.clone(),
                type_name: c.type_name.clone(),
                at: At::InChunk {
                    index,
                    chunk: chunk_pos,
                },
                data: self.open[i].data[range].to_vec(),
                log_time: time,
            }));
        }
        Ok(None)
    }
}

/// Opens a ROS 1 bag as a sample source: reads the index, runs the first
/// pass (counts, laser mount), then streams in memory bounded by the chunks
/// that overlap in time.
pub fn open<'o>(
    path: &Path,
    opts: &'o ReadOptions,
) -> Result<Box<dyn SampleSource + 'o>, InputError> {
    super::bag_stream::open_with(path, opts, || Ros1Messages::open(path, opts))
}
