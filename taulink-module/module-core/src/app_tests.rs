use super::*;
use crate::channels::{ticks_to_us, us_to_ticks};
use crate::hm10::relay::MAX_FRAME_LEN;
use crate::ppm::FailsafeOutput;
use crate::ppm::waveform::edges;
use telemetry::cobs;

#[derive(Default)]
struct FakeLink {
    channels: Vec<ChannelFrame>,
    records: Vec<Vec<u8>>,
    room: usize,
    stats: LinkStats,
    binds: u32,
    input_timeout_ms: u16,
}

impl LinkPort for FakeLink {
    fn send_channels(&mut self, channels: &ChannelFrame) {
        self.channels.push(*channels);
    }
    fn set_input_timeout_ms(&mut self, timeout_ms: u16) {
        self.input_timeout_ms = timeout_ms;
    }
    fn can_send_record(&self) -> bool {
        self.room > 0
    }
    fn send_record(&mut self, record: &[u8]) {
        self.room -= 1;
        self.records.push(record.to_vec());
    }
    fn stats(&self) -> LinkStats {
        self.stats
    }
    fn start_bind(&mut self) {
        self.binds += 1;
    }
}

#[derive(Default)]
struct FakeHandset {
    telemetry: Vec<Vec<u8>>,
    stats: Vec<LinkStats>,
    /// The radio's selected model.
    model: Option<u8>,
    /// Requests the radio made, oldest first.
    requests: std::collections::VecDeque<HandsetRequest>,
    /// The last tag failures the radio was told.
    tag_failures: Option<crate::ports::TagFailures>,
}

impl HandsetOutput for FakeHandset {
    fn on_telemetry(&mut self, record: &[u8]) {
        self.telemetry.push(record.to_vec());
    }
    fn on_link_stats(&mut self, stats: &LinkStats) {
        self.stats.push(*stats);
    }
    fn on_tag_failures(&mut self, failures: crate::ports::TagFailures) {
        self.tag_failures = Some(failures);
    }
    fn model_id(&self) -> Option<u8> {
        self.model
    }
    fn take_request(&mut self) -> Option<HandsetRequest> {
        self.requests.pop_front()
    }
}

fn app(settings: Settings) -> App<FakeLink, FakeHandset> {
    App::new(settings, FakeLink::default(), FakeHandset::default(), false).unwrap()
}

fn cobs_frame(record: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; MAX_FRAME_LEN];
    let n = cobs::encode(record, &mut out).unwrap();
    out.truncate(n);
    out.push(0);
    out
}

#[test]
fn taranis_ppm_reaches_the_link() {
    let mut app = app(Settings::default());
    let widths = [1500u16, 1500, 988, 1500, 2012, 1000, 1750, 1250];
    let stream = edges(&widths, 22_500, 20, 7);
    // As the capture task: a tick after each edge, and one at the release deadline when
    // no edge comes before it.
    for (i, &t) in stream.iter().enumerate() {
        app.on_ppm_edge(t);
        app.on_ppm_tick(t);
        let next = stream.get(i + 1).copied().unwrap_or(u32::MAX);
        if let Some(deadline) = app.ppm_deadline_us().filter(|d| *d < next) {
            app.on_ppm_tick(deadline);
        }
    }
    // 20 frames: 19 frame ends (18 sync edges, and the last frame's quiet line after it),
    // the first 4 acquire the lock; the fifth locks at its sync edge, the rest go out early.
    let sent = &app.link().channels;
    assert_eq!(sent.len(), 15);
    let expected: Vec<u16> = widths.iter().map(|w| us_to_ticks(*w)).collect();
    assert!(sent.iter().all(|ch| ch.as_slice() == expected.as_slice()));
    assert_eq!(app.input_stats().frames, 15);
    app.on_ppm_tick(7 + 20 * 22_500 + 250_001);
    assert_eq!(app.input_stats().losses, 1);
}

#[test]
fn crsf_channels_go_to_the_link_only_in_crsf_mode() {
    let channels = ChannelFrame::from_ticks(&[172, 992, 1811, 992]);
    let mut ppm_mode = app(Settings::default());
    ppm_mode.on_handset_channels(&channels);
    assert!(ppm_mode.link().channels.is_empty());
    let mut crsf_mode = app(Settings {
        input: InputProtocol::Crsf,
        ..Settings::default()
    });
    crsf_mode.on_handset_channels(&channels);
    assert_eq!(crsf_mode.link().channels, vec![channels]);
}

#[test]
fn flight_telemetry_fans_out_to_handset_and_phone() {
    let mut app = app(Settings::default());
    app.on_link_record(&[0x55]);
    app.on_phone_connected();
    let records = [vec![0x08, 0x00, 0x7B, 0x00], vec![0x14, 0x64, 0x00, 0xC5]];
    for record in &records {
        app.on_link_record(record);
    }
    // The handset gets everything; the phone only what came after it connected.
    assert_eq!(app.handset().telemetry[0], vec![0x55]);
    assert_eq!(app.handset().telemetry[1..], records);
    let mut stream = Vec::new();
    let mut frame = [0u8; MAX_FRAME_LEN];
    while let Some(n) = app.next_phone_frame(&mut frame) {
        stream.extend_from_slice(&frame[..n]);
    }
    let mut expected = cobs_frame(&records[0]);
    expected.extend(cobs_frame(&records[1]));
    assert_eq!(stream, expected);
}

