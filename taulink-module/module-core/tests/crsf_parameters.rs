//! The radio's device tool, end to end: a scripted CRSF parameter client written from the
//! protocol (its own frame builder and parser below, as the ExpressLRS Lua script behaves on
//! EdgeTX; not our encoder) talks to the module core over its JR-line byte interface
//! (`App::on_handset_bytes` / `next_handset_bytes`) while the core runs the real link master
//! over the mock air, driven as the firmware's link task drives it (`next_link_step`,
//! `poll_session`, `on_session_end`, `on_bind_outcome`). The script pings, reads every
//! parameter chunk by chunk, sets the packet rate to F500 (the link restarts at F500), runs
//! Bind through the command handshake with a flight side listening for a bind (which then
//! follows at F500), and Saves; a new core built from the mock flash has the new settings.

#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;

use common::{BIND_ID, FlightHooks, FlightSide, ModuleApp, ModuleHooks, module_settings};
use embassy_futures::block_on;
use embassy_futures::select::{Either, select};
use module_core::air::AirLink;
use module_core::app::{Action, App};
use module_core::handset::Handset;
use module_core::session::{BindOutcome, LinkStep, POLL_MS};
use module_core::settings::{InputProtocol, OutputProtocol, RateMode, SettingsStore};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};
use telemetry::channels::FailsafeValues;
use telemetry::link::core::Follower;
use telemetry::link::follower::{bind_follower, run_follower};
use telemetry::link::master::{bind_master, run_master};
use telemetry::link::{Band, LinkParams};
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

// ---- The client's own CRSF codec (CRSF spec, github.com/tbs-fpv/tbs-crsf-spec) ----

