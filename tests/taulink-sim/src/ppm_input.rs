//! Free-running PPM into the module, as the module firmware takes it: EdgeTX's PPM edge train
//! (8 channels every 22.5 ms of the handset's crystal, its defaults and the module's, which
//! `module_core::ppm::Decoder` locks to) captured at 1 µs and decoded by the module's own
//! decoder with its factory `DecoderConfig`. A frame goes to the link when the firmware's
//! `ppm_in` task releases it: at an edge that ends it, or — once locked, the usual case — at
//! the decoder's `release_deadline_us`, a sync gap (2 501 µs) after its last channel closed,
//! the proof that no split pulse or extra channel follows. Only the radio is modelled here;
//! the decision is the module's code.
//!
//! The handset stamps each frame's index `k` into channels 1–3 at 4 µs steps (8 bits each),
//! so a period captured 1 µs off still names its frame; the other channels carry
//! pseudo-random values in EdgeTX's ±100 % range (988…2012 µs).

use std::collections::VecDeque;

use module_core::ppm::{Decoded, Decoder, DecoderConfig};
use telemetry::channels::{CHANNEL_CENTER, Channels};
use telemetry::handset::crsf::channels::ticks_to_us;

use crate::handset::HandsetFrame;

/// Channels per frame: EdgeTX's PPM default (and flight-sitl's handset).
pub const PPM_CHANNELS: usize = 8;
/// EdgeTX's frame length for 8 channels (22.5 ms + 2 ms per channel above 8), handset µs.
const PPM_FRAME_US: f64 = 22_500.0;
/// The shortest channel period EdgeTX makes at −100 % (988 µs) and its span to +100 %.
const WIDTH_MIN_US: u16 = 988;
const WIDTH_SPAN_US: u64 = 1_024;
/// The stamp: 8 bits in each of the first three channels, one step every 4 µs (a capture
/// error of ±1 µs stays inside its step).
const STAMP_CHANNELS: usize = 3;
const STAMP_STEP_US: u16 = 4;
/// The firmware's timer wake-ups come on embassy-nrf's RTC1 ticks (32 768 Hz): the task
/// that waits for the release deadline runs at the first tick at or after it.
const RTC_TICK_US: f64 = 1e6 / 32_768.0;

fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Channel periods of frame `k` on link `salt`, µs (handset µs): the stamp, then
/// pseudo-random values.
pub fn widths_us(salt: u64, k: u64) -> [u16; PPM_CHANNELS] {
    let mut widths = [0u16; PPM_CHANNELS];
    for (i, w) in widths.iter_mut().enumerate() {
        let offset = if i < STAMP_CHANNELS {
            ((k >> (8 * i)) & 0xFF) as u16 * STAMP_STEP_US
        } else {
            (mix64(salt ^ (k << 5) ^ i as u64) % (WIDTH_SPAN_US + 1)) as u16
        };
        *w = WIDTH_MIN_US + offset;
    }
    widths
}

/// The frame index stamped into channels decoded from a PPM frame.
pub fn stamp(channels: &Channels) -> u64 {
    channels
        .iter()
        .take(STAMP_CHANNELS)
        .enumerate()
        .map(|(i, ticks)| {
            let us = ticks_to_us(*ticks).saturating_sub(WIDTH_MIN_US - STAMP_STEP_US / 2);
            u64::from(us / STAMP_STEP_US) << (8 * i)
        })
        .sum()
}

/// One edge on the line: when (virtual µs), and the frame whose last channel period it
/// closes, if it does (its capture is the latency's start).
#[derive(Clone, Copy, Debug)]
struct Edge {
    at_us: f64,
    closes: Option<u64>,
}

/// The handset's PPM output and the module's capture and decoder.
pub struct PpmInput {
    salt: u64,
    crystal_ppm: f64,
    decoder: Decoder,
    next_frame_us: f64,
    next_k: u64,
    edges: VecDeque<Edge>,
    /// The last frame whose last channel closed: (k, virtual µs of that edge).
    closed: Option<(u64, u64)>,
    /// The previous edge: (capture reading, virtual µs it was read at).
    last_capture: Option<(u32, u64)>,
    released: Option<HandsetFrame>,
    rejected: u32,
    /// The release deadline the task last woke for (since the last edge).
    woken_for: Option<u32>,
}

impl PpmInput {
    /// A handset whose first frame starts at `first_us` (virtual), its crystal `crystal_ppm`
    /// fast, on link `salt`.
    pub fn new(salt: u64, first_us: f64, crystal_ppm: f64) -> Self {
        Self {
            salt,
            crystal_ppm,
            // The module's factory configuration (`App::new`).
            decoder: Decoder::new(DecoderConfig::default()),
            next_frame_us: first_us,
            next_k: 0,
            edges: VecDeque::new(),
            closed: None,
            last_capture: None,
            released: None,
            rejected: 0,
            woken_for: None,
        }
    }

