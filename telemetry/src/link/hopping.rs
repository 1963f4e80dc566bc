//! Frequency bands, the channel grid, and the pseudo-random hop sequence derived from the
//! bind ID: a permutation of all channels, so no channel repeats within one hop cycle.
//!
//! Band plans and what they mean legally (the user's call; nothing here is legal advice):
//!
//! * [`Band::Mhz433`] — 430.2 … 439.5 MHz, 300 kHz grid: the 70 cm **amateur** band, as
//!   Tau Labs and OpenLRSng use it. A radio-amateur licence is needed. The factory band
//!   (module and flight side must agree on it to bind).
//! * [`Band::Ism433`] — only the 433.05 … 434.79 MHz ISM/LPD sub-band, licence-exempt as a
//!   short-range device in ITU Region 1 under national rules (in the EU: ERC/REC 70-03,
//!   10 mW e.r.p. with a duty-cycle limit). The 32 hop positions sit on a per-rate grid
//!   whose occupied bandwidth (Carson: 2 × (deviation + bit rate / 2)) stays inside the
//!   sub-band; neighbouring positions overlap, so the independent channels are fewer:
//!
//!   | mode | deviation | occupied | grid | spans (edges) | independent channels |
//!   |---|---|---|---|---|---|
//!   | L50 | 30 kHz | 79 kHz | 50 kHz | 433.105 … 434.735 MHz | 21 |
//!   | M100 | 45 kHz | 148 kHz | 50 kHz | 433.071 … 434.769 MHz | 11 |
//!   | F250 | 90 kHz | 308 kHz | 40 kHz | 433.146 … 434.694 MHz | 5 |
//!   | F500 | 150 kHz | 556 kHz | 30 kHz | 433.177 … 434.663 MHz | 3 |
//!
//!   (independent channels = 1.74 MHz / occupied bandwidth, rounded down). Binding happens on
//!   433.920 MHz, off every grid.
//! * [`Band::Mhz868`] — 863.15 … 869.66 MHz, 210 kHz grid: the EU SRD band, across
//!   several ERC/REC 70-03 sub-bands (863–865, 865–868, 868.0–868.6, 868.7–869.2,
//!   869.4–869.65 MHz) whose duty-cycle limits are 0.1 … 10 %. The link hops over all of
//!   them and transmits in up to 3 of 4 slots (the uplink), i.e. each channel at most once
//!   per 32-slot cycle but the band as a whole far above any of those limits: it keeps
//!   **no** sub-band's duty cycle and is not licence-exempt as it stands.
//! * [`Band::Mhz915`] — 903.5 … 926.75 MHz, 750 kHz grid: the US 902–928 MHz ISM band
//!   (FCC §15.247 frequency hopping; 32 channels is fewer than the 50 it asks of a
//!   narrow-band hopper).

use super::rate::RateMode;

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
    /// 433.05–434.79 MHz only (ISM / LPD, licence-exempt at low power): a per-rate grid
    /// ([`Band::grid`]).
    Ism433,
}

/// Centre of the 433.05–434.79 MHz ISM sub-band.
const ISM433_CENTRE_HZ: u32 = 433_920_000;

impl Band {
    /// The hop grid at `rate`: frequency of channel 0 and channel spacing. The spacing is a
    /// multiple of 10 kHz: the Si4432 hop step register (0x7A) counts in 10 kHz in every
    /// band (carrier formula). Only [`Band::Ism433`] depends on the rate: its grid narrows
    /// as the occupied bandwidth grows, centred on 433.92 MHz.
    pub const fn grid(self, rate: RateMode) -> (u32, u32) {
        match self {
            Band::Mhz433 => (430_200_000, 300_000),
            Band::Mhz868 => (863_150_000, 210_000),
            Band::Mhz915 => (903_500_000, 750_000),
            Band::Ism433 => {
                let spacing = match rate {
                    RateMode::L50 | RateMode::M100 => 50_000,
                    RateMode::F250 => 40_000,
                    RateMode::F500 | RateMode::F700 => 30_000,
                };
                // Centre the 31 spacings on the sub-band's centre.
                let half_span = spacing * (HOP_CHANNELS as u32 - 1) / 2;
                (ISM433_CENTRE_HZ - half_span, spacing)
            }
        }
    }

