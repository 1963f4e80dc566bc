//! Byte-stream framing for the telemetry stream and the phone relay: COBS ([`crate::cobs`])
//! with a 0x00 delimiter, so a receiver that joins mid-stream or loses bytes resynchronises
//! at the next zero, and a CRC-16 inside each frame, so a frame damaged outside the link (a UART, a BLE bridge) is dropped.
//!
//! Frame on the wire: `COBS(payload ‖ crc16_be(payload)) ‖ 0x00`.

use crate::checksum::crc16;
use crate::cobs;

/// Framing failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FramingError {
    /// The output buffer is too small; this many bytes are needed.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
    },
}

impl core::fmt::Display for FramingError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FramingError::BufferTooSmall { needed } => {
                write!(f, "buffer too small, need {needed} bytes")
            }
        }
    }
}

impl core::error::Error for FramingError {}

/// Worst-case framed size of a `payload_len`-byte payload: COBS adds one byte per 254 plus
/// one, the CRC two, the delimiter one.
pub const fn framed_len(payload_len: usize) -> usize {
    cobs::max_encoded_len(payload_len + 2) + 1
}

/// Frames `payload` into `out`; returns the framed bytes (delimiter included), postcard's
/// `to_slice` style.
pub fn frame<'o>(payload: &[u8], out: &'o mut [u8]) -> Result<&'o [u8], FramingError> {
    let crc = crc16(payload).to_be_bytes();
    let needed = framed_len(payload.len());
    let too_small = FramingError::BufferTooSmall { needed };
    let body = out.get_mut(..needed - 1).ok_or(too_small)?;
    let encoded = cobs::encode_parts(&[payload, &crc], body).map_err(|_| too_small)?;
    let (framed, _) = out.split_at_mut_checked(encoded + 1).ok_or(too_small)?;
    let (delimiter, _) = framed.split_last_mut().ok_or(too_small)?;
    *delimiter = 0;
    Ok(framed)
}

/// What the deframer made of one delimited frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Deframed {
    /// A good frame: the payload is `payload_len` bytes, readable with [`Deframer::payload`].
    Frame {
        /// Payload length.
        payload_len: usize,
    },
    /// The frame did not fit the buffer; dropped.
    Overflow,
    /// Bad COBS coding or CRC; dropped.
    Corrupt,
}

/// Accumulates stream bytes into frames; a bounded buffer of `N` bytes.
#[derive(Debug)]
pub struct Deframer<const N: usize> {
    buf: [u8; N],
    len: usize,
    overflowed: bool,
    decoded_len: usize,
}

impl<const N: usize> Default for Deframer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Deframer<N> {
    /// An empty deframer.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            overflowed: false,
            decoded_len: 0,
        }
    }

    /// Feeds one byte; returns an outcome at every delimiter (empty frames are skipped).
    pub fn push(&mut self, byte: u8) -> Option<Deframed> {
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflowed = true,
            }
            return None;
        }
        let (len, overflowed) = (self.len, self.overflowed);
        self.len = 0;
        self.overflowed = false;
        if overflowed {
            return Some(Deframed::Overflow);
        }
        if len == 0 {
            return None;
        }
        Some(match self.decode_in_place(len) {
            Some(payload_len) => {
                self.decoded_len = payload_len;
                Deframed::Frame { payload_len }
            }
            None => Deframed::Corrupt,
        })
    }

    /// COBS-decodes `buf[..len]` in place (output never outruns input); checks the CRC.
    fn decode_in_place(&mut self, len: usize) -> Option<usize> {
        let write = cobs::decode_in_place(self.buf.get_mut(..len)?).ok()?;
        let body_len = write.checked_sub(2)?;
        let (body, crc) = self.buf.get(..write)?.split_at_checked(body_len)?;
        let [c0, c1] = crc else {
            return None;
        };
        (crc16(body) == u16::from_be_bytes([*c0, *c1])).then_some(body_len)
    }

    /// The payload of the last good frame.
    pub fn payload(&self) -> &[u8] {
        // Kept: `decoded_len` is only set from a successful `get(..write)` of this buffer.
        self.buf.get(..self.decoded_len).unwrap_or(&[])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(payload: &[u8]) {
        let mut out = vec![0u8; framed_len(payload.len())];
        let n = frame(payload, &mut out).unwrap().len();
        assert_eq!(out[n - 1], 0);
        assert!(!out[..n - 1].contains(&0), "no zero inside a frame");
        let mut d = Deframer::<600>::new();
        let mut got = None;
        for &b in &out[..n] {
            if let Some(r) = d.push(b) {
                got = Some(r);
            }
        }
        assert_eq!(
            got,
            Some(Deframed::Frame {
                payload_len: payload.len()
            })
        );
        assert_eq!(d.payload(), payload);
    }

    #[test]
    fn round_trips_edge_cases() {
        round_trip(&[]);
        round_trip(&[0]);
        round_trip(&[0, 0, 0]);
        round_trip(&[1, 2, 3]);
        round_trip(&(1..=254).collect::<Vec<u8>>());
        round_trip(&(0..=255).cycle().take(520).collect::<Vec<u8>>());
        round_trip(&[0x11; 300]);
    }

    #[test]
    fn known_encoding() {
        // Payload 11 00 22, CRC-16/CCITT-FALSE of it appended, then COBS.
        let crc = crc16(&[0x11, 0x00, 0x22]).to_be_bytes();
        let mut out = [0u8; 16];
        let n = frame(&[0x11, 0x00, 0x22], &mut out).unwrap().len();
        assert_eq!(&out[..3], &[0x02, 0x11, 0x04]);
        assert_eq!(&out[3..6], &[0x22, crc[0], crc[1]]);
        assert_eq!((n, out[6]), (7, 0));
    }

    #[test]
    fn a_body_ending_on_a_full_block_gets_no_empty_block() {
        // payload ‖ crc of 254 non-zero bytes is one full block: 0xFF, the 254 bytes, the
        // delimiter, the same bytes the module's relay sends for that record. (The framing's
        // own COBS used to add an empty block, 0x01, before the delimiter.)
        let (payload, crc) = (1..=255u8)
            .map(|fill| ([fill; 252], crc16(&[fill; 252]).to_be_bytes()))
            .find(|(_, crc)| !crc.contains(&0))
            .unwrap();
        let mut out = [0u8; 300];
        let n = frame(&payload, &mut out).unwrap().len();
        assert_eq!(n, 256);
        assert_eq!(out[0], 0xFF);
        assert_eq!(&out[1..253], &payload);
        assert_eq!(&out[253..256], &[crc[0], crc[1], 0]);
    }

    #[test]
    fn resynchronises_after_garbage_and_drops_corruption() {
        let mut a = [0u8; 16];
        let n = frame(b"abc", &mut a).unwrap().len();
        let mut d = Deframer::<32>::new();
        let mut outcomes = Vec::new();
        let mut bad = a;
        bad[2] ^= 0x40;
        for &b in [0x55, 0x66]
            .iter()
            .chain(&[0u8])
            .chain(&bad[..n])
            .chain(&a[..n])
        {
            if let Some(r) = d.push(b) {
                outcomes.push(r);
            }
        }
        assert_eq!(
            outcomes,
            vec![
                Deframed::Corrupt,
                Deframed::Corrupt,
                Deframed::Frame { payload_len: 3 }
            ]
        );
        assert_eq!(d.payload(), b"abc");
        let mut small = Deframer::<4>::new();
        let results: Vec<_> = a[..n].iter().filter_map(|&b| small.push(b)).collect();
        assert_eq!(results, vec![Deframed::Overflow]);
    }
}
