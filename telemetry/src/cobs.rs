//! Consistent Overhead Byte Stuffing (Cheshire & Baker, IEEE/ACM ToN 1999): removes every
//! 0x00 from a record so 0x00 can delimit frames. Each block starts with a code byte
//! `n` = 1 + the number of non-zero bytes that follow; a block with `n` < 0xFF stands for
//! those bytes plus one zero (except the last block, whose zero is implied by the frame end).
//!
//! The one COBS of the workspace: the telemetry stream's framing ([`crate::framing`]) and the
//! module's HM-10 phone relay both use it, so a relayed record is the link frame byte for
//! byte. The encoding is the canonical one (no empty block after a record that ends on a
//! full 254-byte run; the empty record is `[0x01]`). Not the `cobs` crate that postcard
//! brings in: it encodes the empty record as nothing, decodes a frame with a 0x00 inside up
//! to that zero as a good one, and its errors are not `Copy`.

/// Why a COBS frame could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer is too short; `needed` bytes would do.
    BufferTooSmall {
        /// Bytes the output needs.
        needed: usize,
    },
    /// A 0x00 inside the frame (not allowed in COBS data).
    ZeroInFrame,
    /// A code byte points past the end of the frame.
    Truncated,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => write!(f, "COBS buffer too small, {needed} needed"),
            Self::ZeroInFrame => f.write_str("zero byte inside a COBS frame"),
            Self::Truncated => f.write_str("COBS frame truncated"),
        }
    }
}

impl core::error::Error for Error {}

/// Largest encoding of `len` bytes: one code byte per started 254-byte run, plus one.
pub const fn max_encoded_len(len: usize) -> usize {
    len + len / 254 + 1
}

/// Encodes `record` into `out` (no trailing delimiter); returns the encoded length.
pub fn encode(record: &[u8], out: &mut [u8]) -> Result<usize, Error> {
    encode_parts(&[record], out)
}

/// Encodes the concatenation of `parts` as one record, e.g. a payload and its CRC without
/// copying them together first; returns the encoded length (no trailing delimiter).
pub fn encode_parts(parts: &[&[u8]], out: &mut [u8]) -> Result<usize, Error> {
    let record_len = parts.iter().map(|part| part.len()).sum();
    let needed = max_encoded_len(record_len);
    if out.len() < needed {
        return Err(Error::BufferTooSmall { needed });
    }
    let mut code_at = 0usize;
    let mut write_at = 1usize;
    let mut code = 1u8;
    let put = |index: usize, value: u8, out: &mut [u8]| {
        if let Some(slot) = out.get_mut(index) {
            *slot = value;
        }
    };
    for &byte in parts.iter().flat_map(|part| part.iter()) {
        // A full block (254 data bytes) is closed only when more input follows, so a record
        // ending on a full block gets no empty trailing block (the canonical encoding).
        if code == 0xFF {
            put(code_at, code, out);
            code_at = write_at;
            write_at += 1;
            code = 1;
        }
        if byte == 0 {
            put(code_at, code, out);
            code_at = write_at;
            write_at += 1;
            code = 1;
        } else {
            put(write_at, byte, out);
            write_at += 1;
            code += 1;
        }
    }
    put(code_at, code, out);
    Ok(write_at)
}

/// Decodes a frame (without its delimiter) in place; returns the record length. The record
/// is never longer than the frame, so decoding can overwrite the frame as it goes.
pub fn decode_in_place(frame: &mut [u8]) -> Result<usize, Error> {
    let mut read_at = 0usize;
    let mut write_at = 0usize;
    let len = frame.len();
    while read_at < len {
        let code = usize::from(*frame.get(read_at).ok_or(Error::Truncated)?);
        if code == 0 {
            return Err(Error::ZeroInFrame);
        }
        let block_end = read_at + code;
        if block_end > len {
            return Err(Error::Truncated);
        }
        for index in read_at + 1..block_end {
            let byte = *frame.get(index).ok_or(Error::Truncated)?;
            if byte == 0 {
                return Err(Error::ZeroInFrame);
            }
            *frame.get_mut(write_at).ok_or(Error::Truncated)? = byte;
            write_at += 1;
        }
        read_at = block_end;
        if code < 0xFF && read_at < len {
            *frame.get_mut(write_at).ok_or(Error::Truncated)? = 0;
            write_at += 1;
        }
    }
    Ok(write_at)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(record: &[u8]) -> Vec<u8> {
        let mut encoded = vec![0u8; max_encoded_len(record.len())];
        let n = encode(record, &mut encoded).unwrap();
        encoded.truncate(n);
        assert!(!encoded.contains(&0));
        let mut frame = encoded.clone();
        let m = decode_in_place(&mut frame).unwrap();
        assert_eq!(&frame[..m], record);
        encoded
    }

    #[test]
    fn worked_examples() {
        // The examples of the COBS paper / Wikipedia table.
        assert_eq!(round_trip(&[0x00]), [0x01, 0x01]);
        assert_eq!(round_trip(&[0x00, 0x00]), [0x01, 0x01, 0x01]);
        assert_eq!(
            round_trip(&[0x11, 0x22, 0x00, 0x33]),
            [0x03, 0x11, 0x22, 0x02, 0x33]
        );
        assert_eq!(
            round_trip(&[0x11, 0x00, 0x00, 0x00]),
            [0x02, 0x11, 0x01, 0x01, 0x01]
        );
        assert_eq!(round_trip(&[]), [0x01]);
    }

    #[test]
    fn long_runs_split_at_254() {
        let record: Vec<u8> = (1..=254u32).map(|b| b as u8).collect();
        let encoded = round_trip(&record);
        assert_eq!(encoded[0], 0xFF);
        assert_eq!(encoded.len(), 255);
        let mut with_zero = record.clone();
        with_zero.push(0);
        assert_eq!(&round_trip(&with_zero)[255..], &[0x01, 0x01]);
        let record: Vec<u8> = (0..600u32).map(|b| (b % 255 + 1) as u8).collect();
        assert_eq!(round_trip(&record).len(), 600 + 3);
    }

    #[test]
    fn malformed_frames_are_errors() {
        assert_eq!(decode_in_place(&mut [0x05, 1, 2]), Err(Error::Truncated));
        assert_eq!(decode_in_place(&mut [0x03, 1, 0]), Err(Error::ZeroInFrame));
        assert_eq!(decode_in_place(&mut [0x00]), Err(Error::ZeroInFrame));
        assert_eq!(
            encode(&[1, 2, 3], &mut [0u8; 3]),
            Err(Error::BufferTooSmall { needed: 4 })
        );
    }

    proptest::proptest! {
        #[test]
        fn any_record_round_trips(record in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..700)) {
            round_trip(&record);
        }

        #[test]
        fn parts_encode_as_their_concatenation(
            head in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300),
            tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300),
        ) {
            let whole = [head.as_slice(), tail.as_slice()].concat();
            let mut expected = vec![0u8; max_encoded_len(whole.len())];
            let n = encode(&whole, &mut expected).unwrap();
            let mut got = vec![0u8; max_encoded_len(whole.len())];
            let m = encode_parts(&[&head, &tail], &mut got).unwrap();
            proptest::prop_assert_eq!(&got[..m], &expected[..n]);
        }

        #[test]
        fn any_frame_decodes_or_errors(mut frame in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let len = frame.len();
            if let Ok(n) = decode_in_place(&mut frame) {
                proptest::prop_assert!(n <= len);
            }
        }
    }
}
