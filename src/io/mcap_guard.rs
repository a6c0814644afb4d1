//! Checks an MCAP's records before the `mcap` crate parses them, so that a
//! corrupt length field is an error instead of a huge allocation (which
//! aborts the process): every string, byte array and map prefix must fit in
//! its record, every record in its chunk, and a chunk's stated size must be
//! plausible for its compressed size.

use std::borrow::Cow;

/// Largest uncompressed chunk accepted at any compression ratio (bytes).
const MAX_CHUNK: u64 = 1 << 30;
/// Uncompressed size always accepted, whatever the compressed size (bytes).
const FREE_CHUNK: u64 = 64 << 20;
/// Largest accepted ratio of uncompressed to compressed chunk size above
/// [`FREE_CHUNK`] (lz4 tops out near 255, zstd on real sensor data near 10).
const MAX_RATIO: u64 = 256;

/// MCAP opcodes.
mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const ATTACHMENT: u8 = 0x09;
    pub const ATTACHMENT_INDEX: u8 = 0x0A;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// One field of a record body, as the MCAP specification lays it out.
#[derive(Clone, Copy)]
enum Field {
    /// Fixed-size fields (bytes).
    Fixed(usize),
    /// A string or byte array with a u32 length prefix.
    Bytes32,
    /// A byte array with a u64 length prefix.
    Bytes64,
    /// A map with a u32 byte-length prefix whose entries are two strings.
    StrMap,
    /// A map or array with a u32 byte-length prefix of fixed-size entries.
    Table32,
}

/// The fields of each record type (unknown opcodes are not checked).
fn layout(opcode: u8) -> &'static [Field] {
    use Field::*;
    match opcode {
        op::HEADER => &[Bytes32, Bytes32],
        op::FOOTER => &[Fixed(20)],
        op::SCHEMA => &[Fixed(2), Bytes32, Bytes32, Bytes32],
        op::CHANNEL => &[Fixed(4), Bytes32, Bytes32, StrMap],
        op::MESSAGE => &[Fixed(22)],
        op::CHUNK => &[Fixed(28), Bytes32, Bytes64],
        op::MESSAGE_INDEX => &[Fixed(2), Table32],
        op::CHUNK_INDEX => &[Fixed(32), Table32, Fixed(8), Bytes32, Fixed(16)],
        op::ATTACHMENT => &[Fixed(16), Bytes32, Bytes32, Bytes64, Fixed(4)],
        op::ATTACHMENT_INDEX => &[Fixed(40), Bytes32, Bytes32],
        op::STATISTICS => &[Fixed(42), Table32],
        op::METADATA => &[Bytes32, StrMap],
        op::METADATA_INDEX => &[Fixed(16), Bytes32],
        op::SUMMARY_OFFSET => &[Fixed(17)],
        op::DATA_END => &[Fixed(4)],
        _ => &[],
    }
}

fn u32_at(b: &[u8], i: usize) -> Option<usize> {
    Some(u32::from_le_bytes(b.get(i..i + 4)?.try_into().ok()?) as usize)
}

fn u64_at(b: &[u8], i: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(i..i + 8)?.try_into().ok()?))
}

/// Skips one length-prefixed field at `pos` (prefix of `width` bytes);
/// returns the position after it.
fn skip_prefixed(body: &[u8], pos: usize, width: usize) -> Result<usize, String> {
    let len = match width {
        4 => u32_at(body, pos).map(|n| n as u64),
        _ => u64_at(body, pos),
    }
    .ok_or_else(|| format!("record ends inside a length prefix at byte {pos}"))?;
    let left = (body.len() - pos - width) as u64;
    if len > left {
        return Err(format!(
            "field at byte {pos} claims {len} bytes, only {left} left in the record"
        ));
    }
    Ok(pos + width + len as usize)
}

