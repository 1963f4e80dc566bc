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
}

impl HandsetOutput for FakeHandset {
    fn on_telemetry(&mut self, record: &[u8]) {
        self.telemetry.push(record.to_vec());
    }
    fn on_link_stats(&mut self, stats: &LinkStats) {
        self.stats.push(*stats);
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
    let Some(Action::Save(saved)) = app.on_bind_outcome(BindOutcome::Offered { accepted: true })
    else {
        panic!("an accepted offer is saved");
    };
    assert_eq!(saved.bind_id, 0xABCD_0123);
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
        app.on_bind_outcome(BindOutcome::Offered { accepted: false }),
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
    assert_eq!(
        app.on_hm10_configured(Outcome::PhoneConnected { baud: 9_600 }),
        Some(9_600)
    );
    app.on_link_record(&[4, 5, 6]);
    assert!(app.next_phone_frame(&mut frame).is_some(), "relay open");
}

#[test]
fn a_low_module_battery_shows_on_the_led_with_hysteresis() {
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
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
    let saved = app.on_bind_outcome(BindOutcome::Offered { accepted: true });
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
fn the_phrase_keys_the_link_ends_and_a_new_phrase_restarts_the_link() {
    use crate::session::{LinkStep, SessionEnd};
    use telemetry::link::LinkKey;
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        ..Settings::default()
    });
    app.on_radio_present(true);
    let LinkStep::RunMaster(params) = app.next_link_step(0, 7) else {
        panic!("bound: the master runs");
    };
    assert_eq!(app.master(params).params().bind_id, 0x0101_0101, "unkeyed");
    assert_eq!(app.poll_session(50), None);

    let Ok(Action::Save(saved)) = app.set_setting_text("phrase", "correct horse battery staple")
    else {
        panic!("a valid phrase is taken and saved");
    };
    let key = LinkKey::from_phrase("correct horse battery staple");
    assert_eq!(saved.link_key, Some(key));
    assert_eq!(
        app.poll_session(100),
        Some(SessionEnd::SettingsChanged),
        "the running master stops"
    );
    app.on_session_end(SessionEnd::SettingsChanged);
    assert_eq!(app.next_link_step(150, 7), LinkStep::Probe);
    app.on_radio_present(true);
    let LinkStep::RunMaster(params) = app.next_link_step(200, 7) else {
        panic!("the master runs again");
    };
    // Keyed: the identity on air is the key's, not the stored bind ID.
    assert_eq!(app.master(params).params().bind_id, key.bind_id());
    let follower = app.follower(params, FailsafeValues::default(), 250_000);
    assert_eq!(follower.params().bind_id, key.bind_id());

    // A bad phrase changes nothing and restarts nothing.
    assert_eq!(
        app.set_setting_text("phrase", &"x".repeat(65)),
        Err(TextError::BadPhrase)
    );
    assert_eq!(app.settings().link_key, Some(key));
    assert_eq!(app.poll_session(250), None);
}

#[test]
fn the_hm10_always_gets_a_pin_the_factory_one_from_the_chip_id() {
    let mut app = app(Settings::default());
    let script = app.hm10_script(0, 0x1234_5678_9ABC_DEF0);
    let factory = Pin::factory(0x1234_5678_9ABC_DEF0);
    assert_eq!(script.pin(), Some(factory));
    assert!((100_000..=999_999).contains(&factory.value()));
    assert_ne!(factory, Pin::factory(0x1234_5678_9ABC_DEF1), "per chip");
    assert_eq!(app.parameter_commands().ble_pin, Some(factory), "shown");
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

#[test]
fn a_phrase_typed_on_the_radio_keys_the_link_but_never_while_the_quad_is_armed() {
    use crate::session::{LinkStep, SessionEnd};
    use telemetry::link::LinkKey;
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        ..Settings::default()
    });
    app.on_radio_present(true);
    let LinkStep::RunMaster(_) = app.next_link_step(0, 7) else {
        panic!("bound: the master runs");
    };
    assert_eq!(info_row(&app, params::PHRASE_KEY), params::NO_PHRASE);

    // The flight side reports armed: the phrase is refused, nothing restarts or is saved.
    app.on_link_record(&arm_record(true));
    radio_writes(
        &mut app,
        params::BIND_PHRASE,
        b"correct horse battery staple\0",
    );
    assert_eq!(app.settings().link_key, None);
    assert_eq!(app.take_action(), None);
    assert_eq!(app.poll_session(50), None);
    assert_eq!(info_row(&app, params::PHRASE_KEY), "refused: quad armed");

    // Disarmed: the same write keys the link, is saved at once and restarts the link.
    app.on_link_record(&arm_record(false));
    radio_writes(
        &mut app,
        params::BIND_PHRASE,
        b"  correct horse battery staple\0",
    );
    let key = LinkKey::from_phrase("correct horse battery staple");
    assert_eq!(
        app.settings().link_key,
        Some(key),
        "trimmed like every path"
    );
    let Some(Action::Save(saved)) = app.take_action() else {
        panic!("the new key is saved at once");
    };
    assert_eq!(saved.link_key, Some(key));
    assert_eq!(app.poll_session(100), Some(SessionEnd::SettingsChanged));
    assert_eq!(
        info_row(&app, params::PHRASE_KEY),
        key.fingerprint().to_string()
    );

    // An empty commit (the pilot backed out of the editor) keeps the phrase.
    radio_writes(&mut app, params::BIND_PHRASE, b"\0");
    assert_eq!(app.settings().link_key, Some(key));
    assert_eq!(app.take_action(), None);
    assert_eq!(info_row(&app, params::PHRASE_KEY), "empty: phrase kept");
}