    /// Frequency of grid channel `channel` (0..[`HOP_CHANNELS`]) at `rate`.
    pub const fn channel_hz_at(self, channel: u8, rate: RateMode) -> u32 {
        let (base, spacing) = self.grid(rate);
        base + channel as u32 * spacing
    }

    /// Frequency of channel 0 at L50 (every band but [`Band::Ism433`] has only this grid).
    pub const fn base_hz(self) -> u32 {
        self.grid(RateMode::L50).0
    }

    /// Channel spacing at L50 (every band but [`Band::Ism433`] has only this grid).
    pub const fn spacing_hz(self) -> u32 {
        self.grid(RateMode::L50).1
    }

    /// Frequency of grid channel `channel` at L50 ([`Band::channel_hz_at`] for any rate).
    pub const fn channel_hz(self, channel: u8) -> u32 {
        self.channel_hz_at(channel, RateMode::L50)
    }

    /// The fixed bind frequency: mid-band, off the hop grid so bind traffic never lands on a
    /// bound link's channel.
    pub const fn bind_hz(self) -> u32 {
        match self {
            Band::Mhz433 => 434_050_000,
            Band::Mhz868 => 868_300_000,
            Band::Mhz915 => 915_125_000,
            // Half-way between grid positions at every rate.
            Band::Ism433 => ISM433_CENTRE_HZ,
        }
    }

    /// Wire code (bind packets).
    pub const fn code(self) -> u8 {
        match self {
            Band::Mhz433 => 0,
            Band::Mhz868 => 1,
            Band::Mhz915 => 2,
            Band::Ism433 => 3,
        }
    }

    /// Inverse of [`Band::code`].
    pub const fn from_code(code: u8) -> Option<Band> {
        match code {
            0 => Some(Band::Mhz433),
            1 => Some(Band::Mhz868),
            2 => Some(Band::Mhz915),
            3 => Some(Band::Ism433),
            _ => None,
        }
    }
}

/// Every band, in code order.
pub const BANDS: [Band; 4] = [Band::Mhz433, Band::Mhz868, Band::Mhz915, Band::Ism433];

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
        for band in BANDS {
            assert_eq!(Band::from_code(band.code()), Some(band));
            for rate in RateMode::ALL {
                let (_, spacing) = band.grid(rate);
                assert_eq!(spacing % 10_000, 0);
                let on_grid =
                    (0..HOP_CHANNELS as u8).any(|c| band.channel_hz_at(c, rate) == band.bind_hz());
                assert!(!on_grid, "{band:?} {rate:?}");
            }
        }
    }

    #[test]
    fn the_ism_plan_keeps_the_occupied_bandwidth_inside_433_05_to_434_79() {
        let last = (HOP_CHANNELS - 1) as u8;
        // Deviation per mode (radio_rfm22b::link::modem_for) and Carson's bandwidth.
        for (rate, deviation, independent) in [
            (RateMode::L50, 30_000u32, 21u32),
            (RateMode::M100, 45_000, 11),
            (RateMode::F250, 90_000, 5),
            (RateMode::F500, 150_000, 3),
            (RateMode::F700, 150_000, 3),
        ] {
            let occupied = 2 * (deviation + rate.bit_rate_bps() / 2);
            let low = Band::Ism433.channel_hz_at(0, rate) - occupied / 2;
            let high = Band::Ism433.channel_hz_at(last, rate) + occupied / 2;
            assert!(low >= 433_050_000, "{rate:?}: {low}");
            assert!(high <= 434_790_000, "{rate:?}: {high}");
            assert_eq!(1_740_000 / occupied, independent, "{rate:?}");
        }
    }
}
