//! `std_msgs` integer arrays (`Int16MultiArray` … `UInt64MultiArray`), as
//! robots publish raw encoder tick counters.

use crate::io::cdr::{CdrError, CdrReader};
use crate::robot::TicksType;

/// The `data` of a `std_msgs/*MultiArray` of type `ty`, each element widened
/// exactly; the layout (`dim`, `data_offset`) is read and not kept.
pub fn read_int_array(r: &mut CdrReader<'_>, ty: TicksType) -> Result<Vec<i128>, CdrError> {
    // MultiArrayDimension: string label, uint32 size, uint32 stride.
    let dims = r.seq_len(12)?;
    for _ in 0..dims {
        r.string()?;
        r.u32()?;
        r.u32()?;
    }
    let _data_offset = r.u32()?;
    let data = r.int_seq(ty.bits(), ty.signed())?;
    r.finish()?;
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::cdr::CdrWriter;

    #[test]
    fn reads_data_after_a_layout_with_dimensions() {
        let mut w = CdrWriter::new();
        w.seq_len(1);
        w.string("wheels");
        w.u32(2);
        w.u32(2);
        w.u32(0);
        w.seq_len(2);
        w.i64(-5);
        w.i64(1 << 40);
        let bytes = w.bytes().to_vec();
        let mut r = CdrReader::new(&bytes).unwrap();
        let data = read_int_array(&mut r, TicksType::Int64MultiArray).unwrap();
        assert_eq!(data, [-5, 1 << 40]);
        let mut r = CdrReader::new(&bytes[..bytes.len() - 8]).unwrap();
        assert!(read_int_array(&mut r, TicksType::Int64MultiArray).is_err());
    }
}
