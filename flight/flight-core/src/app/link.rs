//! The flight side of the TauLink link: the follower's hooks (channels → the loop's
//! `LinkInput`, failsafe counting, setting changes from the phone checked by
//! `authority::ChangeGate` — signed with the phrase's key, fresh, disarmed — then applied and
//! echoed, or refused with the reason, one telemetry message per [`REPORT_PERIOD_US`] when the downlink stream is
//! empty), the link's parameters (the stored bind; an unbound controller runs no link) and
//! the explicit bind: only the console's `bind` command, while disarmed, opens a bind window
//! of [`BIND_WINDOW_US`], and only a bind inside that window is stored. Nothing binds at
//! boot, and no default link ID exists that every unbound controller would share.
//!
//! The air protocol is the setting `link.protocol`: `taulink` (factory), or `olrs38` /
//! `olrs39` to obey an existing OpenLRSng transmitter (`super::openlrs`; OpenLRSng frames
//! cannot be authenticated). The loop sees both the same way (`on_link_channels`).
//!
//! The link key (spec §12, from the binding phrase the console's `phrase` sets) is applied
//! here too: [`FlightApp::follower`] builds the follower keyed when a key is stored, and a
//! key change asks the link task to restart its follower at once
//! ([`FlightApp::link_restart_due`]), so the new key is in force without a reboot.
//!
//! Watchdog: every hook call checks the link task in, whatever the slot length; the
//! follower calls its hooks at least every 50 ms in every sync state, and the adapter
//! checks in while it waits outside the follower (bind window, retry after a radio error).

use openlrs::BindData;
use openlrs::rx::Config as OpenLrsConfig;
use telemetry::channels::FailsafeValues;
use telemetry::link::core::Follower;
use telemetry::link::follower::FollowerHooks;
use telemetry::link::{Band, LinkParams};
use telemetry::messages::{
    Decoded, FRAMED_MAX_BYTES, Message, MessageReader, SysIdResult, encode_message,
};

use super::{FlightApp, Task};
use crate::authority::{ChangeGate, Reply};
use crate::pipeline::{ChannelMap, Protocol, bind_band, protocol, store_link, stored_link};
use crate::report::{LinkSeen, Reporter, Snapshot, sysid_messages};
use crate::supervisor::FlightMode;
use crate::sysid::ekf::Identification;

/// How long the follower listens for a bind offer after the console's `bind` command, µs:
/// long enough to walk to the handset and start its bind, short enough that a forgotten
/// window closes by itself.
pub const BIND_WINDOW_US: u64 = 30_000_000;
/// The follower declares failsafe after this long without a valid packet, µs.
pub const FAILSAFE_US: u64 = 500_000;
/// Telemetry message period, µs.
pub const REPORT_PERIOD_US: u64 = 20_000;

/// What the hooks keep between slots.
pub(super) struct LinkSide {
    map: ChannelMap,
    reporter: Reporter,
    reader: MessageReader,
    /// The answer to the last change from the phone, still to send.
    reply: Option<Message>,
    gate: ChangeGate,
    /// Seeds the follower's epoch nonces (spec §12.2), from the firmware's RNG at boot.
    nonce_seed: u64,
    last_report_us: Option<u64>,
    last_state: Option<(bool, bool, FlightMode)>,
    failsafes: u16,
    was_failsafe: bool,
    /// Identification results (roll, pitch, yaw) still to send.
    sysid: heapless::Deque<SysIdResult, 3>,
    pub(super) bind: BindState,
    /// The OpenLRSng side's state (channels, downlink bytes waiting for room).
    pub(super) openlrs: super::openlrs::OpenLrsSide,
    /// The link key changed since the running follower was built: restart it.
    key_changed: bool,
}

/// Where the explicit bind stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum BindState {
    /// No bind asked for: a bind result is ignored.
    Closed,
    /// The console asked; the link task has not opened the window yet.
    Requested,
    /// The link task is listening for an offer.
    Open,
}

