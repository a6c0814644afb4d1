//! A pre-pass over an MCAP's top-level records that refuses chunks the `mcap`
//! crate would turn into a huge allocation (and so abort the process): a
//! header claiming an absurd uncompressed size, or a record inside a chunk
//! whose length field runs past the chunk's end.

/// Largest uncompressed chunk accepted at any compression ratio (bytes).
const MAX_CHUNK: u64 = 1 << 30;
/// Uncompressed size always accepted, whatever the compressed size (bytes).
const FREE_CHUNK: u64 = 64 << 20;
/// Largest accepted ratio of uncompressed to compressed chunk size above
/// [`FREE_CHUNK`] (lz4 tops out near 255, zstd on real sensor data near 10).
const MAX_RATIO: u64 = 256;

/// Checks every chunk header that can be read; `lenient` accepts a file cut
/// short (no end magic). Read errors are left to the main reader, which
/// reports them with context; only an implausible chunk size is an error here.
pub(crate) fn check_chunk_sizes(bytes: &[u8], lenient: bool) -> Result<(), String> {
    use mcap::read::{LinearReader, Options};
    let records = if lenient {
        LinearReader::new_with_options(bytes, Options::IgnoreEndMagic.into())
    } else {
        LinearReader::new(bytes)
    };
    let Ok(records) = records else {
        return Ok(());
    };
    for (i, rec) in records.enumerate() {
        let Ok(rec) = rec else { return Ok(()) };
        if let mcap::records::Record::Chunk { header, data } = rec {
            let n = header.uncompressed_size;
            let limit = MAX_CHUNK.min(FREE_CHUNK.max(MAX_RATIO.saturating_mul(data.len() as u64)));
            if n > limit {
                return Err(format!(
                    "corrupt MCAP: chunk (record {i}) claims {n} uncompressed bytes from {} \
                     compressed ones (at most {limit} accepted)",
                    data.len()
                ));
            }
            check_chunk_records(&header.compression, &data, n as usize)
                .map_err(|m| format!("corrupt MCAP: chunk (record {i}): {m}"))?;
        }
    }
    Ok(())
}

/// Decompresses one chunk (at most `n` bytes) and checks that every record
/// length inside stays within it. Unknown compressions are left to `mcap`.
fn check_chunk_records(compression: &str, data: &[u8], n: usize) -> Result<(), String> {
    use std::io::Read;
    let owned;
    let body: &[u8] = match compression {
        "" => data,
        "zstd" => {
            owned = zstd::bulk::decompress(data, n).map_err(|e| format!("zstd: {e}"))?;
            &owned
        }
        "lz4" => {
            let mut out = Vec::new();
            lz4::Decoder::new(data)
                .and_then(|d| d.take(n as u64 + 1).read_to_end(&mut out))
                .map_err(|e| format!("lz4: {e}"))?;
            if out.len() > n {
                return Err(format!("decompresses to more than the {n} bytes stated"));
            }
            owned = out;
            &owned
        }
        _ => return Ok(()),
    };
    let mut pos = 0usize;
    while body.len() - pos >= 9 {
        let len = u64::from_le_bytes(body[pos + 1..pos + 9].try_into().unwrap_or([0; 8]));
        let left = (body.len() - pos - 9) as u64;
        if len > left {
            return Err(format!(
                "record at byte {pos} claims {len} bytes, only {left} left in the chunk"
            ));
        }
        pos += 9 + len as usize;
    }
    Ok(())
}
