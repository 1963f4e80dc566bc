//! The application core: input source → link → fan-out to the handset and the HM-10, and
//! link → PPM output in the receiver role. A pure struct: the firmware calls the `on_*`
//! methods from its tasks and carries out what they return.
//!
//! Security (spec §12): the link loops are built here ([`App::master`], [`App::follower`]),
//! keyed with the link's key agreed at bind (a link without one runs only by the explicit
//! `plain` setting); the binds agree it with CPace on the binding phrase's derivation
//! (`crate::phrase`), and phones prove the phrase the same way before they get the change
//! key of the flight side's settings. The module's secrets come from one seed of the
//! hardware RNG ([`App::seed_random`]), each under its own label. The HM-10's boot script
//! ([`App::hm10_script`]) always sets a pairing PIN with bonding — the one set in `ble_pin`,
//! else this chip's factory PIN — and the relay opens only once it did.

use crate::air::AirLink;
use crate::button::ButtonEvent;
use crate::channels::ChannelFrame;
use crate::hm10::relay::{MAX_RECORD_LEN, Relay, RelayStats};
use crate::params::{self, Commands, Effect};
use crate::phrase::{PhoneAccess, PhraseJob, PhraseNote};
use crate::ports::{HandsetOutput, HandsetRequest, LinkPort, LinkStats, TagFailures};
use crate::ppm::{self, Decoded, Decoder, DecoderConfig, Encoder, EncoderConfig};
use crate::session::{BindOutcome, LinkStep, Session, SessionEnd};
use crate::settings::{InputProtocol, Role, Settings};
use crate::status::LinkState;
use taulink_handset::crsf::address;
use taulink_handset::crsf::params::ParameterChunk;
use telemetry::change_auth::ChangeKey;
use telemetry::channels::FailsafeValues;
use telemetry::link::alarm::TagAlarm;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::FollowerBind;
use telemetry::link::master::MasterBind;
use telemetry::link::{Entropy, LinkKey, LinkParams};
use telemetry::messages::LinkSecurity;

use crate::hm10::at::{Configurator, Pin};
use crate::settings::TextError;

/// Something the firmware must do after an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action {
    /// Show this state on the LED.
    Led(LinkState),
    /// Persist these settings.
    Save(Settings),
}

/// The actions waiting for [`App::take_action`], one slot per kind: a request can never be
/// lost to a full queue, and repeats coalesce — only the newest LED state matters, and a save
/// writes the settings as they are when it is taken (so no change made after it is lost).
#[derive(Debug, Default)]
struct Outbox {
    led: Option<LinkState>,
    save: bool,
}

impl Outbox {
    fn put(&mut self, action: Action) {
        match action {
            Action::Led(state) => self.led = Some(state),
            Action::Save(_) => self.save = true,
        }
    }
}

/// The module's supply (the radio battery on JR pin 3) counts as low below this: 1.1 V per
/// cell of a 6-cell NiMH pack, 3.3 V per cell of a 2S Li-ion pack, both near empty.
pub const MODULE_BATTERY_LOW_MV: u16 = 6_600;
/// The low warning ends only above the threshold plus this (a loaded pack recovers a little).
pub const MODULE_BATTERY_HYSTERESIS_MV: u16 = 200;
/// Below this the reading is no battery at all (a bench supply on the debug header).
pub const MODULE_BATTERY_ABSENT_MV: u16 = 1_000;

/// Input health counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InputStats {
    /// Frames handed to the link.
    pub frames: u32,
    /// PPM frames dropped by the decoder.
    pub rejected: u32,
    /// Times the PPM lock was lost.
    pub losses: u32,
}

/// The module core.
pub struct App<L: LinkPort, H: HandsetOutput> {
    settings: Settings,
    link: L,
    handset: H,
    decoder: Decoder,
    encoder: Encoder,
    relay: Relay,
    radio_present: bool,
    binding: bool,
    /// A long press not yet taken by the link session.
    bind_request: bool,
    session: Session,
    was_connected: bool,
    led: LinkState,
    input: InputStats,
    /// The radio's parameter commands (bind, save) and what changed.
    commands: Commands,
    /// A setting the running link uses changed: end the session at the next poll.
    restart_request: bool,
    /// The module's supply is below [`MODULE_BATTERY_LOW_MV`] (until it recovers by the
    /// hysteresis).
    battery_low: bool,
    /// What the JR line asked of the firmware, for [`App::take_action`].
    actions: Outbox,
    /// The radio model the running link step's identity was built for (model match).
    link_model: Option<u8>,
    /// The chip's unique ID (for the factory PIN), once the HM-10 script asked for it.
    unique_id: Option<u64>,
    /// The module's secrets (spec §12), from the RNG at boot.
    entropy: Entropy,
    /// Seeds the link's epoch nonces (spec §12.2).
    nonce_seed: u64,
    /// The phone's exchanges with the module (CPace on the phrase).
    phone: PhoneAccess,
    /// A phrase from the radio being derived ([`App::step_phrase_job`]).
    phrase_job: Option<PhraseJob>,
    /// Tag failures at this end over the last seconds (spec §12.2).
    alarm: TagAlarm,
    /// The flight side's last `LinkSecurity` report.
    flight_security: LinkSecurity,
    /// Core ticks since boot (the alarm's clock: 10 Hz).
    ticks: u64,
    /// The tag failures last told the phone, and the tick.
    security_sent: (TagFailures, u64),
}