#[test]
fn phone_records_wait_for_room_on_the_link() {
    let mut app = app(Settings::default());
    app.link.room = 1;
    let mut stream = b"OK+CONN".to_vec();
    for i in 0..3u8 {
        stream.extend(cobs_frame(&[0xA0 + i, 0x00, i]));
    }
    app.on_phone_bytes(&stream);
    assert_eq!(app.link().records, vec![vec![0xA0, 0x00, 0]]);
    app.link.room = 5;
    app.on_tick();
    assert_eq!(app.link().records.len(), 3);
    assert_eq!(app.link().records[2], vec![0xA2, 0x00, 2]);
    assert_eq!(app.relay_stats().to_flight.records, 0, "nothing dropped");
}

#[test]
fn receiver_role_outputs_ppm_and_stops_on_failsafe() {
    let mut app = app(Settings {
        role: Role::Receiver,
        failsafe: FailsafeOutput::StopPulses,
        ..Settings::default()
    });
    assert_eq!(app.next_ppm_frame(), None);
    app.link.stats.connected = true;
    app.on_tick();
    let values: Vec<u16> = [1100u16, 1200, 1300, 1400, 1500, 1600, 1700, 1800]
        .iter()
        .map(|w| us_to_ticks(*w))
        .collect();
    app.on_link_channels(&ChannelFrame::from_ticks(&values));
    let frame = app.next_ppm_frame().unwrap();
    let widths: Vec<u16> = frame.slots()[..8].iter().map(|s| s.period_us).collect();
    let expected: Vec<u16> = values.iter().map(|v| ticks_to_us(*v)).collect();
    assert_eq!(widths, expected);
    assert_eq!(frame.length_us(), 22_500);
    app.link.stats.connected = false;
    app.on_tick();
    assert_eq!(app.next_ppm_frame(), None, "stop pulses on failsafe");
    // The transmitter role never drives the PPM output.
    assert_eq!(self::app(Settings::default()).next_ppm_frame(), None);
}

#[test]
fn a_factory_receiver_stops_pulses_on_failsafe_and_the_link_gets_the_input_timeout() {
    let mut app = app(Settings {
        role: Role::Receiver,
        ..Settings::default()
    });
    assert_eq!(app.link().input_timeout_ms, 500);
    app.link.stats.connected = true;
    app.on_tick();
    app.on_link_channels(&ChannelFrame::from_ticks(&[us_to_ticks(1600); 8]));
    assert!(app.next_ppm_frame().is_some());
    app.link.stats.connected = false;
    app.on_tick();
    assert_eq!(
        app.next_ppm_frame(),
        None,
        "no held throttle on a lost link"
    );
    let app = self::app(Settings {
        input_timeout_ms: 250,
        ..Settings::default()
    });
    assert_eq!(app.link().input_timeout_ms, 250);
}

#[test]
fn led_follows_radio_bind_and_link() {
    let mut app = app(Settings::default());
    assert_eq!(app.on_tick(), None, "starts as NoRadio");
    assert_eq!(
        app.on_radio_present(true),
        Some(Action::Led(LinkState::Unbound))
    );
    assert_eq!(
        app.on_button(ButtonEvent::LongPress),
        Some(Action::Led(LinkState::Binding))
    );
    assert_eq!(app.on_button(ButtonEvent::LongPress), None);
    assert_eq!(app.link().binds, 1, "one bind per long press while binding");
    // No peer: back to unbound, and the next press binds again.
    assert_eq!(app.on_bind_failed(), Some(Action::Led(LinkState::Unbound)));
    assert_eq!(
        app.on_button(ButtonEvent::LongPress),
        Some(Action::Led(LinkState::Binding))
    );
    assert_eq!(app.link().binds, 2);
    let Action::Save(saved) = app.on_bind_complete(0x1234_5678) else {
        panic!("bind must save");
    };
    assert_eq!(saved.bind_id, 0x1234_5678);
    assert_eq!(app.on_tick(), Some(Action::Led(LinkState::Searching)));
    app.link.stats = LinkStats {
        connected: true,
        rssi_dbm: -70,
        link_quality_percent: 98,
        ..LinkStats::default()
    };
    assert_eq!(app.on_tick(), Some(Action::Led(LinkState::Connected)));
    assert_eq!(app.handset().stats.last(), Some(&app.link().stats));
    app.link.stats.connected = false;
    assert_eq!(app.on_tick(), Some(Action::Led(LinkState::Failsafe)));
    assert_eq!(
        app.on_radio_present(false),
        Some(Action::Led(LinkState::NoRadio))
    );
}

