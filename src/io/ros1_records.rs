//! The records of a ROS 1 bag, format 2.0 (wiki.ros.org/Bags/Format/2.0):
//! after the magic line `#ROSBAG V2.0\n`, every record is a u32 header
//! length, header fields (each a u32 length then `name=value`, the value
//! binary), a u32 data length and the data. The `op` field says what the
//! record is. Chunks hold message data and connection records, compressed
//! with `none`, `bz2` or `lz4` (the LZ4 frame format, which roslz4 writes).
//! Every length is checked against what holds it before anything is
//! allocated, so a corrupt field is an error, never a huge allocation.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};

/// The first line of every ROS 1 bag of format 2.0.
pub const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// Record kinds (`op` field).
pub(crate) mod op {
    pub const MSG_DATA: u8 = 0x02;
    pub const BAG_HEADER: u8 = 0x03;
    pub const CHUNK: u8 = 0x05;
    pub const CHUNK_INFO: u8 = 0x06;
    pub const CONNECTION: u8 = 0x07;
}

/// Largest decompressed chunk accepted (bytes); `rosbag record` writes
/// chunks of 768 KiB by default.
const MAX_CHUNK: u64 = 1 << 30;

/// A record's header fields, in file order.
pub(crate) struct Fields<'a>(Vec<(&'a [u8], &'a [u8])>);

impl<'a> Fields<'a> {
    /// Splits a record header into its `name=value` fields.
    pub(crate) fn parse(header: &'a [u8]) -> Result<Self, String> {
        let mut fields = Vec::new();
        let mut pos = 0;
        while pos < header.len() {
            let len = u32_le(header, pos)
                .ok_or_else(|| format!("header field length cut at header byte {pos}"))?;
            let start = pos + 4;
            let field = header
                .get(start..start.saturating_add(len as usize))
                .ok_or_else(|| {
                    format!("header field at header byte {pos} claims {len} bytes past its end")
                })?;
            let eq = field
                .iter()
                .position(|&b| b == b'=')
                .ok_or_else(|| format!("header field at header byte {pos} has no '='"))?;
            fields.push((&field[..eq], &field[eq + 1..]));
            pos = start + len as usize;
        }
        Ok(Self(fields))
    }

    /// The value of field `name`.
    pub(crate) fn get(&self, name: &str) -> Result<&'a [u8], String> {
        self.0
            .iter()
            .find(|(n, _)| *n == name.as_bytes())
            .map(|(_, v)| *v)
            .ok_or_else(|| format!("record has no '{name}' field"))
    }

    /// The value of field `name` as text.
    pub(crate) fn text(&self, name: &str) -> Result<&'a str, String> {
        std::str::from_utf8(self.get(name)?).map_err(|_| format!("field '{name}' is not UTF-8"))
    }

    /// The record kind.
    pub(crate) fn op(&self) -> Result<u8, String> {
        match self.get("op")? {
            [op] => Ok(*op),
            v => Err(format!(
                "'op' field of {} bytes where 1 was expected",
                v.len()
            )),
        }
    }

    /// A little-endian u32 field.
    pub(crate) fn u32(&self, name: &str) -> Result<u32, String> {
        let v = self.get(name)?;
        u32_le(v, 0)
            .filter(|_| v.len() == 4)
            .ok_or_else(|| format!("field '{name}' of {} bytes where 4 were expected", v.len()))
    }

    /// A little-endian u64 field.
    pub(crate) fn u64(&self, name: &str) -> Result<u64, String> {
        let v = self.get(name)?;
        match <[u8; 8]>::try_from(v) {
            Ok(b) => Ok(u64::from_le_bytes(b)),
            Err(_) => Err(format!(
                "field '{name}' of {} bytes where 8 were expected",
                v.len()
            )),
        }
    }

    /// A ROS time field (u32 sec, u32 nsec) in nanoseconds.
    pub(crate) fn time(&self, name: &str) -> Result<u64, String> {
        let v = self.get(name)?;
        if v.len() != 8 {
            return Err(format!(
                "field '{name}' of {} bytes where 8 were expected",
                v.len()
            ));
        }
        let (sec, nsec) = (u32_le(v, 0).unwrap_or(0), u32_le(v, 4).unwrap_or(0));
        Ok(sec as u64 * 1_000_000_000 + nsec as u64)
    }
}

/// A little-endian u32 at `pos`, if the bytes are there.
pub(crate) fn u32_le(b: &[u8], pos: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(pos..pos + 4)?.try_into().ok()?))
}

/// One record read from the file: its header and data bytes and where the
/// next record starts.
pub(crate) struct FileRecord {
    pub header: Vec<u8>,
    pub data: Vec<u8>,
    pub next: u64,
}

/// Reads the record at byte `pos` of a file of `len` bytes.
pub(crate) fn read_record(file: &mut File, len: u64, pos: u64) -> Result<FileRecord, String> {
    let mut at = pos;
    let header = read_prefixed(file, len, &mut at, "record header")?;
    let data = read_prefixed(file, len, &mut at, "record data")?;
    Ok(FileRecord {
        header,
        data,
        next: at,
    })
}

