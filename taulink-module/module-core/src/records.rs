//! Telemetry *records*: what the module core moves between the air link, the handset
//! encoders and the HM-10 relay.
//!
//! The telemetry stream on the link is a byte stream of frames `COBS(payload ‖ crc16_be) ‖
//! 0x00` (`telemetry::framing`), each payload one postcard [`Message`]. A record is the
//! COBS-decoded body of one such frame, `payload ‖ crc16_be(payload)`, with its CRC checked.
//! Keeping the CRC inside the record makes the HM-10 relay's own framing (COBS + 0x00) of a
//! record byte-identical to the link frame, so a phone decodes the relay stream with
//! `telemetry::messages::MessageReader` exactly as the flight side decodes the link stream,
//! and a phone's frame reaches the link unchanged.

use telemetry::checksum::crc16;
use telemetry::framing::{Deframed, Deframer, frame};
use telemetry::messages::{MESSAGE_MAX_BYTES, Message};

use crate::hm10::relay::MAX_RECORD_LEN;

/// CRC bytes at the end of a record.
pub const CRC_BYTES: usize = 2;
/// Largest frame of one record on a stream (COBS code bytes, delimiter).
pub const MAX_STREAM_FRAME_LEN: usize = telemetry::framing::framed_len(MAX_RECORD_LEN);

/// Why a record was not accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordError {
    /// Shorter than its CRC.
    TooShort,
    /// The CRC does not match the payload.
    Crc,
    /// Longer than [`MAX_RECORD_LEN`] or the output buffer.
    TooLong,
    /// The payload is not a message this firmware knows.
    UnknownMessage,
}

impl core::fmt::Display for RecordError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::TooShort => "record shorter than its CRC",
            Self::Crc => "record CRC mismatch",
            Self::TooLong => "record too long",
            Self::UnknownMessage => "record holds no known message",
        })
    }
}

impl core::error::Error for RecordError {}

/// The payload of `record` after checking its CRC.
pub fn payload(record: &[u8]) -> Result<&[u8], RecordError> {
    let body_len = record
        .len()
        .checked_sub(CRC_BYTES)
        .ok_or(RecordError::TooShort)?;
    let (body, crc) = record
        .split_at_checked(body_len)
        .ok_or(RecordError::TooShort)?;
    let [c0, c1] = crc else {
        return Err(RecordError::TooShort);
    };
    if crc16(body) == u16::from_be_bytes([*c0, *c1]) {
        Ok(body)
    } else {
        Err(RecordError::Crc)
    }
}

/// The message a record carries.
pub fn decode(record: &[u8]) -> Result<Message, RecordError> {
    postcard::from_bytes::<Message>(payload(record)?).map_err(|_| RecordError::UnknownMessage)
}

/// The record of `message` into `out`; returns it.
pub fn encode<'o>(message: &Message, out: &'o mut [u8]) -> Result<&'o [u8], RecordError> {
    let mut scratch = [0u8; MESSAGE_MAX_BYTES];
    let body = postcard::to_slice(message, &mut scratch).map_err(|_| RecordError::TooLong)?;
    with_crc(body, out)
}

/// `payload ‖ crc16_be(payload)` into `out`.
pub fn with_crc<'o>(payload: &[u8], out: &'o mut [u8]) -> Result<&'o [u8], RecordError> {
    let len = payload.len() + CRC_BYTES;
    if len > MAX_RECORD_LEN {
        return Err(RecordError::TooLong);
    }
    let slot = out.get_mut(..len).ok_or(RecordError::TooLong)?;
    let (body, crc) = slot
        .split_at_mut_checked(payload.len())
        .ok_or(RecordError::TooLong)?;
    body.copy_from_slice(payload);
    crc.copy_from_slice(&crc16(payload).to_be_bytes());
    Ok(slot)
}

/// The stream frame of `record` (checked) into `out`; returns it.
pub fn to_stream<'o>(record: &[u8], out: &'o mut [u8]) -> Result<&'o [u8], RecordError> {
    frame(payload(record)?, out).map_err(|_| RecordError::TooLong)
}