#[test]
fn a_receiver_takes_band_and_rate_from_the_bind_offer() {
    let mut app = app(Settings {
        role: Role::Receiver,
        plain: true,
        ..Settings::default()
    });
    let offer = telemetry::link::LinkParams::new(
        0x0102_0304,
        telemetry::link::Band::Mhz868,
        telemetry::link::RateMode::M100,
        telemetry::channels::ChannelFormat::Full16,
        4,
    );
    let Action::Save(saved) = app.on_bind_offer_accepted(&offer) else {
        panic!("bind must save");
    };
    assert_eq!(saved.bind_id, 0x0102_0304);
    assert_eq!(saved.rate, crate::settings::RateMode::M100);
    assert_eq!(saved.band, crate::settings::Band::Mhz868);
    assert_eq!(crate::air::link_params(&saved), Some(offer));
}

#[test]
fn a_receiver_takes_an_f500_offer_and_its_telemetry_ratio() {
    // The old settings had no F500 and a fixed ratio: such an offer kept the old rate, and
    // the saved settings then gave other link parameters than the master's.
    let mut app = app(Settings {
        role: Role::Receiver,
        plain: true,
        ..Settings::default()
    });
    let offer = telemetry::link::LinkParams::new(
        0x0A0B_0C0D,
        telemetry::link::Band::Mhz915,
        telemetry::link::RateMode::F500,
        telemetry::channels::ChannelFormat::Full16,
        16,
    );
    let Action::Save(saved) = app.on_bind_offer_accepted(&offer) else {
        panic!("bind must save");
    };
    assert_eq!(saved.rate, telemetry::link::RateMode::F500);
    assert_eq!(saved.telemetry_ratio, 16);
    assert_eq!(crate::air::link_params(&saved), Some(offer));
}

#[test]
fn a_long_press_stops_the_link_and_the_bind_outcome_is_saved_or_undone() {
    use crate::session::{BindOutcome, LinkStep, SessionEnd};
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        link_key: Some(telemetry::link::LinkKey::from_bytes([0x11; 16])),
        ..Settings::default()
    });
    assert_eq!(app.next_link_step(0, 7), LinkStep::Probe);
    app.on_radio_present(true);
    assert!(matches!(app.next_link_step(0, 7), LinkStep::RunMaster(_)));
    assert_eq!(app.poll_session(50), None);
    app.on_button(ButtonEvent::LongPress);
    assert_eq!(app.poll_session(100), Some(SessionEnd::BindRequested));
    assert_eq!(app.poll_session(150), None, "one press, one bind");
    app.on_session_end(SessionEnd::BindRequested);
    let LinkStep::BindMaster { params, .. } = app.next_link_step(200, 0xABCD_0123) else {
        panic!("a transmitter binds as master");
    };
    assert_eq!(params.bind_id, 0xABCD_0123);
    let key = telemetry::link::LinkKey::from_bytes([1; 16]);
    let bound = BindOutcome::Offered(telemetry::link::master::MasterBind::Bound(Some(key)));
    let Some(Action::Save(saved)) = app.on_bind_outcome(bound) else {
        panic!("an accepted offer is saved");
    };
    assert_eq!(saved.bind_id, 0xABCD_0123);
    assert!(saved.link_key.is_some(), "the module key is stored");
    assert_eq!(app.settings().bind_id, 0xABCD_0123);
    // A bind nobody answers keeps the old ID and ends the Binding LED.
    assert_eq!(app.next_link_step(300, 0), LinkStep::Probe);
    app.on_radio_present(true);
    app.next_link_step(300, 0);
    app.on_button(ButtonEvent::LongPress);
    app.poll_session(350);
    app.on_session_end(SessionEnd::BindRequested);
    app.next_link_step(400, 0x5555_5555);
    assert_eq!(
        app.on_bind_outcome(BindOutcome::Offered(
            telemetry::link::master::MasterBind::NoAnswer
        )),
        Some(Action::Led(LinkState::Searching))
    );
    assert_eq!(app.settings().bind_id, 0xABCD_0123);
}

#[test]
fn the_hm10_script_outcome_decides_the_relay() {
    use crate::hm10::at::{Outcome, Stage};
    let mut app = app(Settings::default());
    assert_eq!(app.on_hm10_configured(Outcome::NoModule), None);
    assert_eq!(
        app.on_hm10_configured(Outcome::Failed { stage: Stage::Name }),
        None
    );
    assert_eq!(
        app.on_hm10_configured(Outcome::Configured { baud: 115_200 }),
        Some(115_200)
    );
    // Not connected yet: a record from the link is held back, not sent as AT input.
    app.on_link_record(&[1, 2, 3]);
    let mut frame = [0u8; MAX_FRAME_LEN];
    assert_eq!(app.next_phone_frame(&mut frame), None);
    app.on_phone_connected();
    app.on_link_record(&[4, 5, 6]);
    assert!(app.next_phone_frame(&mut frame).is_some(), "relay open");
}

