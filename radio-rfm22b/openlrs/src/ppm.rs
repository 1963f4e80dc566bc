//! PPM input of the TX (`processPulse`, TX.h): pulse widths in µs, edge to edge. A pulse over
//! 2500 µs is sync, one over 700 µs a channel; anything else, or a 17th channel, drops the
//! frame (OpenLRSng `TX.h` input capture).

use super::channels::{CENTER_BITS, us_to_bits};

/// Channels a PPM frame may carry.
pub const PPM_CHANNELS: usize = 16;
/// Sync pulses are longer than this (µs).
pub const SYNC_MIN_US: u16 = 2500;
/// Channel pulses are longer than this (µs).
pub const CHANNEL_MIN_US: u16 = 700;
/// `TX_CONFIG_GETMINCH()` default: a frame needs more than 5 channels.
pub const DEFAULT_MIN_CHANNELS: u8 = 5;

/// Accumulates pulses into channel frames.
#[derive(Debug, Clone)]
pub struct PpmDecoder {
    min_channels: u8,
    /// `None` after a glitch or before the first sync: ignore pulses until the next sync.
    count: Option<usize>,
    work: [u16; PPM_CHANNELS],
    channels: [u16; PPM_CHANNELS],
}

/// What one pulse did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pulse {
    /// A channel value was collected.
    Channel,
    /// Sync ended a frame of this many channels, now in [`PpmDecoder::channels`].
    FrameAccepted {
        /// Channels in the frame.
        channels: usize,
    },
    /// Sync ended a frame that was too short, glitched or over 16 channels.
    FrameDropped,
    /// A glitch or a 17th channel: the rest of this frame is ignored.
    Glitch,
}

impl PpmDecoder {
    /// A decoder that accepts frames of more than `min_channels` channels (0 = any).
    pub fn new(min_channels: u8) -> Self {
        Self {
            min_channels,
            count: None,
            work: [0; PPM_CHANNELS],
            channels: [CENTER_BITS; PPM_CHANNELS],
        }
    }

    /// The last accepted channel values (10-bit), centre until the first frame.
    pub fn channels(&self) -> &[u16; PPM_CHANNELS] {
        &self.channels
    }

    /// Feeds one pulse width in µs.
    pub fn pulse(&mut self, width_us: u16) -> Pulse {
        if width_us > SYNC_MIN_US {
            let outcome = match self.count {
                Some(n) if n > usize::from(self.min_channels) => {
                    for (dst, &src) in self.channels.iter_mut().zip(self.work.iter()).take(n) {
                        *dst = src;
                    }
                    Pulse::FrameAccepted { channels: n }
                }
                _ => Pulse::FrameDropped,
            };
            self.count = Some(0);
            return outcome;
        }
        match self.count {
            Some(n) if width_us > CHANNEL_MIN_US && n < PPM_CHANNELS => {
                if let Some(slot) = self.work.get_mut(n) {
                    *slot = us_to_bits(width_us);
                }
                self.count = Some(n + 1);
                Pulse::Channel
            }
            _ => {
                self.count = None;
                Pulse::Glitch
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_channels_accepted() {
        let mut d = PpmDecoder::new(DEFAULT_MIN_CHANNELS);
        assert_eq!(d.pulse(1500), Pulse::Glitch);
        assert_eq!(d.pulse(5000), Pulse::FrameDropped);
        for w in [1100, 1200, 1300, 1400, 1500, 1600] {
            assert_eq!(d.pulse(w), Pulse::Channel);
        }
        assert_eq!(d.pulse(9000), Pulse::FrameAccepted { channels: 6 });
        assert_eq!(d.channels()[..7], [112, 212, 312, 412, 512, 612, 512]);
    }
}
