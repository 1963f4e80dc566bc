//! PPM output for the receiver role: frames as slot durations the firmware loads into the
//! nRF52840 PWM (`SequencePwm`, waveform load mode: one PWM period per slot).
//!
//! A frame is one slot per channel (a `pulse_us` pulse, then the line idles until the
//! channel period is over), one sync slot (its pulse ends the last channel) and an idle
//! tail slot with no pulse. The tail is what makes frame joins glitch-free: if the next
//! frame starts late, the PWM repeats the last slot, and a slot without a pulse only
//! stretches the sync gap (we keep ≥ 4.5 ms of it: decoders look for "longer than 2.5–4 ms" —
//! openLRSng 2.5 ms, Betaflight 2.7 ms, dRonin 3 ms, ExpressLRS' PPM input 4 ms of idle line). New
//! channel values are latched only when the firmware asks for the next frame, so a frame is never a
//! mix of old and new values.

use crate::channels::{ChannelFrame, MAX_CHANNELS, ticks_to_us};

/// What the output does while the link is in failsafe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FailsafeOutput {
    /// Keep sending the last values received.
    HoldLast,
    /// Stop the pulses (the flight controller sees "no PPM" and runs its own failsafe).
    StopPulses,
}

/// Output timing. The defaults are EdgeTX's PPM defaults (`radio/src/pulses/ppm.cpp`): 8
/// channels, 22.5 ms, 300 µs pulses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EncoderConfig {
    /// Channels per frame (1…16).
    pub channels: usize,
    /// Nominal frame length, µs.
    pub frame_us: u32,
    /// Separator pulse width, µs.
    pub pulse_us: u16,
    /// The sync gap is never shorter than this; the frame grows instead.
    pub min_sync_us: u32,
    /// Length of the pulse-free tail slot, µs (part of the sync gap).
    pub idle_tail_us: u16,
    /// Channel periods are clipped to this minimum, µs.
    pub min_width_us: u16,
    /// Channel periods are clipped to this maximum, µs.
    pub max_width_us: u16,
    /// Failsafe behaviour.
    pub failsafe: FailsafeOutput,
}

impl Default for EncoderConfig {
    fn default() -> Self {
        Self {
            channels: 8,
            frame_us: 22_500,
            pulse_us: 300,
            min_sync_us: 4_500,
            idle_tail_us: 1_000,
            // ±114 % around 1500 µs: 8 × 2100 µs still leaves a 5.7 ms sync in 22.5 ms.
            min_width_us: 900,
            max_width_us: 2_100,
            // Holding the last values would hold the throttle on a lost link.
            failsafe: FailsafeOutput::StopPulses,
        }
    }
}

/// Why an [`EncoderConfig`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// Channel count outside 1…16.
    ChannelCount,
    /// The pulse does not fit in the shortest channel or the tail does not fit in the sync.
    PulseTooLong,
    /// A slot would exceed the PWM's 15-bit COUNTERTOP (32 767 µs at 1 MHz).
    SlotTooLong,
    /// The idle tail must be at least 3 µs (the PWM's smallest COUNTERTOP).
    NoIdleTail,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::ChannelCount => "PPM output needs 1 to 16 channels",
            Self::PulseTooLong => "PPM pulse or idle tail longer than the slot holding it",
            Self::SlotTooLong => "PPM slot longer than the PWM counter's 32767 µs",
            Self::NoIdleTail => "PPM idle tail shorter than 3 µs",
        })
    }
}

impl core::error::Error for ConfigError {}

/// Most µs one PWM period can last at 1 MHz (COUNTERTOP is 15 bits).
pub const MAX_SLOT_US: u32 = 32_767;

/// One PWM period: a pulse of `pulse_us` at its start, then idle until `period_us`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Slot {
    /// Slot length, µs.
    pub period_us: u16,
    /// Pulse at the start of the slot, µs (0: none).
    pub pulse_us: u16,
}

/// One PPM frame as PWM slots: channels, then the sync slot, then the idle tail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    slots: [Slot; MAX_CHANNELS + 2],
    len: usize,
}

impl Frame {
    /// The slots in output order.
    pub fn slots(&self) -> &[Slot] {
        // Kept: `len` is only set by `build`, to channels + 2 with channels ≤ MAX_CHANNELS
        // checked when the encoder is made (the frame stays `Copy`, which a heapless::Vec
        // would not be).
        self.slots.get(..self.len).unwrap_or(&[])
    }

    /// Total frame length, µs.
    pub fn length_us(&self) -> u32 {
        self.slots().iter().map(|s| u32::from(s.period_us)).sum()
    }