#[test]
fn a_low_module_battery_shows_on_the_led_with_hysteresis() {
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        link_key: Some(telemetry::link::LinkKey::from_bytes([0x11; 16])),
        ..Settings::default()
    });
    assert_eq!(
        app.on_radio_present(true),
        Some(Action::Led(LinkState::Searching))
    );
    assert_eq!(app.on_module_battery(7_400), None);
    assert_eq!(
        app.on_module_battery(6_500),
        Some(Action::Led(LinkState::LowBattery))
    );
    assert_eq!(app.on_module_battery(6_700), None, "inside the hysteresis");
    assert_eq!(
        app.on_module_battery(6_900),
        Some(Action::Led(LinkState::Searching))
    );
    // No battery at all (a bench supply) is not a low battery.
    assert_eq!(app.on_module_battery(300), None);
}

/// The "Model" row as the radio reads it.
fn model_row(app: &App<FakeLink, FakeHandset>) -> String {
    let entry = params::entry(params::MODEL, app.settings(), app.parameter_commands()).unwrap();
    // parent, type, "Model\0", text\0
    let text = &entry[2 + "Model".len() + 1..entry.len() - 1];
    String::from_utf8(text.to_vec()).unwrap()
}

/// Runs the link task's steps from a probe to the running master's parameters.
fn running_master(
    app: &mut App<FakeLink, FakeHandset>,
    now_ms: u32,
) -> telemetry::link::LinkParams {
    for _ in 0..3 {
        match app.next_link_step(now_ms, 0x1234_5678) {
            LinkStep::Probe => {
                app.on_radio_present(true);
            }
            LinkStep::RunMaster(params) => return params,
            other => panic!("{other:?}"),
        }
    }
    panic!("no master");
}

#[test]
fn model_match_flies_the_selected_models_identity_and_says_mismatch() {
    let settings = Settings {
        input: InputProtocol::Crsf,
        bind_id: 0x0BAD_F00D,
        model_match: true,
        bound_models: 1 << 3,
        link_key: Some(telemetry::link::LinkKey::from_bytes([0x22; 16])),
        ..Settings::default()
    };
    let base = crate::air::link_params(&settings).unwrap();
    let mut app = app(settings);
    // The radio selected model 3, bound: the link runs under model 3's identity.
    app.handset_mut().model = Some(3);
    app.on_handset_idle(0);
    assert_eq!(running_master(&mut app, 0), base.for_model(3));
    assert_eq!(model_row(&app), "3 bound");
    assert_eq!(app.poll_session(50), None);
    // The pilot selects model 5 on the radio: the link restarts under model 5's identity,
    // which no receiver bound under model 3 hears; the row says why nothing answers.
    app.handset_mut().model = Some(5);
    app.on_handset_idle(100);
    assert_eq!(app.poll_session(100), Some(SessionEnd::SettingsChanged));
    app.on_session_end(SessionEnd::SettingsChanged);
    assert_eq!(running_master(&mut app, 150), base.for_model(5));
    assert_eq!(model_row(&app), "5 Model mismatch");
    // Bind under model 5: the module keeps its ID (model 3's receiver still flies) and
    // records model 5 as bound.
    app.on_button(ButtonEvent::LongPress);
    assert_eq!(app.poll_session(200), Some(SessionEnd::BindRequested));
    app.on_session_end(SessionEnd::BindRequested);
    let LinkStep::BindMaster { params, .. } = app.next_link_step(250, 0x9999_0001) else {
        panic!("bind next");
    };
    assert_eq!(params, base.for_model(5));
    let saved = app.on_bind_outcome(BindOutcome::Offered(
        telemetry::link::master::MasterBind::Bound(Some(telemetry::link::LinkKey::from_bytes(
            [1; 16],
        ))),
    ));
    assert!(
        matches!(saved, Some(Action::Save(s)) if s.bind_id == base.bind_id
        && s.bound_models == (1 << 3) | (1 << 5))
    );
    assert_eq!(model_row(&app), "5 bound");
}

#[test]
fn model_match_off_flies_one_identity_for_every_model() {
    let settings = Settings {
        input: InputProtocol::Crsf,
        bind_id: 0x0BAD_F00D,
        link_key: Some(telemetry::link::LinkKey::from_bytes([0x22; 16])),
        ..Settings::default()
    };
    let base = crate::air::link_params(&settings).unwrap();
    let mut app = app(settings);
    app.handset_mut().model = Some(3);
    app.on_handset_idle(0);
    assert_eq!(running_master(&mut app, 0), base);
    app.handset_mut().model = Some(5);
    app.on_handset_idle(100);
    assert_eq!(app.poll_session(100), None, "another model changes nothing");
    assert_eq!(model_row(&app), "any (match off)");
    // Turned on from the radio's device tool: the link restarts under the model.
    let effect = params::write(
        params::MODEL_MATCH,
        &[1],
        &mut app.settings,
        &mut app.commands,
    );
    app.apply(effect);
    assert_eq!(app.poll_session(150), Some(SessionEnd::SettingsChanged));
    app.on_session_end(SessionEnd::SettingsChanged);
    assert_eq!(running_master(&mut app, 200), base.for_model(5));
    // Without a model ID from the radio (PPM input) the link runs on the plain identity.
    app.handset_mut().model = None;
    app.on_handset_idle(300);
    assert_eq!(app.poll_session(300), Some(SessionEnd::SettingsChanged));
    app.on_session_end(SessionEnd::SettingsChanged);
    assert_eq!(running_master(&mut app, 350), base);
    assert_eq!(model_row(&app), "no ID from radio");
}

