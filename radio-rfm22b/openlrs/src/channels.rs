//! RC channel values: the 10-bit "bits" scale and its µs mapping, the 2-bit switch channels,
//! the channel packing of modes 0..7 (`packChannels`/`unpackChannels`), and the one mapping
//! between OpenLRSng's values and TauLink's channels (CRSF ticks, `telemetry::channels`),
//! which both TauLink ends use when they speak OpenLRSng.

use taulink_handset::crsf::channels::{ticks_to_us, us_to_ticks};

/// Most channels any mode carries (dRonin's mode 7, 16 + 4).
pub const MAX_CHANNELS: usize = 20;
/// Largest uplink packet, header included (mode 7).
pub const MAX_PACKET_LEN: usize = 22;
/// Channel value OpenLRSng starts from before any input arrives (1500 µs).
pub const CENTER_BITS: u16 = 512;

/// `flags & 7`: how many channels travel and how. Modes 1..6 are OpenLRSng's; 0 (4 ch) and
/// 7 (16+4 ch) exist only in dRonin, whose packing generalises the same way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelMode(u8);

impl ChannelMode {
    /// The mode in the low three bits of the bind flags.
    pub const fn from_flags(flags: u8) -> Self {
        Self(flags & 7)
    }

    /// The raw mode number 0..7.
    pub const fn number(self) -> u8 {
        self.0
    }

    /// Whether real OpenLRSng firmware accepts this mode (its packet-size table has 0 for 0, 7).
    pub const fn is_openlrsng(self) -> bool {
        self.0 >= 1 && self.0 <= 6
    }

    /// Full-resolution groups of 4 channels in 5 bytes (`config / 2 + 1`).
    pub const fn full_groups(self) -> usize {
        (self.0 / 2) as usize + 1
    }

    /// Whether a switch byte (4 channels at 2 bits) follows the groups (`config & 1`).
    pub const fn has_switch_byte(self) -> bool {
        self.0 & 1 != 0
    }

    /// Channels carried.
    pub const fn channel_count(self) -> usize {
        (self.full_groups() + self.has_switch_byte() as usize) * 4
    }

    /// Uplink packet size, header byte included (`pktsizes[]`, extended as dRonin does).
    pub const fn packet_size(self) -> usize {
        1 + 5 * self.full_groups() + self.has_switch_byte() as usize
    }
}

/// `servoUs2Bits`: 1 µs steps over 1000..1999 µs, 16 µs steps out to 800/2200 µs.
pub const fn us_to_bits(us: u16) -> u16 {
    if us < 800 {
        0
    } else if us < 1000 {
        (us - 799) / 16
    } else if us < 2000 {
        us - 988
    } else if us < 2200 {
        (us - 1992) / 16 + 1011
    } else {
        1023
    }
}

/// `servoBits2Us`, the inverse mapping (808..2192 µs).
pub const fn bits_to_us(bits: u16) -> u16 {
    if bits < 12 {
        808 + bits * 16
    } else if bits < 1012 {
        bits + 988
    } else if bits < 1024 {
        2000 + (bits - 1011) * 16
    } else {
        2192
    }
}

/// A TauLink channel value (CRSF ticks, 172..1811 = 988..2012 µs) as OpenLRSng sends it:
/// through its pulse width, so a stick at 1500 µs is 1500 µs at both ends.
pub fn ticks_to_bits(ticks: u16) -> u16 {
    us_to_bits(ticks_to_us(ticks))
}

/// An OpenLRSng channel value as a TauLink channel (CRSF ticks), through its pulse width;
/// the inverse of [`ticks_to_bits`] for every value inside CRSF's range (881..2159 µs).
pub fn bits_to_ticks(bits: u16) -> u16 {
    us_to_ticks(bits_to_us(bits))
}

/// `twoBitfy`: a channel quantised to a 3-position-plus switch (0..3).
pub const fn two_bitfy(bits: u16) -> u8 {
    if bits < 256 {
        0
    } else if bits < 512 {
        1
    } else if bits < 768 {
        2
    } else {
        3
    }
}

/// The value a 2-bit switch channel unpacks to: 12, 345, 678 or 1011.
pub const fn switch_to_bits(two_bits: u8) -> u16 {
    (two_bits & 3) as u16 * 333 + 12
}

/// Packs `channels` (10-bit values) into `payload` (the packet after the header byte) and
/// returns the payload length. Missing channels count as [`CENTER_BITS`]; values above
/// 1023 keep only their low 10 bits, as on air.
pub fn pack(mode: ChannelMode, channels: &[u16], payload: &mut [u8]) -> Result<usize, Error> {
    let needed = mode.packet_size() - 1;
    let payload = payload
        .get_mut(..needed)
        .ok_or(Error::BufferTooSmall { needed })?;
    let ch = |i: usize| channels.get(i).copied().unwrap_or(CENTER_BITS);
    let (groups, switch) = payload.split_at_mut(5 * mode.full_groups());
    for (g, group) in groups.chunks_exact_mut(5).enumerate() {
        let base = 4 * g;
        let mut high = 0u8;
        for (k, slot) in group.iter_mut().take(4).enumerate() {
            let value = ch(base + k);
            // Low 8 bits in bytes 0..3, bits 9..8 of channel k at bits 2k+1..2k of byte 4.
            *slot = (value & 0xFF) as u8;
            high |= (((value >> 8) & 3) as u8) << (2 * k);
        }
        if let Some(last) = group.get_mut(4) {
            *last = high;
        }
    }
    if let Some(byte) = switch.first_mut() {
        let base = 4 * mode.full_groups();
        *byte = (0..4).fold(0u8, |acc, k| acc | (two_bitfy(ch(base + k)) << (6 - 2 * k)));
    }
    Ok(needed)
}

