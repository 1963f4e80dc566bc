//! The flight side of the TauLink link: the follower's hooks (channels → the loop's
//! `LinkInput`, failsafe counting, setting changes from the phone checked by
//! `authority::ChangeGate` — signed with the phrase's key, fresh, disarmed — then applied and
//! echoed, or refused with the reason, one telemetry message per [`REPORT_PERIOD_US`] when the downlink stream is
//! empty), the link's parameters (the stored bind; an unbound controller runs no link) and
//! the explicit bind: only the console's `bind` command, while disarmed, opens a bind window
//! of [`BIND_WINDOW_US`], and only a bind inside that window is stored. Nothing binds at
//! boot, and no default link ID exists that every unbound controller would share.
//!
//! The air protocol is the setting `link.protocol`: `taulink` (factory), or `openlrs38` /
//! `openlrs39` to obey an existing OpenLRSng transmitter (`super::openlrs`; OpenLRSng frames
//! cannot be authenticated). The loop sees both the same way (`on_link_channels`).
//!
//! The link key (spec §12.1) is what the bind agreed with the module (CPace, on the phrase
//! given with `bind`, or without one); [`FlightApp::follower`] builds the follower keyed with
//! it, and a key change (a new bind, `defaults`) asks the link task to restart its follower
//! at once ([`FlightApp::link_restart_due`]). A link without a key (an unauthenticated bind)
//! runs only while `link.unauthenticated` allows it.
//!
//! Dynamic transmit power (`telemetry::link::power`, setting `link.dynamic_power`, on by
//! factory): the downlink's power step follows the master's reports of how it hears us, up
//! to the radio's maximum; the follower loop writes it into the radio between steps.
//!
//! Watchdog: every hook call checks the link task in, whatever the slot length; the
//! follower calls its hooks at least every 50 ms in every sync state, and the adapter
//! checks in while it waits outside the follower (bind window, retry after a radio error).

use openlrs::BindData;
use openlrs::rx::Config as OpenLrsConfig;
use telemetry::channels::FailsafeValues;
use telemetry::crsf_record::{self, MAX_RECORD_PAYLOAD};
use telemetry::framing::{Deframed, Deframer, frame, framed_len};
use telemetry::link::alarm::TagAlarm;
use telemetry::link::core::Follower;
use telemetry::link::core::follower::SyncState;
use telemetry::link::follower::{FollowerBind, FollowerHooks};
use telemetry::link::phrase::PHRASE_MAX_BYTES;
use telemetry::link::power::{MAX_STEP, PowerControl, PowerInput};
use telemetry::link::{Band, BindRefusal, Entropy, LinkParams, PhraseError, check_phrase};
use telemetry::messages::{
    FRAMED_MAX_BYTES, LinkSecurity, Message, SysIdResult, decode_change, encode_message,
};

use super::{FlightApp, Task};
use crate::authority::{ChangeGate, Reply};
use crate::pipeline::{ChannelMap, Protocol, bind_band, protocol, store_link, stored_link};
use crate::report::{LinkSeen, Reporter, Snapshot, sysid_messages};
use crate::settings::handles;
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
    /// The uplink stream's records: messages from the phone, CRSF records from the radio.
    deframer: Deframer<{ framed_len(MAX_RECORD_PAYLOAD) }>,
    /// The answer to the last change from the phone, still to send.
    reply: Option<Message>,
    gate: ChangeGate,
    /// The link's secrets (bind scalars, nonce seed, change session), from the firmware's RNG
    /// at boot.
    entropy: Entropy,
    /// Seeds the follower's epoch nonces (spec §12.2).
    nonce_seed: u64,
    /// The binding phrase given with `bind`, until the window closes (never stored).
    bind_phrase: Option<heapless::String<PHRASE_MAX_BYTES>>,
    /// How the last bind window ended.
    last_bind: Option<BindReport>,
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
    /// Tag failures over the last seconds (spec §12.2).
    alarm: TagAlarm,
    /// The tag failures and alert last sent, and when (a `LinkSecurity` message goes out when
    /// they change, at most once a second).
    security_sent: (u32, bool, Option<u64>),
    /// A `LinkSecurity` message is due.
    security_due: Option<LinkSecurity>,
    /// Dynamic transmit power (`link.dynamic_power`), up to the radio's maximum.
    power: PowerControl,
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
            deframer: Deframer::new(),
            reply: None,
            // Seeded by the firmware's RNG (`FlightApp::seed_random`).
            gate: ChangeGate::new(0),
            entropy: Entropy::new([0; 32]),
            nonce_seed: 0,
            bind_phrase: None,
            last_bind: None,
            last_report_us: None,
            last_state: None,
            failsafes: 0,
            // The follower starts in failsafe (no link yet): that is not a failsafe event.
            was_failsafe: true,
            sysid: heapless::Deque::new(),
            bind: BindState::Closed,
            openlrs: super::openlrs::OpenLrsSide::new(),
            key_changed: false,
            alarm: TagAlarm::default(),
            security_sent: (0, false, None),
            security_due: None,
            power: PowerControl::new(MAX_STEP, true),
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