#[test]
fn a_keyed_link_runs_with_its_links_key_and_an_unkeyed_one_only_by_the_plain_setting() {
    use crate::session::{LinkStep, SessionEnd};
    use telemetry::link::LinkKey;
    let module_key = LinkKey::from_bytes([0x3C; 16]);
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        link_key: Some(module_key),
        ..Settings::default()
    });
    app.on_radio_present(true);
    let LinkStep::RunMaster(params) = app.next_link_step(0, 7) else {
        panic!("bound with a key: the master runs");
    };
    // The link's key is the module key's for this bind ID; identity stays the bind ID's.
    assert_eq!(
        app.link_key_for(&params),
        Some(module_key.for_link(0x0101_0101))
    );
    assert!(app.master(params).has_key());
    assert_eq!(app.master(params).params().bind_id, params.bind_id);
    assert_eq!(
        info_row(&app, params::LINK_KEY),
        format!(
            "{} no phrase",
            module_key.for_link(0x0101_0101).fingerprint()
        )
    );
    // Bound without a key (an unauthenticated bind): no link unless `plain` is on.
    let mut plain = crate::app::tests::app(Settings {
        bind_id: 0x0202_0202,
        ..Settings::default()
    });
    plain.on_radio_present(true);
    assert_eq!(plain.next_link_step(0, 7), LinkStep::WaitForBind);
    plain.set_setting_text("plain", "on").unwrap();
    assert_eq!(plain.poll_session(50), Some(SessionEnd::SettingsChanged));
    plain.on_session_end(SessionEnd::SettingsChanged);
    assert_eq!(plain.next_link_step(100, 7), LinkStep::Probe);
    plain.on_radio_present(true);
    let LinkStep::RunMaster(params) = plain.next_link_step(150, 7) else {
        panic!("unauthenticated by the explicit setting");
    };
    assert!(!plain.master(params).has_key());
    assert_eq!(
        info_row(&plain, params::LINK_KEY),
        format!("{} no phrase", params::UNAUTHENTICATED)
    );
}

#[test]
fn the_hm10_always_gets_a_pin_the_factory_one_from_the_chip_id() {
    let mut app = app(Settings::default());
    let script = app.hm10_script(0, 0x1234_5678_9ABC_DEF0);
    let factory = Pin::factory(0x1234_5678_9ABC_DEF0);
    assert_eq!(script.pin(), Some(factory));
    assert!((100_000..=999_999).contains(&factory.value()));
    assert_ne!(factory, Pin::factory(0x1234_5678_9ABC_DEF1), "per chip");
    assert_eq!(
        app.parameter_commands().ble_pin,
        None,
        "not shown before it is set"
    );
    app.on_hm10_configured(crate::hm10::at::Outcome::Configured { baud: 115_200 });
    assert_eq!(
        app.parameter_commands().ble_pin,
        Some(factory),
        "shown once set"
    );
    // Set by the owner: that one, shown at once, applied at the next boot's script.
    app.set_setting_text("ble_pin", "271828").unwrap();
    assert_eq!(app.parameter_commands().ble_pin, Pin::new(271_828));
    assert_eq!(app.hm10_script(0, 1).pin(), Pin::new(271_828));
}

/// The radio writes `value` to parameter `number` (as the Lua tool's PARAMETER_WRITE).
fn radio_writes(app: &mut App<FakeLink, FakeHandset>, number: u8, value: &[u8]) {
    app.handset_mut().requests.push_back(HandsetRequest::Write {
        origin: address::RADIO,
        number,
        value: heapless::Vec::from_slice(value).unwrap(),
    });
    app.on_handset_idle(0);
}

fn info_row(app: &App<FakeLink, FakeHandset>, number: u8) -> String {
    let entry = params::entry(number, app.settings(), app.parameter_commands()).unwrap();
    let name_end = entry[2..].iter().position(|b| *b == 0).unwrap() + 2;
    String::from_utf8(entry[name_end + 1..entry.len() - 1].to_vec()).unwrap()
}