// ---- Key changes from the phone (telemetry::module_record) ----

use telemetry::link::LinkKey;
use telemetry::module_record::{self, KeyAnswer, KeyOutcome, KeyRefusal, KeySigner, ModuleRecord};

/// The phone sends `record` over the HM-10.
fn phone_sends(app: &mut App<FakeLink, FakeHandset>, record: &ModuleRecord) {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(record, &mut payload).unwrap();
    let mut framed = [0u8; MAX_RECORD_LEN];
    let record = crate::records::with_crc(&payload[..n], &mut framed).unwrap();
    app.on_phone_bytes(&cobs_frame(record));
}

/// The module's answers waiting for the phone.
fn phone_answers(app: &mut App<FakeLink, FakeHandset>) -> Vec<KeyAnswer> {
    let mut answers = Vec::new();
    let mut frame = [0u8; MAX_FRAME_LEN];
    while let Some(n) = app.next_phone_frame(&mut frame) {
        let len = cobs::decode_in_place(&mut frame[..n - 1]).unwrap();
        let payload = crate::records::payload(&frame[..len]).unwrap();
        if let Ok(ModuleRecord::KeyAnswer(answer)) = module_record::decode(payload) {
            answers.push(answer);
        }
    }
    answers
}

/// Status and info of the "Phone Phrase" command row.
fn phone_row(app: &App<FakeLink, FakeHandset>) -> (u8, String) {
    let entry = params::entry(
        params::PHONE_PHRASE,
        app.settings(),
        app.parameter_commands(),
    )
    .unwrap();
    let at = 2 + "Phone Phrase".len() + 1;
    (
        entry[at],
        String::from_utf8(entry[at + 2..entry.len() - 1].to_vec()).unwrap(),
    )
}

fn old_key() -> LinkKey {
    LinkKey::from_phrase("correct horse battery staple")
}

fn new_key() -> LinkKey {
    LinkKey::from_phrase("tr0ub4dor and 3")
}

#[test]
fn a_phone_proposal_waits_for_the_pilots_confirmation_on_the_radio() {
    let mut app = app(Settings {
        bind_id: 0x0101_0101,
        ..Settings::default()
    });
    app.seed_link_nonces(42);
    app.on_radio_present(true);
    let crate::session::LinkStep::RunMaster(_) = app.next_link_step(0, 7) else {
        panic!("bound: the master runs");
    };
    phone_sends(&mut app, &ModuleRecord::ProposeKey(new_key().to_bytes()));
    let [waiting] = phone_answers(&mut app)[..] else {
        panic!("one answer");
    };
    assert_eq!(waiting.outcome, KeyOutcome::AwaitingConfirmation);
    assert_eq!(waiting.fingerprint, Some(new_key().fingerprint().0));
    assert_eq!(app.settings().link_key, None, "nothing changes by itself");
    assert!(
        app.link().records.is_empty(),
        "a module record never goes to the flight side"
    );
    let fingerprint = new_key().fingerprint().to_string();
    assert_eq!(phone_row(&app), (0, format!("{fingerprint} from phone")));

    // The pilot starts the command: the radio asks to confirm, showing the fingerprint.
    radio_writes(&mut app, params::PHONE_PHRASE, &[1]);
    assert_eq!(phone_row(&app), (3, format!("Use key {fingerprint}?")));
    radio_writes(&mut app, params::PHONE_PHRASE, &[4]);
    assert_eq!(app.settings().link_key, Some(new_key()));
    assert!(matches!(app.take_action(), Some(Action::Save(s)) if s.link_key == Some(new_key())));
    assert_eq!(
        app.poll_session(50),
        Some(crate::session::SessionEnd::SettingsChanged)
    );
    assert_eq!(phone_row(&app), (0, format!("Key {fingerprint} set")));
    let [applied] = phone_answers(&mut app)[..] else {
        panic!("one answer");
    };
    assert_eq!(applied.outcome, KeyOutcome::Applied);
    assert_eq!(applied.fingerprint, Some(new_key().fingerprint().0));
}

