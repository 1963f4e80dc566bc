//! RC channel values and their bit packing: 16 channels × 11 bit (CRSF resolution, 22 bytes),
//! a compact 8 × 11 bit (11 bytes), or the stick format of F700 (the four sticks and three
//! of the twelve aux channels per packet, round-robin, 10 bytes), plus per-channel failsafe
//! values.

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
    /// 16 channels in 10 bytes, as ExpressLRS' fast modes do it: channels 1–4 (the sticks)
    /// at full 11 bits in every packet, and aux group `g` (channels `5+3g ..= 7+3g`, g = 0..3)
    /// after them, the group index in bits 77–78; bit 79 is reserved (0). The sender cycles
    /// the groups, so every aux channel travels in one packet of four.
    Sticks16,
}

/// Aux channels per [`ChannelFormat::Sticks16`] packet.
pub const STICKS16_AUX_PER_PACKET: usize = 3;
/// Aux groups of [`ChannelFormat::Sticks16`]: the 12 aux channels, 3 at a time.
pub const STICKS16_GROUPS: u8 = 4;
/// Channels that travel in every [`ChannelFormat::Sticks16`] packet.
pub const STICKS: usize = 4;

impl ChannelFormat {
    /// Channels carried.
    pub const fn count(self) -> usize {
        match self {
            ChannelFormat::Full16 | ChannelFormat::Sticks16 => 16,
            ChannelFormat::Compact8 => 8,
        }
    }

    /// Channels in one packet.
    pub const fn per_packet(self) -> usize {
        match self {
            ChannelFormat::Sticks16 => STICKS + STICKS16_AUX_PER_PACKET,
            _ => self.count(),
        }
    }

    /// Packed size in bytes (Sticks16: 77 channel bits and the 2-bit group, 10 bytes).
    pub const fn packed_bytes(self) -> usize {
        match self {
            ChannelFormat::Sticks16 => 10,
            _ => (self.count() * CHANNEL_BITS as usize).div_ceil(8),
        }
    }

    /// Aux groups the sender cycles through (1: every packet carries every channel).
    pub const fn groups(self) -> u8 {
        match self {
            ChannelFormat::Sticks16 => STICKS16_GROUPS,
            _ => 1,
        }
    }

    /// Wire code (bind packets).
    pub const fn code(self) -> u8 {
        match self {
            ChannelFormat::Full16 => 0,
            ChannelFormat::Compact8 => 1,
            ChannelFormat::Sticks16 => 2,
        }
    }

    /// Inverse of [`ChannelFormat::code`].
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(ChannelFormat::Full16),
            1 => Some(ChannelFormat::Compact8),
            2 => Some(ChannelFormat::Sticks16),
            _ => None,
        }
    }
}

/// Which channels a packet of `format` with aux group `group` carries, in packing order.
fn carried(format: ChannelFormat, group: u8) -> impl Iterator<Item = usize> {
    let (sticks, aux_from, aux_len) = match format {
        ChannelFormat::Sticks16 => (
            STICKS,
            STICKS + usize::from(group % STICKS16_GROUPS) * STICKS16_AUX_PER_PACKET,
            STICKS16_AUX_PER_PACKET,
        ),
        _ => (format.count(), 0, 0),
    };
    (0..sticks).chain(aux_from..aux_from + aux_len)
}

/// Bit offset of the [`ChannelFormat::Sticks16`] group index.
const GROUP_BIT: usize = (STICKS + STICKS16_AUX_PER_PACKET) * CHANNEL_BITS as usize;

fn put_bits(out: &mut [u8], bit: usize, value: u32, bits: usize) {
    for k in 0..bits {
        if value & (1 << k) != 0
            && let Some(byte) = out.get_mut((bit + k) / 8)
        {
            *byte |= 1 << ((bit + k) % 8);
        }
    }
}

fn get_bits(bytes: &[u8], bit: usize, bits: usize) -> u32 {
    let mut v = 0u32;
    for k in 0..bits {
        let set = bytes
            .get((bit + k) / 8)
            .is_some_and(|b| b & (1 << ((bit + k) % 8)) != 0);
        if set {
            v |= 1 << k;
        }
    }
    v
}