fn arm_record(armed: bool) -> Vec<u8> {
    let message = telemetry::messages::Message::ArmState(telemetry::messages::ArmState {
        armed,
        failsafe: false,
        arming_blockers: 0,
    });
    let mut out = [0u8; MAX_RECORD_LEN];
    crate::records::encode(&message, &mut out).unwrap().to_vec()
}

/// Runs the phrase job the firmware runs in steps; how many steps it took.
fn derive(app: &mut App<FakeLink, FakeHandset>) -> u32 {
    let mut steps = 0;
    while app.step_phrase_job(256) {
        steps += 1;
    }
    steps + 1
}

#[test]
fn a_phrase_typed_on_the_radio_is_derived_in_steps_and_never_taken_while_armed() {
    use telemetry::link::PhraseSecret;
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        link_key: Some(telemetry::link::LinkKey::from_bytes([1; 16])),
        ..Settings::default()
    });
    app.seed_random(&[4; 32]);
    let salt = app.settings().phrase_salt;
    assert_ne!(salt, [0; 8], "a salt drawn at boot");
    app.on_radio_present(true);
    let _ = app.next_link_step(0, 7);
    assert!(info_row(&app, params::LINK_KEY).ends_with("no phrase"));

    // The flight side reports armed: the phrase is refused, nothing is derived or saved.
    app.on_link_record(&arm_record(true));
    radio_writes(
        &mut app,
        params::BIND_PHRASE,
        b"amber kettle under the oak\0",
    );
    assert!(!app.step_phrase_job(1));
    assert_eq!(app.settings().phrase_prs, None);
    assert_eq!(app.take_action(), None);
    assert_eq!(info_row(&app, params::LINK_KEY), "refused: quad armed");

    // Disarmed: the write starts the derivation; when it ends the phrase is in force (for
    // the next bind) and saved; the running link is not touched.
    app.on_link_record(&arm_record(false));
    radio_writes(
        &mut app,
        params::BIND_PHRASE,
        b"  amber kettle under the oak\0",
    );
    assert_eq!(info_row(&app, params::LINK_KEY), "deriving phrase...");
    assert_eq!(derive(&mut app), 4096 / 256, "in steps");
    let expected = PhraseSecret::derive("amber kettle under the oak", salt);
    assert_eq!(
        app.settings().phrase(),
        Some(expected),
        "trimmed like every path"
    );
    let Some(Action::Save(saved)) = app.take_action() else {
        panic!("the new phrase is saved");
    };
    assert_eq!(saved.phrase_prs, Some(expected.prs));
    assert_eq!(app.poll_session(100), None, "the link keeps running");
    assert!(info_row(&app, params::LINK_KEY).ends_with("+phrase"));

    // An empty commit (the pilot backed out of the editor) keeps the phrase; a weak one is
    // refused with the reason.
    radio_writes(&mut app, params::BIND_PHRASE, b"\0");
    assert_eq!(app.settings().phrase(), Some(expected));
    assert_eq!(info_row(&app, params::LINK_KEY), "empty: phrase kept");
    radio_writes(&mut app, params::BIND_PHRASE, b"short one\0");
    assert_eq!(info_row(&app, params::LINK_KEY), "refused: < 12 chars");
    radio_writes(
        &mut app,
        params::BIND_PHRASE,
        b"correct horse battery staple\0",
    );
    assert_eq!(info_row(&app, params::LINK_KEY), "refused: famous phrase");
    assert_eq!(app.settings().phrase(), Some(expected));
}

// ---- The phone (telemetry::module_record) ----

use telemetry::module_record::{self, Answer, ModuleRecord, Outcome, PhoneSession, Refusal};

/// The phone sends `record` over the HM-10.
fn phone_sends(app: &mut App<FakeLink, FakeHandset>, record: &ModuleRecord) {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(record, &mut payload).unwrap();
    phone_sends_payload(app, &payload[..n]);
}

fn phone_sends_payload(app: &mut App<FakeLink, FakeHandset>, payload: &[u8]) {
    let mut framed = [0u8; MAX_RECORD_LEN];
    let record = crate::records::with_crc(payload, &mut framed).unwrap();
    app.on_phone_bytes(&cobs_frame(record));
}

/// The module's records waiting for the phone.
fn phone_hears(app: &mut App<FakeLink, FakeHandset>) -> Vec<ModuleRecord> {
    let mut records = Vec::new();
    let mut frame = [0u8; MAX_FRAME_LEN];
    while let Some(n) = app.next_phone_frame(&mut frame) {
        let len = cobs::decode_in_place(&mut frame[..n - 1]).unwrap();
        let payload = crate::records::payload(&frame[..len]).unwrap();
        if let Ok(record) = module_record::decode(payload) {
            records.push(record);
        }
    }
    records
}

/// A module with the phrase set, a keyed link and the relay open.
fn module_with_phrase() -> App<FakeLink, FakeHandset> {
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        link_key: Some(telemetry::link::LinkKey::from_bytes([7; 16])),
        ..Settings::default()
    });
    app.seed_random(&[9; 32]);
    app.set_setting_text("phrase", "amber kettle under the oak")
        .unwrap();
    app.on_hm10_configured(crate::hm10::at::Outcome::Configured { baud: 115_200 });
    app.on_phone_connected();
    let _ = app.take_action();
    app
}