/// Splits a telemetry byte stream into records. Bounded (one record); a frame that is
/// corrupt or too long is dropped and counted, and the splitter resynchronises at the next
/// 0x00, so bytes lost on the way cost at most the frames they touched.
#[derive(Debug, Default)]
pub struct Splitter {
    deframer: Deframer<MAX_STREAM_FRAME_LEN>,
    dropped: u32,
}

impl Splitter {
    /// A splitter waiting for the next delimiter.
    pub const fn new() -> Self {
        Self {
            deframer: Deframer::new(),
            dropped: 0,
        }
    }

    /// Frames dropped so far (corrupt or longer than a record).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// One stream byte; at the end of a good frame the record goes into `out` (≥
    /// [`MAX_RECORD_LEN`]) and its length is returned.
    pub fn push<'o>(&mut self, byte: u8, out: &'o mut [u8]) -> Option<&'o [u8]> {
        match self.deframer.push(byte)? {
            Deframed::Frame { .. } => match with_crc(self.deframer.payload(), out) {
                Ok(record) => Some(record),
                Err(_) => {
                    self.dropped = self.dropped.saturating_add(1);
                    None
                }
            },
            Deframed::Overflow | Deframed::Corrupt => {
                self.dropped = self.dropped.saturating_add(1);
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::cobs;
    use telemetry::messages::{Battery, FlightMode, encode_message};

    fn battery() -> Message {
        Message::Battery(Battery {
            voltage_mv: 11_870,
            current_ca: 1234,
            used_mah: 456,
            remaining_percent: 71,
        })
    }

    #[test]
    fn record_framed_by_the_relay_is_the_link_frame() {
        let mut record = [0u8; MAX_RECORD_LEN];
        let len = encode(&battery(), &mut record).unwrap().len();
        let mut relay_frame = [0u8; 80];
        let n = cobs::encode(&record[..len], &mut relay_frame).unwrap();
        relay_frame[n] = 0;
        let mut link_frame = [0u8; 80];
        let m = encode_message(&battery(), &mut link_frame).unwrap().len();
        assert_eq!(&relay_frame[..=n], &link_frame[..m]);
        let mut stream = [0u8; 80];
        let streamed = to_stream(&record[..len], &mut stream).unwrap();
        assert_eq!(streamed, &link_frame[..m]);
    }

    #[test]
    fn splitter_recovers_records_and_counts_damage() {
        let mut stream = Vec::new();
        let mut buf = [0u8; 80];
        for message in [battery(), Message::FlightMode(FlightMode::AltitudeHold)] {
            let n = encode_message(&message, &mut buf).unwrap().len();
            stream.extend_from_slice(&buf[..n]);
        }
        // Damage the first frame: its CRC fails, the second still arrives.
        stream[2] ^= 0x01;
        let mut splitter = Splitter::new();
        let mut got = Vec::new();
        let mut record = [0u8; MAX_RECORD_LEN];
        for &b in &stream {
            if let Some(len) = splitter.push(b, &mut record).map(<[u8]>::len) {
                got.push(decode(&record[..len]).unwrap());
            }
        }
        assert_eq!(got, vec![Message::FlightMode(FlightMode::AltitudeHold)]);
        assert_eq!(splitter.dropped(), 1);
    }

    #[test]
    fn bad_records_are_refused() {
        assert_eq!(payload(&[1]), Err(RecordError::TooShort));
        assert_eq!(payload(&[1, 2, 3]), Err(RecordError::Crc));
        let mut out = [0u8; 8];
        let record = with_crc(&[0xFF, 0xFF], &mut out).unwrap();
        assert_eq!(decode(record), Err(RecordError::UnknownMessage));
        assert_eq!(
            with_crc(&[0; 63], &mut [0u8; 80]),
            Err(RecordError::TooLong)
        );
    }
}
