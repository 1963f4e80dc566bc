//! The application ends of the simulated link: the handset's channel frames (`handset`:
//! each frame's sample index stamped inside the sticks, so the flight side can measure
//! latency and check every value), telemetry sources and sinks with known byte streams, and
//! the shared record both ends write into.

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::rc::Rc;

use si4432_sim::RadioId;

use telemetry::channels::{CHANNEL_MAX, ChannelFormat, Channels, MAX_CHANNELS};
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::FollowerHooks;
use telemetry::link::master::MasterHooks;
use telemetry::link::schedule::SlotKind;

use crate::handset::{Handset, HandsetKind};
use crate::ppm_input;

/// Samples older than this at their output are not counted as latency (the link was down:
/// that time shows up as failsafe, not as latency).
const MAX_BACKLOG_US: u64 = 1_000_000;
/// Channels that carry the sample stamp, low and high 11 bits: two sticks, present in every
/// packet of every format.
const STAMP_LOW: usize = 0;
const STAMP_HIGH: usize = 1;
/// Hop records kept for the hop-sequence check.
const HOP_RECORDS: usize = 20_000;
/// PPM frames the module handed the link that an output may still name (256 × 22.5 ms =
/// 5.8 s, far beyond `MAX_BACKLOG_US`).
const INPUT_FRAMES: usize = 256;

fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Byte `index` of the test stream `salt`.
pub fn stream_byte(salt: u64, index: u64) -> u8 {
    (mix64(salt ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15)) >> 24) as u8
}

/// The channels of handset sample `k` on link `salt`.
pub fn sample_channels(salt: u64, k: u64) -> Channels {
    let mut ch = [0u16; 16];
    for (i, c) in ch.iter_mut().enumerate() {
        *c = (mix64(salt ^ (k << 5) ^ i as u64) % (u64::from(CHANNEL_MAX) + 1)) as u16;
    }
    if let Some(c) = ch.get_mut(STAMP_LOW) {
        *c = (k & 0x7FF) as u16;
    }
    if let Some(c) = ch.get_mut(STAMP_HIGH) {
        *c = ((k >> 11) & 0x7FF) as u16;
    }
    ch
}

/// The handset sample index stamped into `channels` by a handset of `kind`.
fn stamp(channels: &Channels, kind: HandsetKind) -> u64 {
    if kind == HandsetKind::Ppm {
        return ppm_input::stamp(channels);
    }
    let get = |i: usize| u64::from(channels.get(i).copied().unwrap_or(0));
    get(STAMP_LOW) | (get(STAMP_HIGH) << 11)
}

/// Fills up to 256 bytes of test stream `salt` from index `*written` into `write`.
fn feed(salt: u64, written: &mut u64, free: usize, write: impl FnOnce(&[u8]) -> usize) {
    let bytes: Vec<u8> = (0..free.min(256) as u64)
        .map(|i| stream_byte(salt, *written + i))
        .collect();
    *written += write(&bytes) as u64;
}

/// Drains a stream with `read`, checking every byte against test stream `salt`.
fn check(
    salt: u64,
    read_index: &mut u64,
    ok: &mut u64,
    bad: &mut u64,
    mut read: impl FnMut(&mut [u8]) -> usize,
) {
    let mut buf = [0u8; 256];
    loop {
        let n = read(&mut buf);
        if n == 0 {
            return;
        }
        for &b in buf.iter().take(n) {
            if b == stream_byte(salt, *read_index) {
                *ok += 1;
            } else {
                *bad += 1;
            }
            *read_index += 1;
        }
    }
}

