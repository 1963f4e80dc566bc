//! The follower's (flight side's) link logic, sans IO: acquisition (dwell on one hop channel
//! for a whole hop cycle until the master's packet lands there, listened in windows of at
//! most [`MAX_LISTEN_US`], never on a channel the master only listens on), tracking (re-timing the
//! slot grid on every packet heard), failsafe after a configurable silence, and resync.

use crate::channels::{CHANNEL_CENTER, Channels, FailsafeValues};
use crate::frame::{
    Downlink, Frame, LinkReport, Received, Rejection, decode, downlink_overhead, encode, open,
    peek_sealed, seal,
};
use crate::link::auth::{LinkKey, TagContext};
use crate::link::bind::LinkParams;
use crate::link::hopping::{HOP_CHANNELS, HopSequence};
use crate::link::quality::{Counters, LqWindow, RssiFilter};
use crate::link::radio::{LinkRx, RadioConfig};
use crate::link::schedule::{Schedule, SlotKind};
use crate::link::stream::{StreamReceiver, StreamSender};

use super::end::{report, stream_in, stream_out, stream_room};
use super::epoch::{FollowerEpoch, NonceSource};
use super::{MAX_LISTEN_US, STREAM_RX_BYTES, STREAM_TX_BYTES, Step};

/// Default failsafe delay.
pub const DEFAULT_FAILSAFE_US: u64 = 250_000;
/// The follower opens its receive window this long before the expected slot start, to
/// absorb clock drift between packets (40 ppm × one hop cycle at 20 ms slots ≈ 26 µs), the
/// grid estimate's lateness (a packet is timestamped after the nIRQ latency and its FIFO
/// read-out) and a preemption of its own receiver set-up. On the flight image the loop's
/// interrupt executor preempts the link task for ≈ 100–150 µs every IMU sample, at a phase
/// to the slots that holds for seconds (1 kHz against 250 Hz, a few hundred ppm apart): the
/// read-out then ends ≈ 250 µs after the packet and the set-up takes ≈ 250 µs instead of
/// ≈ 100. With 100 µs the window opened after the master's preamble for seconds at a time
/// (PIL, issue 28); with 300 µs, once the flight log and the CRSF device side had grown the
/// loop's exchange, for ≈ 1 s every 3.5–15 s; with 500 µs none in 30 s. Opening earlier
/// costs receiver current only: the slot before is on another hop channel, and its listen
/// ends where this window opens.
pub const RX_EARLY_US: u64 = 500;
/// While tracking, a packet of the tracked slot moves the grid later by at most this much
/// (an earlier estimate is taken whole). A packet is timestamped after the nIRQ latency and
/// its FIFO read-out, so its estimate of the slot start is never early, only late — by
/// hundreds of µs when a higher-priority task preempts the read-out (the flight loop's
/// interrupt executor, ≈ 150 µs in the PIL, issue 28), which taken whole left the follower's
/// next receive window opening after the master's preamble, every slot, until a resync.
/// Two crystals drift apart by ≤ 100 ppm: ≤ 2 µs per 20 ms slot, ≤ 13 µs over the
/// [`RESYNC_MISSES`] slots of F250 a tracking follower can go without a packet.
pub const MAX_RETIME_LATE_US: u64 = 20;
/// Consecutive missed uplinks after which the follower gives up tracking and re-acquires:
/// one hop cycle, i.e. every channel failed once.
pub const RESYNC_MISSES: u32 = HOP_CHANNELS as u32;
/// Accepted uplinks in a row that must carry the save-failsafe flag before the follower
/// stores their channels as its failsafe values (spec §6, §12.2): one frame alone — a
/// forgery that beat its 2⁻³² — never rewrites them. The master sets the flag in
/// [`SAVE_FAILSAFE_REPEATS`](super::master::SAVE_FAILSAFE_REPEATS) uplinks in a row.
pub const SAVE_FAILSAFE_FRAMES: u8 = 2;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sync {
    Acquiring {
        index: u8,
        dwell_end_us: Option<u64>,
    },
    Tracking {
        slot: u8,
        slot_start_us: u64,
        misses: u32,
    },
}