/// Reads a u32 length and that many bytes at `*at`, advancing it.
fn read_prefixed(file: &mut File, len: u64, at: &mut u64, what: &str) -> Result<Vec<u8>, String> {
    let mut n = [0u8; 4];
    if *at + 4 > len {
        return Err(format!("file ends inside the length of a {what}"));
    }
    file.seek(SeekFrom::Start(*at))
        .and_then(|_| file.read_exact(&mut n))
        .map_err(|e| format!("cannot read: {e}"))?;
    let n = u32::from_le_bytes(n) as u64;
    if *at + 4 + n > len {
        return Err(format!(
            "{what} claims {n} bytes, only {} left in the file (truncated?)",
            len - *at - 4
        ));
    }
    let mut buf = vec![0u8; n as usize];
    file.read_exact(&mut buf)
        .map_err(|e| format!("cannot read: {e}"))?;
    *at += 4 + n;
    Ok(buf)
}

/// A record inside a decompressed chunk: its offset in the chunk, header
/// and data.
pub(crate) type ChunkRecord<'a> = (usize, &'a [u8], &'a [u8]);

/// The records inside a decompressed chunk, or an error at the first that
/// does not fit.
pub(crate) fn chunk_records(chunk: &[u8]) -> Result<Vec<ChunkRecord<'_>>, String> {
    let mut out = Vec::new();
    let mut pos = 0;
    while pos < chunk.len() {
        let cut = |what: &str| format!("record at chunk byte {pos}: {what} runs past the chunk");
        let hlen = u32_le(chunk, pos).ok_or_else(|| cut("header length"))? as usize;
        let header = chunk
            .get(pos + 4..(pos + 4).saturating_add(hlen))
            .ok_or_else(|| cut("header"))?;
        let d = pos + 4 + hlen;
        let dlen = u32_le(chunk, d).ok_or_else(|| cut("data length"))? as usize;
        let data = chunk
            .get(d + 4..(d + 4).saturating_add(dlen))
            .ok_or_else(|| cut("data"))?;
        out.push((pos, header, data));
        pos = d + 4 + dlen;
    }
    Ok(out)
}

/// Decompresses a chunk's data (`compression` none, bz2 or lz4) and checks
/// that it has the stated `size` (bytes).
pub(crate) fn decompress(compression: &str, data: Vec<u8>, size: u32) -> Result<Vec<u8>, String> {
    let size = size as u64;
    if size > MAX_CHUNK {
        return Err(format!("chunk claims {size} uncompressed bytes"));
    }
    let out = match compression {
        "none" => data,
        "bz2" => inflate(bzip2::read::BzDecoder::new(&data[..]), size, "bz2")?,
        "lz4" => {
            let dec = lz4::Decoder::new(&data[..]).map_err(|e| format!("lz4: {e}"))?;
            inflate(dec, size, "lz4")?
        }
        other => {
            return Err(format!(
                "chunk compression '{other}' is not supported (none, bz2, lz4 are)"
            ))
        }
    };
    if out.len() as u64 != size {
        return Err(format!(
            "chunk holds {} bytes after decompression, its header says {size}",
            out.len()
        ));
    }
    Ok(out)
}

/// Reads a decompressor to its end, at most one byte beyond `size`.
fn inflate(r: impl Read, size: u64, what: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(size.min(64 << 20) as usize);
    r.take(size + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("{what} chunk does not decompress: {e}"))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(name: &str, value: &[u8]) -> Vec<u8> {
        let mut f = ((name.len() + 1 + value.len()) as u32)
            .to_le_bytes()
            .to_vec();
        f.extend_from_slice(name.as_bytes());
        f.push(b'=');
        f.extend_from_slice(value);
        f
    }

    #[test]
    fn fields_are_split_at_the_first_equals_sign() {
        let mut h = field("op", &[7]);
        h.extend(field("topic", b"/a=b"));
        h.extend(field("conn", &3u32.to_le_bytes()));
        let f = Fields::parse(&h).unwrap();
        assert_eq!(f.op().unwrap(), 7);
        assert_eq!(f.text("topic").unwrap(), "/a=b");
        assert_eq!(f.u32("conn").unwrap(), 3);
        assert!(f.u64("conn").is_err());
        assert!(f.get("time").is_err());
        // A field length past the end is an error, not a panic.
        h.extend(1000u32.to_le_bytes());
        assert!(Fields::parse(&h).is_err());
    }

    #[test]
    fn unknown_compression_and_wrong_size_are_errors() {
        assert!(decompress("zstd", vec![1, 2], 2)
            .unwrap_err()
            .contains("'zstd'"));
        assert!(decompress("none", vec![1, 2], 3).is_err());
        assert!(decompress("bz2", vec![1, 2, 3], 3).is_err());
        assert!(decompress("lz4", vec![1, 2, 3], 3).is_err());
        assert_eq!(decompress("none", vec![1, 2], 2).unwrap(), vec![1, 2]);
    }
}
