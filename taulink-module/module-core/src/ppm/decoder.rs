//! PPM input decoder fed with hardware edge timestamps (µs, free-running wrapping u32).
//!
//! The firmware captures one edge polarity only (TIMER1 CAPTURE through PPI),
//! so each interval between edges is one channel *period* as EdgeTX makes it (pulse plus
//! gap: EdgeTX `radio/src/pulses/ppm.cpp` sets each period to the channel value and pulses
//! for its first 300 µs); the polarity of the line does not matter. An interval longer
//! than `sync_min_us` ends a frame. Every period from `glitch_below_us` up to the sync gap is a
//! channel: one outside `channel_min_us..=channel_max_us` (700…2300 µs, wider than EdgeTX's
//! ±150 % extended limits, 732…2268 µs) is clamped to that range and counted, never dropped, so
//! one channel out of range never costs the others their frame. A period shorter than
//! `glitch_below_us` is not a channel at all (a spike or a split pulse: an extra edge shifts
//! every channel after it), so that frame is dropped. Frames need 4…16 channels, and
//! `lock_frames` consecutive clean frames with the same channel count lock the decoder (Betaflight needs 25, dRonin 10, §2.2; 5 at
//! 22.5 ms is 112 ms). A locked decoder hands out every clean frame of its channel count; a
//! different count must itself repeat `lock_frames` times before it replaces the old one, so
//! one glitch never changes the channel layout.
//!
//! A locked frame is handed out as soon as it is known to be right, by one of two proofs:
//!
//! * **Agreement (early release).** At the edge that closes the locked count's last channel,
//!   a frame whose every channel is within `early_release_within_us` (factory 200 µs) of the
//!   last frame handed out goes at once: that edge is the end of the frame's channels, unless
//!   a split pulse (one extra edge, §10 of the spec) made it the end of the one before, and a
//!   split cannot hide there unless the frame moved far: to pass, a split of channel k < N
//!   into `a + b` needs `a` within T of the last value of k, `b` within T of the last value of
//!   k + 1 and every later channel within T of its neighbour's last value, so channel k itself
//!   must have jumped by at least `max(b, 500) − T ≥ (last k+1) − 2T` (≥ 588 µs for channels
//!   in EdgeTX's ±100 %) in that very frame; a split of the last channel releases its first
//!   part, within T of its last value. Whatever the split, every channel handed out early is
//!   within T of the last frame handed out — that is the rule itself — so the worst an
//!   undetected split does is one frame (22.5 ms) up to T off on some channels. The line is
//!   still watched until the sync gap: an extra period or a glitch after an early release is
//!   counted ([`Reject::GapNotClean`]) and the next frame must prove its sync gap again.
//! * **Sync gap (held).** Otherwise — a switch flip, a stick snap, the first frame after
//!   lock, after a loss or after a gap that was not clean — once its last channel period has
//!   closed and no edge followed for longer than `sync_min_us`, the line is in the sync gap,
//!   so the frame had exactly the locked count and no split pulse ([`Decoder::release_due`],
//!   called by the capture task at [`Decoder::release_deadline_us`]): 2.5 ms later, never
//!   dropped. An extra period (a split pulse, a longer frame) arrives within the gap's first
//!   2.5 ms and holds the frame for the checks at its sync edge, which drop it.
//!
//! Both save the rest of the sync gap (≈ 8 ms of a 22.5 ms frame at centred sticks) over
//! waiting for the next frame's first edge.

use crate::channels::{ChannelFrame, MAX_CHANNELS, us_to_ticks};

/// Decoder timing limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderConfig {
    /// An interval longer than this ends the frame (openLRSng uses 2500 µs, §2.2).
    pub sync_min_us: u32,
    /// A period shorter than this is a glitch (it drops the frame), not a channel. Below any
    /// period a radio makes: EdgeTX's −150 % is 732 µs.
    pub glitch_below_us: u32,
    /// Channel periods below this are clamped up to it.
    pub channel_min_us: u32,
    /// Channel periods above this (up to the sync gap) are clamped down to it.
    pub channel_max_us: u32,
    /// Fewest channels a frame may carry.
    pub min_channels: usize,
    /// Consecutive clean frames of one channel count needed to lock.
    pub lock_frames: u8,
    /// Without an accepted frame for this long the lock is lost.
    pub loss_timeout_us: u32,
    /// A locked frame goes out at its last channel's closing edge when every channel is
    /// within this of the last frame handed out (the agreement rule, module doc); `None`:
    /// every locked frame waits for its sync gap.
    pub early_release_within_us: Option<u32>,
}

