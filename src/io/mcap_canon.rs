//! Makes an MCAP file's summary section canonical: the `mcap` writer emits
//! the repeated schema and channel records in hash-map order, which differs
//! from run to run. Sorting each run of them by id (group offsets and lengths
//! unchanged) and recomputing the summary CRC makes equal content give equal
//! bytes.

const OP_SCHEMA: u8 = 0x03;
const OP_CHANNEL: u8 = 0x04;
/// Footer record: opcode, length, summary_start, summary_offset_start, crc.
const FOOTER: usize = 1 + 8 + 8 + 8 + 4;
const MAGIC_LEN: usize = 8;

fn u64_at(b: &[u8], i: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(i..i + 8)?.try_into().ok()?))
}

/// CRC-32 (IEEE, reflected), as MCAP uses.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Sorts the schema and channel runs of the summary section by id, in place.
/// Returns `false` (leaving `mcap` untouched) if the layout is not the
/// expected one.
pub fn canonicalize_summary(mcap: &mut [u8]) -> bool {
    canonicalize_summary_tail(mcap, 0)
}

/// [`canonicalize_summary`] on the end of a file only: `tail` holds the
/// file's bytes from offset `base` to its end, and `base` is at or before the
/// summary section (so a long file need not be read whole).
pub fn canonicalize_summary_tail(tail: &mut [u8], base: usize) -> bool {
    let mcap = tail;
    let n = base + mcap.len();
    if n < 2 * MAGIC_LEN + FOOTER || mcap.len() < MAGIC_LEN + FOOTER {
        return false;
    }
    // Absolute file offsets; `at(i)` is where offset i sits in `mcap`.
    let at = |i: usize| i - base;
    let footer = n - MAGIC_LEN - FOOTER;
    let (Some(start), Some(offsets)) =
        (u64_at(mcap, at(footer) + 9), u64_at(mcap, at(footer) + 17))
    else {
        return false;
    };
    let end = if offsets == 0 {
        footer
    } else {
        offsets as usize
    };
    let start = start as usize;
    if start == 0 || start < base || start > end || end > footer {
        return false;
    }
    // Records of the summary section before the summary offsets.
    let mut recs: Vec<(u8, usize, usize)> = Vec::new();
    let mut i = start;
    while i < end {
        let Some(len) = u64_at(mcap, at(i) + 1) else {
            return false;
        };
        let Some(stop) = (i + 9).checked_add(len as usize) else {
            return false;
        };
        if stop > end {
            return false;
        }
        recs.push((mcap[at(i)], at(i), at(stop)));
        i = stop;
    }
    let id = |b: &[u8], r: &(u8, usize, usize)| u16::from_le_bytes([b[r.1 + 9], b[r.1 + 10]]);
    let mut k = 0;
    while k < recs.len() {
        let op = recs[k].0;
        let run_end = recs[k..]
            .iter()
            .position(|r| r.0 != op)
            .map_or(recs.len(), |p| k + p);
        if (op == OP_SCHEMA || op == OP_CHANNEL) && run_end - k > 1 {
            let run = &recs[k..run_end];
            if run.iter().any(|r| r.2 - r.1 < 11) {
                return false;
            }
            let mut sorted: Vec<_> = run.to_vec();
            sorted.sort_by_key(|r| id(mcap, r));
            let bytes: Vec<u8> = sorted
                .iter()
                .flat_map(|r| mcap[r.1..r.2].to_vec())
                .collect();
            mcap[run[0].1..run[run.len() - 1].2].copy_from_slice(&bytes);
        }
        k = run_end;
    }
    let crc_at = at(footer) + 25;
    if mcap[crc_at..crc_at + 4] != [0, 0, 0, 0] {
        let crc = crc32(&mcap[at(start)..crc_at]);
        mcap[crc_at..crc_at + 4].copy_from_slice(&crc.to_le_bytes());
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_known_string() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    fn small_mcap() -> Vec<u8> {
        let mut w = mcap::WriteOptions::new()
            .compression_threads(0)
            .create(std::io::Cursor::new(Vec::new()))
            .unwrap();
        for t in ["/a", "/b", "/c", "/d", "/e"] {
            let s = w
                .add_schema(&format!("x{t}"), "ros2msg", b"int32 x\n")
                .unwrap();
            w.add_channel(s, t, "cdr", &Default::default()).unwrap();
        }
        w.finish().unwrap();
        w.into_inner().into_inner()
    }

    #[test]
    fn summary_becomes_sorted_with_a_valid_crc() {
        let mut b = small_mcap();
        let n = b.len();
        let footer = n - MAGIC_LEN - FOOTER;
        let start = u64_at(&b, footer + 9).unwrap() as usize;
        let stored = |b: &[u8]| u32::from_le_bytes(b[footer + 25..footer + 29].try_into().unwrap());
        // Our CRC covers what the mcap writer's CRC covers.
        assert_eq!(stored(&b), crc32(&b[start..footer + 25]));
        assert!(canonicalize_summary(&mut b));
        assert_eq!(stored(&b), crc32(&b[start..footer + 25]));
        // Every run of channels is now in id order, and equal across runs.
        for _ in 0..3 {
            let mut c = small_mcap();
            canonicalize_summary(&mut c);
            assert!(c == b);
        }
        let summary = mcap::Summary::read(&b).unwrap().unwrap();
        assert_eq!(summary.channels.len(), 5);
    }
}