/// Whether the follower is locked to the master.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SyncState {
    /// Scanning for the master.
    Acquiring,
    /// Keyed links: on the master's slot grid by the timing of its uplinks, sending the
    /// epoch nonce in downlink slots until the master's nonce comes back under it; nothing
    /// from the uplinks is taken meanwhile (failsafe as while acquiring).
    Handshake,
    /// On the master's slot grid, taking its channels.
    Tracking,
}

/// What an uplink slot brought.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Heard {
    /// A valid uplink, taken.
    Accepted,
    /// Keyed links before the epoch is in force: an uplink of the expected slot whose tag
    /// cannot be checked yet; only its timing is taken.
    TimingOnly,
    /// Nothing usable.
    Nothing,
}

/// Whether a sealed frame names the slot being tracked: a tag failure is counted only
/// then — a forger or replayer aims at that slot, while a neighbouring link's frames (which
/// F700, sending no chip header, lets through) name any slot.
fn names_tracked_slot(bytes: &[u8], sync: Sync) -> bool {
    let Sync::Tracking { slot, .. } = sync else {
        return false;
    };
    bytes.get(2) == Some(&slot)
}

/// The follower's state.
#[derive(Debug)]
pub struct Follower {
    params: LinkParams,
    schedule: Schedule,
    hops: HopSequence,
    sync: Sync,
    failsafe_us: u64,
    failsafe_values: FailsafeValues,
    in_failsafe: bool,
    output: Channels,
    last_valid_us: Option<u64>,
    updates: u32,
    updated_mask: u16,
    /// Telemetry towards the master.
    pub downlink_stream: StreamSender<STREAM_TX_BYTES>,
    /// Telemetry from the master.
    pub uplink_stream: StreamReceiver<STREAM_RX_BYTES>,
    lq: LqWindow,
    rssi: RssiFilter,
    remote: Option<LinkReport>,
    /// When `remote` arrived.
    remote_us: Option<u64>,
    /// The power step the application asked for.
    tx_power: Option<u8>,
    counters: Counters,
    resyncs: u32,
    key: Option<LinkKey>,
    /// Keyed links: the epoch of the frame counter (spec §12.2).
    epoch: FollowerEpoch,
    /// Keyed links: the key of the epoch this follower was last in force under, until its
    /// next one: its nonce frames prove it to the master after a resync.
    previous: Option<LinkKey>,
    /// Keyed links: an uplink was taken under the epoch in force (tag failures count from
    /// then: before it the master may still tag with the epoch it is leaving).
    flying: bool,
    /// Accepted uplinks in a row with the save-failsafe flag.
    failsafe_flags: u8,
    nonces: NonceSource,
    /// The latest time the follower was told (stirs the nonces).
    now_us: u64,
}

impl Follower {
    /// A follower of a bound link, in failsafe until it hears the master.
    pub fn new(params: LinkParams, failsafe_values: FailsafeValues, failsafe_us: u64) -> Self {
        let mut output = [CHANNEL_CENTER; 16];
        failsafe_values.apply(&mut output);
        Self {
            params,
            schedule: params.schedule(),
            hops: HopSequence::new(params.bind_id),
            sync: Sync::Acquiring {
                index: 0,
                dwell_end_us: None,
            },
            failsafe_us,
            failsafe_values,
            in_failsafe: true,
            output,
            last_valid_us: None,
            updates: 0,
            updated_mask: 0,
            downlink_stream: StreamSender::new(),
            uplink_stream: StreamReceiver::new(),
            lq: LqWindow::new(),
            rssi: RssiFilter::default(),
            remote: None,
            remote_us: None,
            tx_power: None,
            counters: Counters::default(),
            resyncs: 0,
            key: None,
            epoch: FollowerEpoch::None,
            previous: None,
            flying: false,
            failsafe_flags: 0,
            nonces: NonceSource::new(0),
            now_us: 0,
        }
    }

