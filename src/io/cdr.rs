//! A small reader and writer for OMG CDR, the byte encoding of ROS 2 messages:
//! a 4-byte encapsulation header (`00 01` little endian, `00 00` big endian),
//! every primitive aligned to its size counted from after the header, strings
//! as a u32 length (including the NUL) then bytes, sequences as a u32 count.
//!
//! The reader also reads the ROS 1 serialisation ([`CdrReader::ros1`]), which
//! is the same walk through the fields without the encapsulation header,
//! without alignment and with strings as a u32 length then bytes (no NUL);
//! `std_msgs/Header` carries a `seq` before its stamp there
//! (wiki.ros.org/roscpp/Overview/MessagesSerializationAndAdaptingTypes).

/// A message that does not decode: where (byte offset from the start of the
/// message, header included) and what was expected there.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("CDR: expected {expected} at byte {offset}")]
pub struct CdrError {
    /// Byte offset from the start of the message.
    pub offset: usize,
    /// What the schema wanted there.
    pub expected: String,
}

/// Reads primitives from one CDR-encoded message, in schema order.
#[derive(Debug, Clone)]
pub struct CdrReader<'a> {
    /// Body after the 4-byte encapsulation header.
    body: &'a [u8],
    /// Position in `body`.
    pos: usize,
    little: bool,
    /// ROS 1 serialisation: no header, no alignment, strings without NUL.
    ros1: bool,
}

/// Bytes of the encapsulation header.
const HEADER: usize = 4;

impl<'a> CdrReader<'a> {
    /// Starts reading a message; checks the encapsulation header.
    pub fn new(data: &'a [u8]) -> Result<Self, CdrError> {
        if data.len() < HEADER {
            return Err(CdrError {
                offset: 0,
                expected: "4-byte encapsulation header".into(),
            });
        }
        let little = match (data[0], data[1]) {
            (0, 1) => true,
            (0, 0) => false,
            (a, b) => {
                return Err(CdrError {
                    offset: 0,
                    expected: format!("CDR encapsulation 00 00 or 00 01, found {a:02x} {b:02x}"),
                })
            }
        };
        Ok(Self {
            body: &data[HEADER..],
            pos: 0,
            little,
            ros1: false,
        })
    }

    /// Starts reading a ROS 1 message (little endian, packed, no header).
    pub fn ros1(data: &'a [u8]) -> Self {
        Self {
            body: data,
            pos: 0,
            little: true,
            ros1: true,
        }
    }

    /// Whether this reads the ROS 1 serialisation.
    pub fn is_ros1(&self) -> bool {
        self.ros1
    }

    fn err(&self, expected: impl Into<String>) -> CdrError {
        CdrError {
            offset: self.pos + if self.ros1 { 0 } else { HEADER },
            expected: expected.into(),
        }
    }

    /// Where the next `N`-byte primitive starts: `pos` rounded up to a
    /// multiple of `N` in CDR (every primitive is a power of two in size),
    /// `pos` itself in ROS 1.
    #[inline(always)]
    fn aligned<const N: usize>(&self) -> usize {
        if self.ros1 {
            self.pos
        } else {
            (self.pos + (N - 1)) & !(N - 1)
        }
    }

