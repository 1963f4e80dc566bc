//! FrSky S.Port (SmartPort) data frames as EdgeTX parses them: `7E physId 10 id id v v v v crc`
//! with 0x7D byte stuffing (EdgeTX `frsky_sport.cpp`), the value IDs we push, a streaming decoder
//! and the push scheduler for PPM mode.

use core::fmt;

use super::stuffing::{self, Writer, stuffed_len};

pub mod decoder;
pub mod schedule;

pub use decoder::{Decoder, Event, Rejection};
pub use schedule::Scheduler;

/// Frame start; also what a bus master sends before a physical ID to poll it.
pub const START: u8 = stuffing::FRAME;
/// Escape byte: the next byte was XORed with [`STUFF_XOR`].
pub const STUFF: u8 = stuffing::ESCAPE;
/// XOR applied to an escaped byte.
pub const STUFF_XOR: u8 = stuffing::ESCAPE_XOR;
/// Primitive of a sensor data frame.
pub const DATA_FRAME: u8 = 0x10;
/// Longest frame on the wire: start, physical ID, and 8 bytes that may each be escaped.
pub const MAX_WIRE_LEN: usize = 2 + 2 * 8;

/// Value IDs EdgeTX knows (`frsky_defs.h`) plus the four DIY IDs we use.
pub mod value_id {
    /// RSSI in dB, low byte only. A non-zero RSSI is EdgeTX's "streaming" heartbeat (1 s).
    pub const RSSI: u16 = 0xF101;
    /// Valid frame rate %, shown as 100 − value.
    pub const VFR: u16 = 0xF010;
    /// A1, raw 0…255 over 13.2 V.
    pub const A1: u16 = 0xF102;
    /// A2, raw 0…255 over 13.2 V.
    pub const A2: u16 = 0xF103;
    /// Receiver battery, raw 0…255 over 13.2 V.
    pub const RXBT: u16 = 0xF104;
    /// SWR (hidden sensor; openLRSng puts its profile number here).
    pub const SWR: u16 = 0xF105;
    /// Battery voltage in 0.01 V.
    pub const VFAS: u16 = 0x0210;
    /// Current in 0.1 A.
    pub const CURRENT: u16 = 0x0200;
    /// Fuel / remaining charge in %.
    pub const FUEL: u16 = 0x0600;
    /// Temperature 1 in °C.
    pub const TMP1: u16 = 0x0400;
    /// Barometric altitude in cm (EdgeTX "Alt").
    pub const ALT: u16 = 0x0100;
    /// Vertical speed in cm/s (EdgeTX "VSpd").
    pub const VARIO: u16 = 0x0110;
    /// Cell voltages, FLVSS format (EdgeTX "Cels"): bits 0–3 first cell index, 4–7 cell
    /// count, 8–19 and 20–31 two cells in 2 mV steps.
    pub const CELLS: u16 = 0x0300;
    /// TauLink link quality in % (DIY range: EdgeTX lists it as "5100"; rename it "LQ" and
    /// set the unit to %).
    pub const TAULINK_LQ: u16 = 0x5100;
    /// TauLink flight-mode number (DIY range: listed as "5101"; rename it "FM").
    pub const TAULINK_FLIGHT_MODE: u16 = 0x5101;
    /// TauLink tag failures at both ends of a keyed link (DIY range: listed as "5102";
    /// rename it "TAG").
    pub const TAULINK_TAG_FAILURES: u16 = 0x5102;
    /// TauLink tag alert: 1 while the tag failures run above what noise explains, else 0
    /// (DIY range: listed as "5103"; rename it "TALR" and put an alarm on it).
    pub const TAULINK_TAG_ALERT: u16 = 0x5103;
}

/// Physical IDs: 5-bit sensor ID plus three parity bits.
pub mod physical_id {
    /// ID 24, what FrSky receivers use for RSSI/RxBt and openLRSng's TX pushes with.
    pub const RECEIVER: u8 = 0x98;
    /// ID 27, Betaflight's and dRonin's sensor ID.
    pub const SENSOR_27: u8 = 0x1B;