/// Unpacks a payload (after the header byte) into `channels`, which must hold
/// `mode.channel_count()` values; returns how many were written.
pub fn unpack(mode: ChannelMode, payload: &[u8], channels: &mut [u16]) -> Result<usize, Error> {
    let needed = mode.packet_size() - 1;
    let payload = payload.get(..needed).ok_or(Error::PacketTooShort {
        needed,
        got: payload.len(),
    })?;
    let count = mode.channel_count();
    let channels = channels
        .get_mut(..count)
        .ok_or(Error::BufferTooSmall { needed: count })?;
    let (groups, switch) = payload.split_at(5 * mode.full_groups());
    let mut out = channels.iter_mut();
    for group in groups.chunks_exact(5) {
        let [b0, b1, b2, b3, high] = [0, 1, 2, 3, 4].map(|i| group.get(i).copied().unwrap_or(0));
        for (k, low) in [b0, b1, b2, b3].into_iter().enumerate() {
            if let Some(slot) = out.next() {
                *slot = ((u16::from(high) >> (2 * k)) & 3) << 8 | u16::from(low);
            }
        }
    }
    if let Some(&byte) = switch.first() {
        for k in 0..4 {
            if let Some(slot) = out.next() {
                *slot = switch_to_bits(byte >> (6 - 2 * k));
            }
        }
    }
    Ok(count)
}

/// Channel packing failures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer holds fewer than `needed` entries.
    BufferTooSmall {
        /// Entries required.
        needed: usize,
    },
    /// The received payload is shorter than the mode's packet.
    PacketTooShort {
        /// Payload bytes required.
        needed: usize,
        /// Payload bytes present.
        got: usize,
    },
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => write!(f, "buffer too small, need {needed}"),
            Self::PacketTooShort { needed, got } => {
                write!(f, "payload of {got} bytes, mode needs {needed}")
            }
        }
    }
}

impl core::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_table_matches_openlrsng_and_dronin() {
        let sizes: [usize; 8] = core::array::from_fn(|m| ChannelMode(m as u8).packet_size());
        assert_eq!(sizes, [6, 7, 11, 12, 16, 17, 21, 22]);
        let counts: [usize; 8] = core::array::from_fn(|m| ChannelMode(m as u8).channel_count());
        assert_eq!(counts, [4, 8, 8, 12, 12, 16, 16, 20]);
    }

    #[test]
    fn taulink_channels_map_through_microseconds() {
        use taulink_handset::crsf::channels::{TICKS_CENTRE, TICKS_MAX_NOMINAL, TICKS_MIN_NOMINAL};
        assert_eq!(bits_to_ticks(CENTER_BITS), TICKS_CENTRE);
        assert_eq!(ticks_to_bits(TICKS_CENTRE), CENTER_BITS);
        // ±100 % (988 / 2012 µs) fall in OpenLRSng's 16 µs steps outside 1000..1999 µs:
        // they come back as 984 and 2016 µs.
        assert_eq!(bits_to_us(ticks_to_bits(TICKS_MIN_NOMINAL)), 984);
        assert_eq!(bits_to_us(ticks_to_bits(TICKS_MAX_NOMINAL)), 2016);
        assert_eq!(bits_to_ticks(12), us_to_ticks(1000));
        // Every OpenLRSng value CRSF can express survives the round trip.
        for bits in 0..1024 {
            if (881..=2159).contains(&bits_to_us(bits)) {
                assert_eq!(ticks_to_bits(bits_to_ticks(bits)), bits, "{bits}");
            }
        }
    }

    #[test]
    fn conversion_edges() {
        assert_eq!(us_to_bits(1500), 512);
        assert_eq!(bits_to_us(512), 1500);
        assert_eq!(us_to_bits(2300), 1023);
        assert_eq!(bits_to_us(1023), 2192);
        assert_eq!(switch_to_bits(2), 678);
    }

    #[test]
    fn pack_then_unpack_mode_1() {
        let ch = [0x3FF, 0x100, 0x2AA, 0x055, 100, 300, 600, 900];
        let mut p = [0u8; 6];
        assert_eq!(pack(ChannelMode(1), &ch, &mut p), Ok(6));
        assert_eq!(p, [0xFF, 0x00, 0xAA, 0x55, 0b00_10_01_11, 0b00_01_10_11]);
        let mut out = [0u16; 8];
        assert_eq!(unpack(ChannelMode(1), &p, &mut out), Ok(8));
        assert_eq!(out, [0x3FF, 0x100, 0x2AA, 0x055, 12, 345, 678, 1011]);
    }
}
