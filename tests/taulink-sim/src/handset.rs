//! The pilot's handset as the module's input sees it: when each channel frame is generated
//! (the mixer run that samples the sticks), when it has arrived at the module, and — for a
//! CRSF handset that follows the module — how it re-times itself on the module's 0x3A timing
//! frames as EdgeTX does. The module's side of that exchange is the real
//! `taulink_handset::crsf::Responder` (what `module-core` runs); only the radio is
//! modelled here. A PPM handset is an edge train into the module's own PPM decoder
//! (`ppm_input.rs`).
//!
//! EdgeTX's mixer scheduler (`ModuleSyncStatus` in `telemetry.cpp`): a timing frame sets
//! `refreshRate` to its interval (clamped to 850 … 50 000 µs) and `currentLag` to its offset;
//! every frame's period is then `refreshRate + currentLag` (clamped), and what was applied
//! is taken off `currentLag` — the whole offset lands on the next period. Without a timing
//! frame for 2 s it falls back to its CRSF default of 4 ms.

use std::collections::VecDeque;

use taulink_handset::HandsetTelemetry;
use taulink_handset::crsf::responder::{Config, LinkSchedule, Responder, taulink_device_info};
use taulink_handset::crsf::{Decoded, Decoder, Frame, Message, frame_type};
use telemetry::channels::Channels;
use telemetry::mock::SplitMix64;

use crate::ppm_input::PpmInput;
use crate::probe::sample_channels;

/// What feeds the module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandsetKind {
    /// EdgeTX on CRSF following the module's timing frames (what an EdgeTX pilot flies).
    CrsfSynced,
    /// EdgeTX on CRSF ignoring them: frames every 4 ms of its own crystal.
    Crsf,
    /// Free-running PPM: an 8-channel frame every 22.5 ms of the handset's crystal, decoded
    /// and released by the module's `ppm::Decoder` as its firmware does.
    Ppm,
    /// The 1 kHz sample stream the simulator measured with before (not synchronised to
    /// anything, no line time): comparable with earlier figures.
    Free1k,
}

impl HandsetKind {
    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            HandsetKind::CrsfSynced => "crsf-synced",
            HandsetKind::Crsf => "crsf",
            HandsetKind::Ppm => "ppm",
            HandsetKind::Free1k => "free-1k",
        }
    }
}

/// The CRSF line speed: EdgeTX's and ExpressLRS' default for external modules.
pub const CRSF_BAUD: u32 = 400_000;
/// A CRSF RC-channels frame on the wire: address, length, type, 22 bytes, CRC.
const CRSF_RC_FRAME_BYTES: u32 = 26;
/// EdgeTX's CRSF period before (or without) timing frames (`CROSSFIRE_PERIOD`).
const CRSF_DEFAULT_PERIOD_US: f64 = 4_000.0;
/// EdgeTX's clamps on the requested period.
const EDGETX_MIN_PERIOD_US: i64 = 850;
const EDGETX_MAX_PERIOD_US: i64 = 50_000;
/// EdgeTX drops the sync 2 s after the last timing frame.
const SYNC_VALID_US: u64 = 2_000_000;
/// The legacy sampler's period.
const FREE_PERIOD_US: f64 = 1_001.0;
/// The handset's crystal error: +50 ppm (a handset crystal's tolerance; the module's MCU
/// clock runs +20 ppm in the chip world, so they drift 30 ppm apart).
pub const HANDSET_PPM: f64 = 50.0;
/// The mixer run between sampling the sticks and the frame leaving on the line: EdgeTX's
/// mixer task takes a few hundred µs on a Taranis-class MCU; modelled as 100 µs ± 50 µs.
const MIXER_RUN_US: (f64, f64) = (50.0, 150.0);