    /// The physical ID byte of sensor `id` (0…27): b5 = i0^i1^i2, b6 = i2^i3^i4,
    /// b7 = i0^i2^i4.
    pub const fn with_parity(id: u8) -> Option<u8> {
        if id > 27 {
            return None;
        }
        let [i0, i1, i2, i3, i4] = [id & 1, id >> 1 & 1, id >> 2 & 1, id >> 3 & 1, id >> 4 & 1];
        let b5 = i0 ^ i1 ^ i2;
        let b6 = i2 ^ i3 ^ i4;
        let b7 = i0 ^ i2 ^ i4;
        Some(id | b5 << 5 | b6 << 6 | b7 << 7)
    }
}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer is shorter than the stuffed frame.
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
    },
    /// The physical ID is 0x7E or 0x7D, which a receiver cannot tell from framing.
    ReservedPhysicalId,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => write!(f, "buffer too small, need {needed} bytes"),
            Self::ReservedPhysicalId => f.write_str("physical id collides with framing bytes"),
        }
    }
}

impl core::error::Error for Error {}

/// S.Port checksum over unstuffed bytes: add with end-around carry, then complement
/// (`0xFF − sum`). Over the 7 bytes primitive…value it gives the CRC byte; over all 8 a valid
/// frame folds to 0xFF.
pub fn checksum(bytes: &[u8]) -> u8 {
    let mut sum: u16 = 0;
    for &b in bytes {
        sum += u16::from(b);
        sum += sum >> 8;
        sum &= 0xFF;
    }
    0xFF - sum as u8
}

/// One data frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// Physical (sensor) ID byte, parity bits included.
    pub physical_id: u8,
    /// Primitive: 0x10 for data; 0x00 for FrSky's "nothing new" frame.
    pub primitive: u8,
    /// Value ID (sent little-endian).
    pub value_id: u16,
    /// Value (sent little-endian; signed sensors use two's complement).
    pub value: u32,
}

impl Frame {
    /// A data frame (primitive 0x10).
    pub const fn data(physical_id: u8, value_id: u16, value: u32) -> Self {
        Self {
            physical_id,
            primitive: DATA_FRAME,
            value_id,
            value,
        }
    }

    /// The 7 bytes the checksum covers: primitive, value ID, value.
    pub fn body(&self) -> [u8; 7] {
        let [i0, i1] = self.value_id.to_le_bytes();
        let [v0, v1, v2, v3] = self.value.to_le_bytes();
        [self.primitive, i0, i1, v0, v1, v2, v3]
    }

    /// The checksum byte.
    pub fn crc(&self) -> u8 {
        checksum(&self.body())
    }

    /// Writes `7E physId` and the stuffed body + CRC; returns the bytes written (10…18).
    pub fn encode<'o>(&self, out: &'o mut [u8]) -> Result<&'o [u8], Error> {
        if matches!(self.physical_id, START | STUFF) {
            return Err(Error::ReservedPhysicalId);
        }
        let body = self.body();
        let crc = self.crc();
        let needed = 2 + stuffed_len(body.into_iter().chain([crc]));
        let Some(out) = out.get_mut(..needed) else {
            return Err(Error::BufferTooSmall { needed });
        };
        let mut w = Writer::new(&mut *out);
        w.raw(START);
        w.raw(self.physical_id);
        for byte in body.into_iter().chain([crc]) {
            w.stuffed(byte);
        }
        Ok(out)
    }
}

/// The FLVSS cell value for cells `first` and `first + 1` of `count`, each `cell_mv`
/// (EdgeTX shows `raw / 5` hundredths of a volt, raw in 2 mV steps); the second slot is 0
/// past the last cell.
pub const fn flvss_value(count: u8, first: u8, cell_mv: u16) -> u32 {
    let raw = (cell_mv / 2) as u32 & 0xFFF;
    let second = if first + 1 < count { raw } else { 0 };
    (first as u32 & 0x0F) | ((count as u32 & 0x0F) << 4) | (raw << 8) | (second << 20)
}
