//! Frequency bands, the channel grid, and the pseudo-random hop sequence derived from the
//! bind ID: a permutation of all channels, so no channel repeats within one hop cycle.

/// Channels per band and entries per hop cycle. A power of two so the 8-bit slot counter
/// carried in every frame (which wraps at 256) always names a whole number of hop cycles.
pub const HOP_CHANNELS: usize = 32;

/// Radio band.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Band {
    /// 430–440 MHz (the 70 cm allocation Tau Labs and OpenLRSng use; licence needed outside
    /// the 433.05–434.79 MHz LPD sub-band).
    Mhz433,
    /// 863–870 MHz (EU SRD).
    Mhz868,
    /// 902–928 MHz (US ISM; ExpressLRS' FCC915 grid spans the same 903.5–926.9 MHz).
    Mhz915,
}

impl Band {
    /// Frequency of channel 0.
    pub const fn base_hz(self) -> u32 {
        match self {
            Band::Mhz433 => 430_200_000,
            Band::Mhz868 => 863_150_000,
            Band::Mhz915 => 903_500_000,
        }
    }

    /// Channel spacing. A multiple of 10 kHz: the Si4432 hop step register (0x7A) counts in
    /// 10 kHz in every band (carrier formula).
    pub const fn spacing_hz(self) -> u32 {
        match self {
            Band::Mhz433 => 300_000,
            Band::Mhz868 => 210_000,
            Band::Mhz915 => 750_000,
        }
    }

    /// Frequency of grid channel `channel` (0..[`HOP_CHANNELS`]).
    pub const fn channel_hz(self, channel: u8) -> u32 {
        self.base_hz() + channel as u32 * self.spacing_hz()
    }

    /// The fixed bind frequency: mid-band, off the hop grid so bind traffic never lands on a
    /// bound link's channel.
    pub const fn bind_hz(self) -> u32 {
        match self {
            Band::Mhz433 => 434_050_000,
            Band::Mhz868 => 868_300_000,
            Band::Mhz915 => 915_125_000,
        }
    }

    /// Wire code (bind packets).
    pub const fn code(self) -> u8 {
        match self {
            Band::Mhz433 => 0,
            Band::Mhz868 => 1,
            Band::Mhz915 => 2,
        }
    }

    /// Inverse of [`Band::code`].
    pub const fn from_code(code: u8) -> Option<Band> {
        match code {
            0 => Some(Band::Mhz433),
            1 => Some(Band::Mhz868),
            2 => Some(Band::Mhz915),
            _ => None,
        }
    }
}

/// SplitMix32-style mixer (Steele et al., "Fast splittable pseudorandom number generators",
/// 2014, with 32-bit constants): every input bit affects every output bit, so IDs that differ
/// in one bit give unrelated sequences (Tau Labs' list used only the ID's low byte, §1b).
pub const fn mix32(mut x: u32) -> u32 {
    x = x.wrapping_add(0x9E37_79B9);
    x = (x ^ (x >> 16)).wrapping_mul(0x85EB_CA6B);
    x = (x ^ (x >> 13)).wrapping_mul(0xC2B2_AE35);
    x ^ (x >> 16)
}

/// The hop sequence of one bound link.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HopSequence {
    channels: [u8; HOP_CHANNELS],
}

impl HopSequence {
    /// The sequence for `bind_id`: a Fisher–Yates shuffle of the grid driven by a counter-mode
    /// mixer seeded with the ID. A shuffle (not "draw and reject duplicates", Tau Labs' bug)
    /// is a permutation by construction.
    pub fn new(bind_id: u32) -> Self {
        let mut channels = [0u8; HOP_CHANNELS];
        for (value, slot) in (0u8..).zip(channels.iter_mut()) {
            *slot = value;
        }
        let mut counter = bind_id;
        for i in (1..HOP_CHANNELS).rev() {
            counter = counter.wrapping_add(1);
            // i < 32, so the modulo bias of a 32-bit draw is below 1e-8.
            let j = (mix32(counter ^ 0x5EED_0F0F) % (i as u32 + 1)) as usize;
            channels.swap(i, j);
        }
        Self { channels }
    }

    /// Grid channel for hop index `index` (taken modulo the cycle length).
    pub fn channel(&self, index: usize) -> u8 {
        self.channels
            .get(index % HOP_CHANNELS)
            .copied()
            .unwrap_or(0)
    }

    /// Grid channel used in slot `slot` (one hop per slot).
    pub fn channel_for_slot(&self, slot: u32) -> u8 {
        self.channel(slot as usize % HOP_CHANNELS)
    }

    /// The whole cycle.
    pub fn channels(&self) -> &[u8; HOP_CHANNELS] {
        &self.channels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequences_are_permutations() {
        for id in [0u32, 1, 2, 0xDEAD_BEEF, 0xFFFF_FFFF, 12345] {
            let seq = HopSequence::new(id);
            let mut seen = [false; HOP_CHANNELS];
            for &ch in seq.channels() {
                assert!(!seen[ch as usize], "duplicate {ch} for id {id:#x}");
                seen[ch as usize] = true;
            }
            assert!(seen.iter().all(|s| *s));
        }
    }

    #[test]
    fn sequences_depend_on_every_id_bit() {
        let base = HopSequence::new(0x1234_5678);
        for bit in 0..32 {
            let other = HopSequence::new(0x1234_5678 ^ (1 << bit));
            let same = base
                .channels()
                .iter()
                .zip(other.channels())
                .filter(|(a, b)| a == b)
                .count();
            // A random pair of permutations agrees in ~1 place on average.
            assert!(same < 8, "bit {bit}: {same} equal positions");
        }
    }

    #[test]
    fn deterministic() {
        assert_eq!(HopSequence::new(42), HopSequence::new(42));
    }

    #[test]
    fn grids_stay_in_band() {
        let last = (HOP_CHANNELS - 1) as u8;
        assert_eq!(Band::Mhz433.channel_hz(last), 439_500_000);
        assert!(Band::Mhz868.channel_hz(0) >= 863_000_000);
        assert!(Band::Mhz868.channel_hz(last) <= 870_000_000);
        assert_eq!(Band::Mhz915.channel_hz(last), 926_750_000);
        for band in [Band::Mhz433, Band::Mhz868, Band::Mhz915] {
            assert_eq!(band.spacing_hz() % 10_000, 0);
            assert_eq!(Band::from_code(band.code()), Some(band));
            let on_grid = (0..HOP_CHANNELS as u8).any(|c| band.channel_hz(c) == band.bind_hz());
            assert!(!on_grid);
        }
    }
}