impl Default for DecoderConfig {
    fn default() -> Self {
        Self {
            sync_min_us: 2500,
            glitch_below_us: 500,
            // 700…2300 µs covers EdgeTX's extended limits (±150 %: 732…2268 µs); sync above
            // 2.5 ms as openLRSng's TX (`TX.h`), where Betaflight waits for 2.7 ms, dRonin 3 ms.
            channel_min_us: 700,
            channel_max_us: 2300,
            min_channels: 4,
            lock_frames: 5,
            // Between ELRS' 1 s and the 100 ms an FC allows before its own failsafe (§2.2).
            loss_timeout_us: 250_000,
            // What a stick moves in one 22.5 ms frame at the fastest: a full-travel flick
            // (1 024 µs) takes ≈ 0.1 s, 230 µs a frame. Flying moves far less, so nearly
            // every frame goes early; and a frame wrongly released (an undetected split
            // pulse) is off by at most this, 20 % of the travel, for one frame.
            early_release_within_us: Some(200),
        }
    }
}

/// Why a frame was not handed out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reject {
    /// A period shorter than `glitch_below_us` (a spike or a split pulse).
    ShortPeriod {
        /// The period in µs.
        period_us: u32,
    },
    /// More than 16 channel periods before a sync gap.
    TooManyChannels,
    /// Fewer channels than the minimum.
    TooFewChannels {
        /// Channels the frame had.
        count: usize,
    },
    /// A clean frame whose channel count differs from the locked one (not yet confirmed).
    CountMismatch {
        /// The locked count.
        locked: usize,
        /// The count of this frame.
        count: usize,
    },
    /// A frame already released early (it agreed with the last one) was followed by another
    /// period or a glitch before its sync gap: it may have been a split pulse. It is out;
    /// this counts it, and the next frame is held for its sync gap.
    GapNotClean {
        /// Periods seen before the sync gap (the locked count + 1 for a split pulse).
        count: usize,
    },
}

/// What the end of a frame produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Decoded {
    /// A clean frame while locked: the channels, mapped to link values.
    Frame(ChannelFrame),
    /// A clean frame on the way to a lock.
    Acquiring {
        /// Its channel count.
        count: usize,
        /// How many consecutive clean frames with this count so far.
        consistent: u8,
    },
    /// The frame was dropped.
    Rejected(Reject),
}

/// The lock was lost: no accepted frame for longer than the timeout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lost {
    /// Time since the last accepted frame, µs.
    pub silent_us: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Searching,
    Acquiring { count: usize, consistent: u8 },
    Locked { count: usize },
}

/// The PPM input decoder. Feed [`Decoder::on_edge`] with every captured edge and call
/// [`Decoder::on_tick`] now and then (same clock) for loss detection.
///
/// ```
/// use module_core::ppm::{Decoded, Decoder, DecoderConfig};
///
/// let mut decoder = Decoder::new(DecoderConfig::default());
/// let mut last = None;
/// // Seven frames of four 1500 µs channels every 20 ms: the first gap only finds sync, the
/// // next four frame ends acquire the lock, the sixth is handed out.
/// for frame in 0..7u32 {
///     for edge in 0..5u32 {
///         if let Some(Decoded::Frame(channels)) = decoder.on_edge(frame * 20_000 + edge * 1_500) {
///             last = Some(channels);
///         }
///     }
/// }
/// assert_eq!(last.unwrap().as_slice(), &[992; 4]);
/// ```
#[derive(Debug, Clone)]
pub struct Decoder {
    config: DecoderConfig,
    previous_edge_us: Option<u32>,
    /// A sync gap has been seen, so periods are channel periods.
    synced: bool,
    periods_us: [u16; MAX_CHANNELS],
    collected: usize,
    glitch: Option<Reject>,
    state: State,
    /// A different count seen while locked, and how often in a row.
    pending: Option<(usize, u8)>,
    last_good_us: u32,
    clamped: u32,
    /// The locked count's last channel period closed at this edge (no glitch so far): the
    /// frame is released once the line stays quiet for a sync gap.
    complete_at_us: Option<u32>,
    /// The current frame was released (early or at its deadline); its sync edge hands out
    /// nothing more, only checks that the gap was clean.
    released: bool,
    /// The last frame handed out (its count and periods), what an early release must agree
    /// with; `None` after a lock loss or a gap that was not clean, so the next frame proves
    /// its sync gap.
    last_released: Option<(usize, [u16; MAX_CHANNELS])>,
    /// Frames released at their last channel's closing edge.
    early_releases: u32,
}