/// Packs the first `format.count()` channels, LSB first (the CRSF RC-channels layout), into
/// `out`, which must be exactly `format.packed_bytes()` long; returns false otherwise. Values
/// above 2047 are clamped. [`ChannelFormat::Sticks16`] packs aux group 0; see [`pack_group`].
pub fn pack(channels: &Channels, format: ChannelFormat, out: &mut [u8]) -> bool {
    pack_group(channels, format, 0, out)
}

/// [`pack`] with the aux group (`group mod format.groups()`) a
/// [`ChannelFormat::Sticks16`] packet carries; the other formats ignore it.
pub fn pack_group(channels: &Channels, format: ChannelFormat, group: u8, out: &mut [u8]) -> bool {
    if out.len() != format.packed_bytes() {
        return false;
    }
    out.fill(0);
    let mut bit = 0usize;
    for index in carried(format, group) {
        let value = channels.get(index).copied().unwrap_or(0);
        put_bits(
            out,
            bit,
            u32::from(value.min(CHANNEL_MAX)),
            CHANNEL_BITS as usize,
        );
        bit += CHANNEL_BITS as usize;
    }
    if format == ChannelFormat::Sticks16 {
        put_bits(out, GROUP_BIT, u32::from(group % STICKS16_GROUPS), 2);
    }
    true
}

/// Unpacks the channels a packet of `format` carries from `bytes` into `channels`, leaving
/// the rest unchanged; returns false (touching nothing) if `bytes` has the wrong length (or,
/// for [`ChannelFormat::Sticks16`], its reserved bit set).
pub fn unpack(bytes: &[u8], format: ChannelFormat, channels: &mut Channels) -> bool {
    unpack_mask(bytes, format, channels).is_some()
}

/// [`unpack`], answering which channels were refreshed (bit `i` = channel `i`), or `None`
/// when nothing was touched.
pub fn unpack_mask(bytes: &[u8], format: ChannelFormat, channels: &mut Channels) -> Option<u16> {
    if bytes.len() != format.packed_bytes() {
        return None;
    }
    let group = if format == ChannelFormat::Sticks16 {
        if get_bits(bytes, GROUP_BIT + 2, 1) != 0 {
            return None;
        }
        get_bits(bytes, GROUP_BIT, 2) as u8
    } else {
        0
    };
    let mut bit = 0usize;
    let mut mask = 0u16;
    for index in carried(format, group) {
        if let Some(value) = channels.get_mut(index) {
            *value = get_bits(bytes, bit, CHANNEL_BITS as usize) as u16;
            mask |= 1 << index;
        }
        bit += CHANNEL_BITS as usize;
    }
    Some(mask)
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
    fn sticks16_carries_the_sticks_and_one_aux_group() {
        let mut ch = [0u16; 16];
        for (i, c) in ch.iter_mut().enumerate() {
            *c = (i as u16 * 131 + 7) & CHANNEL_MAX;
        }
        ch[0] = 2047;
        let mut seen = 0u16;
        for group in 0..STICKS16_GROUPS {
            let mut buf = [0u8; 10];
            assert!(pack_group(&ch, ChannelFormat::Sticks16, group, &mut buf));
            let mut out = [5u16; 16];
            let mask = unpack_mask(&buf, ChannelFormat::Sticks16, &mut out).unwrap();
            let first = 4 + 3 * usize::from(group);
            assert_eq!(mask, 0x000F | (0b111 << first));
            for i in 0..16 {
                let expected = if mask & (1 << i) != 0 { ch[i] } else { 5 };
                assert_eq!(out[i], expected, "group {group} channel {i}");
            }
            seen |= mask;
        }
        // Four packets carry all sixteen channels, the sticks in each.
        assert_eq!(seen, 0xFFFF);
        assert_eq!(ChannelFormat::Sticks16.per_packet(), 7);
    }

    #[test]
    fn sticks16_refuses_its_reserved_bit() {
        let mut buf = [0u8; 10];
        buf[9] = 0x80;
        let mut out = [5u16; 16];
        assert!(!unpack(&buf, ChannelFormat::Sticks16, &mut out));
        assert_eq!(out, [5; 16]);
        assert_eq!(ChannelFormat::from_code(2), Some(ChannelFormat::Sticks16));
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