/// Why the console's `bind` was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindError {
    /// The motors may turn.
    Armed,
    /// The phrase given does not meet the rules.
    Phrase(PhraseError),
    /// The hardware RNG failed at boot: the key agreement's secret scalar would come from
    /// the weak fallback seeds, and a recording of the bind could then test phrase guesses
    /// offline. A power cycle retries the RNG.
    NoRandomness,
}

/// How a bind window ended, for `status` and the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BindReport {
    /// Bound and stored; the key's fingerprint (`None`: an unauthenticated link).
    Bound {
        /// The link's bind ID.
        bind_id: u32,
        /// The agreed key's fingerprint.
        fingerprint: Option<u32>,
    },
    /// An offer came but was not bound.
    Refused(BindRefusal),
    /// No offer came.
    NoOffer,
}

/// A bind window to open ([`LinkStep::Bind`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BindRequest {
    /// Where to listen.
    pub band: Band,
    /// How long, µs.
    pub window_us: u64,
    /// The binding phrase given with `bind` (held for this window only).
    pub phrase: Option<heapless::String<PHRASE_MAX_BYTES>>,
    /// `link.unauthenticated`: an unauthenticated offer may be taken.
    pub allow_plain: bool,
    /// The window's CPace randomness.
    pub random: [u8; 32],
}

impl BindRequest {
    /// What the follower's bind takes from the request.
    pub fn auth(&self) -> telemetry::link::FollowerAuth<'_> {
        telemetry::link::FollowerAuth {
            phrase: self.phrase.as_deref(),
            stored: None,
            allow_plain: self.allow_plain,
        }
    }
}