    /// Authenticates the link with `key` (spec §12): only uplinks whose tag verifies are
    /// accepted — a forger who knows the header and hop sequence (the public bind ID's) but
    /// not the key moves neither the channels, nor the failsafe values, nor the sync state —
    /// and downlinks are sealed.
    ///
    /// Tags cover a counter in an epoch of both ends' 64-bit nonces: the follower draws its
    /// nonce at every (re)acquisition and sends it in its downlink slots; until the master's
    /// nonce comes back in a [`Frame::MasterNonce`] uplink tagged under both, the follower
    /// takes only timing from uplinks (channels stay failsafe); from then every frame is
    /// tagged with the epoch key ([`LinkKey::epoch_key`]). Seed the nonces with
    /// [`Follower::with_nonce_seed`].
    pub fn with_key(mut self, key: LinkKey) -> Self {
        self.key = Some(key);
        self
    }

    /// Seeds the epoch nonces (keyed links) with `seed`, which should come from a hardware
    /// RNG at every boot: a nonce must never repeat under one key, across reboots too (each
    /// draw is also stirred with the time, but a boot-to-lock time can repeat).
    pub fn with_nonce_seed(mut self, seed: u64) -> Self {
        self.nonces = NonceSource::new(seed);
        self
    }

    /// Whether the link is authenticated ([`Follower::with_key`]).
    pub fn has_key(&self) -> bool {
        self.key.is_some()
    }

    /// Radio configuration of this link.
    pub fn radio_config(&self) -> RadioConfig {
        self.params.radio_config()
    }

    /// Link parameters.
    pub fn params(&self) -> &LinkParams {
        &self.params
    }

    fn dwell_us(&self) -> u64 {
        // One full hop cycle plus a slot: the master visits every channel once per cycle.
        (HOP_CHANNELS as u64 + 1) * u64::from(self.schedule.slot_us())
    }

    /// Whether the master never sends an uplink at hop index `index`: when the telemetry
    /// ratio N divides the hop cycle, the slots on index `i` all have the same `s mod N`,
    /// so every index with `i mod N = N − 1` carries downlink slots only (8 of the 32 at
    /// the factory 1:4). A dwell there would wait a whole cycle for nothing.
    fn downlink_only(&self, index: u8) -> bool {
        let n = usize::from(self.schedule.telemetry_ratio);
        n >= 2
            && HOP_CHANNELS.is_multiple_of(n)
            && self.schedule.kind(u32::from(index)) == SlotKind::Downlink
    }

    /// The first hop index from `index` on (wrapping) that carries uplinks.
    fn uplink_index(&self, index: u8) -> u8 {
        let cycle = HOP_CHANNELS as u8;
        let mut i = index % cycle;
        // At most N − 1 steps: index N·k is never downlink-only (the loop is bounded anyway).
        for _ in 0..HOP_CHANNELS {
            if !self.downlink_only(i) {
                break;
            }
            i = (i + 1) % cycle;
        }
        i
    }

    /// When failsafe will be declared if nothing arrives (None while in failsafe).
    fn failsafe_deadline_us(&self) -> Option<u64> {
        if self.in_failsafe {
            return None;
        }
        self.last_valid_us.map(|t| t + self.failsafe_us)
    }

    /// A listen that would end at `end_us` ends at the failsafe deadline instead if that
    /// comes first, so failsafe is declared on time, not at the end of a slot or of a dwell
    /// (up to 660 ms). The listen then resumes for the rest of its window.
    fn listen_until(&self, now_us: u64, end_us: u64) -> u64 {
        match self.failsafe_deadline_us() {
            Some(deadline) if deadline > now_us => end_us.min(deadline),
            _ => end_us,
        }
    }

    fn check_failsafe(&mut self, now_us: u64) {
        if self.in_failsafe {
            return;
        }
        let silent = self
            .last_valid_us
            .is_none_or(|t| now_us.saturating_sub(t) >= self.failsafe_us);
        if silent {
            self.in_failsafe = true;
            self.failsafe_values.apply(&mut self.output);
        }
    }