    #[inline(always)]
    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N], CdrError> {
        let aligned = self.aligned::<N>();
        match self.body.get(aligned..aligned + N) {
            Some(b) => {
                self.pos = aligned + N;
                let mut a = [0u8; N];
                a.copy_from_slice(b);
                if !self.little {
                    a.reverse();
                }
                Ok(a)
            }
            None => Err(self.short(aligned, what)),
        }
    }

    /// The error of a primitive at `aligned` that runs past the end.
    #[cold]
    #[inline(never)]
    fn short(&mut self, aligned: usize, what: &str) -> CdrError {
        self.pos = aligned.min(self.body.len());
        self.err(what)
    }

    /// The bytes of `n` consecutive `N`-byte primitives, aligned once for
    /// the first (the others then fall on multiples of `N` too), so a whole
    /// array costs one bounds check; `None`, with nothing read, when they do
    /// not all fit (the caller then reads them one by one for the error).
    /// An empty run reads nothing and does not align, as reading no element
    /// does not.
    #[inline(always)]
    fn run<const N: usize>(&mut self, n: usize) -> Option<&'a [u8]> {
        if n == 0 {
            return Some(&[]);
        }
        let aligned = self.aligned::<N>();
        let end = aligned.checked_add(n.checked_mul(N)?)?;
        let bytes = self.body.get(aligned..end)?;
        self.pos = end;
        Some(bytes)
    }

    /// A `float64` from 8 bytes in this message's byte order.
    #[inline(always)]
    fn f64_of(&self, b: &[u8]) -> f64 {
        let a: [u8; 8] = b.try_into().expect("8-byte chunk");
        if self.little {
            f64::from_le_bytes(a)
        } else {
            f64::from_be_bytes(a)
        }
    }

    /// A `float32` from 4 bytes in this message's byte order.
    #[inline(always)]
    fn f32_of(&self, b: &[u8]) -> f32 {
        let a: [u8; 4] = b.try_into().expect("4-byte chunk");
        if self.little {
            f32::from_le_bytes(a)
        } else {
            f32::from_be_bytes(a)
        }
    }

    /// Reads a `uint8`/`byte`/`bool`.
    #[inline]
    pub fn u8(&mut self) -> Result<u8, CdrError> {
        Ok(self.take::<1>("uint8")?[0])
    }

    /// Reads an `int32`.
    #[inline]
    pub fn i32(&mut self) -> Result<i32, CdrError> {
        Ok(i32::from_le_bytes(self.take("int32")?))
    }

    /// Reads a `uint32`.
    #[inline]
    pub fn u32(&mut self) -> Result<u32, CdrError> {
        Ok(u32::from_le_bytes(self.take("uint32")?))
    }

    /// Reads a sequence of integers of `bits` (16, 32 or 64) bits, signed or
    /// not, each widened exactly to `i128`.
    pub fn int_seq(&mut self, bits: u32, signed: bool) -> Result<Vec<i128>, CdrError> {
        let n = self.seq_len(bits as usize / 8)?;
        (0..n)
            .map(|_| {
                Ok(match (bits, signed) {
                    (16, true) => i16::from_le_bytes(self.take("int16")?) as i128,
                    (16, false) => u16::from_le_bytes(self.take("uint16")?) as i128,
                    (32, true) => i32::from_le_bytes(self.take("int32")?) as i128,
                    (32, false) => u32::from_le_bytes(self.take("uint32")?) as i128,
                    (_, true) => i64::from_le_bytes(self.take("int64")?) as i128,
                    (_, false) => u64::from_le_bytes(self.take("uint64")?) as i128,
                })
            })
            .collect()
    }

    /// Reads a `float32`.
    #[inline]
    pub fn f32(&mut self) -> Result<f32, CdrError> {
        Ok(f32::from_le_bytes(self.take("float32")?))
    }

    /// Reads a `float64`.
    #[inline]
    pub fn f64(&mut self) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.take("float64")?))
    }

    /// Reads a sequence length and checks that `elem_size`-byte elements of
    /// that count can still fit (so a corrupt count cannot allocate gigabytes).
    #[inline]
    pub fn seq_len(&mut self, elem_size: usize) -> Result<usize, CdrError> {
        let n = self.u32()? as usize;
        let left = self.body.len().saturating_sub(self.pos);
        if n.saturating_mul(elem_size.max(1)) > left {
            return Err(self.err(format!(
                "sequence of {n} elements of {elem_size} bytes (only {left} bytes left)"
            )));
        }
        Ok(n)
    }

    /// Reads a `string` (u32 length including the NUL, bytes, NUL).
    #[inline]
    pub fn string(&mut self) -> Result<&'a str, CdrError> {
        let n = self.seq_len(1)?;
        let bytes = &self.body[self.pos..self.pos + n];
        let text = match bytes.split_last() {
            _ if self.ros1 => bytes,
            None => &[][..],
            Some((0, rest)) => rest,
            Some(_) => return Err(self.err("NUL-terminated string")),
        };
        let s = std::str::from_utf8(text).map_err(|_| self.err("UTF-8 string"))?;
        self.pos += n;
        Ok(s)
    }

    /// Reads a `float32[]` sequence into `out` (cleared first).
    pub fn f32_seq_into(&mut self, out: &mut Vec<f32>) -> Result<(), CdrError> {
        let n = self.seq_len(4)?;
        out.clear();
        out.reserve_exact(n);
        match self.run::<4>(n) {
            Some(b) => out.extend(b.chunks_exact(4).map(|c| self.f32_of(c))),
            None => {
                for _ in 0..n {
                    out.push(self.f32()?);
                }
            }
        }
        Ok(())
    }

    /// Reads a `float64[]` sequence.
    pub fn f64_seq(&mut self) -> Result<Vec<f64>, CdrError> {
        let n = self.seq_len(8)?;
        match self.run::<8>(n) {
            Some(b) => Ok(b.chunks_exact(8).map(|c| self.f64_of(c)).collect()),
            None => (0..n).map(|_| self.f64()).collect(),
        }
    }

    /// Reads a fixed `float64[N]` array (no count on the wire).
    pub fn f64_array<const N: usize>(&mut self) -> Result<[f64; N], CdrError> {
        let mut a = [0.0; N];
        match self.run::<8>(N) {
            Some(b) => {
                for (v, c) in a.iter_mut().zip(b.chunks_exact(8)) {
                    *v = self.f64_of(c);
                }
            }
            None => {
                for v in &mut a {
                    *v = self.f64()?;
                }
            }
        }
        Ok(a)
    }

    /// Checks that the message has been consumed, allowing up to 3 bytes of
    /// end padding (none in ROS 1, which does not pad).
    pub fn finish(&self) -> Result<(), CdrError> {
        let left = self.body.len() - self.pos;
        if left > if self.ros1 { 0 } else { 3 } {
            return Err(self.err(format!("end of message ({left} bytes left over)")));
        }
        Ok(())
    }
}