impl Decoder {
    /// A decoder searching for sync.
    pub fn new(config: DecoderConfig) -> Self {
        Self {
            config,
            previous_edge_us: None,
            synced: false,
            periods_us: [0; MAX_CHANNELS],
            collected: 0,
            glitch: None,
            state: State::Searching,
            pending: None,
            last_good_us: 0,
            clamped: 0,
            complete_at_us: None,
            released: false,
            last_released: None,
            early_releases: 0,
        }
    }

    /// When [`Decoder::release_due`] will hand out the frame in progress (same clock as the
    /// edges): a sync gap after its last channel, if that channel has closed. The capture
    /// task wakes then if no edge came first.
    pub fn release_deadline_us(&self) -> Option<u32> {
        self.complete_at_us
            .map(|t| t.wrapping_add(self.config.sync_min_us).wrapping_add(1))
    }

    /// The frame in progress, if its last channel closed more than a sync gap before
    /// `now_us` with no edge since: it is complete and clean (the same checks as at its sync
    /// edge, which then hands out nothing). Once per frame.
    pub fn release_due(&mut self, now_us: u32) -> Option<Decoded> {
        let closed_at = self.complete_at_us?;
        let quiet_us = now_us.wrapping_sub(closed_at);
        // A `now` read just before the last edge's capture wraps to a huge value: not quiet.
        if quiet_us <= self.config.sync_min_us || quiet_us > u32::MAX / 2 {
            return None;
        }
        let State::Locked { count } = self.state else {
            self.complete_at_us = None;
            return None;
        };
        self.complete_at_us = None;
        self.released = true;
        self.pending = None;
        Some(self.accept(closed_at, count))
    }

    /// The channel count locked to, if any.
    pub fn locked_count(&self) -> Option<usize> {
        match self.state {
            State::Locked { count } => Some(count),
            _ => None,
        }
    }

    /// Channel periods clamped into `channel_min_us..=channel_max_us` so far.
    pub fn clamped(&self) -> u32 {
        self.clamped
    }

    /// Frames handed out at their last channel's closing edge (the agreement rule) so far.
    pub fn early_releases(&self) -> u32 {
        self.early_releases
    }

