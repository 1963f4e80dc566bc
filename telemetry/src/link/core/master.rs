//! The master's (module's) link logic, sans IO: it owns the slot counter, so it never waits
//! for anyone — every slot it either sends channels or listens for telemetry, on the hop
//! channel of that slot, whether or not the follower is there.

use crate::channels::{CHANNEL_CENTER, Channels, pack_group};
use crate::frame::{
    Frame, LinkReport, NONCE_FRAME_BYTES, Received, Rejection, Uplink, decode, encode, open,
    peek_sealed, seal, sealed_uplink_bytes, uplink_overhead,
};
use crate::link::auth::{LinkKey, TagContext};
use crate::link::bind::LinkParams;
use crate::link::hopping::HopSequence;
use crate::link::quality::{Counters, LqWindow, RssiFilter};
use crate::link::radio::{LinkRx, RadioConfig};
use crate::link::schedule::{Schedule, SlotKind};
use crate::link::stream::{StreamReceiver, StreamSender};

use super::end::{STREAM_CHUNK_BYTES, report, stream_in, stream_out, stream_ready, stream_room};
use super::epoch::{MasterEpoch, NonceVerdict};
use super::follower::DEFAULT_FAILSAFE_US;
use super::{STREAM_RX_BYTES, STREAM_TX_BYTES, Step};

/// Uplinks that carry a save-failsafe request, so one lost packet does not lose it (storing
/// twice is harmless: the follower keeps the channels of the last flagged packet).
pub const SAVE_FAILSAFE_REPEATS: u8 = 8;

/// Slots within which an epoch heard from its follower counts as live (spec §12.2): the
/// follower's default failsafe period, at least one downlink period.
fn live_slots(params: &LinkParams) -> u32 {
    let schedule = params.schedule();
    let slots = DEFAULT_FAILSAFE_US / u64::from(schedule.slot_us().max(1));
    u32::try_from(slots)
        .unwrap_or(u32::MAX)
        .max(u32::from(schedule.telemetry_ratio))
}

/// The master's state.
#[derive(Debug)]
pub struct Master {
    params: LinkParams,
    schedule: Schedule,
    hops: HopSequence,
    slot: u32,
    channels: Channels,
    /// Uplinks still to carry the save-failsafe flag.
    save_failsafe: u8,
    /// Uplinks carry the input-lost flag (the application has no fresh channels).
    input_lost: bool,
    /// The aux group the next uplink carries ([`ChannelFormat::Sticks16`]; cycles per
    /// uplink sent).
    ///
    /// [`ChannelFormat::Sticks16`]: crate::channels::ChannelFormat::Sticks16
    aux_group: u8,
    report_due: bool,
    heard: bool,
    /// Telemetry towards the follower.
    pub uplink_stream: StreamSender<STREAM_TX_BYTES>,
    /// Telemetry from the follower.
    pub downlink_stream: StreamReceiver<STREAM_RX_BYTES>,
    lq: LqWindow,
    rssi: RssiFilter,
    remote: Option<LinkReport>,
    /// When `remote` arrived.
    remote_us: Option<u64>,
    /// The power step the application asked for.
    tx_power: Option<u8>,
    counters: Counters,
    last_downlink_us: Option<u64>,
    key: Option<LinkKey>,
    /// Keyed links: the epoch in use (spec §12.2).
    epoch: MasterEpoch,
    /// Keyed links: the next uplink carries the master's nonce of the pending epoch instead
    /// of channels (set at adoption and at every repeat of the follower's nonce, which says
    /// it has not got it).
    master_nonce_due: bool,
    /// The uplink planned in this slot is the master's nonce.
    planned_nonce: bool,
    /// Stream bytes [`Master::uplink_len`] counted for this slot's uplink: [`Master::plan`]
    /// takes no more, so the frame keeps the length the radio was started with.
    stream_cap: Option<usize>,
}