/// Everything measured on one link.
#[derive(Clone, Debug, Default)]
pub struct Record {
    /// Time the bind completed on the follower (µs), if binding.
    pub bound_us: Option<u64>,
    /// The parameters the follower stored (from the bind, or given).
    pub follower_params: Option<telemetry::link::LinkParams>,
    /// Uplink latencies input → output, µs.
    pub latencies_us: Vec<u32>,
    /// Generation time (virtual µs) of each handset frame, by sample index.
    pub generated_us: Vec<u64>,
    /// PPM: the newest frames the module's decoder handed the link (sample index,
    /// channels), what the flight side's outputs must match (the values come out of the
    /// module's capture, not from a table).
    pub input_frames: VecDeque<(u64, Channels)>,
    /// PPM frames the module's decoder dropped (must stay 0: the line is clean).
    pub input_rejected: u32,
    /// PPM frames the module's decoder handed the link, and of them at their last channel's
    /// closing edge (early release).
    pub input_released: (u32, u32),
    /// Per channel: outputs that refreshed it with its right value.
    pub channel_updates: [u64; MAX_CHANNELS],
    /// Timing frames the handset followed.
    pub handset_corrections: u32,
    /// Channel outputs that matched their sample exactly.
    pub outputs_ok: u64,
    /// Channel outputs that did not (must stay 0).
    pub outputs_bad: u64,
    /// Uplink stream bytes received correct / wrong.
    pub up_bytes_ok: u64,
    /// Uplink stream bytes received wrong (must stay 0).
    pub up_bytes_bad: u64,
    /// Downlink stream bytes received correct.
    pub down_bytes_ok: u64,
    /// Downlink stream bytes received wrong (must stay 0).
    pub down_bytes_bad: u64,
    /// (time µs, entering?) failsafe transitions on the follower.
    pub failsafe_changes: Vec<(u64, bool)>,
    /// For each failsafe entry: time since the last valid channel update, µs.
    pub silence_before_failsafe_us: Vec<u64>,
    /// Time of the last valid channel update, µs.
    pub last_output_us: u64,
    /// (slot mod 256, grid channel) of the master's slots.
    pub master_hops: Vec<(u8, u8)>,
    /// (slot mod 256, grid channel) the follower tracked.
    pub follower_hops: Vec<(u8, u8)>,
    /// Latest snapshot of both ends.
    pub now: Snapshot,
    /// Sum and count of uplink LQ readings (one per follower step while tracking).
    pub uplink_lq_sum: (u64, u64),
    /// Sum and count of downlink LQ readings (one per master slot from the 100th downlink).
    pub downlink_lq_sum: (u64, u64),
    /// Frames an attacking radio sent (`--attack`).
    pub attacker_sent: u64,
    /// Frames of the attacking radio that a victim's link core accepted: its count of valid
    /// frames rose on a packet the medium delivered from the attacker (must stay 0).
    pub attacker_accepted: u64,
    /// Times the flight side was power-cycled.
    pub power_cycles: u32,
    /// Boots after which the flight side ran another link than the module's (must stay 0).
    pub rebinds: u32,
    /// Keyed links: epochs the master adopted and verified nonce frames it refused.
    pub handshakes: (u32, u32),
    /// Keyed links: tag failures counted by the master, and by the flight side's
    /// followers (summed over its boots).
    pub tag_failures: (u32, u32),
    /// `--attack guess`: what the guesser recorded and found.
    pub guess: Option<crate::attack::GuessFigures>,
}

impl Record {
    /// Mean uplink LQ over the run (while tracking).
    pub fn uplink_lq_mean(&self) -> f64 {
        self.uplink_lq_sum.0 as f64 / self.uplink_lq_sum.1.max(1) as f64
    }

    /// Mean downlink LQ over the run (from the 100th downlink on).
    pub fn downlink_lq_mean(&self) -> f64 {
        self.downlink_lq_sum.0 as f64 / self.downlink_lq_sum.1.max(1) as f64
    }
}

