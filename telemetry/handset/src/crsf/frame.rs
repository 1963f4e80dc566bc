//! One CRSF frame: `[address][len][type][payload…][crc]` (CRSF spec), its CRC and its
//! encoding into a caller buffer.

use core::fmt;

use crc::{CRC_8_DVB_S2, Crc};
use heapless::Vec;

/// CRC-8/DVB-S2 (poly 0xD5, init 0, no reflection) over type + payload.
pub const FRAME_CRC: Crc<u8> = Crc::<u8>::new(&CRC_8_DVB_S2);

/// Longest frame on the wire, address byte to CRC.
pub const MAX_FRAME_LEN: usize = 64;
/// Longest payload: 64 minus address, length, type and CRC.
pub const MAX_PAYLOAD_LEN: usize = MAX_FRAME_LEN - 4;
/// Smallest value of the length byte (type + CRC, empty payload).
pub const MIN_LENGTH_BYTE: u8 = 2;
/// Largest value of the length byte (everything after it in a 64-byte frame).
pub const MAX_LENGTH_BYTE: u8 = (MAX_FRAME_LEN - 2) as u8;

/// Frame types this module knows (TBS spec `crsf.md`).
pub mod frame_type {
    /// GPS position, speed, heading, altitude, satellites.
    pub const GPS: u8 = 0x02;
    /// Battery voltage, current, used capacity, remaining %.
    pub const BATTERY_SENSOR: u8 = 0x08;
    /// VARIO: vertical speed, i16 cm/s (EdgeTX "VSpd").
    pub const VARIO: u8 = 0x07;
    /// BARO_ALTITUDE: packed altitude (EdgeTX "Alt").
    pub const BARO_ALTITUDE: u8 = 0x09;
    /// Link RSSI / LQ / SNR both ways.
    pub const LINK_STATISTICS: u8 = 0x14;
    /// 16 RC channels × 11 bit.
    pub const RC_CHANNELS_PACKED: u8 = 0x16;
    /// Pitch, roll, yaw.
    pub const ATTITUDE: u8 = 0x1E;
    /// Flight mode as a NUL-terminated string.
    pub const FLIGHT_MODE: u8 = 0x21;
    /// Device discovery request (extended header).
    pub const DEVICE_PING: u8 = 0x28;
    /// Device discovery answer (extended header).
    pub const DEVICE_INFO: u8 = 0x29;
    /// Command frame with its own inner CRC (extended header).
    pub const COMMAND: u8 = 0x32;
    /// PARAMETER_SETTINGS_ENTRY: one chunk of a parameter's description, module → radio.
    pub const PARAMETER_SETTINGS_ENTRY: u8 = 0x2B;
    /// PARAMETER_READ: the radio asks for one chunk of a parameter.
    pub const PARAMETER_READ: u8 = 0x2C;
    /// PARAMETER_WRITE: the radio sets a parameter (or steps a command).
    pub const PARAMETER_WRITE: u8 = 0x2D;
    /// "Radio ID" frame; sub-type 0x10 carries the timing correction (extended header).
    pub const RADIO_ID: u8 = 0x3A;
    /// First type that carries `destination, origin` before its payload.
    pub const FIRST_EXTENDED: u8 = 0x28;
}

/// Device addresses.
pub mod address {
    /// Broadcast.
    pub const BROADCAST: u8 = 0x00;
    /// Flight controller, also the generic serial sync byte.
    pub const FLIGHT_CONTROLLER: u8 = 0xC8;
    /// Radio / handset.
    pub const RADIO: u8 = 0xEA;
    /// Receiver.
    pub const RECEIVER: u8 = 0xEC;
    /// Transmitter module: us, as the radio sees us.
    pub const TX_MODULE: u8 = 0xEE;
}