#[test]
fn a_proposal_is_declined_by_cancel_expires_unseen_and_is_never_taken_armed() {
    let mut app = app(Settings {
        link_key: Some(old_key()),
        ..Settings::default()
    });
    phone_sends(&mut app, &ModuleRecord::ProposeKey(new_key().to_bytes()));
    radio_writes(&mut app, params::PHONE_PHRASE, &[1]);
    radio_writes(&mut app, params::PHONE_PHRASE, &[5]);
    assert_eq!(app.settings().link_key, Some(old_key()));
    let answers = phone_answers(&mut app);
    assert_eq!(
        answers.last().unwrap().outcome,
        KeyOutcome::Refused(KeyRefusal::Declined)
    );
    assert_eq!(
        answers.last().unwrap().fingerprint,
        Some(old_key().fingerprint().0)
    );
    assert_eq!(phone_row(&app), (0, "Cancelled".into()));

    // Nobody confirms: the proposal expires and the phone is told.
    phone_sends(&mut app, &ModuleRecord::ProposeKey(new_key().to_bytes()));
    phone_answers(&mut app);
    for _ in 0..crate::phrase::PROPOSAL_TICKS {
        app.on_tick();
    }
    assert_eq!(
        phone_answers(&mut app).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::Expired))
    );
    radio_writes(&mut app, params::PHONE_PHRASE, &[1]);
    assert_eq!(phone_row(&app).0, 0, "nothing left to confirm");

    // Armed: a proposal is refused at once; one that arrived disarmed is refused at the
    // confirmation if the quad armed meanwhile.
    app.on_link_record(&arm_record(true));
    phone_sends(&mut app, &ModuleRecord::ProposeKey(new_key().to_bytes()));
    assert_eq!(
        phone_answers(&mut app).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::Armed))
    );
    app.on_link_record(&arm_record(false));
    phone_sends(&mut app, &ModuleRecord::ProposeKey(new_key().to_bytes()));
    radio_writes(&mut app, params::PHONE_PHRASE, &[1]);
    app.on_link_record(&arm_record(true));
    radio_writes(&mut app, params::PHONE_PHRASE, &[4]);
    assert_eq!(app.settings().link_key, Some(old_key()));
    assert_eq!(
        phone_answers(&mut app).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::Armed))
    );
    assert_eq!(phone_row(&app), (0, "refused: quad armed".into()));
}

#[test]
fn a_key_signed_under_the_current_phrase_is_applied_at_once_and_only_once() {
    let mut app = app(Settings {
        link_key: Some(old_key()),
        ..Settings::default()
    });
    app.seed_link_nonces(0xDEAD_BEEF);
    let mut phone = KeySigner::new(&old_key());
    // The phone does not know the session yet: refused once, with the session.
    phone_sends(&mut app, &ModuleRecord::SignedKey(phone.seal(&new_key())));
    let [first] = phone_answers(&mut app)[..] else {
        panic!("one answer");
    };
    assert_eq!(
        first.outcome,
        KeyOutcome::Refused(KeyRefusal::NotAuthenticated)
    );
    assert_eq!(app.settings().link_key, Some(old_key()));
    assert!(phone.on_answer(&first), "the phone signs again");
    let signed = phone.seal(&new_key());
    phone_sends(&mut app, &ModuleRecord::SignedKey(signed));
    let [applied] = phone_answers(&mut app)[..] else {
        panic!("one answer");
    };
    assert_eq!(applied.outcome, KeyOutcome::Applied);
    assert_eq!(
        app.settings().link_key,
        Some(new_key()),
        "no confirmation needed"
    );
    assert!(matches!(app.take_action(), Some(Action::Save(s)) if s.link_key == Some(new_key())));
    assert!(app.link().records.is_empty());

    // The recorded record replayed: its counter is used up (and the key it carries is only
    // valid under the old phrase anyway).
    app.set_setting_text("phrase", "correct horse battery staple")
        .unwrap();
    phone_sends(&mut app, &ModuleRecord::SignedKey(signed));
    assert_eq!(
        phone_answers(&mut app).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::Replayed))
    );
    assert_eq!(app.settings().link_key, Some(old_key()));
    // Another boot, another session: the recording fails there too.
    app.seed_link_nonces(1);
    phone_sends(&mut app, &ModuleRecord::SignedKey(signed));
    assert_eq!(
        phone_answers(&mut app).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::NotAuthenticated))
    );
    // A phone with another phrase, and a module without one.
    let mut stranger = KeySigner::new(&LinkKey::from_phrase("guess"));
    let answer = KeyAnswer {
        outcome: KeyOutcome::Refused(KeyRefusal::NotAuthenticated),
        fingerprint: None,
        session: applied.session,
        counter: 0,
    };
    stranger.on_answer(&answer);
    phone_sends(
        &mut app,
        &ModuleRecord::SignedKey(stranger.seal(&new_key())),
    );
    assert_eq!(app.settings().link_key, Some(old_key()));
    let mut plain = self::app(Settings::default());
    phone_sends(&mut plain, &ModuleRecord::SignedKey(phone.seal(&new_key())));
    assert_eq!(
        phone_answers(&mut plain).last().map(|a| a.outcome),
        Some(KeyOutcome::Refused(KeyRefusal::NoPhrase))
    );
    assert_eq!(plain.settings().link_key, None);
}