/// Checks that every length prefix of a record body fits in the body.
pub(crate) fn check_record(opcode: u8, body: &[u8]) -> Result<(), String> {
    let mut pos = 0usize;
    for field in layout(opcode) {
        pos = match *field {
            Field::Fixed(n) => {
                if body.len() - pos < n {
                    return Err(format!(
                        "record of {} bytes is too short for its fields",
                        body.len()
                    ));
                }
                pos + n
            }
            Field::Bytes32 | Field::Table32 => skip_prefixed(body, pos, 4)?,
            Field::Bytes64 => skip_prefixed(body, pos, 8)?,
            Field::StrMap => {
                let end = skip_prefixed(body, pos, 4)?;
                let map = &body[..end];
                let mut p = pos + 4;
                while p < end {
                    p = skip_prefixed(map, p, 4)?;
                    p = skip_prefixed(map, p, 4)?;
                }
                end
            }
        };
    }
    Ok(())
}

/// The records in `bytes` (a file after its magic, or a chunk's records):
/// `(offset, opcode, body)`; stops at the first record that runs past the end.
fn records(bytes: &[u8]) -> impl Iterator<Item = (usize, u8, &[u8])> {
    let mut pos = 0usize;
    std::iter::from_fn(move || {
        let len = u64_at(bytes, pos + 1)?;
        let start = pos + 9;
        if len > (bytes.len() - start) as u64 {
            return None;
        }
        let end = start + len as usize;
        let r = (pos, bytes[pos], &bytes[start..end]);
        pos = end;
        Some(r)
    })
}

/// A chunk record's body made readable: its header checked, its records
/// decompressed (within the stated size), checked against the stated CRC
/// when there is one, and each record checked with [`check_record`].
/// Unknown compressions give `Ok(None)` (left to `mcap` to report).
pub(crate) fn open_chunk(body: &[u8]) -> Result<Option<Cow<'_, [u8]>>, String> {
    check_record(op::CHUNK, body)?;
    let n = u64_at(body, 16).unwrap_or(0);
    let crc = u32_at(body, 24).unwrap_or(0) as u32;
    let clen = u32_at(body, 28).unwrap_or(0);
    let compression = &body[32..32 + clen];
    let data_at = 32 + clen + 8;
    let data_len = u64_at(body, 32 + clen).unwrap_or(0) as usize;
    let data = &body[data_at..data_at + data_len];
    let limit = MAX_CHUNK.min(FREE_CHUNK.max(MAX_RATIO.saturating_mul(data.len() as u64)));
    if n > limit {
        return Err(format!(
            "chunk claims {n} uncompressed bytes from {} compressed ones (at most {limit} accepted)",
            data.len()
        ));
    }
    let n = n as usize;
    let inner: Cow<[u8]> = match compression {
        b"" => Cow::Borrowed(data),
        b"zstd" => Cow::Owned(zstd::bulk::decompress(data, n).map_err(|e| format!("zstd: {e}"))?),
        b"lz4" => {
            use std::io::Read;
            let mut out = Vec::new();
            lz4::Decoder::new(data)
                .and_then(|d| d.take(n as u64 + 1).read_to_end(&mut out))
                .map_err(|e| format!("lz4: {e}"))?;
            Cow::Owned(out)
        }
        _ => return Ok(None),
    };
    if inner.len() != n {
        return Err(format!(
            "chunk decompresses to {} bytes, {n} stated",
            inner.len()
        ));
    }
    if crc != 0 && crc32fast::hash(&inner) != crc {
        return Err("chunk CRC does not match its records".into());
    }
    let mut end = 0usize;
    for (pos, opcode, rec) in records(&inner) {
        check_record(opcode, rec).map_err(|m| format!("record at byte {pos} of the chunk: {m}"))?;
        end = pos + 9 + rec.len();
    }
    if end != inner.len() {
        return Err(format!(
            "record at byte {end} of the chunk runs past its end ({} bytes)",
            inner.len()
        ));
    }
    Ok(Some(inner))
}

/// The records of an opened chunk, `(opcode, body)` (all checked by [`open_chunk`]).
pub(crate) fn chunk_records(inner: &[u8]) -> impl Iterator<Item = (u8, &[u8])> {
    records(inner).map(|(_, opcode, body)| (opcode, body))
}