/// One exchange of the phone with `phrase`: the module's grant or refusal.
fn exchange(
    app: &mut App<FakeLink, FakeHandset>,
    phrase: &str,
) -> (Option<PhoneSession>, ModuleRecord) {
    for _ in 0..crate::phrase::HELLO_TICKS {
        app.on_tick();
    }
    let _ = phone_hears(app);
    phone_sends(app, &ModuleRecord::Hello);
    let heard = phone_hears(app);
    let Some(ModuleRecord::Challenge(challenge)) = heard.last() else {
        return (None, *heard.last().expect("an answer"));
    };
    let (phone, response) = PhoneSession::respond(phrase, challenge, &[3; 32]).unwrap();
    phone_sends(app, &ModuleRecord::Response(response));
    let reply = *phone_hears(app).last().expect("an answer");
    (Some(phone), reply)
}

/// Issue 30, finding 2: `ProposeKey` put the link key itself on BLE and the module kept it
/// for the pilot to confirm on the radio. Version 1 records are no longer read: the
/// proposal is dropped unanswered, nothing is pending, nothing changes.
#[test]
fn a_key_proposed_in_the_clear_is_never_taken() {
    let mut app = module_with_phrase();
    let before = *app.settings();
    // Version 1's ProposeKey: marker, version 1, variant 0, the key's 16 bytes.
    let mut proposal = vec![module_record::MARKER, 1, 0];
    proposal.extend([0x5A; 16]);
    phone_sends_payload(&mut app, &proposal);
    assert!(phone_hears(&mut app).is_empty(), "not even answered");
    assert_eq!(*app.settings(), before);
    assert_eq!(app.take_action(), None);
    // No module record carries a key in the clear: the only key-bearing one is sealed.
    let (_, granted) = exchange(&mut app, "amber kettle under the oak");
    let ModuleRecord::Granted(granted) = granted else {
        panic!("granted: {granted:?}");
    };
    let link_key = app.link_key_for(&crate::air::link_params(app.settings()).unwrap());
    let change_key = telemetry::change_auth::ChangeKey::from_link_key(&link_key.unwrap());
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(&ModuleRecord::Granted(granted), &mut payload).unwrap();
    for secret in [link_key.unwrap().to_bytes(), [7; 16]] {
        assert!(
            !payload[..n].windows(16).any(|w| w == secret),
            "a key in clear"
        );
    }
    let _ = change_key;
}

#[test]
fn a_phone_with_the_phrase_gets_the_change_key_and_sets_a_new_phrase() {
    let mut app = module_with_phrase();
    let (phone, granted) = exchange(&mut app, "amber kettle under the oak");
    let ModuleRecord::Granted(granted) = granted else {
        panic!("granted: {granted:?}");
    };
    let mut phone = phone.unwrap();
    let link_key = app
        .link_key_for(&crate::air::link_params(app.settings()).unwrap())
        .unwrap();
    assert_eq!(
        phone.on_granted(&granted),
        Ok(Some(telemetry::change_auth::ChangeKey::from_link_key(
            &link_key
        ))),
        "the flight side's change key, for signed setting changes"
    );
    let set = phone.set_phrase("brass lantern at the weir").unwrap();
    phone_sends(&mut app, &ModuleRecord::SetPhrase(set));
    assert_eq!(
        phone_hears(&mut app).last(),
        Some(&ModuleRecord::Answer(Answer {
            outcome: Outcome::Applied,
            counter: 1
        }))
    );
    let salt = app.settings().phrase_salt;
    assert_eq!(
        app.settings().phrase(),
        Some(telemetry::link::PhraseSecret::derive(
            "brass lantern at the weir",
            salt
        ))
    );
    assert!(matches!(app.take_action(), Some(Action::Save(_))));
    // The same record again: a replay.
    phone_sends(&mut app, &ModuleRecord::SetPhrase(set));
    assert!(matches!(
        phone_hears(&mut app).last(),
        Some(ModuleRecord::Answer(Answer {
            outcome: Outcome::Refused(Refusal::Replayed),
            ..
        }))
    ));
}

#[test]
fn wrong_phrases_are_refused_and_lock_the_phone_out_after_five() {
    let mut app = module_with_phrase();
    for _ in 0..module_record::PHONE_FAILURES {
        let (_, reply) = exchange(&mut app, "amber kettle under the elm");
        assert_eq!(
            reply,
            ModuleRecord::Answer(Answer {
                outcome: Outcome::Refused(Refusal::NotAuthenticated),
                counter: 0
            })
        );
    }
    // Even the right phrase is refused now, until the module restarts.
    let (_, reply) = exchange(&mut app, "amber kettle under the oak");
    assert!(matches!(
        reply,
        ModuleRecord::Answer(Answer {
            outcome: Outcome::Refused(Refusal::Locked),
            ..
        })
    ));
    // A module without a phrase has nothing to run the exchange on.
    let mut bare = crate::app::tests::app(Settings::default());
    bare.on_hm10_configured(crate::hm10::at::Outcome::Configured { baud: 115_200 });
    bare.on_phone_connected();
    let (_, reply) = exchange(&mut bare, "amber kettle under the oak");
    assert!(matches!(
        reply,
        ModuleRecord::Answer(Answer {
            outcome: Outcome::Refused(Refusal::NoPhrase),
            ..
        })
    ));
}