impl<L: LinkPort, H: HandsetOutput> App<L, H> {
    /// The core with its settings and plug-ins; the PPM output takes its failsafe behaviour
    /// and the link its handset-input timeout from the settings.
    pub fn new(
        settings: Settings,
        mut link: L,
        handset: H,
        phone_connected: bool,
    ) -> Result<Self, ppm::encoder::ConfigError> {
        let encoder = Encoder::new(EncoderConfig {
            failsafe: settings.failsafe,
            ..EncoderConfig::default()
        })?;
        link.set_input_timeout_ms(settings.input_timeout_ms);
        link.set_tx_power(settings.tx_power, settings.dynamic_power);
        Ok(Self {
            settings,
            link,
            handset,
            decoder: Decoder::new(DecoderConfig::default()),
            encoder,
            relay: Relay::new(phone_connected),
            radio_present: false,
            binding: false,
            bind_request: false,
            session: Session::new(),
            was_connected: false,
            led: LinkState::NoRadio,
            input: InputStats::default(),
            commands: Commands::default(),
            restart_request: false,
            battery_low: false,
            actions: Outbox::default(),
            link_model: None,
            unique_id: None,
            entropy: Entropy::new([0; 32]),
            nonce_seed: 0,
            phone: PhoneAccess::default(),
            phrase_job: None,
            alarm: TagAlarm::default(),
            flight_security: LinkSecurity {
                tag_failures: 0,
                alert: false,
            },
            ticks: 0,
            security_sent: (TagFailures::default(), 0),
        })
    }

    /// The master for `params` (from `LinkStep::RunMaster`), keyed with that link's key
    /// ([`App::link_key_for`]: `Master::with_key`, every frame sealed, only verified
    /// downlinks taken), else unkeyed (the explicit `plain` setting).
    pub fn master(&self, params: LinkParams) -> Master {
        let master = Master::new(params);
        match self.link_key_for(&params) {
            Some(key) => master.with_key(key).with_nonce_seed(self.nonce_seed),
            None => master,
        }
    }

    /// The key of the link `params`: in the transmitter role the module's key for that
    /// link (each model's link its own, `LinkKey::for_link`), in the receiver role the key
    /// the master handed over; `None` without one.
    pub fn link_key_for(&self, params: &LinkParams) -> Option<LinkKey> {
        let key = self.settings.link_key?;
        Some(match self.settings.role {
            Role::Transmitter => key.for_link(params.bind_id),
            Role::Receiver => key,
        })
    }

    /// The module's secrets from 32 bytes of the nRF52840's RNG at every boot (spec §12):
    /// the seed of the link's epoch nonces (§12.2: a keyed end's nonce must never repeat,
    /// across reboots too), the CPace randomness of binds and phone exchanges, each new
    /// module key, and — drawn once and stored — the salt of the phrase's derivation; each
    /// under its own label, so none tells anything of another.
    pub fn seed_random(&mut self, random: &[u8; 32]) {
        let mut entropy = Entropy::new(*random);
        self.nonce_seed = entropy.draw_u64(b"link nonces");
        if self.settings.phrase_salt == [0; 8] {
            let salt = entropy.draw(b"phrase salt");
            self.settings.phrase_salt = core::array::from_fn(|i| salt.get(i).copied().unwrap_or(0));
        }
        self.entropy = entropy;
    }

    /// The change key of the flight link in force (what a phone that proved the phrase
    /// gets), if it is keyed.
    fn change_key(&self) -> Option<ChangeKey> {
        let params = crate::air::link_params(&self.settings)?;
        let params = match self.link_model() {
            Some(m) => params.for_model(m),
            None => params,
        };
        self.link_key_for(&params)
            .map(|k| ChangeKey::from_link_key(&k))
    }

