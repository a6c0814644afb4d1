//! Reads a ROS 2 bag in MCAP (CDR messages, chunks plain or zstd/lz4) into a
//! [`Recording`]. Message types are recognised by schema name; topics come from
//! [`super::TopicConfig`]. Every problem is an [`InputError`] naming the file, the
//! topic and the message index (0-based, counted per topic).

use std::collections::HashMap;
use std::path::Path;

use super::mcap_streams::{channel_roles, Role, State};
use super::options::ReadOptions;
use crate::error::InputError;
use crate::recording::Recording;

/// Reads an MCAP file into a [`Recording`] (streams sorted by stamp).
pub fn read_mcap(path: &Path, opts: &ReadOptions) -> Result<Recording, InputError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    read_mcap_bytes(&bytes, &file, opts)
}

/// Like [`read_mcap`] for an MCAP already in memory; `file` names it in errors.
pub fn read_mcap_bytes(
    bytes: &[u8],
    file: &str,
    opts: &ReadOptions,
) -> Result<Recording, InputError> {
    let mcap_err = |e: mcap::McapError, after: usize| {
        let mut msg = format!("corrupt or truncated MCAP: {e}");
        if let Some(src) = std::error::Error::source(&e) {
            msg.push_str(&format!(" ({src})"));
        }
        InputError::new(file, msg).at(format!("after {after} messages"))
    };
    if let Err(e) = mcap::read::footer(bytes) {
        return Err(truncated(bytes, file, e));
    }
    super::mcap_guard::check_file(bytes, false)
        .map_err(|m| InputError::new(file, m).at("after 0 messages"))?;
    let mut stream = mcap::read::RawMessageStream::new(bytes).map_err(|e| mcap_err(e, 0))?;
    let mut st = State::new(file, opts);
    let mut total = 0usize;
    // Per channel: topic, roles, messages seen so far.
    let mut channels: HashMap<u16, (String, Vec<Role>, usize)> = HashMap::new();
    while let Some(msg) = stream.next() {
        let msg = msg.map_err(|e| mcap_err(e, total))?;
        total += 1;
        let id = msg.header.channel_id;
        let (topic, rs, count) = match channels.entry(id) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let ch = stream.get_channel(id).ok_or_else(|| {
                    InputError::new(file, format!("message refers to unknown channel {id}"))
                        .at(format!("after {total} messages"))
                })?;
                let r = channel_roles(&ch, opts)
                    .map_err(|m| InputError::new(file, m).topic(&ch.topic))?;
                e.insert((ch.topic.clone(), r, 0))
            }
        };
        let i = *count;
        *count += 1;
        for role in rs {
            st.handle(*role, &msg.data, msg.header.log_time)
                .map_err(|m| {
                    InputError::new(file, m)
                        .topic(topic.as_str())
                        .at(format!("message {i}"))
                })?;
        }
    }
    st.finish()
}

/// The error for a file without a valid footer: names the last message that
/// could still be read (topic and per-topic index), so the cut can be found.
fn truncated(bytes: &[u8], file: &str, e: mcap::McapError) -> InputError {
    // Only the complete records of the cut file are read.
    let lenient = super::mcap_guard::check_file(bytes, true)
        .map_err(|_| mcap::McapError::UnexpectedEof)
        .and_then(|end| {
            mcap::read::RawMessageStream::new_with_options(
                &bytes[..end],
                mcap::read::Options::IgnoreEndMagic.into(),
            )
        });
    let mut last: Option<(String, usize)> = None;
    let mut counts: HashMap<u16, usize> = HashMap::new();
    if let Ok(mut stream) = lenient {
        while let Some(Ok(m)) = stream.next() {
            let id = m.header.channel_id;
            let c = counts.entry(id).or_insert(0);
            if let Some(ch) = stream.get_channel(id) {
                last = Some((ch.topic.clone(), *c));
            }
            *c += 1;
        }
    }
    let base = format!("truncated or corrupt MCAP (no valid footer: {e})");
    match last {
        Some((topic, i)) => InputError::new(
            file,
            format!("{base}; the last readable message is this one"),
        )
        .topic(topic)
        .at(format!("message {i}")),
        None => InputError::new(file, format!("{base}; no message is readable")),
    }
}