    /// Frames the decoder dropped (none on a clean line).
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// Runs the line and the module's capture task up to `now_us`: the newest frame the
    /// decoder has released, if any; `closed` sees every frame when its last channel closes.
    pub fn advance(
        &mut self,
        now_us: u64,
        mut closed: impl FnMut(HandsetFrame),
    ) -> Option<HandsetFrame> {
        let now = now_us as f64;
        loop {
            if self.edges.is_empty() && self.next_frame_us <= now {
                self.emit_frame();
            }
            let edge = self.edges.front().copied();
            let release = self.release_at_us();
            match (edge, release) {
                // The task waits for the deadline with the edge pending; a deadline the
                // edge beats never fires (the edge ends or extends the frame).
                (_, Some(r)) if r <= now && edge.is_none_or(|e| r < e.at_us) => {
                    let capture = self.capture(r);
                    self.woken_for = self.decoder.release_deadline_us();
                    self.tick(capture, r as u64);
                }
                (Some(e), _) if e.at_us <= now => {
                    self.edges.pop_front();
                    self.edge(e, &mut closed);
                }
                _ => break,
            }
        }
        self.released
    }

    /// The next frame's edges on the line: one at its start and one closing each channel
    /// period, in the handset's (fast) microseconds.
    fn emit_frame(&mut self) {
        let k = self.next_k;
        self.next_k += 1;
        let scale = 1.0 / (1.0 + self.crystal_ppm * 1e-6);
        let start = self.next_frame_us;
        let mut t = start;
        self.edges.push_back(Edge {
            at_us: t,
            closes: None,
        });
        let widths = widths_us(self.salt, k);
        for (i, w) in widths.iter().enumerate() {
            t += f64::from(*w) * scale;
            self.edges.push_back(Edge {
                at_us: t,
                closes: (i + 1 == PPM_CHANNELS).then_some(k),
            });
        }
        self.next_frame_us = start + PPM_FRAME_US * scale;
    }

    /// TIMER1 at 1 MHz, captured in hardware: the whole microseconds since boot (its 20 ppm
    /// against virtual time change a 2.5 ms gap by 0.05 µs and are left out).
    fn capture(&self, at_us: f64) -> u32 {
        at_us.floor() as u64 as u32
    }

    /// When the capture task releases the frame in progress, virtual µs: the first RTC tick
    /// at or after the decoder's deadline (the few µs from the RTC interrupt to the task
    /// running are left out).
    fn release_at_us(&self) -> Option<f64> {
        // The decoder releases at its own deadline; were it not to, the task would not spin
        // on that deadline here (the next edge ends the frame).
        let deadline = self
            .decoder
            .release_deadline_us()
            .filter(|d| self.woken_for != Some(*d))?;
        let (capture, at_us) = self.last_capture?;
        let deadline_us = at_us + u64::from(deadline.wrapping_sub(capture));
        Some((deadline_us as f64 / RTC_TICK_US).ceil() * RTC_TICK_US)
    }

    /// The firmware's `ppm_in` task at an edge: `App::on_ppm_edge`, then `App::on_ppm_tick`.
    fn edge(&mut self, e: Edge, closed: &mut impl FnMut(HandsetFrame)) {
        let capture = self.capture(e.at_us);
        let at_us = e.at_us.floor() as u64;
        self.last_capture = Some((capture, at_us));
        self.woken_for = None;
        if let Some(k) = e.closes {
            self.closed = Some((k, at_us));
            closed(HandsetFrame {
                k,
                generated_us: at_us,
                arrived_us: at_us,
                channels: [CHANNEL_CENTER; telemetry::channels::MAX_CHANNELS],
            });
        }
        let outcome = self.decoder.on_edge(capture);
        self.take(outcome, at_us);
        self.tick(capture, at_us);
    }

    /// `App::on_ppm_tick`: a frame whose sync gap is proven goes out; loss detection.
    fn tick(&mut self, capture: u32, at_us: u64) {
        let outcome = self.decoder.release_due(capture);
        self.take(outcome, at_us);
        let _ = self.decoder.on_tick(capture);
    }

    /// What `App` forwards to the link (`AirLink::send_channels`: the decoded channels, the
    /// rest of the 16 centred).
    fn take(&mut self, outcome: Option<Decoded>, at_us: u64) {
        match outcome {
            Some(Decoded::Frame(decoded)) => {
                let Some((k, closed_us)) = self.closed else {
                    return;
                };
                let mut channels = [CHANNEL_CENTER; telemetry::channels::MAX_CHANNELS];
                for (slot, value) in channels.iter_mut().zip(decoded.as_slice()) {
                    *slot = *value;
                }
                self.released = Some(HandsetFrame {
                    k,
                    generated_us: closed_us,
                    arrived_us: at_us,
                    channels,
                });
            }
            Some(Decoded::Rejected(_)) => self.rejected += 1,
            Some(Decoded::Acquiring { .. }) | None => {}
        }
    }
}