impl LinkSide {
    /// Hooks reading the sticks and switches through `map` (from the settings).
    pub(super) fn new(map: ChannelMap) -> Self {
        Self {
            map,
            reporter: Reporter::new(),
            reader: MessageReader::new(),
            reply: None,
            // Seeded by the firmware's RNG (`FlightApp::seed_change_session`).
            gate: ChangeGate::new(0),
            nonce_seed: 0,
            last_report_us: None,
            last_state: None,
            failsafes: 0,
            // The follower starts in failsafe (no link yet): that is not a failsafe event.
            was_failsafe: true,
            sysid: heapless::Deque::new(),
            bind: BindState::Closed,
            openlrs: super::openlrs::OpenLrsSide::new(),
            key_changed: false,
        }
    }

    /// A new setup's channel map (arm switch, mode switch) takes effect.
    pub(super) fn set_channel_map(&mut self, map: ChannelMap) {
        self.map = map;
    }

    /// A finished identification: its three results replace any still unsent.
    pub(super) fn queue_identification(&mut self, id: &Identification) {
        self.sysid.clear();
        for r in sysid_messages(id) {
            // Capacity 3 after the clear: cannot fail.
            let _ = self.sysid.push_back(r);
        }
    }
}

/// What the link task does next ([`FlightApp::next_link_step`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinkStep {
    /// Listen for a bind offer on `band` for `window_us` (the console asked), at the radio's
    /// lowest power step; then report with [`FlightApp::on_bind_result`].
    Bind {
        /// Where to listen.
        band: Band,
        /// How long, µs.
        window_us: u64,
    },
    /// Run the follower on the stored link, the app as its hooks, until the radio fails or a
    /// bind is asked for ([`FlightApp::bind_requested`]).
    Follow(LinkParams),
    /// Never bound: run no link; wait (checking in) until a bind is asked for.
    WaitForBind,
    /// `link.protocol` is OpenLRSng: listen for an OpenLRSng transmitter's bind packets for
    /// `window_us` with a receiver that has no bind data (`Receiver::new(config, None)`),
    /// answering at the bind power; then report with [`FlightApp::on_openlrs_bind_result`].
    BindOpenLrs {
        /// Binding version and band (the bind frequency).
        config: OpenLrsConfig,
        /// How long, µs.
        window_us: u64,
    },
    /// `link.protocol` is OpenLRSng: run its receiver role on the stored bind data, feeding
    /// the app with [`FlightApp::on_openlrs_step`] after every `rx_step`, until the radio
    /// fails or a bind is asked for.
    FollowOpenLrs {
        /// Binding version, band, failsafe delay; no bind window at start.
        config: OpenLrsConfig,
        /// What the transmitter sent when binding.
        data: BindData,
    },
}

impl FlightApp {
    /// The link task's next step: a requested bind first, else the stored link, else
    /// nothing until the owner binds.
    pub fn next_link_step(&mut self) -> LinkStep {
        // Whatever comes next is built from the key in force now.
        self.link.key_changed = false;
        if let Protocol::OpenLrs(version) = protocol(&self.live) {
            return self.next_openlrs_step(version);
        }
        if let Some((band, window_us)) = self.take_bind_request() {
            return LinkStep::Bind { band, window_us };
        }
        match self.link_params() {
            Some(params) => LinkStep::Follow(params),
            None => LinkStep::WaitForBind,
        }
    }

    /// The follower for `params` (from [`LinkStep::Follow`]) with the stored link key, if
    /// there is one (`Follower::with_key`: only uplinks sealed with the key are accepted,
    /// identity and hop sequence derived from it), else unkeyed as before spec §12.
    /// `failsafe_us`: the silence after which it flies failsafe ([`FAILSAFE_US`]).
    pub fn follower(&self, params: LinkParams, failsafe_us: u64) -> Follower {
        let follower = Follower::new(params, FailsafeValues::default(), failsafe_us);
        match self.live.link_key() {
            Some(key) => follower.with_key(key).with_nonce_seed(self.link.nonce_seed),
            None => follower,
        }
    }

    /// The link task must end what it runs (a follower, a wait for a bind) and ask
    /// [`FlightApp::next_link_step`] again: a bind was asked for, or the link key changed.
    pub fn link_restart_due(&self) -> bool {
        self.link.bind == BindState::Requested || self.link.key_changed
    }