impl Master {
    /// A master for a bound link, starting at slot 0 with centred channels.
    pub fn new(params: LinkParams) -> Self {
        Self {
            params,
            schedule: params.schedule(),
            hops: HopSequence::new(params.bind_id),
            slot: 0,
            channels: [CHANNEL_CENTER; 16],
            save_failsafe: 0,
            input_lost: false,
            aux_group: 0,
            report_due: false,
            heard: false,
            uplink_stream: StreamSender::new(),
            downlink_stream: StreamReceiver::new(),
            lq: LqWindow::new(),
            rssi: RssiFilter::default(),
            remote: None,
            remote_us: None,
            tx_power: None,
            counters: Counters::default(),
            last_downlink_us: None,
            key: None,
            epoch: MasterEpoch::new(0, live_slots(&params)),
            master_nonce_due: false,
            planned_nonce: false,
            stream_cap: None,
        }
    }

    /// Authenticates the link with `key` (spec §12): every frame is sealed with a tag and
    /// only tagged downlinks are accepted; the link identity (header) and the hop sequence
    /// stay the public bind ID's, which verify nothing. Tags cover a counter in an epoch of
    /// both ends' 64-bit nonces: the master adopts a verified fresh follower nonce from a
    /// [`Frame::Nonce`] downlink, answers with its own in a [`Frame::MasterNonce`] uplink,
    /// and once a downlink verifies under the new epoch's key, tags and accepts frames only
    /// with it (until then the epoch in force stays: a replayed nonce frame never takes the
    /// link away from its follower). Seed its nonces with [`Master::with_nonce_seed`].
    pub fn with_key(mut self, key: LinkKey) -> Self {
        self.key = Some(key);
        self
    }

    /// Seeds the master's epoch nonces (keyed links) with `seed`, which should come from a
    /// hardware RNG at every boot: the master's nonce is what keeps a replayed follower nonce
    /// from restarting an old epoch's counters, across reboots too (each draw is also stirred
    /// with the time).
    pub fn with_nonce_seed(mut self, seed: u64) -> Self {
        self.epoch = MasterEpoch::new(seed, live_slots(&self.params));
        self
    }

    /// Whether the link is authenticated ([`Master::with_key`]).
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

    /// The schedule.
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Sets the channel values sent from the next uplink on.
    pub fn set_channels(&mut self, channels: &Channels) {
        self.channels = *channels;
    }

    /// Whether the channels are stale because the application's input stopped (handset
    /// unplugged or frozen). While set, every uplink carries the input-lost flag and the
    /// follower flies its failsafe instead of the channels; the link, its statistics and the
    /// telemetry streams keep running. No save-failsafe request goes out meanwhile.
    pub fn set_input_lost(&mut self, lost: bool) {
        self.input_lost = lost;
    }

    /// Whether uplinks carry the input-lost flag.
    pub fn input_lost(&self) -> bool {
        self.input_lost
    }

    /// Asks the follower to store the current channels as its failsafe values (flag set in
    /// the next [`SAVE_FAILSAFE_REPEATS`] uplinks).
    pub fn request_save_failsafe(&mut self) {
        self.save_failsafe = SAVE_FAILSAFE_REPEATS;
    }

    /// The slot about to run.
    pub fn slot(&self) -> u32 {
        self.slot
    }

    /// Plans the current slot, which starts at `slot_start_us`, writing an uplink frame into
    /// `buf` when it is an uplink slot.
    pub fn plan(&mut self, slot_start_us: u64, buf: &mut [u8]) -> Step {
        let channel = self.hops.channel_for_slot(self.slot);
        match self.schedule.kind(self.slot) {
            SlotKind::Downlink => Step::Listen {
                channel,
                from_us: slot_start_us,
                until_us: slot_start_us + u64::from(self.schedule.listen_end_offset_us()),
            },
            SlotKind::Uplink => match self.build_uplink(buf) {
                Some(len) => Step::Transmit {
                    channel,
                    at_us: slot_start_us + u64::from(self.schedule.rate.tx_lead_us()),
                    len,
                },
                // Only with a buffer smaller than max_frame_bytes: skip the slot, never panic.
                None => Step::Idle,
            },
        }
    }

    /// The hop channel of the current slot.
    pub fn channel(&self) -> u8 {
        self.hops.channel_for_slot(self.slot)
    }

