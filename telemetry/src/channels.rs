//! RC channel values and their bit packing: 16 channels × 11 bit (CRSF resolution, 22 bytes)
//! or a compact 8 × 11 bit (11 bytes), plus per-channel failsafe values.

/// Channels carried in full mode.
pub const MAX_CHANNELS: usize = 16;
/// Bits per channel value: CRSF's 0..=2047 (172 ↔ 988 µs, 992 ↔ 1500 µs, 1811 ↔ 2012 µs).
pub const CHANNEL_BITS: u32 = 11;
/// Largest channel value.
pub const CHANNEL_MAX: u16 = (1 << CHANNEL_BITS) - 1;
/// CRSF's centre value (1500 µs).
pub const CHANNEL_CENTER: u16 = 992;

/// Channel values, always 16 wide; the compact format carries only the first 8.
pub type Channels = [u16; MAX_CHANNELS];

/// How many channels an uplink packet carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChannelFormat {
    /// 16 channels, 22 bytes.
    Full16,
    /// 8 channels, 11 bytes (for the long-range mode, leaving room for uplink telemetry).
    Compact8,
}

impl ChannelFormat {
    /// Channels carried.
    pub const fn count(self) -> usize {
        match self {
            ChannelFormat::Full16 => 16,
            ChannelFormat::Compact8 => 8,
        }
    }

    /// Packed size in bytes.
    pub const fn packed_bytes(self) -> usize {
        (self.count() * CHANNEL_BITS as usize).div_ceil(8)
    }

    /// Wire code (bind packets).
    pub const fn code(self) -> u8 {
        match self {
            ChannelFormat::Full16 => 0,
            ChannelFormat::Compact8 => 1,
        }
    }

    /// Inverse of [`ChannelFormat::code`].
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(ChannelFormat::Full16),
            1 => Some(ChannelFormat::Compact8),
            _ => None,
        }
    }
}

/// Packs the first `format.count()` channels, LSB first (the CRSF RC-channels layout), into
/// `out`, which must be exactly `format.packed_bytes()` long; returns false otherwise. Values
/// above 2047 are clamped.
pub fn pack(channels: &Channels, format: ChannelFormat, out: &mut [u8]) -> bool {
    if out.len() != format.packed_bytes() {
        return false;
    }
    out.fill(0);
    let mut bit = 0usize;
    for &value in channels.iter().take(format.count()) {
        let v = u32::from(value.min(CHANNEL_MAX));
        for k in 0..CHANNEL_BITS as usize {
            if v & (1 << k) != 0
                && let Some(byte) = out.get_mut((bit + k) / 8)
            {
                *byte |= 1 << ((bit + k) % 8);
            }
        }
        bit += CHANNEL_BITS as usize;
    }
    true
}

/// Unpacks `format.count()` channels from `bytes` into the front of `channels`, leaving the
/// rest unchanged; returns false (touching nothing) if `bytes` has the wrong length.
pub fn unpack(bytes: &[u8], format: ChannelFormat, channels: &mut Channels) -> bool {
    if bytes.len() != format.packed_bytes() {
        return false;
    }
    let mut bit = 0usize;
    for value in channels.iter_mut().take(format.count()) {
        let mut v = 0u16;
        for k in 0..CHANNEL_BITS as usize {
            let set = bytes
                .get((bit + k) / 8)
                .is_some_and(|b| b & (1 << ((bit + k) % 8)) != 0);
            if set {
                v |= 1 << k;
            }
        }
        *value = v;
        bit += CHANNEL_BITS as usize;
    }
    true
}

/// What one channel does when the link is lost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Failsafe {
    /// Keep the last received value.
    Hold,
    /// Go to this value.
    Value(u16),
}

/// Per-channel failsafe settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FailsafeValues(pub [Failsafe; MAX_CHANNELS]);

impl Default for FailsafeValues {
    /// Sticks centred, throttle (channel 3, AETR order) at its minimum, aux channels held.
    fn default() -> Self {
        let mut values = [Failsafe::Hold; MAX_CHANNELS];
        for (i, v) in values.iter_mut().enumerate().take(4) {
            *v = Failsafe::Value(if i == 2 { 172 } else { CHANNEL_CENTER });
        }
        Self(values)
    }
}

impl FailsafeValues {
    /// Every channel set to the matching value in `channels` (the "save failsafe" command).
    pub fn from_channels(channels: &Channels) -> Self {
        Self(channels.map(Failsafe::Value))
    }

    /// Applies the failsafe settings to the last output `channels`.
    pub fn apply(&self, channels: &mut Channels) {
        for (value, rule) in channels.iter_mut().zip(self.0.iter()) {
            if let Failsafe::Value(v) = rule {
                *value = *v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_round_trip_and_layout() {
        let mut ch = [0u16; 16];
        for (i, c) in ch.iter_mut().enumerate() {
            *c = (i as u16 * 131 + 7) & CHANNEL_MAX;
        }
        let mut buf = [0u8; 22];
        assert!(pack(&ch, ChannelFormat::Full16, &mut buf));
        // CRSF layout: byte 0 = ch0 bits 0..7; byte 1 = ch0 bits 8..10 | ch1 bits 0..4 << 3.
        assert_eq!(buf[0], 7);
        assert_eq!(buf[1], ((138 & 0x1F) << 3) as u8);
        let mut out = [0u16; 16];
        assert!(unpack(&buf, ChannelFormat::Full16, &mut out));
        assert_eq!(out, ch);
    }

    #[test]
    fn compact_carries_eight_and_keeps_the_rest() {
        let ch = [2047u16; 16];
        let mut buf = [0u8; 11];
        assert!(pack(&ch, ChannelFormat::Compact8, &mut buf));
        assert_eq!(buf, [0xFF; 11]);
        let mut out = [5u16; 16];
        assert!(unpack(&buf, ChannelFormat::Compact8, &mut out));
        assert_eq!(&out[..8], &[2047; 8]);
        assert_eq!(&out[8..], &[5; 8]);
    }

    #[test]
    fn wrong_lengths_are_refused() {
        let mut buf = [0u8; 21];
        assert!(!pack(&[0; 16], ChannelFormat::Full16, &mut buf));
        let mut out = [9u16; 16];
        assert!(!unpack(&buf, ChannelFormat::Full16, &mut out));
        assert_eq!(out, [9; 16]);
    }

    #[test]
    fn clamps_out_of_range() {
        let mut ch = [0u16; 16];
        ch[0] = 5000;
        let mut buf = [0u8; 22];
        pack(&ch, ChannelFormat::Full16, &mut buf);
        let mut out = [0u16; 16];
        unpack(&buf, ChannelFormat::Full16, &mut out);
        assert_eq!(out[0], 2047);
        assert_eq!(out[1], 0);
    }

    #[test]
    fn failsafe_applies_per_channel() {
        let mut ch = [1500u16; 16];
        FailsafeValues::default().apply(&mut ch);
        assert_eq!(&ch[..4], &[992, 992, 172, 992]);
        assert_eq!(ch[4], 1500);
        let saved = FailsafeValues::from_channels(&[300; 16]);
        saved.apply(&mut ch);
        assert_eq!(ch, [300; 16]);
    }
}