/// Writes a little-endian CDR message (header `00 01 00 00`).
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// An empty message with its encapsulation header.
    pub fn new() -> Self {
        Self {
            buf: vec![0, 1, 0, 0],
        }
    }

    /// Empties the message for reuse (keeps the allocation).
    pub fn clear(&mut self) {
        self.buf.truncate(HEADER);
    }

    fn align(&mut self, n: usize) {
        let body = self.buf.len() - HEADER;
        let pad = body.next_multiple_of(n) - body;
        self.buf.extend(std::iter::repeat_n(0u8, pad));
    }

    /// Writes a `uint8`.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// Writes an `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Writes a `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Writes an `int64`.
    pub fn i64(&mut self, v: i64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Writes a `float32`.
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Writes a `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Writes a `string`.
    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// Writes a sequence count.
    pub fn seq_len(&mut self, n: usize) {
        self.u32(n as u32);
    }

    /// Writes a `float32[]` sequence.
    pub fn f32_seq(&mut self, v: &[f32]) {
        self.seq_len(v.len());
        for &x in v {
            self.f32(x);
        }
    }

    /// Writes a `float64[]` sequence.
    pub fn f64_seq(&mut self, v: &[f64]) {
        self.seq_len(v.len());
        for &x in v {
            self.f64(x);
        }
    }

    /// Writes a fixed `float64[N]` array (no count).
    pub fn f64_array(&mut self, v: &[f64]) {
        for &x in v {
            self.f64(x);
        }
    }

    /// The encoded message, header included.
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_with_alignment() {
        let mut w = CdrWriter::new();
        w.u8(7);
        w.f64(1.5);
        w.string("laser");
        w.f32_seq(&[1.0, f32::NAN, f32::INFINITY]);
        w.i32(-3);
        let b = w.bytes().to_vec();
        // u8 at 0, f64 aligned to 8 (7 pad bytes) from after the header.
        assert_eq!(b.len(), 4 + 8 + 8 + 4 + 6 + 2 + 4 + 12 + 4);
        let mut r = CdrReader::new(&b).unwrap();
        assert_eq!(r.u8().unwrap(), 7);
        assert_eq!(r.f64().unwrap(), 1.5);
        assert_eq!(r.string().unwrap(), "laser");
        let mut v = Vec::new();
        r.f32_seq_into(&mut v).unwrap();
        assert_eq!(v[0], 1.0);
        assert!(v[1].is_nan());
        assert_eq!(v[2], f32::INFINITY);
        assert_eq!(r.i32().unwrap(), -3);
        r.finish().unwrap();
    }

    #[test]
    fn integer_sequences_widen_exactly() {
        let mut w = CdrWriter::new();
        w.u8(1);
        w.seq_len(2);
        w.i64(i64::MIN);
        w.i64(-1);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        r.u8().unwrap();
        assert_eq!(r.int_seq(64, true).unwrap(), [i64::MIN as i128, -1]);
        r.finish().unwrap();
        let mut r = CdrReader::new(w.bytes()).unwrap();
        r.u8().unwrap();
        assert_eq!(r.int_seq(64, false).unwrap()[1], u64::MAX as i128);
        let mut w = CdrWriter::new();
        w.seq_len(3);
        for v in [-2, 0, 65535] {
            w.i32(v);
        }
        let mut r = CdrReader::new(w.bytes()).unwrap();
        assert_eq!(r.int_seq(32, true).unwrap(), [-2, 0, 65535]);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        assert_eq!(r.int_seq(16, false).unwrap().len(), 3);
    }

    #[test]
    fn big_endian_is_read() {
        let mut b = vec![0, 0, 0, 0];
        b.extend_from_slice(&7u32.to_be_bytes());
        b.extend_from_slice(&[0; 4]);
        b.extend_from_slice(&2.25f64.to_be_bytes());
        let mut r = CdrReader::new(&b).unwrap();
        assert_eq!(r.u32().unwrap(), 7);
        assert_eq!(r.f64().unwrap(), 2.25);
    }

    #[test]
    fn short_message_names_offset_and_type() {
        let mut w = CdrWriter::new();
        w.u32(1);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        r.u32().unwrap();
        let e = r.f64().unwrap_err();
        assert_eq!(e.offset, 8);
        assert!(e.expected.contains("float64"));
        assert!(CdrReader::new(&[0, 1]).is_err());
        assert!(CdrReader::new(&[9, 9, 0, 0]).is_err());
    }

    /// Bytes of a little-endian CDR message: header, then `body`.
    fn le(body: &[&[u8]]) -> Vec<u8> {
        let mut b = vec![0, 1, 0, 0];
        for part in body {
            b.extend_from_slice(part);
        }
        b
    }

    #[test]
    fn arrays_are_read_whole_in_every_byte_order() {
        // float64[] of 2: count, 4 pad bytes to the 8-byte boundary, values.
        let b = le(&[
            &2u32.to_le_bytes(),
            &[0; 4],
            &1.25f64.to_le_bytes(),
            &(-3.5f64).to_le_bytes(),
        ]);
        let mut r = CdrReader::new(&b).unwrap();
        assert_eq!(r.f64_seq().unwrap(), [1.25, -3.5]);
        r.finish().unwrap();
        let mut b = vec![0, 0, 0, 0];
        b.extend_from_slice(&2u32.to_be_bytes());
        b.extend_from_slice(&0.5f32.to_be_bytes());
        b.extend_from_slice(&7.0f32.to_be_bytes());
        b.extend_from_slice(&[0; 4]);
        b.extend_from_slice(&9.75f64.to_be_bytes());
        let mut r = CdrReader::new(&b).unwrap();
        let mut v = vec![1.0; 5];
        r.f32_seq_into(&mut v).unwrap();
        assert_eq!(v, [0.5, 7.0]);
        assert_eq!(r.f64_array::<1>().unwrap(), [9.75]);
        r.finish().unwrap();
        // ROS 1: no header, no padding.
        let mut b = 1u32.to_le_bytes().to_vec();
        b.extend_from_slice(&6.0f64.to_le_bytes());
        b.extend_from_slice(&(-1.0f64).to_le_bytes());
        let mut r = CdrReader::ros1(&b);
        assert_eq!(r.f64_seq().unwrap(), [6.0]);
        assert_eq!(r.f64_array::<1>().unwrap(), [-1.0]);
        r.finish().unwrap();
    }

    #[test]
    fn a_cut_array_fails_at_the_first_missing_element() {
        // u32, 4 pad bytes, then 2 whole float64 and half of a third.
        let b = le(&[&[0; 8], &[0; 16], &[0; 4]]);
        let mut r = CdrReader::new(&b).unwrap();
        r.u32().unwrap();
        let e = r.f64_array::<3>().unwrap_err();
        // The third float64 would start at body byte 24, header included 28.
        assert_eq!(e.offset, 28);
        assert!(e.expected.contains("float64"), "{e}");
    }

    #[test]
    fn an_empty_array_reads_nothing_and_does_not_align() {
        // float64[] of 0, then a uint8 right after the count (no padding).
        let b = le(&[&0u32.to_le_bytes(), &[9]]);
        let mut r = CdrReader::new(&b).unwrap();
        assert!(r.f64_seq().unwrap().is_empty());
        assert_eq!(r.u8().unwrap(), 9);
        r.finish().unwrap();
    }

    #[test]
    fn huge_sequence_count_is_an_error_not_an_allocation() {
        let mut w = CdrWriter::new();
        w.u32(u32::MAX);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        let mut v = Vec::new();
        assert!(r.f32_seq_into(&mut v).is_err());
    }
}