/// One channel frame: its sample index, when it was generated and when the module's input
/// had it for the link (virtual µs), and the channels it handed over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandsetFrame {
    /// Sample index (stamped into the channels).
    pub k: u64,
    /// When the mixer sampled the sticks (PPM: when the frame's last channel period closed
    /// at the module's input).
    pub generated_us: u64,
    /// When the module's input handed the frame to the link (CRSF: fully arrived; PPM:
    /// released by the module's decoder).
    pub arrived_us: u64,
    /// The 16 channel values the link gets.
    pub channels: Channels,
}

/// A handset and the module's CRSF responder.
pub struct Handset {
    kind: HandsetKind,
    salt: u64,
    ppm: Option<PpmInput>,
    rng: SplitMix64,
    next_tick_us: f64,
    next_k: u64,
    refresh_us: i64,
    current_lag_us: i64,
    sync_until_us: Option<u64>,
    in_flight: VecDeque<HandsetFrame>,
    latest: Option<HandsetFrame>,
    responder: Responder,
    decoder: Decoder,
    rc_frame: Frame,
    telemetry: HandsetTelemetry,
    corrections: u32,
}

impl Handset {
    /// A handset of `kind` on link `salt` (its channel values), booting at a phase drawn
    /// from it.
    pub fn new(kind: HandsetKind, salt: u64) -> Self {
        let mut rng = SplitMix64::new(salt ^ 0x04A2_D5E7);
        let first = 1_000.0 + rng.unit() * 5_000.0;
        let rc = [0u8; 22];
        Self {
            kind,
            salt,
            ppm: (kind == HandsetKind::Ppm).then(|| PpmInput::new(salt, first, HANDSET_PPM)),
            rng,
            next_tick_us: first,
            next_k: 0,
            refresh_us: 0,
            current_lag_us: 0,
            sync_until_us: None,
            in_flight: VecDeque::new(),
            latest: None,
            responder: Responder::new(Config::new(CRSF_BAUD, taulink_device_info(0, 1, 0))),
            decoder: Decoder::new(),
            rc_frame: Frame::new(0xEE, frame_type::RC_CHANNELS_PACKED, &rc)
                .unwrap_or_else(|_| empty_rc_frame()),
            telemetry: HandsetTelemetry::default(),
            corrections: 0,
        }
    }

    /// The module's air schedule, as `module-core` hands it to its responder (period: the
    /// slot; phase: when an uplink's channels are latched), in virtual µs.
    pub fn set_schedule(&mut self, period_us: u32, latch_us: u64) {
        self.responder.set_link_schedule(Some(LinkSchedule {
            period_us,
            phase_us: latch_us,
        }));
    }

    /// What the handset is.
    pub fn kind(&self) -> HandsetKind {
        self.kind
    }

    /// Timing frames the handset has followed.
    pub fn corrections(&self) -> u32 {
        self.corrections
    }

    /// PPM frames the module's decoder handed the link, and how many of them at their last
    /// channel's closing edge ((0, 0) for the other kinds).
    pub fn ppm_released(&self) -> (u32, u32) {
        self.ppm.as_ref().map_or((0, 0), PpmInput::released)
    }

    /// PPM frames the module's decoder dropped (0 for the other kinds).
    pub fn rejected(&self) -> u32 {
        self.ppm.as_ref().map_or(0, PpmInput::rejected)
    }

    /// Runs the handset and the module's input (CRSF responder or PPM decoder) up to
    /// `now_us`; the newest frame the input has handed over by then, if any, and every frame
    /// generated so far through `generated`.
    pub fn advance(
        &mut self,
        now_us: u64,
        mut generated: impl FnMut(HandsetFrame),
    ) -> Option<HandsetFrame> {
        if let Some(ppm) = &mut self.ppm {
            return ppm.advance(now_us, generated);
        }
        loop {
            let arrival = self.in_flight.front().map(|f| f.arrived_us);
            let tick = self.next_tick_us;
            match arrival {
                Some(a) if a <= now_us && (a as f64) <= tick => {
                    if let Some(frame) = self.in_flight.pop_front() {
                        self.arrive(frame);
                    }
                }
                _ if tick <= now_us as f64 => {
                    let frame = self.generate();
                    generated(frame);
                    self.in_flight.push_back(frame);
                }
                _ => break,
            }
        }
        self.latest
    }