/// Why a frame could not be built or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer is shorter than the encoded frame.
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
    },
    /// The payload does not fit a 64-byte frame.
    PayloadTooLong {
        /// Bytes offered.
        length: usize,
    },
    /// A typed message was read from a frame of another type.
    WrongType {
        /// Type byte found.
        found: u8,
    },
    /// The payload length does not match what the frame type carries.
    PayloadLength {
        /// Frame type.
        frame_type: u8,
        /// Bytes found.
        length: usize,
    },
    /// A string field has no NUL terminator.
    Unterminated,
    /// A string is longer than the field holds, or is not UTF-8.
    BadString,
    /// A sub-type or command this module does not decode.
    Unsupported {
        /// The sub-type byte.
        sub_type: u8,
    },
    /// A command frame's inner CRC (poly 0xBA) does not match.
    InnerCrc,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => write!(f, "buffer too small, need {needed} bytes"),
            Self::PayloadTooLong { length } => write!(f, "payload of {length} bytes too long"),
            Self::WrongType { found } => write!(f, "unexpected frame type {found:#04x}"),
            Self::PayloadLength { frame_type, length } => {
                write!(f, "frame type {frame_type:#04x} with {length}-byte payload")
            }
            Self::Unterminated => f.write_str("string without NUL terminator"),
            Self::BadString => f.write_str("string too long or not UTF-8"),
            Self::Unsupported { sub_type } => write!(f, "unsupported sub-type {sub_type:#04x}"),
            Self::InnerCrc => f.write_str("command inner CRC mismatch"),
        }
    }
}

impl core::error::Error for Error {}

/// A frame: address byte, type and payload. The length byte and CRC are derived on encode
/// and checked by the [`Decoder`](super::Decoder).
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// Byte 0: the sync byte (0xC8) or the destination address.
    pub address: u8,
    /// Frame type (see [`frame_type`]).
    pub frame_type: u8,
    /// Payload between type and CRC (for extended types it starts with destination, origin).
    pub payload: Vec<u8, MAX_PAYLOAD_LEN>,
}

impl Frame {
    /// A frame with a copy of `payload`.
    pub fn new(address: u8, frame_type: u8, payload: &[u8]) -> Result<Self, Error> {
        let payload = Vec::from_slice(payload).map_err(|_| Error::PayloadTooLong {
            length: payload.len(),
        })?;
        Ok(Self {
            address,
            frame_type,
            payload,
        })
    }

    /// Value of the length byte: type + payload + CRC.
    pub fn length_byte(&self) -> u8 {
        // The payload holds at most 60 bytes, so this is at most 62.
        (self.payload.len() + 2) as u8
    }

    /// Bytes on the wire, address to CRC.
    pub fn wire_len(&self) -> usize {
        self.payload.len() + 4
    }

    /// CRC-8/DVB-S2 over type and payload.
    pub fn crc(&self) -> u8 {
        let mut digest = FRAME_CRC.digest();
        digest.update(&[self.frame_type]);
        digest.update(&self.payload);
        digest.finalize()
    }

    /// For extended types (≥ 0x28): `(destination, origin)`.
    pub fn extended_addresses(&self) -> Option<(u8, u8)> {
        if self.frame_type < frame_type::FIRST_EXTENDED {
            return None;
        }
        match self.payload.as_slice() {
            [destination, origin, ..] => Some((*destination, *origin)),
            _ => None,
        }
    }

    /// Writes the frame into `out` and returns the bytes written (postcard's `to_slice`
    /// style: the caller never slices `out` by a count).
    pub fn encode<'o>(&self, out: &'o mut [u8]) -> Result<&'o [u8], Error> {
        let needed = self.wire_len();
        let Some(out) = out.get_mut(..needed) else {
            return Err(Error::BufferTooSmall { needed });
        };
        let Some((head, rest)) = (*out).split_first_chunk_mut::<3>() else {
            return Err(Error::BufferTooSmall { needed });
        };
        *head = [self.address, self.length_byte(), self.frame_type];
        let Some((crc, payload)) = rest.split_last_mut() else {
            return Err(Error::BufferTooSmall { needed });
        };
        payload.copy_from_slice(&self.payload);
        *crc = self.crc();
        Ok(out)
    }
}

/// Reads a big-endian integer field of `N` bytes at `offset`.
pub(crate) fn be_bytes<const N: usize>(payload: &[u8], offset: usize) -> Option<[u8; N]> {
    payload.get(offset..)?.first_chunk::<N>().copied()
}