/// Current state of both ends, for the status line.
#[derive(Clone, Copy, Debug, Default)]
pub struct Snapshot {
    /// Uplink LQ measured on the follower.
    pub uplink_lq: u8,
    /// Downlink LQ measured on the master.
    pub downlink_lq: u8,
    /// RSSI of the master's packets at the follower.
    pub follower_rssi_dbm: Option<i16>,
    /// RSSI of the follower's packets at the master.
    pub master_rssi_dbm: Option<i16>,
    /// Valid uplinks received by the follower.
    pub uplinks_received: u32,
    /// Valid downlinks received by the master.
    pub downlinks_received: u32,
    /// Packets rejected by the follower's decoder.
    pub follower_rejected: u32,
    /// Packets rejected by the master's decoder.
    pub master_rejected: u32,
    /// Follower in failsafe.
    pub failsafe: bool,
    /// Follower tracking the master.
    pub tracking: bool,
    /// Times the follower lost and re-acquired.
    pub resyncs: u32,
    /// The follower's first four outputs.
    pub channels: [u16; 4],
}

/// Shared record handle.
pub type Shared = Rc<RefCell<Record>>;

/// Who sent the packet a victim's radio delivered last (from the medium's trace), and the
/// attacker's radio: lets the hooks attribute each frame their core accepted.
#[derive(Clone, Debug)]
pub struct Witness {
    /// Sender of the last packet delivered to this end's radio.
    pub last_sender: Rc<Cell<Option<RadioId>>>,
    /// The attacking radio.
    pub attacker: RadioId,
    accepted_before: u32,
}

impl Witness {
    /// A witness of `last_sender` against `attacker`.
    pub fn new(last_sender: Rc<Cell<Option<RadioId>>>, attacker: RadioId) -> Self {
        Self {
            last_sender,
            attacker,
            accepted_before: 0,
        }
    }

    /// The core's count of accepted frames is now `accepted` (one receive per step or
    /// slot ends at the first accepted frame, so a rise is the last packet delivered):
    /// whether the frame it accepted came from the attacker.
    fn attacker_accepted(&mut self, accepted: u32) -> bool {
        let rose = accepted > self.accepted_before;
        // A restarted core counts from 0 again.
        self.accepted_before = accepted;
        rose && self.last_sender.get() == Some(self.attacker)
    }
}
/// The common time reference of a simulation (virtual µs, not either end's clock).
pub type Now = Rc<dyn Fn() -> u64>;

/// The module's application: handset samples in, telemetry out and in.
pub struct ModuleApp {
    /// Virtual time (the common reference for latency).
    pub now: Now,
    /// Where measurements go.
    pub record: Shared,
    /// Link salt (channel pattern and stream bytes).
    pub salt: u64,
    /// Keep the uplink stream saturated.
    pub telemetry_load: bool,
    /// Under attack: attributes accepted downlinks.
    pub witness: Option<Witness>,
    handset: Handset,
    written: u64,
    read: u64,
}

impl ModuleApp {
    /// A module application fed by a handset of `handset` kind.
    pub fn new(
        now: Now,
        record: Shared,
        salt: u64,
        telemetry_load: bool,
        handset: HandsetKind,
    ) -> Self {
        Self {
            now,
            record,
            salt,
            telemetry_load,
            witness: None,
            handset: Handset::new(handset, salt),
            written: 0,
            read: 0,
        }
    }
}

