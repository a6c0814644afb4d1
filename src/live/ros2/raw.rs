//! Messages as the bytes on the wire: a DDS reader that hands over each
//! sample's CDR payload undecoded (odocal's own decoders in [`crate::io`]
//! read it, exactly as they read a bag), and a writer that sends payloads
//! already encoded (a bag's, as `odocal play` does). RustDDS's own adapters
//! decode into a serde type; these pass bytes through.

use ros2_client::dds::rustdds::{
    self,
    no_key::{Decode, DefaultDecoder, DeserializerAdapter, SerializerAdapter},
    RepresentationIdentifier,
};

/// A CDR payload with its 4-byte encapsulation header (what a bag stores).
#[derive(Debug, Clone, PartialEq)]
pub struct RawCdr(pub Vec<u8>);

/// Why a payload could not be passed on.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RawError(String);

/// Passes payloads through in both directions.
pub struct RawAdapter;

/// The decoder behind [`RawAdapter`]: copies the payload, puts back its
/// encapsulation header.
#[derive(Clone, Copy)]
pub struct RawDecoder;

impl<'de> Decode<'de, RawCdr> for RawDecoder {
    type Error = RawError;

    fn decode_bytes(
        self,
        input: &'de [u8],
        encoding: RepresentationIdentifier,
    ) -> Result<RawCdr, RawError> {
        let mut data = Vec::with_capacity(input.len() + 4);
        data.extend_from_slice(&encoding.to_bytes());
        data.extend_from_slice(&[0, 0]);
        data.extend_from_slice(input);
        Ok(RawCdr(data))
    }
}

impl DeserializerAdapter<RawCdr> for RawAdapter {
    type Error = RawError;
    type Decoded = RawCdr;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &[
            RepresentationIdentifier::CDR_LE,
            RepresentationIdentifier::CDR_BE,
        ]
    }

    fn transform_decoded(decoded: RawCdr) -> RawCdr {
        decoded
    }
}

impl DefaultDecoder<RawCdr> for RawAdapter {
    type Decoder = RawDecoder;
    const DECODER: RawDecoder = RawDecoder;
}

impl SerializerAdapter<RawCdr> for RawAdapter {
    type Error = RawError;

    /// Little-endian CDR, what ROS 2 writes and every bag odocal writes
    /// holds; [`RawCdr::payload`] refuses anything else before it is sent.
    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &RawCdr) -> Result<rustdds::bytes::Bytes, RawError> {
        value.payload().map(rustdds::bytes::Bytes::copy_from_slice)
    }
}

impl RawCdr {
    /// The payload after the encapsulation header, when the header says
    /// little-endian CDR.
    pub fn payload(&self) -> Result<&[u8], RawError> {
        match self.0.get(..4) {
            Some([0, 1, _, _]) => Ok(&self.0[4..]),
            Some(h) => Err(RawError(format!(
                "encapsulation {h:02x?}: only little-endian CDR (00 01) is sent"
            ))),
            None => Err(RawError("a payload shorter than its header".into())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_payload_goes_through_both_ways_with_its_header() {
        let wire = [1u8, 2, 3, 4, 5];
        let got = RawAdapter::from_bytes(&wire, RepresentationIdentifier::CDR_LE).unwrap();
        assert_eq!(got.0, [0, 1, 0, 0, 1, 2, 3, 4, 5]);
        let back = <RawAdapter as SerializerAdapter<RawCdr>>::to_bytes(&got).unwrap();
        assert_eq!(&back[..], &wire);
        let be = RawAdapter::from_bytes(&wire, RepresentationIdentifier::CDR_BE).unwrap();
        assert_eq!(&be.0[..4], &[0, 0, 0, 0]);
        assert!(<RawAdapter as SerializerAdapter<RawCdr>>::to_bytes(&be).is_err());
    }
}
