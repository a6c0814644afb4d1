//! Reads a rosbag2 SQLite file (`.db3`, what `ros2 bag record` wrote before
//! MCAP became the default): table `topics(id, name, type,
//! serialization_format, ...)` and table `messages(id, topic_id, timestamp,
//! data)` with CDR payloads and receive times in ns. Messages come in
//! timestamp order (ties by row id) from one query that a worker thread
//! steps through, handing rows over a small bounded channel, so memory
//! stays bounded whatever the file's size. A reader dropped before the end
//! stops its worker (the query interrupted) and waits for it, so no thread
//! outlives the reader. Errors name the file, the topic and the row id.

use std::collections::HashMap;
use std::path::Path;
use std::sync::mpsc::{sync_channel, Receiver};

use rusqlite::{Connection, InterruptHandle, OpenFlags};

use super::bag_stream::{At, Raw, RawMessages};
use super::mcap_streams::{roles_for, Role, Wire};
use super::options::ReadOptions;
use super::source::SampleSource;
use crate::error::InputError;

/// The first 16 bytes of every SQLite 3 database.
pub const MAGIC: &[u8] = b"SQLite format 3\0";

/// A row of `messages`: id, topic id, timestamp (ns), data.
type Row = (i64, i64, i64, Vec<u8>);

/// Rows handed over by the worker before it waits for the reader.
const CHANNEL_ROWS: usize = 64;

/// The raw messages of a rosbag2 SQLite file, in timestamp order.
pub(crate) struct Db3Messages {
    name: String,
    /// topic id → topic.
    topics: HashMap<i64, Topic>,
    rows: Receiver<Result<Row, String>>,
    /// The worker stepping through the query, and the handle that stops it.
    worker: Option<(std::thread::JoinHandle<()>, InterruptHandle)>,
}

impl Drop for Db3Messages {
    /// Stops the worker: the receiver goes first (a worker waiting to hand
    /// over a row then fails and ends), then the query is interrupted (a
    /// worker inside a long step, e.g. the first, which sorts, ends too).
    fn drop(&mut self) {
        if let Some((worker, interrupt)) = self.worker.take() {
            self.rows = sync_channel(0).1;
            interrupt.interrupt();
            let _ = worker.join();
        }
    }
}

/// A row of table `topics`: name, type and what its messages are for.
struct Topic {
    name: String,
    type_name: std::sync::Arc<str>,
    roles: Vec<Role>,
}

fn open_db(path: &Path, name: &str) -> Result<Connection, InputError> {
    Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(|e| InputError::new(name, format!("cannot open as SQLite: {e}")))
}

impl Db3Messages {
    /// Opens `path`: reads the topics and starts the ordered query.
    pub(crate) fn open(path: &Path, opts: &ReadOptions) -> Result<Self, InputError> {
        let name = path.display().to_string();
        let db = open_db(path, &name)?;
        let topics = read_topics(&db, &name, opts)?;
        let wanted: Vec<String> = topics
            .iter()
            .filter(|(_, t)| !t.roles.is_empty())
            .map(|(id, _)| id.to_string())
            .collect();
        let (tx, rows) = sync_channel(CHANNEL_ROWS);
        let sql = format!(
            "SELECT id, topic_id, timestamp, data FROM messages WHERE topic_id IN ({}) \
             ORDER BY timestamp, id",
            wanted.join(",")
        );
        let interrupt = db.get_interrupt_handle();
        let worker = std::thread::spawn(move || {
            let run = || -> rusqlite::Result<()> {
                let mut stmt = db.prepare(&sql)?;
                let mut it = stmt.query([])?;
                while let Some(r) = it.next()? {
                    let row = (r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?);
                    if tx.send(Ok(row)).is_err() {
                        return Ok(());
                    }
                }
                Ok(())
            };
            if let Err(e) = run() {
                let _ = tx.send(Err(e.to_string()));
            }
        });
        Ok(Self {
            name,
            topics,
            rows,
            worker: Some((worker, interrupt)),
        })
    }
}

/// The roles of each topic of the `topics` table.
fn read_topics(
    db: &Connection,
    name: &str,
    opts: &ReadOptions,
) -> Result<HashMap<i64, Topic>, InputError> {
    let err = |m: String| InputError::new(name, m);
    let tables: Vec<String> = db
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
        .and_then(|mut s| s.query_map([], |r| r.get(0))?.collect())
        .map_err(|e| err(format!("not a readable SQLite database: {e}")))?;
    for t in ["topics", "messages"] {
        if !tables.iter().any(|n| n == t) {
            return Err(err(format!(
                "not a rosbag2 database: it has no table '{t}' (tables: {tables:?})"
            )));
        }
    }
    let rows: Vec<(i64, String, String, String)> = db
        .prepare("SELECT id, name, type, serialization_format FROM topics")
        .and_then(|mut s| {
            s.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))?
                .collect()
        })
        .map_err(|e| {
            err(format!("table 'topics' does not read as rosbag2's: {e}")).topic("topics")
        })?;
    let mut topics = HashMap::new();
    for (id, topic, ty, format) in rows {
        let roles = roles_for(&topic, &ty, &format, Wire::Cdr, opts)
            .map_err(|m| InputError::new(name, m).topic(&topic))?;
        topics.insert(
            id,
            Topic {
                name: topic,
                type_name: ty.as_str().into(),
                roles,
            },
        );
    }
    Ok(topics)
}