impl MasterHooks for ModuleApp {
    fn on_slot(&mut self, _now_us: u64, master: &mut Master) {
        let now = (self.now)();
        // The loop calls in when an uplink's channels are latched: that instant, on the slot
        // grid, is what module-core hands its CRSF responder.
        // (module-core's `AirLink` reports the latch of the telemetry cycle's first slot.)
        let schedule = *master.schedule();
        if schedule.kind(master.slot()) == SlotKind::Uplink {
            let into_cycle = master.slot() % u32::from(schedule.telemetry_ratio.max(1));
            let cycle_latch = now.saturating_sub(u64::from(into_cycle * schedule.slot_us()));
            self.handset.set_schedule(schedule.slot_us(), cycle_latch);
        }
        let latest = {
            let mut rec = self.record.borrow_mut();
            let frame = self
                .handset
                .advance(now, |f| rec.generated_us.push(f.generated_us));
            rec.handset_corrections = self.handset.corrections();
            rec.input_rejected = self.handset.rejected();
            rec.input_released = self.handset.ppm_released();
            if let Some(f) = frame
                && self.handset.kind() == HandsetKind::Ppm
                && rec.input_frames.back().is_none_or(|(k, _)| *k != f.k)
            {
                if rec.input_frames.len() == INPUT_FRAMES {
                    rec.input_frames.pop_front();
                }
                rec.input_frames.push_back((f.k, f.channels));
            }
            frame
        };
        match latest {
            Some(frame) => {
                master.set_input_lost(false);
                master.set_channels(&frame.channels);
            }
            // Nothing from the handset yet: the module says so (the follower flies failsafe).
            None => master.set_input_lost(true),
        }
        if self.telemetry_load {
            let free = master.uplink_stream.free();
            feed(self.salt ^ 0x0F, &mut self.written, free, |b| {
                master.uplink_stream.write(b)
            });
        }
        let mut guard = self.record.borrow_mut();
        let rec = &mut *guard;
        check(
            self.salt ^ 0xF0,
            &mut self.read,
            &mut rec.down_bytes_ok,
            &mut rec.down_bytes_bad,
            |b| master.downlink_stream.read(b),
        );
        if rec.master_hops.len() < HOP_RECORDS {
            let slot = master.slot();
            let ch =
                telemetry::link::HopSequence::new(master.params().bind_id).channel_for_slot(slot);
            rec.master_hops.push((slot as u8, ch));
        }
        rec.now.downlink_lq = master.downlink_lq();
        // From the 100th downlink on, so the window no longer holds acquisition-time misses.
        if master.counters().received >= 100 {
            rec.downlink_lq_sum.0 += u64::from(rec.now.downlink_lq);
            rec.downlink_lq_sum.1 += 1;
        }
        rec.now.master_rssi_dbm = master.downlink_rssi_dbm();
        if let Some(w) = &mut self.witness
            && w.attacker_accepted(master.counters().received)
        {
            rec.attacker_accepted += 1;
        }
        rec.now.downlinks_received = master.counters().received;
        rec.now.master_rejected = master.counters().rejected;
        rec.handshakes = master.handshakes();
        rec.tag_failures.0 = master.counters().tag_failures;
    }
}

/// The flight controller's application: channel outputs checked, telemetry out and in.
pub struct FlightApp {
    /// Virtual time.
    pub now: Now,
    /// Where measurements go.
    pub record: Shared,
    /// Link salt.
    pub salt: u64,
    /// Keep the downlink stream saturated.
    pub telemetry_load: bool,
    /// Under attack: attributes accepted uplinks.
    pub witness: Option<Witness>,
    format: ChannelFormat,
    handset: HandsetKind,
    last_updates: u32,
    last_sample: Option<u64>,
    last_failsafe: bool,
    /// Tag failures of the flight side's earlier boots, and of this boot's follower.
    tag_failures: (u32, u32),
    written: u64,
    read: u64,
}

impl FlightApp {
    /// A flight application for a link with `format`, fed by a handset of `handset` kind.
    pub fn new(
        now: Now,
        record: Shared,
        salt: u64,
        telemetry_load: bool,
        format: ChannelFormat,
        handset: HandsetKind,
    ) -> Self {
        Self {
            now,
            record,
            salt,
            telemetry_load,
            witness: None,
            format,
            handset,
            last_updates: 0,
            last_sample: None,
            last_failsafe: true,
            tag_failures: (0, 0),
            written: 0,
            read: 0,
        }
    }
}