    /// Runs up to `iterations` of the phrase's derivation started from the radio; returns
    /// whether more remain. The firmware calls it an iteration at a time between yields
    /// (the whole derivation is ≈ 2 s of the nRF52840); when it ends the phrase is in force
    /// and a save is queued ([`App::take_action`]).
    pub fn step_phrase_job(&mut self, iterations: u32) -> bool {
        let Some(job) = self.phrase_job.as_mut() else {
            return false;
        };
        let Some(secret) = job.step(iterations) else {
            return true;
        };
        self.phrase_job = None;
        if self.commands.flight_armed {
            self.commands.phrase_note = Some(PhraseNote::Armed);
            return false;
        }
        self.settings.phrase_prs = Some(secret.prs);
        self.commands.phrase_note = Some(PhraseNote::Set);
        self.actions.save = true;
        false
    }

    /// The follower for `LinkStep::RunFollower`'s fields, keyed as [`App::master`].
    pub fn follower(
        &self,
        params: LinkParams,
        failsafe: FailsafeValues,
        failsafe_us: u64,
    ) -> Follower {
        let follower = Follower::new(params, failsafe, failsafe_us);
        match self.link_key_for(&params) {
            Some(key) => follower.with_key(key).with_nonce_seed(self.nonce_seed),
            None => follower,
        }
    }

    /// Changes the setting `name` from `text` (`settings::text`: e.g. `phrase`, `ble_pin`,
    /// `rate`) — the module's text settings path (a console, a host tool). What the link
    /// runs on (key, rate, band, ratio, bind, role) restarts the link at the next
    /// [`App::poll_session`]; the returned action saves the new set. On an error nothing
    /// changes. The PIN reaches the HM-10 at the next power-up (its boot script).
    pub fn set_setting_text(&mut self, name: &str, text: &str) -> Result<Action, TextError> {
        let before = self.settings;
        self.settings.set_text(name, text)?;
        let after = self.settings;
        let link_changed = crate::air::link_params(&before) != crate::air::link_params(&after)
            || before.link_key != after.link_key
            || before.plain != after.plain
            || before.role != after.role;
        if link_changed {
            self.restart_request = true;
        }
        if before.input_timeout_ms != after.input_timeout_ms {
            self.apply(Effect::InputTimeout);
        }
        if before.failsafe != after.failsafe {
            self.apply(Effect::PpmFailsafe);
        }
        if (before.tx_power, before.dynamic_power) != (after.tx_power, after.dynamic_power) {
            self.apply(Effect::TxPower);
        }
        if let (Some(id), Some(_)) = (self.unique_id, self.commands.ble_pin) {
            // The new PIN reaches the HM-10 at the next power-up; the row shows the set one.
            self.commands.ble_pin = Some(self.pin_for(id));
        }
        Ok(Action::Save(self.settings))
    }

    fn pin_for(&self, unique_id: u64) -> Pin {
        self.settings
            .ble_pin
            .unwrap_or_else(|| Pin::factory(unique_id))
    }

    /// The HM-10's boot script, started at `now_ms`: the BLE name, notifications, and the
    /// pairing PIN with bonding (`AT+PASS`, `AT+TYPE3`) — the `ble_pin` setting, else the
    /// factory PIN of the chip whose unique ID is `unique_id` (`Pin::factory`; the nRF52840's
    /// FICR DEVICEID). Never the HM-10's factory no-PIN state. The PIN also shows in the
    /// radio's device tool ("BLE PIN").
    pub fn hm10_script(&mut self, now_ms: u32, unique_id: u64) -> Configurator {
        self.unique_id = Some(unique_id);
        let pin = self.pin_for(unique_id);
        // "TauLink": the BLE name the phone app filters on.
        Configurator::new("TauLink", now_ms).with_pin(pin)
    }

    /// The settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The link plug-in.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The link plug-in, mutable (its task drains what the core queued).
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The handset plug-in.
    pub fn handset(&self) -> &H {
        &self.handset
    }

    /// The handset plug-in, mutable (the JR-line task takes its frames).
    pub fn handset_mut(&mut self) -> &mut H {
        &mut self.handset
    }

    /// Input counters.
    pub fn input_stats(&self) -> InputStats {
        self.input
    }

    /// HM-10 relay counters.
    pub fn relay_stats(&self) -> RelayStats {
        self.relay.stats()
    }

    /// A captured PPM edge (µs, TIMER1 clock).
    pub fn on_ppm_edge(&mut self, timestamp_us: u32) {
        if self.settings.role != Role::Transmitter || self.settings.input != InputProtocol::Ppm {
            return;
        }
        match self.decoder.on_edge(timestamp_us) {
            Some(Decoded::Frame(channels)) => self.forward(&channels),
            Some(Decoded::Rejected(_)) => {
                self.input.rejected = self.input.rejected.saturating_add(1)
            }
            Some(Decoded::Acquiring { .. }) | None => {}
        }
    }