    fn slot_end_us(&self, slot: u8, slot_start_us: u64) -> u64 {
        match self.schedule.kind(u32::from(slot)) {
            // The wait for a packet's start ends where the next slot's window opens, so a
            // missed uplink never delays the next window (the sync word of ours comes long
            // before; a packet that started is received whole).
            SlotKind::Uplink => {
                slot_start_us
                    + u64::from(self.schedule.listen_end_offset_us())
                        .min(u64::from(self.schedule.slot_us()).saturating_sub(RX_EARLY_US))
            }
            SlotKind::Downlink => slot_start_us + u64::from(self.schedule.rate.tx_lead_us()),
        }
    }

    /// Moves past the tracked slot; an uplink slot passed without a packet is a miss.
    fn advance(&mut self, heard: Heard) {
        let Sync::Tracking {
            slot,
            slot_start_us,
            misses,
        } = self.sync
        else {
            return;
        };
        let uplink = self.schedule.kind(u32::from(slot)) == SlotKind::Uplink;
        let misses = match heard {
            Heard::Accepted | Heard::TimingOnly => 0,
            Heard::Nothing if uplink => misses + 1,
            Heard::Nothing => misses,
        };
        if uplink && heard != Heard::Accepted {
            self.lq.push(false);
        }
        if uplink && heard == Heard::Nothing {
            self.counters.missed += 1;
        }
        let next = slot.wrapping_add(1);
        self.sync = if misses >= RESYNC_MISSES {
            self.resyncs += 1;
            self.lq.reset();
            if let Some(key) = self.epoch.key() {
                self.previous = Some(*key);
            }
            self.epoch = FollowerEpoch::None;
            self.flying = false;
            Sync::Acquiring {
                index: next % HOP_CHANNELS as u8,
                dwell_end_us: None,
            }
        } else {
            self.epoch.advance(next, &mut self.nonces, self.now_us);
            Sync::Tracking {
                slot: next,
                slot_start_us: slot_start_us + u64::from(self.schedule.slot_us()),
                misses,
            }
        };
    }

    /// Plans the next step at `now_us`; writes a downlink frame into `buf` when it is time
    /// to send one.
    pub fn plan(&mut self, now_us: u64, buf: &mut [u8]) -> Step {
        self.now_us = now_us;
        self.check_failsafe(now_us);
        // Slots whose window has passed (the loop fell behind) are misses.
        while let Sync::Tracking {
            slot,
            slot_start_us,
            ..
        } = self.sync
        {
            if now_us < self.slot_end_us(slot, slot_start_us) {
                break;
            }
            self.advance(Heard::Nothing);
        }
        match self.sync {
            Sync::Acquiring {
                index,
                dwell_end_us,
            } => {
                let end = match dwell_end_us {
                    Some(end) if now_us < end => end,
                    Some(_) => {
                        let next = self.uplink_index(index.wrapping_add(1));
                        self.sync = Sync::Acquiring {
                            index: next,
                            dwell_end_us: Some(now_us + self.dwell_us()),
                        };
                        now_us + self.dwell_us()
                    }
                    None => {
                        // A resync starts at the slot after the last one tracked, which may
                        // be a downlink-only index.
                        self.sync = Sync::Acquiring {
                            index: self.uplink_index(index),
                            dwell_end_us: Some(now_us + self.dwell_us()),
                        };
                        now_us + self.dwell_us()
                    }
                };
                let Sync::Acquiring { index, .. } = self.sync else {
                    return Step::Idle;
                };
                let channel = self.hops.channel(usize::from(index));
                // The dwell is listened in windows of at most MAX_LISTEN_US on the same
                // channel (the dwell end is kept in `sync`), so the loop returns often
                // enough for the application's watchdog; and it wakes at the failsafe
                // deadline even mid-dwell, so failsafe is declared on time.
                let until_us = self.listen_until(now_us, end.min(now_us + MAX_LISTEN_US));
                Step::Listen {
                    channel,
                    from_us: now_us,
                    until_us,
                }
            }
            Sync::Tracking {
                slot,
                slot_start_us,
                ..
            } => {
                let channel = self.hops.channel_for_slot(u32::from(slot));
                match self.schedule.kind(u32::from(slot)) {
                    SlotKind::Uplink => Step::Listen {
                        channel,
                        from_us: slot_start_us.saturating_sub(RX_EARLY_US),
                        until_us: self.listen_until(now_us, self.slot_end_us(slot, slot_start_us)),
                    },
                    SlotKind::Downlink => match self.build_downlink(slot, buf) {
                        Some(len) => Step::Transmit {
                            channel,
                            at_us: slot_start_us + u64::from(self.schedule.rate.tx_lead_us()),
                            len,
                        },
                        None => Step::Idle,
                    },
                }
            }
        }
    }

