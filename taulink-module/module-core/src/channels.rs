//! Link channels: up to 16 stick/switch values at CRSF resolution, 11 bit, in CRSF ticks
//! like everywhere else in the workspace.
//!
//! The µs ↔ ticks mapping is CRSF's ([`taulink_handset::crsf::channels`], re-exported
//! here): the one CRSF transmitters use (ExpressLRS `fmap(us, 988, 2012, 172, 1811)`,
//! `src/lib/Handset/PPMHandset.cpp`), 988 µs ↔ 172 (−100 %), 1500 µs ↔ 992 (centre), 2012 µs ↔ 1811
//! (+100 %). Beyond ±100 % it extrapolates linearly and clips to the 11-bit range 0…2047
//! (≈ 881…2159 µs), so EdgeTX's extended limits (732…2268 µs) saturate instead of wrapping.

pub use taulink_handset::crsf::channels::{
    TICKS_CENTRE, TICKS_MAX, TICKS_MAX_NOMINAL, TICKS_MIN_NOMINAL, ticks_to_us, us_to_ticks,
};

/// Most channels a frame carries (PPM's 16-channel maximum, CRSF's 16 channels): the
/// link's 16.
pub use telemetry::channels::MAX_CHANNELS;

/// One frame of channel values in ticks as a handset protocol (PPM, CRSF) or the PPM output
/// carries it: 1…16 of them, each 0…2047, with the count the frame had. The link itself
/// always carries all 16 (`telemetry::channels::Channels`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelFrame {
    ticks: [u16; MAX_CHANNELS],
    count: u8,
}

impl ChannelFrame {
    /// `count` channels (clipped to 16), all centred.
    pub fn centered(count: usize) -> Self {
        Self {
            ticks: [TICKS_CENTRE; MAX_CHANNELS],
            count: u8::try_from(count.min(MAX_CHANNELS)).unwrap_or(0),
        }
    }

    /// Channels from ticks; ticks past the 16th are ignored, each is clipped to 2047.
    pub fn from_ticks(ticks: &[u16]) -> Self {
        let mut channels = Self::centered(ticks.len());
        for (slot, value) in channels.ticks.iter_mut().zip(ticks) {
            *slot = (*value).min(TICKS_MAX);
        }
        channels
    }

    /// How many channels the frame carries.
    pub fn count(&self) -> usize {
        usize::from(self.count)
    }

    /// The ticks, one per channel.
    pub fn as_slice(&self) -> &[u16] {
        // Kept: `count` never exceeds the array (every constructor bounds it); the type stays
        // `Copy`, which a heapless::Vec would not be.
        self.ticks.get(..self.count()).unwrap_or(&[])
    }

    /// Ticks of channel `index` (0-based), `None` past the count.
    pub fn get(&self, index: usize) -> Option<u16> {
        self.as_slice().get(index).copied()
    }

    /// Sets channel `index` (clipped to 2047); returns `false` past the count.
    pub fn set(&mut self, index: usize, value: u16) -> bool {
        let count = self.count();
        match self.ticks.get_mut(..count).and_then(|v| v.get_mut(index)) {
            Some(slot) => {
                *slot = value.min(TICKS_MAX);
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_clip_and_bound() {
        let mut ch = ChannelFrame::from_ticks(&[0, 3000, 992]);
        assert_eq!(ch.as_slice(), &[0, 2047, 992]);
        assert!(ch.set(1, 1000));
        assert!(!ch.set(3, 1000));
        assert_eq!(ch.get(1), Some(1000));
        assert_eq!(ch.get(3), None);
        assert_eq!(ChannelFrame::centered(20).count(), 16);
    }
}