    /// PPM frame release and loss detection, on the TIMER1 clock: a locked frame that did
    /// not agree with the last one (so did not go at its last edge, in
    /// [`App::on_ppm_edge`]) goes out once the line has been quiet for a sync gap after its
    /// last channel ([`App::ppm_deadline_us`]), not at the next frame's first edge.
    pub fn on_ppm_tick(&mut self, now_us: u32) {
        if let Some(Decoded::Frame(channels)) = self.decoder.release_due(now_us) {
            self.forward(&channels);
        }
        if self.decoder.on_tick(now_us).is_some() {
            self.input.losses = self.input.losses.saturating_add(1);
        }
    }

    /// When the PPM capture task should call [`App::on_ppm_tick`] if no edge comes first
    /// (TIMER1 clock): the frame in progress is then complete. `None`: nothing pending.
    pub fn ppm_deadline_us(&self) -> Option<u32> {
        self.decoder.release_deadline_us()
    }

    /// Channels decoded from the handset's CRSF RC frames (the CRSF codec calls this).
    pub fn on_handset_channels(&mut self, channels: &ChannelFrame) {
        if self.settings.role == Role::Transmitter && self.settings.input.is_crsf() {
            self.forward(channels);
        }
    }

    /// Channels received over the link (receiver role): they go to the PPM output.
    pub fn on_link_channels(&mut self, channels: &ChannelFrame) {
        if self.settings.role == Role::Receiver {
            self.encoder.set_channels(channels);
        }
    }

    /// A telemetry record received over the link: to the handset and the phone. The flight
    /// side's arm state is kept: no phrase change while it says armed (`crate::phrase`). A
    /// CRSF record (the flight controller's answer to the radio's device tool) goes to the
    /// radio alone.
    pub fn on_link_record(&mut self, record: &[u8]) {
        if let Ok(payload) = crate::records::payload(record)
            && let Ok(frame) = telemetry::crsf_record::decode(payload)
        {
            if self.settings.role == Role::Transmitter {
                self.handset
                    .send_relayed_frame(frame.frame_type, frame.payload);
            }
            return;
        }
        match crate::records::decode(record) {
            Ok(telemetry::messages::Message::ArmState(state)) => {
                self.commands.flight_armed = state.armed;
            }
            Ok(telemetry::messages::Message::LinkSecurity(security)) => {
                self.flight_security = security;
            }
            _ => {}
        }
        if self.settings.role == Role::Transmitter {
            self.handset.on_telemetry(record);
        }
        self.relay.on_link_record(record);
    }

    /// Bytes from the HM-10 UART; complete phone records go to the link while it has room
    /// (the rest waits in the bounded relay queue).
    pub fn on_phone_bytes(&mut self, bytes: &[u8]) {
        self.relay.on_phone_bytes(bytes);
        self.serve_module_records();
        self.flush_uplink();
    }

    /// Module-addressed records from the phone (`telemetry::module_record`, spec §12.5): the
    /// CPace exchange on the phrase, then new phrases in its session; each is answered
    /// (`crate::phrase::PhoneAccess`). Records that fail their CRC or decode are dropped
    /// unanswered, as on the link.
    fn serve_module_records(&mut self) {
        let mut record = [0u8; MAX_RECORD_LEN];
        while let Some(length) = self.relay.next_record_to_module(&mut record) {
            let Some(Ok(payload)) = record.get(..length).map(crate::records::payload) else {
                continue;
            };
            let Ok(module_record) = telemetry::module_record::decode(payload) else {
                continue;
            };
            let change_key = self.change_key();
            let armed = self.commands.flight_armed;
            let entropy = &mut self.entropy;
            let Some(reply) = self.phone.on_record(
                &module_record,
                &mut self.settings,
                armed,
                change_key,
                || entropy.draw(b"phone"),
            ) else {
                continue;
            };
            if reply.changed {
                self.commands.phrase_note = Some(PhraseNote::Set);
                self.apply(Effect::Save);
            }
            self.answer_phone(&reply.reply);
        }
    }

    /// Queues `record` for the phone (dropped without a phone, like telemetry).
    fn answer_phone(&mut self, reply: &telemetry::module_record::ModuleRecord) {
        use telemetry::module_record;
        let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
        let Some(length) = module_record::encode(reply, &mut payload) else {
            return;
        };
        let mut record = [0u8; MAX_RECORD_LEN];
        if let Some(Ok(bytes)) = payload
            .get(..length)
            .map(|p| crate::records::with_crc(p, &mut record))
        {
            self.relay.on_link_record(bytes);
        }
    }