/// Checks every record of a whole MCAP file, chunks opened, up to the
/// footer, and returns where the well-formed records end. A record whose
/// length runs past the end of the file is an error unless `lenient` (a file
/// known to be cut short): then the records before it are all there is to
/// read, and the caller must read only `bytes[..end]` (the `mcap` reader
/// would otherwise overflow on a length near 2⁶⁴).
pub(crate) fn check_file(bytes: &[u8], lenient: bool) -> Result<usize, String> {
    if !bytes.starts_with(mcap::MAGIC) {
        return Ok(bytes.len());
    }
    let start = mcap::MAGIC.len();
    let body = &bytes[start..];
    let mut end = 0usize;
    for (i, (pos, opcode, rec)) in records(body).enumerate() {
        let at = |m: String| format!("corrupt MCAP: record {i} (opcode {opcode:#04x}): {m}");
        check_record(opcode, rec).map_err(at)?;
        if opcode == op::CHUNK {
            open_chunk(rec).map_err(at)?;
        }
        end = pos + 9 + rec.len();
        if opcode == op::FOOTER {
            return Ok(bytes.len());
        }
    }
    if let (Some(len), false) = (u64_at(body, end + 1), lenient) {
        return Err(format!(
            "corrupt MCAP: record at byte {} claims {len} bytes, only {} left in the file",
            start + end,
            body.len() - end - 9
        ));
    }
    Ok(if lenient { start + end } else { bytes.len() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(topic_len_field: u32, topic: &[u8]) -> Vec<u8> {
        let mut b = vec![1, 0, 2, 0];
        b.extend_from_slice(&topic_len_field.to_le_bytes());
        b.extend_from_slice(topic);
        b.extend_from_slice(&3u32.to_le_bytes());
        b.extend_from_slice(b"cdr");
        // metadata map: one entry "k" → "v"
        b.extend_from_slice(&10u32.to_le_bytes());
        for s in [b"k", b"v"] {
            b.extend_from_slice(&1u32.to_le_bytes());
            b.extend_from_slice(s);
        }
        b
    }

    #[test]
    fn a_well_formed_channel_passes_and_a_huge_string_prefix_fails() {
        assert_eq!(check_record(op::CHANNEL, &channel(5, b"/scan")), Ok(()));
        let e = check_record(op::CHANNEL, &channel(2_734_686_212, b"/scan")).unwrap_err();
        assert!(e.contains("claims 2734686212 bytes"), "{e}");
        // A map entry running past the map.
        let mut b = channel(5, b"/scan");
        let n = b.len();
        b[n - 5..n - 1].copy_from_slice(&9u32.to_le_bytes());
        assert!(check_record(op::CHANNEL, &b).is_err());
    }

    #[test]
    fn chunks_of_real_writers_open_and_a_bad_crc_is_refused() {
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .create(std::io::Cursor::new(Vec::new()))
            .unwrap();
        let s = w.add_schema("x", "ros2msg", b"int32 x\n").unwrap();
        let c = w.add_channel(s, "/a", "cdr", &Default::default()).unwrap();
        for k in 0..10u32 {
            let h = mcap::records::MessageHeader {
                channel_id: c,
                sequence: k,
                log_time: k as u64,
                publish_time: k as u64,
            };
            w.write_to_known_channel(&h, &k.to_le_bytes()).unwrap();
        }
        w.finish().unwrap();
        let mut bytes = w.into_inner().into_inner();
        assert_eq!(check_file(&bytes, false), Ok(bytes.len()));
        let body = &bytes[8..];
        let (pos, _, chunk) = records(body).find(|r| r.1 == op::CHUNK).expect("a chunk");
        let inner = open_chunk(chunk).unwrap().unwrap();
        let ops: Vec<u8> = chunk_records(&inner).map(|r| r.0).collect();
        assert_eq!(ops.iter().filter(|&&o| o == op::MESSAGE).count(), 10);
        // Flip the stated CRC.
        bytes[8 + pos + 9 + 24] ^= 1;
        let e = check_file(&bytes, false).unwrap_err();
        assert!(e.contains("CRC"), "{e}");
    }
}