    fn build_downlink(&mut self, slot: u8, buf: &mut [u8]) -> Option<usize> {
        if let (Some(key), FollowerEpoch::Handshake { nonce }) = (&self.key, self.epoch) {
            // The nonce goes out with the link key (the master cannot know anything else
            // yet), alone: no stream data that a replay could inject; after a resync with
            // the proof of the epoch this follower was in force under.
            let proof = self.previous.map(|k| k.rekey_proof(nonce, slot));
            let frame = Frame::Nonce { slot, nonce, proof };
            return seal(&frame, key, &TagContext::FollowerNonce, buf).ok();
        }
        let room = stream_room(&self.params, downlink_overhead(true), self.key.is_some());
        let mut data = [0u8; 64];
        let (stream, data) = stream_out(
            &mut self.downlink_stream,
            &self.uplink_stream,
            room,
            &mut data,
        )?;
        let down = Downlink {
            slot,
            stream,
            report: Some(report(&self.rssi, &self.lq)),
            data,
        };
        match &self.key {
            Some(_) => {
                let key = self.epoch.key()?;
                let counter = self.epoch.counter(slot)?;
                seal(
                    &Frame::Downlink(down),
                    key,
                    &TagContext::Counter(counter),
                    buf,
                )
                .ok()
            }
            None => encode(&Frame::Downlink(down), self.params.bind_id, buf).ok(),
        }
    }

    /// The downlink planned by [`Follower::plan`] has been sent.
    pub fn on_sent(&mut self) {
        self.counters.sent += 1;
        // Sending is not hearing: the run of missed uplinks goes on (a downlink slot is
        // neither a hit nor a miss).
        self.advance(Heard::Nothing);
    }

    /// A planned step was not carried out (e.g. `Idle`); move on.
    pub fn on_skipped(&mut self) {
        self.advance(Heard::Nothing);
    }