    /// The HM-10 configuration found a phone already connected.
    pub fn on_phone_connected(&mut self) {
        self.relay.set_connected(true);
    }

    /// The HM-10's boot script ended: the UART rate to relay records at, or `None` when no
    /// usable module is fitted (the relay then stays off).
    pub fn on_hm10_configured(&mut self, outcome: crate::hm10::at::Outcome) -> Option<u32> {
        use crate::hm10::at::Outcome;
        match outcome {
            Outcome::Configured { baud } => {
                // The PIN is in force only now: the device tool shows it from here on.
                self.commands.ble_pin = self.unique_id.map(|id| self.pin_for(id));
                Some(baud)
            }
            Outcome::NoModule | Outcome::Failed { .. } => {
                self.commands.ble_pin = None;
                None
            }
        }
    }

    /// The next frame for the HM-10 UART (`out` ≥ `hm10::relay::MAX_FRAME_LEN`).
    pub fn next_phone_frame(&mut self, out: &mut [u8]) -> Option<usize> {
        self.relay.next_frame_to_phone(out)
    }

    /// The next PPM output frame (receiver role), at a frame boundary.
    pub fn next_ppm_frame(&mut self) -> Option<ppm::Frame> {
        match self.settings.role {
            Role::Receiver => self.encoder.next_frame(),
            Role::Transmitter => None,
        }
    }

    /// A reading of the module's supply (the radio battery on JR pin 3): it goes to the
    /// handset (S.Port A2) and, when low, to the LED.
    pub fn on_module_battery(&mut self, millivolts: u16) -> Option<Action> {
        self.handset.on_module_battery(millivolts);
        self.battery_low = if millivolts < MODULE_BATTERY_ABSENT_MV {
            false
        } else if self.battery_low {
            millivolts < MODULE_BATTERY_LOW_MV.saturating_add(MODULE_BATTERY_HYSTERESIS_MV)
        } else {
            millivolts < MODULE_BATTERY_LOW_MV
        };
        self.update_led()
    }

    /// The radio answered its probe (or stopped answering).
    pub fn on_radio_present(&mut self, present: bool) -> Option<Action> {
        self.radio_present = present;
        self.session.on_probe(present);
        self.update_led()
    }

    /// A debounced button event; a long press starts binding.
    pub fn on_button(&mut self, event: ButtonEvent) -> Option<Action> {
        if event == ButtonEvent::LongPress && !self.binding {
            self.binding = true;
            self.bind_request = true;
            self.link.start_bind();
        }
        self.update_led()
    }

    /// The link finished binding with `bind_id`: remember it.
    pub fn on_bind_complete(&mut self, bind_id: u32) -> Action {
        self.bound(bind_id, None)
    }

    /// Bound with `bind_id` under radio model `model` (model match): a new ID forgets the
    /// models bound under the old one; the model is recorded as bound.
    fn bound(&mut self, bind_id: u32, model: Option<u8>) -> Action {
        self.binding = false;
        if bind_id != self.settings.bind_id {
            self.settings.bound_models = 0;
        }
        self.settings.bind_id = bind_id;
        if let Some(m) = model.filter(|m| *m < crate::settings::MODEL_IDS) {
            self.settings.bound_models |= 1u64 << m;
        }
        Action::Save(self.settings)
    }

    /// The radio model the link's identity is mixed with: the model the radio selected, with
    /// model match on in the transmitter role; `None` otherwise (or before the radio said).
    pub fn link_model(&self) -> Option<u8> {
        if self.settings.model_match && self.settings.role == Role::Transmitter {
            self.handset.model_id()
        } else {
            None
        }
    }

    /// Bytes the radio sent on the JR line, the last at `now_us`: CRSF channel frames reach
    /// the link (CRSF input only); parameter reads and writes and the bind command are served
    /// (what they ask of the firmware waits in [`App::take_action`]).
    pub fn on_handset_bytes(&mut self, now_us: u64, bytes: &[u8]) {
        if let Some(channels) = self.handset.on_line_bytes(now_us, bytes) {
            self.on_handset_channels(&channels);
        }
        self.serve_handset_requests();
    }

    /// The JR line went idle at `now_us` (the radio's burst is over).
    pub fn on_handset_idle(&mut self, now_us: u64) {
        if let Some(channels) = self.handset.on_line_idle(now_us) {
            self.on_handset_channels(&channels);
        }
        self.serve_handset_requests();
    }

