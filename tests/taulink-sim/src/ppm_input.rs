//! Free-running PPM into the module, as the module firmware takes it: EdgeTX's PPM edge train
//! (8 channels every 22.5 ms of the handset's crystal, its defaults and the module's, which
//! `module_core::ppm::Decoder` locks to) captured at 1 µs and decoded by the module's own
//! decoder with its factory `DecoderConfig`. A frame goes to the link when the firmware's
//! `ppm_in` task releases it: once locked, at the edge closing its last channel when every
//! channel agrees with the frame released before (the usual case), else at the decoder's
//! `release_deadline_us`, a sync gap (2 501 µs) after that edge, the proof that no split
//! pulse or extra channel follows (or at the sync edge while acquiring). Only the radio is
//! modelled here; the decision is the module's code.
//!
//! The channels are what a pilot makes, since the decoder's early release depends on it
//! (a frame that agrees with the last one goes at its last channel's edge, one that jumped
//! waits for its sync gap): channels 1–3 carry the frame's index `k` at 4 µs steps (8 bits
//! each, so a period captured 1 µs off still names its frame) in reflected order — each digit
//! runs up and then back down, a Gray code in base 256 — so they move like slowly driven
//! sticks, never more than 4 µs a frame; channel 4 is a stick moved smoothly (two seeded
//! sines, ≤ 41 µs a frame); channels 5–8 are switches (988 / 1 500 / 2 012 µs), one of them
//! flipped every 4.05 s window at a seeded frame (≈ 0.5 % of frames jump, each held for its
//! sync gap).

use std::collections::VecDeque;

use module_core::ppm::{Decoded, Decoder, DecoderConfig};
use taulink_handset::crsf::channels::ticks_to_us;
use telemetry::channels::{CHANNEL_CENTER, Channels};

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

/// Switch positions: EdgeTX's −100 %, centre, +100 %.
const SWITCH_US: [u16; 3] = [WIDTH_MIN_US, 1_500, WIDTH_MIN_US + WIDTH_SPAN_US as u16];
/// Frames per switch window (4.05 s): one aux switch flips in each, at a seeded frame.
const SWITCH_WINDOW: u64 = 180;
/// The aux channels (5–8).
const AUX: std::ops::Range<usize> = 4..PPM_CHANNELS;

/// Digit `i` of the stamp of frame `k`: its byte, reflected when the index above it is odd.
fn stamp_digit(k: u64, i: usize) -> u16 {
    let digit = (k >> (8 * i)) & 0xFF;
    let above = k >> (8 * (i + 1));
    (if above % 2 == 1 { 0xFF - digit } else { digit }) as u16
}

/// The smooth stick (channel 4) at frame `k`: 1 500 µs ± 400 (2.9 s period) ± 100 (0.7 s),
/// phases seeded by `salt`; at most 2π·(400/2.9 + 100/0.7)·22.5 ms ≈ 40 µs a frame.
fn stick_us(salt: u64, k: u64) -> u16 {
    let t = k as f64 * PPM_FRAME_US * 1e-6;
    let phase = |n: u64| (mix64(salt ^ n) % 6_283) as f64 * 1e-3;
    let tau = std::f64::consts::TAU;
    let us = 1_500.0
        + 400.0 * (tau * t / 2.9 + phase(0x5717)).sin()
        + 100.0 * (tau * t / 0.7 + phase(0x5718)).sin();
    us.round() as u16
}

/// Switch position `n` (any `n`, taken modulo the three).
fn switch_position(n: u64) -> u16 {
    match n % 3 {
        0 => SWITCH_US[0],
        1 => SWITCH_US[1],
        _ => SWITCH_US[2],
    }
}

/// The flip of switch window `w`: (frame, aux channel, new position).
fn flip(salt: u64, w: u64) -> (u64, usize, u16) {
    let h = mix64(salt ^ 0xF11F ^ (w << 8));
    let at = w * SWITCH_WINDOW + h % SWITCH_WINDOW;
    let channel = AUX.start + ((h >> 16) % AUX.len() as u64) as usize;
    let position = switch_position(h >> 24);
    (at, channel, position)
}

/// Switch `channel` at frame `k`: the position of its last flip at or before `k`, else its
/// seeded start position.
fn switch_us(salt: u64, k: u64, channel: usize) -> u16 {
    (0..=k / SWITCH_WINDOW)
        .rev()
        .map(|w| flip(salt, w))
        .find(|(at, c, _)| *c == channel && *at <= k)
        .map_or_else(
            || switch_position(mix64(salt ^ channel as u64)),
            |(_, _, position)| position,
        )
}

/// Channel periods of frame `k` on link `salt`, µs (handset µs): the stamp, the smooth
/// stick, the switches.
pub fn widths_us(salt: u64, k: u64) -> [u16; PPM_CHANNELS] {
    let mut widths = [0u16; PPM_CHANNELS];
    for (i, w) in widths.iter_mut().enumerate() {
        *w = match i {
            _ if i < STAMP_CHANNELS => WIDTH_MIN_US + stamp_digit(k, i) * STAMP_STEP_US,
            _ if AUX.contains(&i) => switch_us(salt, k, i),
            _ => stick_us(salt, k),
        };
    }
    widths
}

/// The frame index stamped into channels decoded from a PPM frame.
pub fn stamp(channels: &Channels) -> u64 {
    let digit = |i: usize| {
        let ticks = channels.get(i).copied().unwrap_or(0);
        let us = ticks_to_us(ticks).saturating_sub(WIDTH_MIN_US - STAMP_STEP_US / 2);
        u64::from(us / STAMP_STEP_US).min(0xFF)
    };
    // From the top digit down: each one is reflected when the index above it is odd.
    (0..STAMP_CHANNELS).rev().fold(0, |above, i| {
        let d = if above % 2 == 1 {
            0xFF - digit(i)
        } else {
            digit(i)
        };
        (above << 8) | d
    })
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
    /// Frames released / released at their last channel's edge (the agreement rule).
    released_frames: u32,
    early_frames: u32,
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
            released_frames: 0,
            early_frames: 0,
            woken_for: None,
        }
    }

    /// Frames the decoder dropped (none on a clean line).
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// Frames handed to the link, and how many of them at their last channel's closing
    /// edge (they agreed with the frame before).
    pub fn released(&self) -> (u32, u32) {
        (self.released_frames, self.early_frames)
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
                self.released_frames += 1;
                self.early_frames += u32::from(at_us == closed_us);
            }
            Some(Decoded::Rejected(_)) => self.rejected += 1,
            Some(Decoded::Acquiring { .. }) | None => {}
        }
    }
}
