//! RC_CHANNELS_PACKED (0x16): 16 channels × 11 bit, packed little-endian bit-first
//! (CRSF spec, `RC_CHANNELS_PACKED`), and the tick ↔ microsecond mapping of ExpressLRS/EdgeTX.

use super::frame::{Error, Frame, address, frame_type};

/// Channels in one frame.
pub const CHANNEL_COUNT: usize = 16;
/// Payload bytes: 16 × 11 bit.
pub const PAYLOAD_LEN: usize = 22;
/// Largest 11-bit value.
pub const TICKS_MAX: u16 = 0x7FF;
/// −100 % = 988 µs.
pub const TICKS_MIN_NOMINAL: u16 = 172;
/// Centre = 1500 µs.
pub const TICKS_CENTRE: u16 = 992;
/// +100 % = 2012 µs.
pub const TICKS_MAX_NOMINAL: u16 = 1811;
/// Pulse width at [`TICKS_MIN_NOMINAL`].
pub const US_MIN_NOMINAL: u16 = 988;
/// Pulse width at [`TICKS_MAX_NOMINAL`].
pub const US_MAX_NOMINAL: u16 = 2012;

// The mapping is the straight line through (172, 988 µs) and (1811, 2012 µs), as ExpressLRS
// `fmap` uses: 1639 ticks span 1024 µs, ≈ 1.6 ticks per µs.
const TICK_SPAN: i32 = (TICKS_MAX_NOMINAL - TICKS_MIN_NOMINAL) as i32;
const US_SPAN: i32 = (US_MAX_NOMINAL - US_MIN_NOMINAL) as i32;

/// Division rounding half away from zero (`divisor` > 0).
fn div_round(numerator: i32, divisor: i32) -> i32 {
    let half = divisor / 2;
    if numerator >= 0 {
        (numerator + half) / divisor
    } else {
        (numerator - half) / divisor
    }
}

/// CRSF ticks → pulse width in µs (rounded). 172 → 988, 992 → 1500, 1811 → 2012; the full
/// 11-bit range maps to 881 … 2159 µs (0 … 1984, the extended-limits range, to 881 … 2120).
pub fn ticks_to_us(ticks: u16) -> u16 {
    let ticks = i32::from(ticks.min(TICKS_MAX));
    let us = i32::from(US_MIN_NOMINAL)
        + div_round((ticks - i32::from(TICKS_MIN_NOMINAL)) * US_SPAN, TICK_SPAN);
    us.clamp(0, i32::from(u16::MAX)) as u16
}

/// Pulse width in µs → CRSF ticks (rounded, clamped to 0 … 2047). 988 → 172, 1000 → 191,
/// 1500 → 992, 2000 → 1792, 2012 → 1811. Inverse of [`ticks_to_us`] on whole µs.
pub fn us_to_ticks(us: u16) -> u16 {
    let ticks = i32::from(TICKS_MIN_NOMINAL)
        + div_round(
            (i32::from(us) - i32::from(US_MIN_NOMINAL)) * TICK_SPAN,
            US_SPAN,
        );
    ticks.clamp(0, i32::from(TICKS_MAX)) as u16
}

/// The 16 channel values in CRSF ticks (11 bit each).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RcChannels {
    /// Channel 1 … 16, 0 … 2047.
    pub ticks: [u16; CHANNEL_COUNT],
}

impl RcChannels {
    /// All channels at centre (992).
    pub const CENTRED: Self = Self {
        ticks: [TICKS_CENTRE; CHANNEL_COUNT],
    };

    /// From pulse widths in µs.
    pub fn from_us(us: &[u16; CHANNEL_COUNT]) -> Self {
        Self {
            ticks: us.map(us_to_ticks),
        }
    }

    /// Pulse widths in µs.
    pub fn to_us(&self) -> [u16; CHANNEL_COUNT] {
        self.ticks.map(ticks_to_us)
    }

    /// Packs into the 22-byte payload. Values above 2047 are clamped.
    pub fn pack(&self) -> [u8; PAYLOAD_LEN] {
        let mut out = [0u8; PAYLOAD_LEN];
        let mut accumulator: u32 = 0;
        let mut bits = 0u32;
        let mut bytes = out.iter_mut();
        for &value in &self.ticks {
            accumulator |= u32::from(value.min(TICKS_MAX)) << bits;
            bits += 11;
            while bits >= 8 {
                if let Some(byte) = bytes.next() {
                    *byte = accumulator as u8;
                }
                accumulator >>= 8;
                bits -= 8;
            }
        }
        // 16 × 11 = 176 bits = 22 bytes exactly: nothing is left over.
        out
    }

    /// Unpacks the first 22 bytes of a payload (EdgeTX may append an "armed" byte).
    pub fn unpack(payload: &[u8]) -> Result<Self, Error> {
        let Some(packed) = payload.first_chunk::<PAYLOAD_LEN>() else {
            return Err(Error::PayloadLength {
                frame_type: frame_type::RC_CHANNELS_PACKED,
                length: payload.len(),
            });
        };
        let mut ticks = [0u16; CHANNEL_COUNT];
        let mut accumulator: u32 = 0;
        let mut bits = 0u32;
        let mut channels = ticks.iter_mut();
        for &byte in packed {
            accumulator |= u32::from(byte) << bits;
            bits += 8;
            if bits >= 11 {
                if let Some(channel) = channels.next() {
                    *channel = (accumulator & u32::from(TICKS_MAX)) as u16;
                }
                accumulator >>= 11;
                bits -= 11;
            }
        }
        Ok(Self { ticks })
    }

    /// Reads a 0x16 frame. Payloads of 22 bytes and EdgeTX's 23 (with armed byte) are accepted.
    pub fn from_frame(frame: &Frame) -> Result<Self, Error> {
        if frame.frame_type != frame_type::RC_CHANNELS_PACKED {
            return Err(Error::WrongType {
                found: frame.frame_type,
            });
        }
        if !matches!(frame.payload.len(), 22 | 23) {
            return Err(Error::PayloadLength {
                frame_type: frame.frame_type,
                length: frame.payload.len(),
            });
        }
        Self::unpack(&frame.payload)
    }

    /// A 0x16 frame as EdgeTX sends it to a module (address 0xEE).
    pub fn to_frame(&self) -> Frame {
        Frame {
            address: address::TX_MODULE,
            frame_type: frame_type::RC_CHANNELS_PACKED,
            payload: heapless::Vec::from_iter(self.pack()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_points_map_exactly() {
        assert_eq!(us_to_ticks(988), 172);
        assert_eq!(us_to_ticks(1500), 992);
        assert_eq!(us_to_ticks(2012), 1811);
        assert_eq!(ticks_to_us(172), 988);
        assert_eq!(ticks_to_us(992), 1500);
        assert_eq!(ticks_to_us(1811), 2012);
    }

    #[test]
    fn extended_limits_saturate_at_eleven_bits() {
        assert_eq!(us_to_ticks(750), 0);
        assert_eq!(us_to_ticks(732), 0);
        assert_eq!(us_to_ticks(2250), 2047);
        // 881 µs is the last width above zero: 172 + (881 − 988)·1639/1024 = 0.7 → 1.
        assert_eq!(us_to_ticks(881), 1);
        assert_eq!(ticks_to_us(0), 881);
        assert_eq!(ticks_to_us(2047), 2159);
    }

    #[test]
    fn round_trip_within_one_microsecond() {
        for us in 881..=2159u16 {
            let back = ticks_to_us(us_to_ticks(us));
            assert!(back.abs_diff(us) <= 1, "{us} µs came back as {back}");
        }
    }
}