    fn generate(&mut self) -> HandsetFrame {
        let tick = self.next_tick_us;
        let k = self.next_k;
        self.next_k += 1;
        let (arrived, period_local) = match self.kind {
            // (PPM frames come from `PpmInput`, never from here.)
            HandsetKind::Free1k | HandsetKind::Ppm => (tick, FREE_PERIOD_US),
            HandsetKind::Crsf | HandsetKind::CrsfSynced => {
                let (lo, hi) = MIXER_RUN_US;
                let mixer = lo + (hi - lo) * self.rng.unit();
                let wire = f64::from(CRSF_RC_FRAME_BYTES * 10) * 1e6 / f64::from(CRSF_BAUD);
                (tick + mixer + wire, self.next_period_us(tick as u64))
            }
        };
        // The handset's crystal runs HANDSET_PPM fast: its microseconds are shorter.
        self.next_tick_us = tick + period_local / (1.0 + HANDSET_PPM * 1e-6);
        HandsetFrame {
            k,
            generated_us: tick as u64,
            arrived_us: arrived as u64,
            channels: sample_channels(self.salt, k),
        }
    }

    /// EdgeTX's `getAdjustedRefreshRate` (or its default period without sync).
    fn next_period_us(&mut self, now_us: u64) -> f64 {
        let synced = self.kind == HandsetKind::CrsfSynced
            && self.sync_until_us.is_some_and(|until| now_us < until);
        if !synced {
            return CRSF_DEFAULT_PERIOD_US;
        }
        let adjusted = (self.refresh_us + self.current_lag_us)
            .clamp(EDGETX_MIN_PERIOD_US, EDGETX_MAX_PERIOD_US);
        self.current_lag_us -= adjusted - self.refresh_us;
        adjusted as f64
    }

    /// A frame is complete at the module: the responder sees it and answers in the reply
    /// window; a synced handset takes the timing frame (EdgeTX's `ModuleSyncStatus::update`).
    fn arrive(&mut self, frame: HandsetFrame) {
        self.latest = Some(frame);
        if !matches!(self.kind, HandsetKind::Crsf | HandsetKind::CrsfSynced) {
            return;
        }
        let _ = self.responder.on_frame(frame.arrived_us, &self.rc_frame);
        let mut out = [0u8; 128];
        // The simulated radio hears nothing if the responder fails (it never has).
        let reply = self
            .responder
            .reply(frame.arrived_us + 20, &self.telemetry, &mut out)
            .unwrap_or(&[]);
        let mut corrections = Vec::new();
        for decoded in self.decoder.feed(reply) {
            if let Decoded::Frame(f) = decoded
                && let Ok(Message::TimingCorrection(t)) = Message::from_frame(&f)
            {
                corrections.push(t);
            }
        }
        if self.kind != HandsetKind::CrsfSynced {
            return;
        }
        for t in corrections {
            let interval = i64::from(t.interval_100ns / 10);
            if interval == 0 {
                continue;
            }
            // EdgeTX: a rate below its minimum becomes a multiple of it.
            self.refresh_us = if interval < EDGETX_MIN_PERIOD_US {
                interval * (EDGETX_MIN_PERIOD_US / (interval + 1))
            } else {
                interval.min(EDGETX_MAX_PERIOD_US)
            };
            self.current_lag_us = i64::from(t.offset_100ns / 10);
            self.sync_until_us = Some(frame.arrived_us + SYNC_VALID_US);
            self.corrections += 1;
        }
    }
}

/// `Frame::new` of a 22-byte RC payload cannot fail; an empty frame keeps this total.
fn empty_rc_frame() -> Frame {
    Frame {
        address: 0xEE,
        frame_type: frame_type::RC_CHANNELS_PACKED,
        payload: Default::default(),
    }
}
