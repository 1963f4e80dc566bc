//! Fresh link identities: avr-libc's `random()` (Park–Miller "minimal standard", which
//! OpenLRSng seeds from `micros()`), `bindRandomize()` and the adaptive hop-channel picker
//! `chooseChannelsPerRSSI()`. Seeds are injected, never read.

use super::bind::{BindData, MAX_HOPS};

/// avr-libc `random()`: x ← 16807·x mod (2³¹ − 1), computed with Schrage's method on a
/// signed 32-bit state exactly as AVR does (so seeds ≥ 2³¹ behave as they do there).
#[derive(Debug, Clone)]
pub struct AvrRandom {
    state: u32,
}

impl AvrRandom {
    /// `srandom(seed)`.
    pub const fn new(seed: u32) -> Self {
        Self { state: seed }
    }

    /// `random()`: the next value in 0..2³¹.
    pub fn next_u31(&mut self) -> u32 {
        // The state is an `unsigned long` read into a signed `long`.
        let mut x = self.state as i32;
        if x == 0 {
            x = 123_459_876;
        }
        let hi = x / 127_773;
        let lo = x % 127_773;
        x = 16_807i32
            .wrapping_mul(lo)
            .wrapping_sub(2_836i32.wrapping_mul(hi));
        if x < 0 {
            x = x.wrapping_add(0x7FFF_FFFF);
        }
        self.state = x as u32;
        self.state % 0x8000_0000
    }
}

/// `bindRandomize(randomChannels)` with `micros()` = `seed` (OpenLRSng retries while 0).
///
/// The magic is four bytes of `random() % 255`, MSB first, so no byte is 0xFF. With
/// `random_channels` each existing hop slot gets a distinct channel 1..50 whose frequency
/// stays at or below `max_frequency_hz`; after 255 draws it gives up and restores
/// `fallback` (OpenLRSng's `bindInitDefaults()`).
pub fn bind_randomize(
    data: &mut BindData,
    seed: u32,
    random_channels: bool,
    max_frequency_hz: u32,
    fallback: &BindData,
) {
    let mut rng = AvrRandom::new(seed);
    data.rf_magic = (0..4).fold(0u32, |magic, _| (magic << 8) + rng.next_u31() % 255);
    if !random_channels {
        return;
    }
    let mut draws: u8 = 0;
    let mut c = 0;
    while c < MAX_HOPS && data.hop_channels.get(c).is_some_and(|&ch| ch != 0) {
        loop {
            if draws == 255 {
                *data = *fallback;
                return;
            }
            draws += 1;
            let ch = (rng.next_u31() % 50 + 1) as u8;
            let taken = data
                .hop_channels
                .get(..c)
                .is_some_and(|used| used.contains(&ch));
            let frequency_hz = u64::from(data.rf_frequency_hz)
                + u64::from(ch) * u64::from(data.rf_channel_spacing) * 10_000;
            if !taken && frequency_hz <= u64::from(max_frequency_hz) {
                if let Some(slot) = data.hop_channels.get_mut(c) {
                    *slot = ch;
                }
                break;
            }
        }
        c += 1;
    }
}

/// Channels the picker scans: 1..254.
pub const SCAN_CHANNELS: usize = 254;

/// `chooseChannelsPerRSSI()` given the maximum RSSI seen on each channel 1..254
/// (`max_rssi[ch − 1]`). Replaces the first `hop_count` hop slots.
///
/// Channels above `max_frequency_hz` are blocked. Each pick takes the quietest channel
/// (lowest number on ties), blocks ±1 (255) and marks ±2 as 200, even if they were blocked —
/// that is what upstream does. The picks are sorted, then element i is swapped with
/// i + n/2 for even i < n/2 so consecutive hops land far apart. Upstream scans with the
/// wrong frequency (it indexes `hopchannel[ch]`) and overflows its 20-entry array for
/// n > 20; this takes the intended RSSI per channel and handles up to 24.
pub fn choose_channels_per_rssi(
    data: &mut BindData,
    max_rssi: &[u8; SCAN_CHANNELS],
    max_frequency_hz: u32,
) {
    let n = data.hop_count();
    // Index 0 unused so that indices are channel numbers, as upstream.
    let mut rssi = [255u8; SCAN_CHANNELS + 1];
    for (ch, (slot, &measured)) in (1u32..).zip(rssi.iter_mut().skip(1).zip(max_rssi.iter())) {
        let f = u64::from(data.rf_frequency_hz)
            + u64::from(ch) * u64::from(data.rf_channel_spacing) * 10_000;
        *slot = if f > u64::from(max_frequency_hz) {
            255
        } else {
            measured
        };
    }
    let mut picked = [0u8; MAX_HOPS];
    for pick in picked.iter_mut().take(n) {
        let mut lowest = 1usize;
        let mut lowest_rssi = 255u8;
        for (ch, &value) in rssi.iter().enumerate().skip(1) {
            if value < lowest_rssi {
                lowest_rssi = value;
                lowest = ch;
            }
        }
        *pick = lowest as u8;
        for (offset, mark) in [(0isize, 255u8), (-1, 255), (1, 255), (-2, 200), (2, 200)] {
            let ch = lowest as isize + offset;
            if (1..=SCAN_CHANNELS as isize).contains(&ch)
                && let Some(slot) = rssi.get_mut(ch as usize)
            {
                *slot = mark;
            }
        }
    }
    let picked = picked.get_mut(..n).unwrap_or_default();
    picked.sort_unstable();
    let half = n / 2;
    for i in (0..half).step_by(2) {
        picked.swap(i, i + half);
    }
    for (slot, &ch) in data.hop_channels.iter_mut().zip(picked.iter()) {
        *slot = ch;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn park_miller_first_values() {
        let mut r = AvrRandom::new(1);
        assert_eq!(r.next_u31(), 16_807);
        assert_eq!(r.next_u31(), 282_475_249);
    }
}
