//! CRSF frames through the link: how the module hands the flight controller (CRSF device
//! 0xC8) the radio's device-tool frames — PING, PARAMETER_READ, PARAMETER_WRITE — and how the
//! flight controller's answers (DEVICE_INFO, PARAMETER_SETTINGS_ENTRY chunks) come back, as
//! records of the telemetry stream. They ride the link's acknowledged stream, so on a keyed
//! link they are authenticated like every frame; the module never relays a phone record of
//! this kind (the phone is not the radio), so only the module's own handset line makes them.
//!
//! **Wire format.** Framed like every stream record (`COBS(payload ‖ crc16_be) ‖ 0x00`,
//! [`crate::framing`]); the payload is [`MARKER`], a chunk limit, the CRSF frame type, then
//! the CRSF payload (extended header first: destination, origin). The marker is above every
//! postcard message number (a message starts with a one-byte varint below 0x80) and differs
//! from the module record's 0xA5, so a reader tells the three apart by the first byte; an
//! older flight side drops it as unknown. The chunk limit (module → flight) is the most
//! parameter-description bytes one chunk may carry to reach the radio in one reply window of
//! its line (`Responder::parameter_chunk_len`), 0 in the other direction.

use crate::handset::crsf::frame::MAX_PAYLOAD_LEN;

/// First payload byte of a CRSF record: the CRSF address of the flight controller.
pub const MARKER: u8 = 0xC8;
/// Bytes before the CRSF payload: marker, chunk limit, frame type.
pub const HEADER_BYTES: usize = 3;
/// Longest record payload the stream carries (a record is at most 64 bytes with its CRC).
pub const MAX_RECORD_PAYLOAD: usize = 62;
/// Longest CRSF payload one record carries.
pub const MAX_CRSF_PAYLOAD: usize = MAX_RECORD_PAYLOAD - HEADER_BYTES;
/// Most description bytes a chunk from the flight controller carries: what fits one record
/// with the chunk frame's own four header bytes.
pub const MAX_RELAYED_CHUNK_DATA: usize = MAX_CRSF_PAYLOAD - 4;

/// One CRSF frame in a record.
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrsfRecord<'a> {
    /// The most chunk data the radio's line takes in one window (module → flight), else 0.
    pub chunk_limit: u8,
    /// CRSF frame type.
    pub frame_type: u8,
    /// CRSF payload (destination, origin, …).
    pub payload: &'a [u8],
}

/// Why a payload is no CRSF record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CrsfRecordError {
    /// Another kind of record (a message, a module record).
    NotCrsf,
    /// Marker but shorter than the header, or longer than a CRSF payload may be.
    Length,
}

/// Whether a record payload is a CRSF record (by its first byte).
pub fn is_crsf_payload(payload: &[u8]) -> bool {
    payload.first() == Some(&MARKER)
}

/// Reads a record payload.
pub fn decode(payload: &[u8]) -> Result<CrsfRecord<'_>, CrsfRecordError> {
    match payload {
        [MARKER, chunk_limit, frame_type, rest @ ..]
            if rest.len() <= MAX_CRSF_PAYLOAD.min(MAX_PAYLOAD_LEN) =>
        {
            Ok(CrsfRecord {
                chunk_limit: *chunk_limit,
                frame_type: *frame_type,
                payload: rest,
            })
        }
        [MARKER, ..] => Err(CrsfRecordError::Length),
        _ => Err(CrsfRecordError::NotCrsf),
    }
}

impl CrsfRecord<'_> {
    /// The record payload into `out`; `None` if the CRSF payload is too long for a record
    /// or `out` too small.
    pub fn encode<'o>(&self, out: &'o mut [u8]) -> Option<&'o [u8]> {
        if self.payload.len() > MAX_CRSF_PAYLOAD {
            return None;
        }
        let len = HEADER_BYTES + self.payload.len();
        let slot = out.get_mut(..len)?;
        let (header, body) = slot.split_at_mut_checked(HEADER_BYTES)?;
        header.copy_from_slice(&[MARKER, self.chunk_limit, self.frame_type]);
        body.copy_from_slice(self.payload);
        Some(slot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_read_round_trips_and_is_told_from_messages() {
        // PARAMETER_READ from the Lua tool to the flight controller: C8 EA 05 00.
        let read = CrsfRecord {
            chunk_limit: 35,
            frame_type: 0x2C,
            payload: &[0xC8, 0xEA, 5, 0],
        };
        let mut out = [0u8; MAX_RECORD_PAYLOAD];
        let bytes = read.encode(&mut out).unwrap();
        assert_eq!(bytes, &[0xC8, 35, 0x2C, 0xC8, 0xEA, 5, 0]);
        assert!(is_crsf_payload(bytes));
        assert_eq!(decode(bytes), Ok(read));
        // A postcard message starts below 0x80, a module record with 0xA5.
        assert_eq!(decode(&[13, 5]), Err(CrsfRecordError::NotCrsf));
        assert_eq!(decode(&[0xA5, 1]), Err(CrsfRecordError::NotCrsf));
        assert_eq!(decode(&[0xC8, 0]), Err(CrsfRecordError::Length));
    }

    #[test]
    fn the_longest_payload_fits_a_record_and_one_more_byte_does_not() {
        let long = [7u8; MAX_CRSF_PAYLOAD + 1];
        let mut out = [0u8; 80];
        let fits = CrsfRecord {
            chunk_limit: 0,
            frame_type: 0x2B,
            payload: &long[..MAX_CRSF_PAYLOAD],
        };
        assert_eq!(fits.encode(&mut out).map(<[u8]>::len), Some(62));
        let over = CrsfRecord {
            payload: &long,
            ..fits
        };
        assert_eq!(over.encode(&mut out), None);
        let mut raw = [7u8; 64];
        raw[0] = MARKER;
        assert_eq!(decode(&raw), Err(CrsfRecordError::Length));
    }
}