    /// The next thing the firmware must do that a JR-line request caused (save the settings,
    /// show the binding LED); call after the `on_handset_*` methods until `None`.
    pub fn take_action(&mut self) -> Option<Action> {
        if let Some(state) = self.actions.led.take() {
            return Some(Action::Led(state));
        }
        // The settings as they are when the firmware asks: a later change is in the save.
        core::mem::take(&mut self.actions.save).then_some(Action::Save(self.settings))
    }

    /// The radio's parameter commands' state.
    pub fn parameter_commands(&self) -> &Commands {
        &self.commands
    }

    fn serve_handset_requests(&mut self) {
        self.commands.radio_model = self.handset.model_id();
        while let Some(request) = self.handset.take_request() {
            match request {
                HandsetRequest::Read {
                    origin,
                    number,
                    chunk,
                } => self.send_parameter(origin, number, chunk),
                HandsetRequest::Write {
                    origin,
                    number,
                    value,
                } => {
                    let effect =
                        params::write(number, &value, &mut self.settings, &mut self.commands);
                    if effect == Effect::DerivePhrase
                        && let Ok(phrase) = crate::phrase::phrase_from_write(&value)
                    {
                        self.phrase_job = Some(PhraseJob::new(phrase, &self.settings));
                    }
                    self.apply(effect);
                    if matches!(effect, Effect::Bind | Effect::Save | Effect::CommandStatus) {
                        // The radio's popup waits for the command's new status.
                        self.send_parameter(origin, number, 0);
                    }
                }
                HandsetRequest::Bind => {
                    if !self.commands.binding {
                        self.commands.binding = true;
                        self.commands.bind_result = None;
                        self.apply(Effect::Bind);
                    }
                }
                HandsetRequest::Relay {
                    frame_type,
                    payload,
                } => self.relay_to_flight(frame_type, &payload),
            }
        }
    }

    /// A radio frame for the flight controller into the link's record stream (the
    /// acknowledged, on a keyed link authenticated, uplink), with the most chunk data the
    /// radio's line takes in one reply window. No room now: dropped, the radio's tool asks
    /// again on its timeout.
    fn relay_to_flight(&mut self, frame_type: u8, payload: &[u8]) {
        use telemetry::crsf_record::{CrsfRecord, MAX_RECORD_PAYLOAD, MAX_RELAYED_CHUNK_DATA};
        let chunk_limit = self
            .handset
            .parameter_chunk_len()
            .min(MAX_RELAYED_CHUNK_DATA);
        let record = CrsfRecord {
            chunk_limit: u8::try_from(chunk_limit).unwrap_or(0),
            frame_type,
            payload,
        };
        let mut body = [0u8; MAX_RECORD_PAYLOAD];
        let mut out = [0u8; MAX_RECORD_LEN];
        if let Some(body) = record.encode(&mut body)
            && let Ok(bytes) = crate::records::with_crc(body, &mut out)
            && self.link.can_send_record()
        {
            self.link.send_record(bytes);
        }
    }

    fn send_parameter(&mut self, destination: u8, number: u8, chunk: u8) {
        let Some(entry) = params::entry(number, &self.settings, &self.commands) else {
            return;
        };
        let chunk_len = self.handset.parameter_chunk_len();
        if let Some(chunk) = ParameterChunk::of_entry(
            &entry,
            chunk_len,
            chunk,
            number,
            destination,
            address::TX_MODULE,
        ) {
            self.handset.send_parameter_chunk(chunk);
        }
    }

    fn apply(&mut self, effect: Effect) {
        match effect {
            Effect::RestartLink => self.restart_request = true,
            Effect::InputTimeout => self
                .link
                .set_input_timeout_ms(self.settings.input_timeout_ms),
            Effect::TxPower => self
                .link
                .set_tx_power(self.settings.tx_power, self.settings.dynamic_power),
            Effect::PpmFailsafe => {
                if let Ok(encoder) = Encoder::new(EncoderConfig {
                    failsafe: self.settings.failsafe,
                    ..EncoderConfig::default()
                }) {
                    self.encoder = encoder;
                }
            }
            Effect::Bind => {
                // As a long press: a deliberate act of the pilot in the radio's menu.
                // A bind already under way (a long press) carries this one.
                if let Some(action) = self.on_button(ButtonEvent::LongPress) {
                    self.actions.put(action);
                }
            }
            Effect::Save => {
                self.actions.save = true;
            }
            Effect::None | Effect::CommandStatus | Effect::DerivePhrase => {}
        }
    }