    /// The length of this slot's uplink, from what it will carry (nonce or channels, report,
    /// the stream bytes ready now, CRC or tag) without building it: the radio can be started
    /// with it (preamble and sync on the air) before the channels are latched and
    /// [`Master::plan`] builds the frame, with the same length — its stream data is capped
    /// to what this one counted (the application may queue more meanwhile; acks, which could
    /// shorten it, only come with a downlink). `None` in a downlink slot.
    pub fn uplink_len(&mut self) -> Option<usize> {
        if self.schedule.kind(self.slot) != SlotKind::Uplink {
            return None;
        }
        self.stream_cap = None;
        if self.master_nonce().is_some() {
            return Some(NONCE_FRAME_BYTES);
        }
        let (format, with_report) = (self.params.format, self.report_due);
        let room = stream_room(
            &self.params,
            uplink_overhead(format, with_report),
            self.key.is_some(),
        );
        let data = stream_ready(&self.uplink_stream, room)?;
        self.stream_cap = Some(data);
        Some(match self.key {
            Some(_) => sealed_uplink_bytes(format, with_report, data),
            None => uplink_overhead(format, with_report) + data,
        })
    }

    /// The master's nonce and the follower's it answers, when this slot's uplink is to
    /// carry it.
    fn master_nonce(&self) -> Option<(&LinkKey, (u64, u64))> {
        let key = self.key.as_ref().filter(|_| self.master_nonce_due)?;
        Some((key, self.epoch.master_nonce_for(self.slot)?))
    }

    /// Builds the uplink into `buf`; returns its length.
    fn build_uplink(&mut self, buf: &mut [u8]) -> Option<usize> {
        self.planned_nonce = self.master_nonce().is_some();
        if let Some((key, (nonce, follower_nonce))) = self.master_nonce() {
            // The follower is still in its handshake: the master's nonce, alone, with the
            // link key under both nonces (only that follower can check it); no channels to
            // take.
            let frame = Frame::MasterNonce {
                slot: self.slot as u8,
                nonce,
            };
            let context = TagContext::MasterNonce { follower_nonce };
            return seal(&frame, key, &context, buf).ok();
        }
        let format = self.params.format;
        let report = self.report_due.then(|| report(&self.rssi, &self.lq));
        let mut packed = [0u8; 22];
        let packed = packed.get_mut(..format.packed_bytes())?;
        pack_group(&self.channels, format, self.aux_group, packed);
        let overhead = uplink_overhead(format, report.is_some());
        let room = stream_room(&self.params, overhead, self.key.is_some());
        let room = room.min(self.stream_cap.take().unwrap_or(usize::MAX));
        let mut data = [0u8; STREAM_CHUNK_BYTES];
        let (stream, data) = stream_out(
            &mut self.uplink_stream,
            &self.downlink_stream,
            room,
            &mut data,
        )?;
        let up = Uplink {
            slot: self.slot as u8,
            stream,
            report,
            save_failsafe: self.save_failsafe > 0 && !self.input_lost,
            input_lost: self.input_lost,
            format,
            packed_channels: packed,
            data,
        };
        let len = match (&self.key, self.epoch.key(), self.frame_counter()) {
            (Some(_), Some(epoch_key), Some(counter)) => seal(
                &Frame::Uplink(up),
                epoch_key,
                &TagContext::Counter(counter),
                buf,
            ),
            // No epoch in force: tagged with the link key in a context no follower checks
            // anything under — it gives timing only.
            (Some(key), _, _) => seal(&Frame::Uplink(up), key, &TagContext::BeforeEpoch, buf),
            (None, _, _) => encode(&Frame::Uplink(up), self.params.bind_id, buf),
        };
        len.ok()
    }

    /// The uplink of the current slot has been sent.
    pub fn on_sent(&mut self) {
        self.counters.sent += 1;
        if self.planned_nonce {
            // It carried neither channels nor flags nor the report.
            self.planned_nonce = false;
            self.master_nonce_due = false;
            self.next_slot();
            return;
        }
        self.aux_group = (self.aux_group + 1) % self.params.format.groups();
        self.save_failsafe = self.save_failsafe.saturating_sub(1);
        self.report_due = false;
        self.next_slot();
    }

    fn next_slot(&mut self) {
        self.stream_cap = None;
        self.slot = self.slot.wrapping_add(1);
        self.epoch.on_slot(self.slot);
    }