    /// The outcome of a listen, at `now_us` (for a packet: when it had fully arrived).
    pub fn on_received(&mut self, outcome: LinkRx, packet: &[u8], now_us: u64) {
        self.now_us = now_us;
        if let LinkRx::Packet { len, rssi_dbm } = outcome {
            let bytes = packet.get(..len).unwrap_or(&[]);
            // Re-time the grid: the master started this slot `packet_end_offset` ago.
            let measured_us =
                now_us.saturating_sub(u64::from(self.schedule.packet_end_offset_us(len)));
            let received = self.decode_uplink(bytes);
            if received == Received::Rejected(Rejection::Tag)
                && self.flying
                && names_tracked_slot(bytes, self.sync)
            {
                self.counters.tag_failures = self.counters.tag_failures.saturating_add(1);
            }
            if let Received::Accepted(Frame::MasterNonce { slot, nonce }) = received
                && self.take_master_nonce(slot, nonce, rssi_dbm, self.retimed(slot, measured_us))
            {
                return;
            }
            if let Received::Accepted(Frame::Uplink(up)) = received {
                let expected = match self.sync {
                    Sync::Acquiring { index, .. } => (up.slot % HOP_CHANNELS as u8) == index,
                    // Spec §5.3 check 4: while tracking only the slot being listened for is
                    // accepted; a replayed frame of another slot would shift the hop phase.
                    Sync::Tracking { slot, .. } => up.slot == slot,
                };
                if expected && self.schedule.kind(u32::from(up.slot)) == SlotKind::Uplink {
                    self.sync = Sync::Tracking {
                        slot: up.slot,
                        slot_start_us: self.retimed(up.slot, measured_us),
                        misses: 0,
                    };
                    self.accept(&up, rssi_dbm, now_us);
                    self.advance(Heard::Accepted);
                    return;
                }
            } else if let Some(slot) = self.timing_only(bytes) {
                if self.epoch == FollowerEpoch::None {
                    // Locked by timing: a fresh epoch nonce for the handshake.
                    self.epoch = FollowerEpoch::Handshake {
                        nonce: self.nonces.draw(now_us),
                    };
                }
                self.sync = Sync::Tracking {
                    slot,
                    slot_start_us: self.retimed(slot, measured_us),
                    misses: 0,
                };
                // Its content is not taken: counted as rejected.
                self.counters.rejected += 1;
                self.advance(Heard::TimingOnly);
                return;
            }
            self.counters.rejected += 1;
        } else if outcome == LinkRx::Corrupted {
            self.counters.rejected += 1;
        }
        self.check_failsafe(now_us);
    }

    /// The start of `slot` from a packet's `measured_us` estimate: while that slot is the one
    /// tracked, no more than [`MAX_RETIME_LATE_US`] after the grid's own.
    fn retimed(&self, slot: u8, measured_us: u64) -> u64 {
        match self.sync {
            Sync::Tracking {
                slot: tracked,
                slot_start_us,
                ..
            } if tracked == slot => measured_us.min(slot_start_us + MAX_RETIME_LATE_US),
            _ => measured_us,
        }
    }

    /// The master's nonce, verified under the handshake's counter of the tracked slot: the
    /// epoch of both nonces is in force from now on. The frame carries nothing else (no
    /// channels, flags or stream); it counts as a packet heard. False if it is not for the
    /// slot being listened for.
    fn take_master_nonce(
        &mut self,
        slot: u8,
        master_nonce: u64,
        rssi_dbm: i16,
        slot_start_us: u64,
    ) -> bool {
        let (Some(link), FollowerEpoch::Handshake { nonce }, Sync::Tracking { slot: tracked, .. }) =
            (&self.key, self.epoch, self.sync)
        else {
            return false;
        };
        if slot != tracked || self.schedule.kind(u32::from(slot)) != SlotKind::Uplink {
            return false;
        }
        self.epoch = FollowerEpoch::InForce {
            nonce,
            master_nonce,
            key: link.epoch_key(nonce, master_nonce),
            wraps: 0,
        };
        self.flying = false;
        self.sync = Sync::Tracking {
            slot,
            slot_start_us,
            misses: 0,
        };
        self.counters.received += 1;
        self.lq.push(true);
        self.rssi.push(rssi_dbm);
        self.advance(Heard::Accepted);
        true
    }