    /// What to send on the JR line at `now_us` (`out` ≥ `handset::MAX_LINE_BURST`), written
    /// into `out`; empty = nothing now.
    pub fn next_handset_bytes<'o>(&mut self, now_us: u64, out: &'o mut [u8]) -> &'o [u8] {
        if self.settings.role != Role::Transmitter {
            return &[];
        }
        self.handset.next_line_bytes(now_us, out)
    }

    /// Takes what the link received (records, channels) and fans it out; the link task calls
    /// it after every slot.
    pub fn poll_link(&mut self) {
        let mut record = [0u8; MAX_RECORD_LEN];
        while let Some(length) = self.link.take_received_record(&mut record) {
            if let Some(bytes) = record.get(..length) {
                self.on_link_record(bytes);
            }
        }
        if let Some(channels) = self.link.take_received_channels() {
            self.on_link_channels(&channels);
        }
    }

    /// The receiver accepted a master's bind offer: remember the bind ID and the offer's band,
    /// rate mode and telemetry ratio, so the link comes back the same after a reboot.
    pub fn on_bind_offer_accepted(&mut self, params: &telemetry::link::LinkParams) -> Action {
        self.settings.rate = params.rate;
        if crate::settings::TELEMETRY_RATIOS.contains(&params.telemetry_ratio) {
            self.settings.telemetry_ratio = params.telemetry_ratio;
        }
        self.settings.band = params.band;
        self.on_bind_complete(params.bind_id)
    }

    /// The bind procedure ended without a peer (timeout or radio failure).
    pub fn on_bind_failed(&mut self) -> Option<Action> {
        self.binding = false;
        self.update_led()
    }

    /// The link task's next step (`crate::session`), at `now_ms`; `random` (hardware RNG)
    /// becomes the bind ID if a master bind is next.
    pub fn next_link_step(&mut self, now_ms: u32, random: u32) -> LinkStep {
        self.link_model = self.link_model();
        self.session.next(
            &self.settings,
            self.link_model,
            now_ms,
            random,
            &mut self.entropy,
        )
    }

    /// While a link step runs (every `session::POLL_MS`): whether it must stop now (a long
    /// press, a setting the link uses changed, the radio selected another model under model
    /// match, or the loop's hook silent for `session::HOOK_SILENCE_MS`).
    pub fn poll_session(&mut self, now_ms: u32) -> Option<SessionEnd> {
        if self.restart_request && !self.bind_request {
            self.restart_request = false;
            if self.session.running() {
                return Some(SessionEnd::SettingsChanged);
            }
        }
        if !self.bind_request && self.session.running() && self.link_model() != self.link_model {
            // The link's identity is the model's: fly the new model's link (or none).
            return Some(SessionEnd::SettingsChanged);
        }
        let end = self.session.poll(now_ms, self.bind_request);
        if end == Some(SessionEnd::BindRequested) {
            self.bind_request = false;
        }
        end
    }

    /// The running link step ended (as `poll_session` said, or its radio failed): nothing
    /// arrives until the next one runs.
    pub fn on_session_end(&mut self, end: SessionEnd) -> Option<Action> {
        // Whatever ended it, the next step is built from the settings in force.
        self.restart_request = false;
        self.link.on_link_stopped();
        self.session.on_end(end);
        self.update_led()
    }

    /// A bind step ended: a success is remembered with its key (and must be saved), anything
    /// else goes back to the previous state.
    pub fn on_bind_outcome(&mut self, outcome: BindOutcome) -> Option<Action> {
        let offered = self.session.on_bind_done();
        let seed = self.session.take_offered_seed();
        let accepted = matches!(
            (outcome, offered, seed),
            (BindOutcome::Offered(MasterBind::Bound(_)), Some(_), _)
                | (BindOutcome::OpenLrs { accepted: true }, _, Some(_))
                | (BindOutcome::Listened(FollowerBind::Bound { .. }), _, _)
        );
        if self.commands.binding {
            self.commands.binding = false;
            self.commands.bind_result = Some(accepted);
        }
        if let (BindOutcome::OpenLrs { accepted: true }, Some(seed)) = (outcome, seed) {
            // An OpenLRSng receiver took the bind data: its seed is the link from now on.
            self.binding = false;
            self.settings.openlrs.hop_seed = seed;
            return Some(Action::Save(self.settings));
        }
        match (outcome, offered) {
            (BindOutcome::Offered(MasterBind::Bound(_)), Some(offer)) => {
                self.settings.link_key = offer.module_key;
                Some(self.bound(offer.bind_id, offer.model))
            }
            (BindOutcome::Listened(FollowerBind::Bound { params, key }), _) => {
                self.settings.link_key = key;
                Some(self.on_bind_offer_accepted(&params))
            }
            _ => self.on_bind_failed(),
        }
    }

    /// Periodic work (≈ 10 Hz): link state, failsafe, handset statistics and
    /// uplink records that waited for room.
    pub fn on_tick(&mut self) -> Option<Action> {
        let stats: LinkStats = self.link.stats();
        if self.settings.role == Role::Transmitter {
            self.handset.on_link_stats(&stats);
        }
        if stats.connected {
            self.was_connected = true;
            self.binding = false;
        }
        self.encoder.set_failsafe(!stats.connected);
        self.phone.on_tick();
        self.watch_tags(stats.tag_failures);
        self.flush_uplink();
        self.update_led()
    }

    /// This end's tag failures (its link session's count) and the flight side's last
    /// report: the alarm follows them, the device tool's row shows them, and the phone is
    /// told of a change at most once a second.
    fn watch_tags(&mut self, down: u32) {
        self.ticks += 1;
        let alert = self.alarm.update(self.ticks * 100_000, down);
        let now = TagFailures {
            down,
            up: self.flight_security.tag_failures,
            alert: alert || self.flight_security.alert,
        };
        self.commands.tag_failures = now;
        if self.settings.role == Role::Transmitter && self.settings.link_key.is_some() {
            self.handset.on_tag_failures(now);
        }
        let (sent, at) = self.security_sent;
        if now != sent && self.ticks.saturating_sub(at) >= 10 {
            self.security_sent = (now, self.ticks);
            self.answer_phone(&telemetry::module_record::ModuleRecord::LinkSecurity(
                telemetry::module_record::LinkSecurity {
                    tag_failures_down: now.down,
                    tag_failures_up: now.up,
                    alert: now.alert,
                },
            ));
        }
    }

    fn forward(&mut self, channels: &ChannelFrame) {
        self.input.frames = self.input.frames.saturating_add(1);
        self.link.send_channels(channels);
    }

    fn flush_uplink(&mut self) {
        let mut record = [0u8; MAX_RECORD_LEN];
        while self.link.can_send_record() {
            let Some(length) = self.relay.next_record_to_flight(&mut record) else {
                break;
            };
            if let Some(bytes) = record.get(..length) {
                self.link.send_record(bytes);
            }
        }
    }

    fn update_led(&mut self) -> Option<Action> {
        let connected = self.link.stats().connected;
        let state = if !self.radio_present {
            LinkState::NoRadio
        } else if self.binding {
            LinkState::Binding
        } else if self.battery_low {
            // Above the link states: a dying radio battery ends the link soon anyway.
            LinkState::LowBattery
        } else if self.settings.bind_id == 0 && self.settings.protocol.openlrs_version().is_none() {
            // An OpenLRSng transmitter flies its bind data from the start, bound or not.
            LinkState::Unbound
        } else if connected {
            LinkState::Connected
        } else if self.was_connected {
            LinkState::Failsafe
        } else {
            LinkState::Searching
        };
        (state != self.led).then(|| {
            self.led = state;
            Action::Led(state)
        })
    }
}