/// What the link task does next ([`FlightApp::next_link_step`]).
#[derive(Debug, Clone, PartialEq)]
pub enum LinkStep {
    /// Listen for a bind offer (the console asked), at the radio's lowest power step; then
    /// report with [`FlightApp::on_bind_result`].
    Bind(BindRequest),
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
        if let Some(request) = self.take_bind_request() {
            return LinkStep::Bind(request);
        }
        match self.link_params() {
            Some(params) => LinkStep::Follow(params),
            None => LinkStep::WaitForBind,
        }
    }

    /// The follower for `params` (from [`LinkStep::Follow`]) with the stored link key, if
    /// there is one (`Follower::with_key`: only uplinks sealed with the key are accepted),
    /// else unkeyed (only a link bound unauthenticated, while `link.unauthenticated`
    /// allows it: see [`FlightApp::link_params`]). `failsafe_us`: the silence after which it
    /// flies failsafe ([`FAILSAFE_US`]).
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

    /// The link key in force changed (a bind, `defaults`): the link restarts with it.
    pub(super) fn on_link_key_changed(&mut self) {
        self.link.key_changed = true;
    }

    /// The link to run: the stored bind — authenticated, or unauthenticated while
    /// `link.unauthenticated` is 1 — or `None` for a controller never bound (it runs no link
    /// and waits for a `bind` command).
    pub fn link_params(&self) -> Option<LinkParams> {
        let plain_allowed = self.live.get(handles::LINK_UNAUTHENTICATED) == 1;
        stored_link(&self.live).filter(|_| self.live.link_key().is_some() || plain_allowed)
    }

    /// The console's `bind [PHRASE]`: refused while armed or for a phrase that breaks the
    /// rules (`telemetry::link::check_phrase`), else the link task is asked to open a bind
    /// window, the phrase held for it. Returns whether a phrase was given.
    pub fn request_bind(&mut self, phrase: &str) -> Result<bool, BindError> {
        if self.armed() {
            return Err(BindError::Armed);
        }
        if self.board.boot.rng_fallback {
            return Err(BindError::NoRandomness);
        }
        let phrase = check_phrase(phrase).map_err(BindError::Phrase)?;
        self.link.bind_phrase = phrase.and_then(|p| heapless::String::try_from(p).ok());
        self.link.bind = BindState::Requested;
        Ok(phrase.is_some())
    }

    /// How the last bind window ended.
    pub fn last_bind(&self) -> Option<BindReport> {
        self.link.last_bind
    }

    /// A bind has been asked for and not yet started: the link task stops its follower and
    /// calls [`FlightApp::take_bind_request`].
    pub fn bind_requested(&self) -> bool {
        self.link.bind == BindState::Requested
    }

    /// The link task starts a bind window if one was asked for (and we are still disarmed):
    /// the band to listen on, the window length, the phrase and the window's randomness. The
    /// task listens at the radio's lowest power step (`RadioConfig::reduced_power`).
    pub fn take_bind_request(&mut self) -> Option<BindRequest> {
        if self.link.bind != BindState::Requested {
            return None;
        }
        if self.armed() {
            self.link.bind = BindState::Closed;
            self.link.bind_phrase = None;
            return None;
        }
        self.link.bind = BindState::Open;
        Some(BindRequest {
            band: bind_band(&self.live),
            window_us: BIND_WINDOW_US,
            phrase: self.link.bind_phrase.take(),
            allow_plain: self.live.get(handles::LINK_UNAUTHENTICATED) == 1,
            random: self.link.entropy.draw(b"bind"),
        })
    }

    /// The bind window ended with `result`. A bound link and its key are stored (and a
    /// save requested) only inside a window the console opened and while disarmed, and the
    /// link restarts with them; returns whether they were.
    pub fn on_bind_result(&mut self, result: &FollowerBind) -> bool {
        let open = self.link.bind == BindState::Open;
        self.link.bind = BindState::Closed;
        self.link.bind_phrase = None;
        self.link.last_bind = Some(match result {
            FollowerBind::Bound { params, key } => BindReport::Bound {
                bind_id: params.bind_id,
                fingerprint: key.map(|k| k.fingerprint().0),
            },
            FollowerBind::Refused(why) => BindReport::Refused(*why),
            FollowerBind::NoOffer => BindReport::NoOffer,
        });
        let FollowerBind::Bound { params, key } = result else {
            return false;
        };
        if !open || self.armed() {
            return false;
        }
        if store_link(&mut self.live, params).is_ok() {
            self.live.set_link_key(*key);
            self.on_link_key_changed();
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
        self.watch_tags(now_us, follower.counters().tag_failures);
        self.follow_power(now_us, follower);
        if self.report_due(now_us) {
            self.report(now_us, follower);
        }
    }

    /// The downlink's power step from the master's latest report (`link::power`), handed to
    /// the follower for its loop to write.
    fn follow_power(&mut self, now_us: u64, follower: &mut Follower) {
        let dynamic = self.live.get(handles::LINK_DYNAMIC_POWER) == 1;
        self.link.power.configure(MAX_STEP, dynamic);
        let params = follower.params();
        let step = self.link.power.update(&PowerInput {
            now_us,
            rate: params.rate,
            // On the master's grid, failsafe or not (a master whose handset input stopped
            // still hears us): the link is up.
            connected: follower.sync_state() == SyncState::Tracking,
            report: follower.remote_report_at(),
            report_period_us: params
                .rate
                .slot_us()
                .saturating_mul(u32::from(params.telemetry_ratio.max(1))),
        });
        follower.set_tx_power(step);
    }

    /// The power step the downlink is sent at (0…7, `telemetry::link::power`).
    pub fn tx_power_step(&self) -> u8 {
        self.link.power.step()
    }

    /// The follower's tag failures at `now_us`: the alarm follows them, and a change is
    /// reported (at most once a second).
    fn watch_tags(&mut self, now_us: u64, tag_failures: u32) {
        let alert = self.link.alarm.update(now_us, tag_failures);
        let (sent, sent_alert, at) = self.link.security_sent;
        let changed = (tag_failures, alert) != (sent, sent_alert);
        let quiet = at.is_none_or(|t| now_us.saturating_sub(t) >= 1_000_000);
        if changed && quiet {
            self.link.security_sent = (tag_failures, alert, Some(now_us));
            self.link.security_due = Some(LinkSecurity {
                tag_failures,
                alert,
            });
        }
    }

    /// Whether the link's tag failures run above what noise explains.
    pub fn tag_alert(&self) -> bool {
        self.link.alarm.alert()
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

    /// Bytes of the module's record stream: the phone's setting changes (signed), and the
    /// radio's device-tool frames for CRSF device 0xC8 (`super::device`).
    pub(super) fn on_uplink_bytes(&mut self, bytes: &[u8]) {
        for b in bytes {
            let Some(Deframed::Frame { .. }) = self.link.deframer.push(*b) else {
                continue;
            };
            let payload = self.link.deframer.payload();
            if crsf_record::is_crsf_payload(payload) {
                let mut record = [0u8; MAX_RECORD_PAYLOAD];
                let len = payload.len().min(MAX_RECORD_PAYLOAD);
                if let (Some(slot), Some(body)) = (record.get_mut(..len), payload.get(..len)) {
                    slot.copy_from_slice(body);
                    self.on_crsf_record(slot_bytes(&record, len));
                }
            } else if let Some(m) = decode_change(payload) {
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
    /// gate (signed, fresh, disarmed); the applied value is echoed and saved (the phone has
    /// no `save` of its own: a change the pilot made must survive the next power cycle), a
    /// refusal answered with its reason and the session to sign the next one with.
    fn apply_link_change(&mut self, message: &Message) {
        let armed = self.armed();
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
            self.request_save();
        }
        self.link.reply = Some(reply.message());
    }

    /// The session of this boot's phone changes (public: every refusal names it).
    pub fn change_session(&self) -> u32 {
        self.link.gate.session()
    }

    /// The link's secrets from 32 bytes of the firmware's RNG at every boot (spec §12): the
    /// session of this boot's phone changes (§12.5: a change recorded in an earlier boot
    /// then never verifies again), the seed of the follower's epoch nonces (§12.2: a keyed
    /// follower's nonce must never repeat under one key, across reboots too) and the CPace
    /// randomness of each bind window (§12.1) — each drawn under its own label, so none
    /// tells anything of another.
    pub fn seed_random(&mut self, random: &[u8; 32]) {
        let mut entropy = Entropy::new(*random);
        self.link.gate = ChangeGate::new(entropy.draw_u64(b"change session") as u32);
        self.link.nonce_seed = entropy.draw_u64(b"link nonces");
        self.link.entropy = entropy;
    }

    /// One telemetry message when the downlink stream is empty: the device tool's answer
    /// first (`super::device`), then a setting echo, then an identification result, then a
    /// state change out of turn, else the rotation. The link's figures go to the flight log
    /// on every report tick, sent or not.
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
        if stream.pending() > 0 || stream.free() < framed_len(MAX_RECORD_PAYLOAD) {
            return; // one message in flight at most: stale telemetry helps nobody
        }
        if self.device_reply_pending() {
            if let Some(reply) = self.take_device_reply() {
                let mut buf = [0u8; framed_len(MAX_RECORD_PAYLOAD)];
                if let Ok(framed) = frame(&reply, &mut buf) {
                    follower.downlink_stream.write(framed);
                }
            }
            return;
        }
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        if let Some(framed) = self.next_report(seen, &mut buf) {
            follower.downlink_stream.write(framed);
        }
    }

    /// The next telemetry message, framed into `buf`, with `seen` as the link's figures:
    /// a setting echo, then an identification result, then a state change out of turn, then
    /// the firmware's health when it changed, the home and the GPS fix when due, else the
    /// rotation. `None` before the loop has run.
    pub(super) fn next_report<'o>(
        &mut self,
        seen: LinkSeen,
        buf: &'o mut [u8; FRAMED_MAX_BYTES],
    ) -> Option<&'o [u8]> {
        let out = *self.last_output()?;
        let snap = Snapshot {
            out,
            battery: self.battery,
            link: seen,
            arming_blockers: self.arming_blockers(),
            sysid: self.link.sysid.front().copied(),
            altitude_m: self.baro_altitude_m(),
            climb_mps: self.view.as_ref().and_then(|v| v.climb_mps),
        };
        let state = (out.armed, out.failsafe, out.mode);
        let message = if let Some(reply) = self.link.reply.take() {
            reply
        } else if let Some(r) = self.link.sysid.pop_front() {
            Message::SysIdResult(r)
        } else if self.link.last_state != Some(state) {
            self.link.last_state = Some(state);
            Reporter::state(&snap)
        } else if let Some(security) = self.link.security_due.take() {
            Message::LinkSecurity(security)
        } else if let Some(health) = self.take_health_report(self.link.last_report_us.unwrap_or(0))
        {
            Message::Health(health)
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

/// The first `len` bytes of `record` (`len` is within it by construction).
fn slot_bytes(record: &[u8; MAX_RECORD_PAYLOAD], len: usize) -> &[u8] {
    record.get(..len).unwrap_or(&[])
}

impl FollowerHooks for FlightApp {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.on_link_step(now_us, follower);
    }
}