fn crc8(poly: u8, bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &byte in bytes {
        crc ^= byte;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ poly
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// `C8 len type payload crc` (the radio starts Lua/param frames with 0xC8).
fn frame(frame_type: u8, payload: &[u8]) -> Vec<u8> {
    let mut body = vec![frame_type];
    body.extend_from_slice(payload);
    let mut out = vec![0xC8, (body.len() + 1) as u8];
    out.extend_from_slice(&body);
    out.push(crc8(0xD5, &body));
    out
}

/// RC channels, all centre, as EdgeTX sends them (0xEE first).
fn rc_frame() -> Vec<u8> {
    let mut packed = [0u8; 22];
    let mut bit = 0;
    for _ in 0..16 {
        for b in 0..11 {
            if (992u16 >> b) & 1 == 1 {
                packed[bit / 8] |= 1 << (bit % 8);
            }
            bit += 1;
        }
    }
    let mut out = frame(0x16, &packed);
    out[0] = 0xEE;
    out
}

/// Splits a reply burst into checked `(type, payload)` frames.
fn parse(mut bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut frames = Vec::new();
    while bytes.len() >= 4 {
        let len = bytes[1] as usize;
        let (this, rest) = bytes.split_at(2 + len);
        let body = &this[2..2 + len - 1];
        assert_eq!(crc8(0xD5, body), this[1 + len], "reply CRC");
        assert!(matches!(this[0], 0xC8 | 0xEA), "EdgeTX accepts C8/EA only");
        frames.push((body[0], body[1..].to_vec()));
        bytes = rest;
    }
    assert!(bytes.is_empty(), "whole frames only");
    frames
}

/// One parameter as the Lua script keeps it.
#[derive(Debug, Clone)]
struct Field {
    parent: u8,
    kind: u8,
    name: String,
    /// Selection options / command info / unit, depending on kind.
    options: Vec<String>,
    value: u32,
    status: u8,
    info: String,
}

fn cstr(data: &[u8], at: &mut usize) -> String {
    let end = data[*at..].iter().position(|&b| b == 0).unwrap() + *at;
    let text = String::from_utf8(data[*at..end].to_vec()).unwrap();
    *at = end + 1;
    text
}

fn parse_field(data: &[u8]) -> Field {
    let mut at = 2;
    let name = cstr(data, &mut at);
    let mut field = Field {
        parent: data[0],
        kind: data[1] & 0x7F,
        name,
        options: Vec::new(),
        value: 0,
        status: 0,
        info: String::new(),
    };
    match field.kind {
        9 => {
            field.options = cstr(data, &mut at).split(';').map(String::from).collect();
            field.value = data[at].into();
            at += 4;
            field.info = cstr(data, &mut at); // unit
        }
        2 => {
            field.value = u16::from_be_bytes([data[at], data[at + 1]]).into();
            at += 8;
            field.info = cstr(data, &mut at);
        }
        13 => {
            field.status = data[at];
            assert!(data[at + 1] > 0, "a command names its poll interval");
            at += 2;
            field.info = cstr(data, &mut at);
        }
        // STRING: the text, then its max length (kept in `value`).
        10 => {
            field.info = cstr(data, &mut at);
            field.value = data[at].into();
            at += 1;
        }
        11 => {}
        // INFO: the text after the name.
        12 => field.info = cstr(data, &mut at),
        other => panic!("unexpected type {other}"),
    }
    assert_eq!(at, data.len(), "{}: no trailing bytes", field.name);
    field
}

// ---- The world: module core + link task + flight side + radio script ----

type Shared<T> = Rc<RefCell<T>>;

/// Link steps the core asked for, in order.
type Steps = Shared<Vec<LinkStep>>;

struct Script {
    app: Shared<ModuleApp>,
    time: VirtualTime,
    t_us: u64,
    /// Every reply frame seen, by type.
    seen: BTreeMap<u8, usize>,
}

impl Script {
    /// One radio frame period (4 ms): `request` (or RC channels) out, the replies back.
    async fn tick(&mut self, request: Option<Vec<u8>>) -> Vec<(u8, Vec<u8>)> {
        self.t_us += 4_000;
        self.time.sleep_until(self.t_us).await;
        let now = common::module_now(self.t_us);
        let bytes = request.unwrap_or_else(rc_frame);
        let mut reply = [0u8; 128];
        let len = {
            let mut app = self.app.borrow_mut();
            app.on_handset_bytes(now, &bytes);
            app.on_handset_idle(now);
            app.next_handset_bytes(now + 20, &mut reply).len()
        };
        let frames = parse(&reply[..len]);
        for (kind, _) in &frames {
            *self.seen.entry(*kind).or_default() += 1;
        }
        frames
    }

    /// Sends `request`, then channels, until a reply of `kind` from the module arrives.
    async fn ask(&mut self, request: Vec<u8>, kind: u8) -> Vec<u8> {
        let mut request = Some(request);
        for _ in 0..50 {
            for (k, payload) in self.tick(request.take()).await {
                if k == kind {
                    return payload;
                }
            }
        }
        panic!("no reply of type {kind:#x}");
    }

    /// Reads parameter `number` chunk by chunk; returns the field and its chunk count.
    async fn read(&mut self, number: u8) -> (Field, usize) {
        let mut data = Vec::new();
        let mut chunk = 0u8;
        loop {
            let reply = self
                .ask(frame(0x2C, &[0xEE, 0xEA, number, chunk]), 0x2B)
                .await;
            assert_eq!(&reply[..3], &[0xEA, 0xEE, number], "addressed and numbered");
            data.extend_from_slice(&reply[4..]);
            if reply[3] == 0 {
                return (parse_field(&data), chunk as usize + 1);
            }
            chunk += 1;
        }
    }

    async fn write(&mut self, number: u8, value: u8) {
        self.tick(Some(frame(0x2D, &[0xEE, 0xEA, number, value])))
            .await;
    }

    /// Steps command `number` with `status` and returns the module's answer.
    async fn command(&mut self, number: u8, status: u8) -> Field {
        let reply = self
            .ask(frame(0x2D, &[0xEE, 0xEA, number, status]), 0x2B)
            .await;
        let mut data = reply[4..].to_vec();
        let mut chunk = 1;
        let mut remaining = reply[3];
        while remaining > 0 {
            let next = self
                .ask(frame(0x2C, &[0xEE, 0xEA, number, chunk]), 0x2B)
                .await;
            data.extend_from_slice(&next[4..]);
            remaining = next[3];
            chunk += 1;
        }
        parse_field(&data)
    }
}

#[test]
fn the_device_tool_reads_everything_changes_the_rate_binds_and_saves() {
    let settings = module_settings(InputProtocol::Crsf, OutputProtocol::Crsf);
    assert_eq!(settings.rate, RateMode::F250);
    let time = VirtualTime::new();
    let medium = Medium::new(time.clone(), ChannelModel::default(), 11);
    let module_node = medium.add_node(Node::default());
    let flight_node = medium.add_node(Node {
        position_m: 50.0,
        ..Node::default()
    });
    let app = Rc::new(RefCell::new(
        App::new(settings, AirLink::new(), Handset::new(&settings), false).unwrap(),
    ));
    let executor = Executor::new(time.clone());
    let steps: Steps = Rc::default();

    // The link task, as module-fw's: ask, run until the core says stop, report back.
    {
        let (app, steps, time) = (app.clone(), steps.clone(), time.clone());
        let mut radio = MockRadio::new(medium.clone(), module_node);
        let mut clock = SimClock::new(time.clone(), common::MODULE_EPOCH_US, 0.0);
        executor.spawn(async move {
            let mut random = 0x4242_0000u32;
            loop {
                random += 1;
                let now_ms = || (common::module_now(time.now_us()) / 1_000) as u32;
                let step = app.borrow_mut().next_link_step(now_ms(), random);
                steps.borrow_mut().push(step);
                let poll = async {
                    loop {
                        time.sleep_until(time.now_us() + u64::from(POLL_MS) * 1_000)
                            .await;
                        if let Some(end) = app.borrow_mut().poll_session(now_ms()) {
                            return end;
                        }
                    }
                };
                match step {
                    LinkStep::Probe => {
                        app.borrow_mut().on_radio_present(true);
                    }
                    LinkStep::RunMaster(params) => {
                        let mut master = app.borrow().master(params);
                        let mut hooks = ModuleHooks { app: app.clone() };
                        let run = run_master(&mut radio, &mut clock, &mut master, &mut hooks);
                        // The master loop only returns on a radio error (none here).
                        let Either::Second(end) = select(run, poll).await;
                        app.borrow_mut().on_session_end(end);
                    }
                    LinkStep::BindMaster {
                        params,
                        auth,
                        key,
                        random,
                        timeout_us,
                    } => {
                        let result = bind_master(
                            &mut radio, &mut clock, &params, &auth, &key, &random, timeout_us,
                        )
                        .await;
                        app.borrow_mut()
                            .on_bind_outcome(BindOutcome::offered(result));
                    }
                    other => panic!("a bound transmitter never asks for {other:?}"),
                }
            }
        });
    }

    // The firmware's 10 Hz housekeeping (link statistics to the handset, LED).
    {
        let (app, time) = (app.clone(), time.clone());
        executor.spawn(async move {
            let mut t = 0;
            loop {
                t += 100_000;
                time.sleep_until(t).await;
                app.borrow_mut().on_tick();
            }
        });
    }

    // The flight side: bound to the module at F250; at 3 s its owner puts it in bind mode
    // (a deliberate act on the receiver), then it follows whatever the offer said.
    let flight = Rc::new(RefCell::new(FlightSide::default()));
    let offered: Shared<Option<LinkParams>> = Rc::default();
    {
        let (flight, offered, time) = (flight.clone(), offered.clone(), time.clone());
        let mut radio = MockRadio::new(medium, flight_node);
        let mut clock = SimClock::new(time.clone(), common::FLIGHT_EPOCH_US, 0.0);
        executor.spawn(async move {
            time.sleep_until(3_000_000).await;
            // The module runs the unauthenticated link (`common::module_settings`): this end
            // allows it too.
            let auth = telemetry::link::FollowerAuth {
                allow_plain: true,
                ..Default::default()
            };
            let bound = bind_follower(
                &mut radio,
                &mut clock,
                Band::Mhz433,
                &auth,
                &[1; 32],
                10_000_000,
            )
            .await
            .unwrap();
            let telemetry::link::follower::FollowerBind::Bound { params, .. } = bound else {
                panic!("the module's offer: {bound:?}");
            };
            *offered.borrow_mut() = Some(params);
            let mut follower = Follower::new(params, FailsafeValues::default(), 500_000);
            let mut hooks = FlightHooks { side: flight };
            let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        });
    }

    // The radio's device tool.
    let report: Shared<Vec<String>> = Rc::default();
    let saved: Shared<Option<module_core::settings::Settings>> = Rc::default();
    {
        let (app, time, report, saved, steps) = (
            app.clone(),
            time.clone(),
            report.clone(),
            saved.clone(),
            steps.clone(),
        );
        executor.spawn(async move {
            let mut script = Script {
                app: app.clone(),
                time,
                t_us: 0,
                seen: BTreeMap::new(),
            };
            // Ping (as the Lua script does: broadcast from the radio) → DEVICE_INFO.
            let info = script.ask(frame(0x28, &[0x00, 0xEA]), 0x29).await;
            let name_end = info[2..].iter().position(|&b| b == 0).unwrap() + 2;
            assert_eq!(&info[2..name_end], b"TauLink");
            let count = info[name_end + 13];
            assert_eq!(count, 24, "DEVICE_INFO's parameter count");

            // Read every parameter.
            let mut fields = Vec::new();
            let mut chunks = 0;
            for number in 1..=count {
                let (field, n) = script.read(number).await;
                chunks += n;
                fields.push(field);
            }
            assert!(chunks > count as usize, "some parameters need several chunks");
            let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
            assert_eq!(
                names,
                [
                    "Packet Rate",
                    "Telem Ratio",
                    "TX Power",
                    "Band",
                    "Handset",
                    "Input",
                    "Telem Output",
                    "Input Timeout",
                    "Receiver Role",
                    "PPM Failsafe",
                    "Bind",
                    "Save",
                    "Model Match",
                    "Model",
                    "Protocol",
                    "OpenLRSng",
                    "OLRS Rate",
                    "OLRS Channels",
                    "OLRS Telem",
                    "Bind Phrase",
                    "BLE PIN",
                    "Link Key",
                    "Tag Fails",
                    "Dynamic Power"
                ]
            );
            assert_eq!(fields[23].options, ["Off", "On"]);
            assert_eq!(fields[23].value, 1, "dynamic power, on from the factory");
            assert_eq!(fields[12].options, ["Off", "On"]);
            assert_eq!(fields[12].value, 0, "model match is off from the factory");
            assert_eq!((fields[13].kind, fields[13].info.as_str()), (12, "any (match off)"));
            assert_eq!(
                fields[14].options,
                ["TauLink", "OLRSng3.8 (no auth)", "OLRSng3.9 (no auth)"]
            );
            assert_eq!(fields[14].options[fields[14].value as usize], "TauLink");
            assert_eq!(fields[16].parent, 16, "OLRS Rate sits in the OpenLRSng folder");
            assert_eq!(fields[16].options[fields[16].value as usize], "19k2bps");
            assert_eq!(fields[17].options[fields[17].value as usize], "8");
            assert_eq!(
                (fields[19].kind, fields[19].info.as_str(), fields[19].value),
                (10, "", 56),
                "the phrase is an empty STRING of at most 56 bytes"
            );
            assert_eq!(
                fields[21].info, "NO AUTH no phrase",
                "an unauthenticated link: the menu says so"
            );
            assert_eq!(
                (fields[22].kind, fields[22].info.as_str()),
                (12, "0 / 0"),
                "the tag failures, both ends"
            );
            let rate = &fields[0];
            assert_eq!(
                rate.options,
                [
                    "L50 (50 Hz)",
                    "M100 (100 Hz)",
                    "F250 (250 Hz)",
                    "F500 (500 Hz)",
                    "F700 (700 Hz)"
                ]
            );
            assert_eq!(rate.options[rate.value as usize], "F250 (250 Hz)");
            assert_eq!(fields[1].options[fields[1].value as usize], "1:4");
            assert_eq!(fields[5].parent, 5, "Input sits in the Handset folder");
            assert_eq!(fields[5].options[fields[5].value as usize], "CRSF 400k");
            assert_eq!((fields[7].value, fields[7].info.as_str()), (500, "ms"));
            assert_eq!(fields[9].parent, 9);
            assert_eq!((fields[10].kind, fields[10].status), (13, 0));
            report
                .borrow_mut()
                .push(format!("read {count} parameters in {chunks} chunks"));

            // Packet rate → F500: the link restarts at F500 and the row says so.
            let runs_before = steps.borrow().len();
            script.write(1, 3).await;
            for _ in 0..100 {
                script.tick(None).await;
            }
            let (rate, _) = script.read(1).await;
            assert_eq!(rate.options[rate.value as usize], "F500 (500 Hz)");
            assert_eq!(rate.info, " (link restarted)");
            let restarted: Vec<LinkStep> = steps.borrow()[runs_before..].to_vec();
            assert!(
                restarted.iter().any(|s| matches!(s,
                    LinkStep::RunMaster(p) if p.rate == telemetry::link::RateMode::F500 && p.bind_id == BIND_ID)),
                "{restarted:?}"
            );

            // Bind through the handshake; the flight side listens from 3 s.
            while script.t_us < 3_100_000 {
                script.tick(None).await;
            }
            let started = script.command(11, 1).await;
            assert_eq!((started.status, started.info.as_str()), (2, "Binding"));
            let mut polls = 0;
            let done = loop {
                for _ in 0..125 {
                    script.tick(None).await; // the 0.5 s poll interval
                }
                polls += 1;
                let field = script.command(11, 6).await;
                if field.status == 0 {
                    break field;
                }
                assert_eq!(field.status, 2, "running until it ends");
                assert!(polls < 40, "bind never ended");
            };
            assert_eq!(done.info, "Bound");
            report.borrow_mut().push(format!("bind ended after {polls} polls"));

            // Save: confirm, then the firmware is asked to persist.
            let asked = script.command(12, 1).await;
            assert_eq!((asked.status, asked.info.as_str()), (3, "Save settings?"));
            let mut before = Vec::new();
            while let Some(action) = app.borrow_mut().take_action() {
                before.push(action);
            }
            assert!(
                !before.iter().any(|a| matches!(a, Action::Save(_))),
                "nothing saved before the confirmation: {before:?}"
            );
            let confirmed = script.command(12, 4).await;
            assert_eq!((confirmed.status, confirmed.info.as_str()), (0, "Saved"));
            let mut actions = Vec::new();
            while let Some(action) = app.borrow_mut().take_action() {
                actions.push(action);
            }
            let to_save = actions.iter().rev().find_map(|a| match a {
                Action::Save(s) => Some(*s),
                _ => None,
            });
            *saved.borrow_mut() = to_save;
            // Let the follower run a while at the new rate.
            for _ in 0..500 {
                script.tick(None).await;
            }
            // The module sees the link up at F500 too (the rate code it reports to the handset).
            let stats = module_core::ports::LinkPort::stats(app.borrow().link());
            assert!(stats.connected);
            assert_eq!(stats.rate_code, telemetry::link::RateMode::F500.code());
            // The pilot types a phrase in the STRING row: the radio writes it NUL-terminated;
            // the key row says it is being derived; once the firmware has run the
            // derivation, the phrase is saved and the row says a phrase is set.
            let mut typed = vec![0xEE, 0xEA, 20];
            typed.extend_from_slice(b"amber kettle under the oak\0");
            script.tick(Some(frame(0x2D, &typed))).await;
            let (key_row, _) = script.read(22).await;
            assert_eq!(key_row.info, "deriving phrase...");
            while app.borrow_mut().step_phrase_job(256) {}
            let (key_row, _) = script.read(22).await;
            assert!(key_row.info.ends_with("+phrase"), "{}", key_row.info);
            let mut phrase_saved = None;
            while let Some(action) = app.borrow_mut().take_action() {
                if let Action::Save(s) = action {
                    phrase_saved = Some(s.phrase());
                }
            }
            let salt = app.borrow().settings().phrase_salt;
            assert_eq!(
                phrase_saved,
                Some(Some(telemetry::link::PhraseSecret::derive(
                    "amber kettle under the oak",
                    salt
                )))
            );
            report
                .borrow_mut()
                .push(format!("reply frames by type: {:?}", script.seen));
        });
    }
    executor.run_until_us(9_000_000);

    for line in report.borrow().iter() {
        eprintln!("{line}");
    }
    let params = offered.borrow().expect("the flight side bound");
    assert_eq!(params.rate, telemetry::link::RateMode::F500);
    assert_ne!(params.bind_id, BIND_ID, "a fresh bind ID");
    // The flight side follows at F500: 500 slots/s, 3 in 4 uplinks = 375 channel updates/s
    // (F250 could give at most 188).
    let side = flight.borrow();
    let last = side.outputs.last().expect("channels arrived").0;
    let in_last_second = side
        .outputs
        .iter()
        .filter(|(t, _)| *t + 1_000_000 > last)
        .count();
    eprintln!("flight side: {in_last_second} channel updates in the last second");
    assert!(in_last_second > 300, "{in_last_second} updates/s");

    // The typed phrase is for the next bind: the running link was not touched.
    let stats = module_core::ports::LinkPort::stats(app.borrow().link());
    assert!(stats.connected, "the link keeps running");

    // Save persisted across a power cycle: mock flash, a new core from the store.
    let to_save = saved.borrow().expect("Save asked the firmware to persist");
    assert_eq!(to_save.rate, RateMode::F500);
    assert_eq!(to_save.bind_id, params.bind_id);
    block_on(async {
        let range = 0..8 * 4096;
        let mut store = SettingsStore::new(
            MockFlashBase::<8, 4, 1024>::new(WriteCountCheck::Twice, None, true),
            range.clone(),
        )
        .unwrap();
        store.save(&to_save).await.unwrap();
        let mut store = SettingsStore::new(store.release(), range).unwrap();
        let loaded = store.load().await.unwrap().unwrap();
        assert_eq!(loaded, to_save);
        let mut rebooted = App::new(loaded, AirLink::new(), Handset::new(&loaded), false).unwrap();
        assert_eq!(rebooted.next_link_step(0, 0), LinkStep::Probe);
        rebooted.on_radio_present(true);
        assert_eq!(
            rebooted.next_link_step(0, 0),
            LinkStep::RunMaster(module_core::air::link_params(&to_save).unwrap())
        );
    });
}