impl RawMessages for Db3Messages {
    fn name(&self) -> &str {
        &self.name
    }

    fn wire(&self) -> Wire {
        Wire::Cdr
    }

    fn next_raw(&mut self) -> Result<Option<Raw>, super::bag_stream::Fail> {
        let (id, topic_id, stamp, data) = match self.rows.recv() {
            Err(_) => return Ok(None),
            Ok(Err(m)) => {
                return Err(
                    InputError::new(&self.name, format!("table 'messages': {m}"))
                        .topic("messages")
                        .into(),
                )
            }
            Ok(Ok(row)) => row,
        };
        let Some(t) = self.topics.get(&topic_id) else {
            return Err(InputError::new(
                &self.name,
                format!("message of topic id {topic_id}, which table 'topics' does not list"),
            )
            .at(At::Row(id).to_string())
            .into());
        };
        let log_time = u64::try_from(stamp).map_err(|_| {
            InputError::new(&self.name, format!("negative timestamp {stamp} ns"))
                .topic(t.name.as_str())
                .at(At::Row(id).to_string())
        })?;
        Ok(Some(Raw {
            roles: t.roles.clone(),
            topic: t.name.clone(),
            type_name: t.type_name.clone(),
            at: At::Row(id),
            data,
            log_time,
        }))
    }
}

/// Opens a rosbag2 SQLite file as a sample source: runs the first pass
/// (counts, laser mount), then streams.
pub fn open<'o>(
    path: &Path,
    opts: &'o ReadOptions,
) -> Result<Box<dyn SampleSource + 'o>, InputError> {
    super::bag_stream::open_with(path, opts, || Db3Messages::open(path, opts))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rosbag2 database of `n` JointState rows (the payloads need not
    /// decode: only the rows are read here).
    fn database(path: &Path, n: i64) {
        let db = Connection::open(path).unwrap();
        db.execute_batch(
            "CREATE TABLE topics (id INTEGER PRIMARY KEY, name TEXT, type TEXT, \
             serialization_format TEXT, offered_qos_profiles TEXT); \
             CREATE TABLE messages (id INTEGER PRIMARY KEY, topic_id INTEGER, \
             timestamp INTEGER, data BLOB); \
             INSERT INTO topics VALUES (1, '/joint_states', 'sensor_msgs/msg/JointState', \
             'cdr', '');",
        )
        .unwrap();
        let tx = db.unchecked_transaction().unwrap();
        for i in 0..n {
            tx.execute(
                "INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?1, ?2)",
                rusqlite::params![1_000_000 * (n - i), vec![0u8; 16]],
            )
            .unwrap();
        }
        tx.commit().unwrap();
    }

    /// Dropped after one message of thousands (its worker waiting on a full
    /// channel, its query open) or before the first (its worker inside the
    /// query's first step, which sorts the whole table), the reader leaves
    /// nothing behind: at once another connection can lock the file for
    /// writing, which a query still open (a worker still alive) would refuse.
    #[test]
    fn a_reader_dropped_early_has_ended_its_worker() {
        let dir = std::env::temp_dir().join(format!("odocal-db3-drop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bag.db3");
        // Stamps in reverse row order: the first step sorts them all.
        database(&path, 300_000);
        let writer = Connection::open(&path).unwrap();
        writer.busy_timeout(std::time::Duration::ZERO).unwrap();
        let free = |w: &Connection| w.execute_batch("BEGIN EXCLUSIVE; COMMIT;");
        // Mid-stream.
        let mut r = Db3Messages::open(&path, &ReadOptions::default()).unwrap();
        let first = r.next_raw().ok().flatten().expect("a first message");
        assert_eq!(first.topic, "/joint_states");
        std::thread::sleep(std::time::Duration::from_millis(20));
        // The negative control: while the reader lives, its open query
        // holds the file.
        assert!(free(&writer).is_err());
        drop(r);
        let mid_stream = free(&writer);
        // Inside the first step.
        let t = std::time::Instant::now();
        drop(Db3Messages::open(&path, &ReadOptions::default()).unwrap());
        let at_once = t.elapsed();
        let first_step = free(&writer);
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            mid_stream.is_ok(),
            "mid-stream: the file is still held: {mid_stream:?}"
        );
        assert!(
            first_step.is_ok(),
            "first step: the file is still held: {first_step:?}"
        );
        eprintln!("dropped in {at_once:?}");
    }
}