impl FollowerHooks for FlightApp {
    fn on_step(&mut self, _now_us: u64, follower: &mut Follower) {
        let now = (self.now)();
        let mut guard = self.record.borrow_mut();
        let rec = &mut *guard;
        if let Some(w) = &mut self.witness
            && w.attacker_accepted(follower.counters().received)
        {
            rec.attacker_accepted += 1;
        }
        if follower.updates() != self.last_updates && !follower.in_failsafe() {
            self.last_updates = follower.updates();
            let out = follower.output();
            let k = stamp(out, self.handset);
            let expected = if self.handset == HandsetKind::Ppm {
                rec.input_frames
                    .iter()
                    .find(|(sample, _)| *sample == k)
                    .map(|(_, channels)| *channels)
            } else {
                Some(sample_channels(self.salt, k))
            };
            // The channels this update refreshed (all the format carries, or the sticks and
            // one aux group) must be sample k's.
            let carried = (1u32 << self.format.count()) - 1;
            let mask = u32::from(follower.updated_channels()) & carried;
            let right = (0..MAX_CHANNELS)
                .filter(|i| mask & (1 << i) != 0)
                .all(|i| expected.is_some_and(|e| out.get(i) == e.get(i)));
            if right && mask != 0 {
                rec.outputs_ok += 1;
                rec.last_output_us = now;
                for (i, n) in rec.channel_updates.iter_mut().enumerate() {
                    if mask & (1 << i) != 0 {
                        *n += 1;
                    }
                }
                // Frame generation → output: every handset frame since the previous output
                // (a stick movement the handset sampled then) first shows at the output now;
                // a frame superseded before it was sent counts with the later one's output.
                // (A frame output again — the handset is slower than the link — is no news.)
                let first = match self.last_sample {
                    Some(last) if k <= last => k + 1,
                    Some(last) => last + 1,
                    None => k,
                };
                for j in first..=k {
                    let Some(&generated) = rec.generated_us.get(j as usize) else {
                        continue;
                    };
                    let latency = now.saturating_sub(generated);
                    if latency <= MAX_BACKLOG_US {
                        rec.latencies_us.push(latency as u32);
                    }
                }
                self.last_sample = Some(k);
            } else {
                rec.outputs_bad += 1;
            }
        }
        if follower.in_failsafe() != self.last_failsafe {
            self.last_failsafe = follower.in_failsafe();
            rec.failsafe_changes.push((now, self.last_failsafe));
            if self.last_failsafe {
                let silence = now.saturating_sub(rec.last_output_us);
                rec.silence_before_failsafe_us.push(silence);
            }
        }
        if self.telemetry_load {
            let free = follower.downlink_stream.free();
            feed(self.salt ^ 0xF0, &mut self.written, free, |b| {
                follower.downlink_stream.write(b)
            });
        }
        check(
            self.salt ^ 0x0F,
            &mut self.read,
            &mut rec.up_bytes_ok,
            &mut rec.up_bytes_bad,
            |b| follower.uplink_stream.read(b),
        );
        if let Some(hop) = follower.tracked_slot()
            && rec.follower_hops.len() < HOP_RECORDS
            && rec.follower_hops.last() != Some(&hop)
        {
            rec.follower_hops.push(hop);
        }
        rec.now.uplink_lq = follower.uplink_lq();
        if follower.sync_state() == SyncState::Tracking {
            rec.uplink_lq_sum.0 += u64::from(rec.now.uplink_lq);
            rec.uplink_lq_sum.1 += 1;
        }
        rec.now.follower_rssi_dbm = follower.uplink_rssi_dbm();
        rec.now.uplinks_received = follower.counters().received;
        rec.now.follower_rejected = follower.counters().rejected;
        rec.now.failsafe = follower.in_failsafe();
        rec.now.tracking = follower.sync_state() == SyncState::Tracking;
        rec.now.resyncs = follower.resyncs();
        // A rebooted flight side's follower counts from 0 again.
        let failures = follower.counters().tag_failures;
        if failures < self.tag_failures.1 {
            self.tag_failures.0 += self.tag_failures.1;
        }
        self.tag_failures.1 = failures;
        rec.tag_failures.1 = self.tag_failures.0 + failures;
        let out = follower.output();
        rec.now.channels = [out[0], out[1], out[2], out[3]];
    }
}