    /// One receive outcome in the current (downlink) slot, at `now_us`. Returns true once
    /// the follower's downlink has been heard (the slot is done); otherwise the loop listens
    /// on for the rest of the window. Then call [`Master::finish_listen`].
    pub fn on_received(&mut self, outcome: LinkRx, packet: &[u8], now_us: u64) -> bool {
        match outcome {
            LinkRx::Packet { len, rssi_dbm } => {
                let bytes = packet.get(..len).unwrap_or(&[]);
                let received = match self.key {
                    Some(key) => self.open_downlink(&key, bytes),
                    None => decode(bytes, self.params.bind_id),
                };
                match received {
                    Received::Accepted(Frame::Downlink(down)) if down.slot == self.slot as u8 => {
                        self.heard(rssi_dbm, now_us);
                        if down.report.is_some() {
                            self.remote = down.report;
                            self.remote_us = Some(now_us);
                        }
                        let (send, receive) = (&mut self.uplink_stream, &mut self.downlink_stream);
                        stream_in(send, receive, down.stream, down.data);
                    }
                    // A verified nonce of this slot: only the epoch moves (its frame carries
                    // nothing else, so a refused replay changes nothing).
                    Received::Accepted(Frame::Nonce { slot, nonce, proof })
                        if slot == self.slot as u8 =>
                    {
                        let verdict = match &self.key {
                            Some(key) => self.epoch.offer(nonce, proof, self.slot, key, now_us),
                            None => NonceVerdict::Refused,
                        };
                        match verdict {
                            NonceVerdict::Adopted | NonceVerdict::Repeated => {
                                // (Again) the follower has not got our nonce: it goes out
                                // in the next uplink.
                                self.master_nonce_due = true;
                                self.heard(rssi_dbm, now_us);
                            }
                            NonceVerdict::Refused => self.counters.rejected += 1,
                        }
                    }
                    _ => self.counters.rejected += 1,
                }
            }
            LinkRx::Corrupted => self.counters.rejected += 1,
            LinkRx::Timeout => {}
        }
        self.heard
    }