/// Like the flight side's signed changes (finding 6): a new phrase refused because the quad
/// is armed is used up, so its recorded copy never applies after disarming.
#[test]
fn a_new_phrase_refused_while_armed_is_used_up() {
    let mut app = module_with_phrase();
    let before = app.settings().phrase();
    let (phone, _) = exchange(&mut app, "amber kettle under the oak");
    let mut phone = phone.unwrap();
    let set = phone.set_phrase("brass lantern at the weir").unwrap();
    app.on_link_record(&arm_record(true));
    phone_sends(&mut app, &ModuleRecord::SetPhrase(set));
    assert!(matches!(
        phone_hears(&mut app).last(),
        Some(ModuleRecord::Answer(Answer {
            outcome: Outcome::Refused(Refusal::Armed),
            ..
        }))
    ));
    app.on_link_record(&arm_record(false));
    phone_sends(&mut app, &ModuleRecord::SetPhrase(set));
    assert!(matches!(
        phone_hears(&mut app).last(),
        Some(ModuleRecord::Answer(Answer {
            outcome: Outcome::Refused(Refusal::Replayed),
            ..
        }))
    ));
    assert_eq!(app.settings().phrase(), before);
}

#[test]
fn tag_failures_show_on_the_radio_and_reach_the_phone_with_the_alert() {
    let mut app = module_with_phrase();
    assert_eq!(info_row(&app, params::TAG_FAILS), "0 / 0");
    // The flight side reports 3; this end counts 25 within a second: above noise.
    let report = telemetry::messages::Message::LinkSecurity(telemetry::messages::LinkSecurity {
        tag_failures: 3,
        alert: false,
    });
    let mut out = [0u8; MAX_RECORD_LEN];
    app.on_link_record(crate::records::encode(&report, &mut out).unwrap());
    for _ in 0..10 {
        app.on_tick();
    }
    app.link_mut().stats.tag_failures = 25;
    app.on_tick();
    assert_eq!(info_row(&app, params::TAG_FAILS), "25 / 3 ALERT");
    // The radio's sensors (S.Port TAG / TALR, CRSF's FM "TAG ALERT") are fed the same.
    assert_eq!(
        app.handset().tag_failures,
        Some(crate::ports::TagFailures {
            down: 25,
            up: 3,
            alert: true
        })
    );
    // The phone is told at most once a second.
    for _ in 0..10 {
        app.on_tick();
    }
    let told = phone_hears(&mut app);
    assert!(
        told.contains(&ModuleRecord::LinkSecurity(module_record::LinkSecurity {
            tag_failures_down: 25,
            tag_failures_up: 3,
            alert: true,
        })),
        "{told:?}"
    );
}

/// Issue 36: the pilot saves faster than the firmware takes actions (eight changes, each
/// saved, and a bind started, before the app task runs). No request is dropped: the LED
/// shows the bind, and the one save carries the last change — a four-deep queue used to keep
/// the first four saves and drop the rest, the last change with them.
#[test]
fn a_save_is_never_lost_when_requests_pile_up() {
    let mut app = app(Settings::default());
    let _ = app.on_radio_present(true);
    while app.take_action().is_some() {}
    for power in 0..8u8 {
        radio_writes(&mut app, params::TX_POWER, &[power]);
        radio_writes(
            &mut app,
            params::SAVE,
            &[taulink_handset::crsf::params::CommandStatus::Start as u8],
        );
        radio_writes(
            &mut app,
            params::SAVE,
            &[taulink_handset::crsf::params::CommandStatus::Confirm as u8],
        );
        if power == 5 {
            radio_writes(
                &mut app,
                params::BIND,
                &[taulink_handset::crsf::params::CommandStatus::Start as u8],
            );
        }
    }
    let mut actions = Vec::new();
    while let Some(action) = app.take_action() {
        actions.push(action);
    }
    let saves: Vec<Settings> = actions
        .iter()
        .filter_map(|a| match a {
            Action::Save(s) => Some(*s),
            Action::Led(_) => None,
        })
        .collect();
    assert_eq!(saves.len(), 1, "{actions:?}");
    assert_eq!(saves[0].tx_power, 7, "the last change is in the save");
    assert!(
        actions.contains(&Action::Led(LinkState::Binding)),
        "{actions:?}"
    );
    assert_eq!(app.take_action(), None);
}