    /// Writes the frame as nRF52840 PWM waveform words (PS §6.16, DECODER.LOAD = WaveForm):
    /// four words per slot, `[compare | polarity, 0, 0, COUNTERTOP]`. Bit 15 set makes the
    /// output high while the counter is below `compare` (embassy-nrf `DutyCycle::inverted`),
    /// so `pulse_high` selects positive pulses. Returns the number of words written, or
    /// `None` when `words` is too short.
    pub fn write_waveform(&self, words: &mut [u16], pulse_high: bool) -> Option<usize> {
        let polarity = if pulse_high { 0x8000 } else { 0 };
        let needed = self.len * 4;
        let out = words.get_mut(..needed)?;
        for (chunk, slot) in out.chunks_exact_mut(4).zip(self.slots()) {
            let compare = if slot.pulse_us == 0 {
                // Compare 0 never matches: the whole period stays at the idle level.
                0
            } else {
                slot.pulse_us | polarity
            };
            chunk.copy_from_slice(&[compare, 0, 0, slot.period_us]);
        }
        Some(needed)
    }
}

/// The double-buffered PPM generator.
#[derive(Debug, Clone)]
pub struct Encoder {
    config: EncoderConfig,
    current: Option<ChannelFrame>,
    pending: Option<ChannelFrame>,
    failsafe: bool,
}

impl Encoder {
    /// A generator that sends nothing until the first channels arrive.
    pub fn new(config: EncoderConfig) -> Result<Self, ConfigError> {
        if config.channels == 0 || config.channels > MAX_CHANNELS {
            return Err(ConfigError::ChannelCount);
        }
        if config.idle_tail_us < 3 {
            return Err(ConfigError::NoIdleTail);
        }
        let sync_slot_us = config
            .min_sync_us
            .saturating_sub(u32::from(config.idle_tail_us));
        if config.pulse_us >= config.min_width_us || u32::from(config.pulse_us) >= sync_slot_us {
            return Err(ConfigError::PulseTooLong);
        }
        let channel_count = u32::try_from(config.channels).unwrap_or(u32::MAX);
        let longest_sync_us = config
            .frame_us
            .saturating_sub(channel_count * u32::from(config.min_width_us))
            .max(config.min_sync_us);
        if longest_sync_us.saturating_sub(u32::from(config.idle_tail_us)) > MAX_SLOT_US {
            return Err(ConfigError::SlotTooLong);
        }
        Ok(Self {
            config,
            current: None,
            pending: None,
            failsafe: false,
        })
    }

    /// New values from the link; they take effect at the next frame boundary. Fresh values
    /// end a failsafe.
    pub fn set_channels(&mut self, channels: &ChannelFrame) {
        self.pending = Some(*channels);
        self.failsafe = false;
    }

    /// The link entered (true) or left (false) failsafe.
    pub fn set_failsafe(&mut self, active: bool) {
        self.failsafe = active;
    }

    /// Called by the firmware at each frame boundary: latches the pending values and
    /// returns the frame to play, or `None` when the line must stay idle (no values yet, or
    /// failsafe with [`FailsafeOutput::StopPulses`]).
    pub fn next_frame(&mut self) -> Option<Frame> {
        if let Some(pending) = self.pending.take() {
            self.current = Some(pending);
        }
        if self.failsafe && self.config.failsafe == FailsafeOutput::StopPulses {
            return None;
        }
        self.current.as_ref().map(|channels| self.build(channels))
    }

    fn build(&self, channels: &ChannelFrame) -> Frame {
        let config = &self.config;
        let mut frame = Frame {
            slots: [Slot::default(); MAX_CHANNELS + 2],
            len: 0,
        };
        let mut channels_us = 0u32;
        for (index, slot) in frame.slots.iter_mut().take(config.channels).enumerate() {
            let width_us = channels
                .get(index)
                .map_or(1_500, ticks_to_us)
                .clamp(config.min_width_us, config.max_width_us);
            channels_us += u32::from(width_us);
            *slot = Slot {
                period_us: width_us,
                pulse_us: config.pulse_us,
            };
        }
        let sync_us = config
            .frame_us
            .saturating_sub(channels_us)
            .max(config.min_sync_us);
        let tail_us = config.idle_tail_us;
        let sync_slot_us = sync_us.saturating_sub(u32::from(tail_us));
        let tail = [
            Slot {
                period_us: u16::try_from(sync_slot_us).unwrap_or(u16::MAX),
                pulse_us: config.pulse_us,
            },
            Slot {
                period_us: tail_us,
                pulse_us: 0,
            },
        ];
        for (slot, extra) in frame.slots.iter_mut().skip(config.channels).zip(tail) {
            *slot = extra;
        }
        frame.len = config.channels + 2;
        frame
    }
}

#[cfg(test)]
#[path = "encoder_tests.rs"]
mod tests;