    /// Decodes an uplink: with a key, its tag is checked in the context of the slot being
    /// listened for — the epoch key under its counter once the epoch is in force; during the
    /// handshake only the master's nonce verifies (the link key, under our nonce); while
    /// acquiring nothing verifies (the follower's fresh nonce is not yet sent).
    fn decode_uplink<'a>(&self, bytes: &'a [u8]) -> Received<'a> {
        let Some(link) = &self.key else {
            return decode(bytes, self.params.bind_id);
        };
        let Sync::Tracking { slot, .. } = self.sync else {
            return Received::Rejected(Rejection::Tag);
        };
        match self.epoch {
            FollowerEpoch::InForce { key, wraps, .. } => open(
                bytes,
                &key,
                &TagContext::Counter(super::epoch::counter(wraps, slot)),
            ),
            // The handshake's context is the master's nonce's alone: nothing else is taken
            // under it (the master sends channels only under an epoch key), so no frame
            // can give channels before the epoch is in force.
            FollowerEpoch::Handshake { nonce } => match open(
                bytes,
                link,
                &TagContext::MasterNonce {
                    follower_nonce: nonce,
                },
            ) {
                received @ Received::Accepted(Frame::MasterNonce { .. }) => received,
                Received::Accepted(_) => Received::Rejected(Rejection::Malformed),
                rejected => rejected,
            },
            FollowerEpoch::None => Received::Rejected(Rejection::Tag),
        }
    }

    /// Keyed links before the epoch is in force: the slot of a well-formed sealed uplink
    /// of the expected slot (the dwell channel's while acquiring), whose timing alone the
    /// follower may take to reach its downlink slot. A forger can at most move the grid
    /// and so delay the handshake, as jamming can.
    fn timing_only(&self, bytes: &[u8]) -> Option<u8> {
        if self.key.is_none() || matches!(self.epoch, FollowerEpoch::InForce { .. }) {
            return None;
        }
        let slot = match peek_sealed(bytes)? {
            Frame::Uplink(up) => up.slot,
            Frame::MasterNonce { slot, .. } => slot,
            _ => return None,
        };
        let expected = match self.sync {
            Sync::Acquiring { index, .. } => (slot % HOP_CHANNELS as u8) == index,
            Sync::Tracking { slot: tracked, .. } => slot == tracked,
        };
        (expected && self.schedule.kind(u32::from(slot)) == SlotKind::Uplink).then_some(slot)
    }

    fn accept(&mut self, up: &crate::frame::Uplink<'_>, rssi_dbm: i16, now_us: u64) {
        self.counters.received += 1;
        self.lq.push(true);
        self.rssi.push(rssi_dbm);
        self.last_valid_us = Some(now_us);
        if up.input_lost {
            // The master's own input stopped: its channels are stale. Fly the failsafe now
            // rather than after `failsafe_us`; the link itself stays tracked.
            if !self.in_failsafe {
                self.in_failsafe = true;
                self.failsafe_values.apply(&mut self.output);
            }
        } else {
            self.updated_mask = up.channels_into_mask(&mut self.output).unwrap_or(0);
            self.failsafe_flags = if up.save_failsafe {
                self.failsafe_flags.saturating_add(1)
            } else {
                0
            };
            if self.failsafe_flags >= SAVE_FAILSAFE_FRAMES {
                self.failsafe_values = FailsafeValues::from_channels(&self.output);
            }
            self.in_failsafe = false;
            self.updates = self.updates.wrapping_add(1);
        }
        if self.key.is_some() {
            self.flying = true;
        }
        if up.report.is_some() {
            self.remote = up.report;
            self.remote_us = Some(now_us);
        }
        let (send, receive) = (&mut self.downlink_stream, &mut self.uplink_stream);
        stream_in(send, receive, up.stream, up.data);
    }

    /// Channel outputs (failsafe values while in failsafe).
    pub fn output(&self) -> &Channels {
        &self.output
    }

    /// Number of channel updates received so far (changes when `output` was refreshed).
    pub fn updates(&self) -> u32 {
        self.updates
    }

    /// Which channels the latest update refreshed (bit `i` = channel `i`): all carried ones,
    /// or with [`ChannelFormat::Sticks16`] the four sticks and one aux group.
    ///
    /// [`ChannelFormat::Sticks16`]: crate::channels::ChannelFormat::Sticks16
    pub fn updated_channels(&self) -> u16 {
        self.updated_mask
    }

    /// In failsafe?
    pub fn in_failsafe(&self) -> bool {
        self.in_failsafe
    }

    /// Locked to the master?
    pub fn sync_state(&self) -> SyncState {
        match (self.sync, self.epoch) {
            (Sync::Acquiring { .. }, _) => SyncState::Acquiring,
            (Sync::Tracking { .. }, FollowerEpoch::Handshake { .. }) => SyncState::Handshake,
            (Sync::Tracking { .. }, _) => SyncState::Tracking,
        }
    }

    /// Slot and hop channel being tracked, if tracking.
    pub fn tracked_slot(&self) -> Option<(u8, u8)> {
        match self.sync {
            Sync::Tracking { slot, .. } => {
                Some((slot, self.hops.channel_for_slot(u32::from(slot))))
            }
            Sync::Acquiring { .. } => None,
        }
    }

    /// Keyed links: the epoch in force as (the follower's nonce, the master's nonce) —
    /// public values (both travel in clear); frames are tagged with
    /// [`LinkKey::epoch_key`]`(follower, master)` of the link key. None during the handshake
    /// and while acquiring.
    pub fn epoch_nonces(&self) -> Option<(u64, u64)> {
        match self.epoch {
            FollowerEpoch::InForce {
                nonce,
                master_nonce,
                ..
            } => Some((nonce, master_nonce)),
            _ => None,
        }
    }

    /// Keyed links: the frame counter (spec §12.2) of the tracked slot in the epoch in force,
    /// under which an uplink of that slot must verify (epoch key) and the follower's
    /// downlink of it is tagged. None while acquiring or in the handshake (where only the
    /// master's nonce verifies, in [`TagContext::MasterNonce`] of
    /// [`Follower::handshake_nonce`] with the link key).
    ///
    /// Public information, not a secret: the slot and its wraps are counted on the grid both
    /// ends share; only the key makes a tag. Read by diagnostics and by the fuzz harnesses
    /// (`tests/fuzz`), which seal fuzzed uplinks under it so they reach channels, flags and
    /// the stream.
    pub fn frame_counter(&self) -> Option<u64> {
        match self.sync {
            Sync::Tracking { slot, .. } => self.epoch.counter(slot),
            Sync::Acquiring { .. } => None,
        }
    }

    /// Keyed links in the handshake: the nonce this follower sends (public: it travels in
    /// clear in its nonce frames).
    pub fn handshake_nonce(&self) -> Option<u64> {
        match self.epoch {
            FollowerEpoch::Handshake { nonce } => Some(nonce),
            FollowerEpoch::None | FollowerEpoch::InForce { .. } => None,
        }
    }

    /// Current failsafe settings.
    pub fn failsafe_values(&self) -> &FailsafeValues {
        &self.failsafe_values
    }

    /// Uplink LQ (% of the last 100 expected uplinks received).
    pub fn uplink_lq(&self) -> u8 {
        self.lq.percent()
    }

    /// Smoothed RSSI of the master's packets.
    pub fn uplink_rssi_dbm(&self) -> Option<i16> {
        self.rssi.dbm()
    }

    /// The master's last report of how it hears us.
    pub fn remote_report(&self) -> Option<LinkReport> {
        self.remote
    }

    /// The master's last report with the time it arrived on this end's clock (dynamic power,
    /// `link::power`, counts missed reports from it).
    pub fn remote_report_at(&self) -> Option<(LinkReport, u64)> {
        self.remote.zip(self.remote_us)
    }

    /// Asks the loop to transmit at power `step` (0…7, `link::power`) from the next slot
    /// on; the loop writes the radio ([`PacketRadio::set_tx_power`](crate::link::PacketRadio::set_tx_power)) when it changes.
    pub fn set_tx_power(&mut self, step: u8) {
        self.tx_power = Some(step);
    }

    /// The power step asked for by [`Follower::set_tx_power`]; `None`: the radio's own, as
    /// configured.
    pub fn tx_power(&self) -> Option<u8> {
        self.tx_power
    }

    /// Packet counters.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// The loop met a radio error and is re-configuring the radio (counted in
    /// [`Counters::radio_errors`]).
    pub fn on_radio_error(&mut self) {
        self.counters.radio_errors = self.counters.radio_errors.saturating_add(1);
    }

    /// Times tracking was lost and acquisition restarted.
    pub fn resyncs(&self) -> u32 {
        self.resyncs
    }
}