    /// The link key in force changed (the console's `phrase`): the link restarts with it.
    pub(super) fn on_link_key_changed(&mut self) {
        self.link.key_changed = true;
    }

    /// The link to run: the stored bind, or `None` for a controller never bound (it runs
    /// no link and waits for a `bind` command).
    pub fn link_params(&self) -> Option<LinkParams> {
        stored_link(&self.live)
    }

    /// The console's `bind`: refused while armed, else the link task is asked to open a
    /// bind window. Returns whether it was accepted.
    pub fn request_bind(&mut self) -> bool {
        if self.flight.armed() {
            return false;
        }
        self.link.bind = BindState::Requested;
        true
    }

    /// A bind has been asked for and not yet started: the link task stops its follower and
    /// calls [`FlightApp::take_bind_request`].
    pub fn bind_requested(&self) -> bool {
        self.link.bind == BindState::Requested
    }

    /// The link task starts a bind window if one was asked for (and we are still disarmed):
    /// the band to listen on and the window length, µs. The task listens at the radio's
    /// lowest power step (`RadioConfig::reduced_power`).
    pub fn take_bind_request(&mut self) -> Option<(Band, u64)> {
        if self.link.bind != BindState::Requested {
            return None;
        }
        if self.flight.armed() {
            self.link.bind = BindState::Closed;
            return None;
        }
        self.link.bind = BindState::Open;
        Some((bind_band(&self.live), BIND_WINDOW_US))
    }

    /// The bind window ended: `offered` is what a module bound us to, if one did. Stored
    /// (and a save requested) only inside a window the console opened and while disarmed;
    /// returns whether it was.
    pub fn on_bind_result(&mut self, offered: Option<&LinkParams>) -> bool {
        let open = self.link.bind == BindState::Open;
        self.link.bind = BindState::Closed;
        let Some(params) = offered else {
            return false;
        };
        if !open || self.flight.armed() {
            return false;
        }
        if store_link(&mut self.live, params).is_ok() {
            self.request_save();
            return true;
        }
        false
    }

    /// The link task is waiting outside the follower (bind window, retry): it is alive.
    pub fn on_link_idle(&mut self) {
        self.watchdog.check_in(Task::Link);
    }

    /// The follower stopped (radio error): the loop sees the link down until it runs again.
    pub fn on_link_down(&mut self) {
        self.watchdog.check_in(Task::Link);
        self.link_input.up = false;
    }