impl<H: HandsetOutput> App<AirLink, H> {
    /// The master loop's hook (transmitter role), at the slot starting at `now_us` (link
    /// clock) and `now_ms` (the session's clock): channels and records in, telemetry out.
    pub fn on_master_slot(&mut self, now_us: u64, now_ms: u32, master: &mut Master) {
        self.session.on_hook(now_ms);
        self.link.on_master_slot(now_us, master);
        self.poll_link();
    }

    /// Right before each OpenLRSng packet (`air::openlrs::run_openlrs_transmitter`).
    pub fn on_openlrs_send(&mut self, tx: &mut openlrs::tx::Transmitter) {
        self.link.on_openlrs_send(tx);
    }

    /// After each OpenLRSng transmitter step at `now_us` (link clock) and `now_ms` (the
    /// session's clock): telemetry out to the handset and the phone, statistics.
    pub fn on_openlrs_step(
        &mut self,
        now_us: u64,
        now_ms: u32,
        tx: &openlrs::tx::Transmitter,
        events: &[openlrs::roles::TxEvent],
    ) {
        self.session.on_hook(now_ms);
        self.link.on_openlrs_step(now_us, tx, events);
        self.poll_link();
    }

    /// The follower loop's hook (receiver role), after every step.
    pub fn on_follower_step(&mut self, now_us: u64, now_ms: u32, follower: &mut Follower) {
        self.session.on_hook(now_ms);
        self.link.on_follower_step(now_us, follower);
        self.poll_link();
    }
}

#[cfg(test)]
#[path = "app_tests.rs"]
mod tests;