    /// Channel periods of the last frame handed out, µs (valid after a `Decoded::Frame`).
    pub fn last_periods_us(&self) -> &[u16] {
        match self.state {
            // Kept: `count` is only set from periods pushed into this array (≤ its length).
            State::Locked { count } => self.periods_us.get(..count).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// One captured edge at `timestamp_us`. Returns what the frame gave when this edge ends
    /// one (or closes the last channel of a locked frame that agrees with the last one,
    /// which goes out at once), `None` inside a frame.
    pub fn on_edge(&mut self, timestamp_us: u32) -> Option<Decoded> {
        let previous = self.previous_edge_us.replace(timestamp_us)?;
        // Wrapping difference: correct across the 2^32 µs (71.6 min) timer wrap.
        let period_us = timestamp_us.wrapping_sub(previous);
        self.complete_at_us = None;
        if period_us > self.config.sync_min_us {
            let released = core::mem::take(&mut self.released);
            let outcome = match (self.synced, released) {
                (false, _) => None,
                (true, false) => Some(self.end_frame(timestamp_us)),
                (true, true) => self.end_released_frame(timestamp_us),
            };
            self.synced = true;
            self.collected = 0;
            self.glitch = None;
            return outcome;
        }
        if !self.synced || self.glitch.is_some() {
            return None;
        }
        if period_us < self.config.glitch_below_us {
            self.glitch = Some(Reject::ShortPeriod { period_us });
            return None;
        }
        let (min, max) = (self.config.channel_min_us, self.config.channel_max_us);
        let clamped = period_us.clamp(min, max.max(min));
        if clamped != period_us {
            self.clamped = self.clamped.saturating_add(1);
        }
        match self.periods_us.get_mut(self.collected) {
            Some(slot) => {
                *slot = u16::try_from(clamped).unwrap_or(u16::MAX);
                self.collected += 1;
                if self.state
                    == (State::Locked {
                        count: self.collected,
                    })
                    && !self.released
                {
                    if self.agrees_with_last_released(self.collected) {
                        self.released = true;
                        self.early_releases = self.early_releases.saturating_add(1);
                        return Some(self.accept(timestamp_us, self.collected));
                    }
                    self.complete_at_us = Some(timestamp_us);
                }
            }
            None => self.glitch = Some(Reject::TooManyChannels),
        }
        None
    }

    /// Loss detection at `now_us` (same clock as the edges). Reports once when a lock is lost;
    /// a decoder still acquiring just starts over.
    pub fn on_tick(&mut self, now_us: u32) -> Option<Lost> {
        if self.state == State::Searching {
            return None;
        }
        let silent_us = now_us.wrapping_sub(self.last_good_us);
        // A `now` read just before the last edge's capture wraps to a huge value: not silence.
        if silent_us <= self.config.loss_timeout_us || silent_us > u32::MAX / 2 {
            return None;
        }
        let was_locked = matches!(self.state, State::Locked { .. });
        self.state = State::Searching;
        self.pending = None;
        self.complete_at_us = None;
        self.last_released = None;
        was_locked.then_some(Lost { silent_us })
    }

    /// Every one of the first `count` periods within `early_release_within_us` of the last
    /// frame handed out, which had `count` channels too.
    fn agrees_with_last_released(&self, count: usize) -> bool {
        let (Some(within_us), Some((last_count, last))) =
            (self.config.early_release_within_us, &self.last_released)
        else {
            return false;
        };
        *last_count == count
            && self
                .periods_us
                .iter()
                .zip(last)
                .take(count)
                .all(|(now, then)| u32::from(now.abs_diff(*then)) <= within_us)
    }

    /// The sync edge of a frame already handed out. Released at its deadline, the gap was
    /// proven quiet; released early, the gap is checked now: another period or a glitch
    /// after the release is counted, and the next frame must prove its own sync gap. The
    /// frame still counts towards a change of the channel count (a handset that went from
    /// 8 to 9 channels agrees on its first 8 every frame).
    fn end_released_frame(&mut self, timestamp_us: u32) -> Option<Decoded> {
        let clean = self.glitch.is_none() && self.locked_count() == Some(self.collected);
        if clean {
            self.pending = None;
            return None;
        }
        self.last_released = None;
        let count = self.collected;
        match self.end_frame(timestamp_us) {
            frame @ Decoded::Frame(_) => Some(frame),
            _ => Some(Decoded::Rejected(Reject::GapNotClean { count })),
        }
    }

    fn end_frame(&mut self, timestamp_us: u32) -> Decoded {
        if let Some(reason) = self.glitch {
            return Decoded::Rejected(reason);
        }
        let count = self.collected;
        if count < self.config.min_channels {
            return Decoded::Rejected(Reject::TooFewChannels { count });
        }
        let lock_frames = self.config.lock_frames.max(1);
        match self.state {
            State::Locked { count: locked } if locked == count => {
                self.pending = None;
                self.accept(timestamp_us, count)
            }
            State::Locked { count: locked } => {
                let consistent = match self.pending {
                    Some((pending, seen)) if pending == count => seen.saturating_add(1),
                    _ => 1,
                };
                if consistent >= lock_frames {
                    self.pending = None;
                    self.state = State::Locked { count };
                    self.accept(timestamp_us, count)
                } else {
                    self.pending = Some((count, consistent));
                    Decoded::Rejected(Reject::CountMismatch { locked, count })
                }
            }
            State::Acquiring {
                count: acquiring,
                consistent,
            } => {
                let consistent = if acquiring == count {
                    consistent.saturating_add(1)
                } else {
                    1
                };
                self.acquire(timestamp_us, count, consistent, lock_frames)
            }
            State::Searching => self.acquire(timestamp_us, count, 1, lock_frames),
        }
    }

    fn acquire(&mut self, timestamp_us: u32, count: usize, consistent: u8, lock: u8) -> Decoded {
        self.last_good_us = timestamp_us;
        if consistent >= lock {
            self.state = State::Locked { count };
            self.accept(timestamp_us, count)
        } else {
            self.state = State::Acquiring { count, consistent };
            Decoded::Acquiring { count, consistent }
        }
    }

    fn accept(&mut self, timestamp_us: u32, count: usize) -> Decoded {
        self.last_good_us = timestamp_us;
        self.last_released = Some((count, self.periods_us));
        let mut channels = ChannelFrame::centered(count);
        for (index, period_us) in self.periods_us.iter().take(count).enumerate() {
            channels.set(index, us_to_ticks(*period_us));
        }
        Decoded::Frame(channels)
    }
}

#[cfg(test)]
#[path = "decoder_tests.rs"]
mod tests;