    /// The follower's hook, after every step (`now_us` on the link's clock).
    pub fn on_link_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.on_link_channels(follower.output(), follower.in_failsafe());
        let mut buf = [0u8; 32];
        loop {
            let n = follower.uplink_stream.read(&mut buf);
            // `read` fills at most `buf`, so the range always exists; none read ends it.
            let Some(bytes) = buf.get(..n).filter(|b| !b.is_empty()) else {
                break;
            };
            self.on_uplink_bytes(bytes);
        }
        if self.report_due(now_us) {
            self.report(now_us, follower);
        }
    }

    /// What every link protocol hands the loop after each step, the one interface the
    /// flight logic sees: the channels (CRSF scale) and whether the link is in failsafe.
    /// Checks the link task in and counts failsafe events.
    pub(super) fn on_link_channels(&mut self, channels: &[u16], failsafe: bool) {
        self.watchdog.check_in(Task::Link);
        if failsafe && !self.link.was_failsafe {
            self.link.failsafes = self.link.failsafes.saturating_add(1);
        }
        self.link.was_failsafe = failsafe;
        self.link_input = self.link.map.link_input(channels, !failsafe);
    }

    /// Bytes of the module's message stream (the phone's setting changes, signed).
    pub(super) fn on_uplink_bytes(&mut self, bytes: &[u8]) {
        for b in bytes {
            if let Some(Decoded::Message(m)) = self.link.reader.push(*b) {
                self.apply_link_change(&m);
            }
        }
    }

    /// Whether a telemetry message is due at `now_us` (then the period restarts).
    pub(super) fn report_due(&mut self, now_us: u64) -> bool {
        let due = self
            .link
            .last_report_us
            .is_none_or(|t| now_us.saturating_sub(t) >= REPORT_PERIOD_US);
        if due {
            self.link.last_report_us = Some(now_us);
        }
        due
    }

    /// A message from the phone (relayed by the module): a setting change goes through the
    /// gate (signed, fresh, disarmed); the applied value is echoed, a refusal answered with
    /// its reason and the session to sign the next one with.
    fn apply_link_change(&mut self, message: &Message) {
        let armed = self.flight.armed();
        let key = self.live.link_key();
        let Some(reply) = self
            .link
            .gate
            .on_message(message, &mut self.live, key, armed)
        else {
            return;
        };
        if matches!(reply, Reply::Applied(_)) {
            self.settings_changed();
        }
        self.link.reply = Some(reply.message());
    }

    /// The session nonce of this boot's phone changes, from the firmware's RNG at boot
    /// (spec §12.5: a change recorded in an earlier boot then never verifies again).
    pub fn seed_change_session(&mut self, random: u32) {
        self.link.gate = ChangeGate::new(random);
    }

    /// The seed of the link follower's epoch nonces (spec §12.2), from the firmware's RNG at
    /// every boot: a keyed follower's nonce must never repeat under one key, across reboots
    /// too, or frames recorded before a reboot could verify again.
    pub fn seed_link_nonces(&mut self, random: u64) {
        self.link.nonce_seed = random;
    }

    /// One telemetry message when the downlink stream is empty: a setting echo, then an
    /// identification result, then a state change out of turn, else the rotation.
    fn report(&mut self, now_us: u64, follower: &mut Follower) {
        let counters = follower.counters();
        let seen = LinkSeen {
            rssi_dbm: follower
                .uplink_rssi_dbm()
                .map_or(0, |r| i8::try_from(r).unwrap_or(i8::MIN)),
            lq_percent: follower.uplink_lq(),
            downlink: follower.remote_report().map(|r| (r.rssi_dbm, r.lq_percent)),
            rate_mode: follower.params().rate.code(),
            received: counters.received,
            missed: counters.missed,
            failsafes: self.link.failsafes,
        };
        self.log.on_link(now_us, &seen);
        let stream = &follower.downlink_stream;
        if stream.pending() > 0 || stream.free() < FRAMED_MAX_BYTES {
            return; // one message in flight at most: stale telemetry helps nobody
        }
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        if let Some(framed) = self.next_report(seen, &mut buf) {
            follower.downlink_stream.write(framed);
        }
    }

    /// The next telemetry message, framed into `buf`, with `seen` as the link's figures:
    /// a setting echo, then an identification result, then a state change out of turn, then
    /// the home and the GPS fix when due, else the rotation. `None` before the loop has run.
    pub(super) fn next_report<'o>(
        &mut self,
        seen: LinkSeen,
        buf: &'o mut [u8; FRAMED_MAX_BYTES],
    ) -> Option<&'o [u8]> {
        let out = self.last_out?;
        let snap = Snapshot {
            out,
            battery: self.battery,
            link: seen,
            arming_blockers: self.arming_blockers(),
            sysid: self.link.sysid.front().copied(),
            altitude_m: self.baro_altitude_m(),
            climb_mps: self.flight.climb_estimate(),
        };
        let state = (out.armed, out.failsafe, out.mode);
        let message = if let Some(reply) = self.link.reply.take() {
            reply
        } else if let Some(r) = self.link.sysid.pop_front() {
            Message::SysIdResult(r)
        } else if self.link.last_state != Some(state) {
            self.link.last_state = Some(state);
            Reporter::state(&snap)
        } else if let Some(home) = self.take_home_report() {
            home
        } else if let Some(gps) = self.take_gps_report() {
            gps
        } else {
            self.link.reporter.next(&snap)
        };
        encode_message(&message, buf).ok()
    }

    /// Link failsafe events since boot.
    pub fn link_failsafes(&self) -> u16 {
        self.link.failsafes
    }
}

impl FollowerHooks for FlightApp {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.on_link_step(now_us, follower);
    }
}