    /// Checks a sealed downlink: a nonce frame with the link key in the follower's nonce
    /// context; anything else with the key of the epoch in force under its counter, else
    /// with the pending epoch's — whose follower is then heard under it, so it comes into
    /// force. Without any epoch nothing verifies. Tag failures are counted where the tag
    /// could be checked: a nonce frame's, and a downlink's under the epoch in force that
    /// no pending epoch explains.
    fn open_downlink<'a>(&mut self, key: &LinkKey, bytes: &'a [u8]) -> Received<'a> {
        if let Some(Frame::Nonce { .. }) = peek_sealed(bytes) {
            let received = open(bytes, key, &TagContext::FollowerNonce);
            self.count_tag_failure(received, bytes);
            return received;
        }
        let slot = self.slot;
        // Only the follower's downlink of this slot is taken under an epoch: whatever else
        // verifies (a frame the follower never sends) neither counts nor makes it live.
        let check = |(epoch_key, counter): (LinkKey, u64)| match open(
            bytes,
            &epoch_key,
            &TagContext::Counter(counter),
        ) {
            received @ Received::Accepted(Frame::Downlink(down)) if down.slot == slot as u8 => {
                received
            }
            Received::Accepted(_) => Received::Rejected(Rejection::Malformed),
            received => received,
        };
        let current = self.epoch.current_check(slot).map(check);
        if let Some(received @ Received::Accepted(_)) = current {
            self.epoch.heard(slot);
            return received;
        }
        if let Some(received @ Received::Accepted(_)) = self.epoch.pending_check(slot).map(check) {
            self.epoch.confirm(slot);
            return received;
        }
        let Some(received) = current else {
            return Received::Rejected(Rejection::Tag);
        };
        self.count_tag_failure(received, bytes);
        received
    }

    /// Counts a tag failure of a frame naming the current slot (a neighbouring link's
    /// frames, which F700 lets through without a chip header, name any slot).
    fn count_tag_failure(&mut self, received: Received<'_>, bytes: &[u8]) {
        if received == Received::Rejected(Rejection::Tag)
            && bytes.get(2) == Some(&(self.slot as u8))
        {
            self.counters.tag_failures = self.counters.tag_failures.saturating_add(1);
        }
    }

    fn heard(&mut self, rssi_dbm: i16, now_us: u64) {
        self.heard = true;
        self.counters.received += 1;
        self.rssi.push(rssi_dbm);
        self.last_downlink_us = Some(now_us);
    }

    /// The downlink slot's listening window is over.
    pub fn finish_listen(&mut self) {
        if !self.heard {
            self.counters.missed += 1;
        }
        self.lq.push(self.heard);
        self.heard = false;
        self.report_due = true;
        self.next_slot();
    }

    /// The current slot was skipped (the loop fell behind).
    pub fn on_skipped(&mut self) {
        if self.schedule.kind(self.slot) == SlotKind::Downlink {
            self.lq.push(false);
            self.counters.missed += 1;
        }
        self.next_slot();
    }

    /// Downlink LQ (% of the last 100 downlink slots that brought valid telemetry).
    pub fn downlink_lq(&self) -> u8 {
        self.lq.percent()
    }

    /// Smoothed RSSI of the follower's packets.
    pub fn downlink_rssi_dbm(&self) -> Option<i16> {
        self.rssi.dbm()
    }

    /// The follower's last report of how it hears us (uplink RSSI and LQ).
    pub fn remote_report(&self) -> Option<LinkReport> {
        self.remote
    }

    /// The follower's last report with the time it arrived on this end's clock (dynamic power,
    /// `link::power`, counts missed reports from it).
    pub fn remote_report_at(&self) -> Option<(LinkReport, u64)> {
        self.remote.zip(self.remote_us)
    }

    /// Asks the loop to transmit at power `step` (0…7, `link::power`) from the next slot
    /// on; the loop writes the radio ([`PacketRadio::set_tx_power`](crate::link::PacketRadio::set_tx_power)) when it changes.
    pub fn set_tx_power(&mut self, step: u8) {
        self.tx_power = Some(step);
    }

    /// The power step asked for by [`Master::set_tx_power`]; `None`: the radio's own, as
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

    /// Keyed links: whether an epoch is in use (uplinks are tagged with its key). Before
    /// the first, nothing the master sends verifies at a follower.
    pub fn has_epoch(&self) -> bool {
        self.epoch.active()
    }

    /// Keyed links: the epoch in use as (the follower's nonce, the master's nonce) — public
    /// values (both travel in clear); the epoch key is
    /// [`LinkKey::epoch_key`]`(follower, master)` of the link key.
    pub fn epoch_nonces(&self) -> Option<(u64, u64)> {
        self.epoch.nonces()
    }

    /// Keyed links: the epoch adopted but not yet heard from its follower, as (the
    /// follower's nonce, the master's nonce); it comes into force with the first downlink
    /// that verifies under it.
    pub fn pending_epoch_nonces(&self) -> Option<(u64, u64)> {
        self.epoch.pending_nonces()
    }

    /// Keyed links: the epochs adopted (each cost one uplink: the master's nonce instead of
    /// channels) and the verified nonce frames refused, since this master started (spec
    /// §12.2: a third radio can force at most one adoption per wrap of the slot counter
    /// while an epoch is in force, and none while it is live).
    pub fn handshakes(&self) -> (u32, u32) {
        self.epoch.handshake_counts()
    }

    /// The frame counter of the current slot in the epoch in force (spec §12.2): the
    /// planned uplink is tagged, and a downlink other than a nonce frame is checked, under
    /// it with the epoch key. None without an epoch in force.
    ///
    /// Public information, not a secret: the slot and its wraps are counted on the grid both
    /// ends share; only the key makes a tag.
    /// Read by diagnostics and by the fuzz harnesses (`tests/fuzz`), which seal fuzzed
    /// frames under it so they reach the state machine behind the tag check.
    pub fn frame_counter(&self) -> Option<u64> {
        self.epoch.counter(self.slot)
    }

    /// Time of the last valid downlink.
    pub fn last_downlink_us(&self) -> Option<u64> {
        self.last_downlink_us
    }
}
