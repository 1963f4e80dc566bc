//! Issue 6 acceptance, PPM mode: a simulated Taranis PPM waveform → the module core's PPM
//! decoder → the real link master over the mock radio → the real follower on the flight side,
//! which must output the same channels; flight telemetry → link → module → S.Port bytes that
//! the `taulink_handset` S.Port decoder turns back into the same voltage, RSSI, LQ and
//! flight mode; and the HM-10 stream, which decodes to the same telemetry messages. A phone
//! record travels the other way to the flight side.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use common::{
    FlightSide, World, flight_attitude, flight_battery, flight_gps, module_now, module_settings,
};
use module_core::channels::{ticks_to_us, us_to_ticks};
use module_core::hm10::relay::MAX_FRAME_LEN;
use module_core::ports::LinkPort;
use module_core::settings::{InputProtocol, OutputProtocol};
use taulink_handset::sport::{self, value_id};
use telemetry::messages::{
    Decoded, FlightMode, Message, MessageReader, SettingChange, encode_message,
};

/// The Taranis' 8 channel periods, µs: the extremes and odd values in between.
const WIDTHS_US: [u16; 8] = [988, 1500, 2012, 1013, 1751, 1102, 1899, 1357];
/// EdgeTX's 8-channel PPM frame.
const FRAME_US: u64 = 22_500;
/// Virtual run time.
const RUN_US: u64 = 4_000_000;

fn spawn_taranis(world: &mut World<'_>) {
    let app = world.app.clone();
    let time = world.time.clone();
    world.executor.spawn(async move {
        let mut frame_start = 50_000u64;
        loop {
            let mut t = frame_start;
            // A pulse starts every channel period and the rest period (EdgeTX
            // `radio/src/pulses/ppm.cpp`).
            for width in WIDTHS_US.iter().map(|w| u64::from(*w)).chain([0]) {
                time.sleep_until(t).await;
                app.borrow_mut().on_ppm_edge(module_now(t) as u32);
                t += width;
            }
            frame_start += FRAME_US;
        }
    });
}

/// Polls the JR line like the firmware's push task (every 2 ms) and keeps what it sends.
fn spawn_jr_line(world: &mut World<'_>) -> common::Shared<Vec<(u64, Vec<u8>)>> {
    let sent = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let (app, time, log) = (world.app.clone(), world.time.clone(), sent.clone());
    world.executor.spawn(async move {
        let mut t = 0;
        loop {
            t += 2_000;
            time.sleep_until(t).await;
            let mut out = [0u8; 128];
            let n = app
                .borrow_mut()
                .next_handset_bytes(module_now(t), &mut out)
                .len();
            if n > 0 {
                log.borrow_mut().push((t, out[..n].to_vec()));
            }
        }
    });
    sent
}

/// A phone: connected from the start, sends one SettingChange at 1 s, reads every 10 ms.
fn spawn_phone(world: &mut World<'_>) -> common::Shared<Vec<u8>> {
    let bytes = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let (app, time, log) = (world.app.clone(), world.time.clone(), bytes.clone());
    world.app.borrow_mut().on_phone_connected();
    world.executor.spawn(async move {
        let mut t = 0;
        loop {
            t += 10_000;
            time.sleep_until(t).await;
            let mut app = app.borrow_mut();
            if t == 1_000_000 {
                let mut frame = [0u8; 64];
                let change = Message::SettingChange(SettingChange {
                    id: 7,
                    value: -1234,
                });
                let n = encode_message(&change, &mut frame).unwrap().len();
                // The HM-10 hands BLE writes over in 20-byte pieces at most.
                for chunk in frame[..n].chunks(5) {
                    app.on_phone_bytes(chunk);
                }
            }
            let mut frame = [0u8; MAX_FRAME_LEN];
            while let Some(n) = app.next_phone_frame(&mut frame) {
                log.borrow_mut().extend_from_slice(&frame[..n]);
            }
        }
    });
    bytes
}

fn last_output(flight: &FlightSide) -> [u16; 16] {
    flight
        .outputs
        .last()
        .expect("the flight side heard the module")
        .1
}

#[test]
fn ppm_to_flight_and_telemetry_back_as_sport_and_hm10() {
    let mut world = World::new(module_settings(InputProtocol::Ppm, OutputProtocol::SPort));
    spawn_taranis(&mut world);
    let jr = spawn_jr_line(&mut world);
    let phone = spawn_phone(&mut world);
    world.run_until(RUN_US);

    // --- Channels: PPM → link → flight side, 11-bit resolution, within 1 µs. ---
    let flight = world.flight.borrow();
    let output = last_output(&flight);
    for (channel, &width) in WIDTHS_US.iter().enumerate() {
        assert_eq!(output[channel], us_to_ticks(width), "channel {channel}");
        assert!(
            ticks_to_us(output[channel]).abs_diff(width) <= 1,
            "channel {channel}: {width} µs came out as {} µs",
            ticks_to_us(output[channel])
        );
    }
    // Channels the PPM stream does not carry stay centred.
    assert!(output[8..].iter().all(|&v| v == 992));
    // Every uplink after the PPM lock carried the Taranis' values (F250, 3 of 4 slots up).
    let locked: Vec<_> = flight
        .outputs
        .iter()
        .filter(|(t, _)| *t > 1_000_000)
        .collect();
    assert!(locked.len() > 500, "{} uplinks in 3 s", locked.len());
    assert!(locked.iter().all(|(_, o)| o[..8] == output[..8]));
    let stats = world.app.borrow().input_stats();
    assert_eq!(stats.rejected, 0);
    assert!(stats.frames > 150, "{} PPM frames forwarded", stats.frames);

    // --- Telemetry: flight → link → module → S.Port bytes → decoder. ---
    let mut decoder = sport::Decoder::new();
    let mut frames = Vec::new();
    for (t, bytes) in jr.borrow().iter() {
        decoder.push_all(bytes, |event| {
            if let sport::Event::Frame(frame) = event {
                frames.push((*t, frame));
            }
        });
    }
    let values = |id: u16| -> Vec<(u64, u32)> {
        frames
            .iter()
            .filter(|(_, f)| f.value_id == id)
            .map(|(t, f)| (*t, f.value))
            .collect()
    };
    // VFAS in 0.01 V: 11.87 V.
    let vfas = values(value_id::VFAS);
    assert!(!vfas.is_empty());
    assert!(vfas.iter().all(|&(_, v)| v == 1187));
    // Flight mode number: AltitudeHold's stable id 5 under DIY ID 0x5101.
    let modes = values(value_id::TAULINK_FLIGHT_MODE);
    assert!(!modes.is_empty() && modes.iter().all(|&(_, v)| v == 5));
    // LQ under DIY ID 0x5100: the follower's uplink LQ; on this clean link 100 %.
    let lq = values(value_id::TAULINK_LQ);
    assert!(!lq.is_empty());
    for &(_, v) in &lq {
        assert!(
            flight.uplink_lq.contains(&(v as u8)),
            "LQ {v} never measured by the flight side"
        );
    }
    assert_eq!(lq.last().unwrap().1, 100);
    assert_eq!(*flight.uplink_lq.last().unwrap(), 100);
    // RSSI 0xF101 = downlink LQ: non-zero in every second once the link is up, and the last
    // value is what the module's link reports.
    let rssi = values(value_id::RSSI);
    let first_up = rssi.iter().find(|&&(_, v)| v > 0).unwrap().0;
    assert!(first_up < 1_000_000, "link up after {first_up} µs");
    let mut window = first_up;
    while window + 1_000_000 <= RUN_US {
        let in_window = rssi
            .iter()
            .filter(|&&(t, v)| t >= window && t < window + 1_000_000 && v > 0)
            .count();
        assert!(
            in_window >= 5,
            "{in_window} non-zero RSSI frames from {window} µs"
        );
        window += 1_000_000;
    }
    let link = world.app.borrow().link().stats();
    assert_eq!(u32::from(link.link_quality_percent), rssi.last().unwrap().1);
    assert_eq!(link.link_quality_percent, 100);

    // --- HM-10: the phone stream decodes to the messages the flight side sent. ---
    let mut reader = MessageReader::new();
    let mut messages = Vec::new();
    for &b in phone.borrow().iter() {
        match reader.push(b) {
            Some(Decoded::Message(m)) => messages.push(m),
            Some(Decoded::Dropped) => panic!("phone stream frame dropped"),
            None => {}
        }
    }
    assert!(messages.contains(&Message::Battery(flight_battery())));
    assert!(messages.contains(&Message::Attitude(flight_attitude())));
    assert!(messages.contains(&Message::Gps(flight_gps())));
    assert!(messages.contains(&Message::FlightMode(FlightMode::AltitudeHold)));
    // Everything the flight side queued before the last 200 ms reached the phone, in order.
    let delivered = messages.len();
    assert!(
        delivered + 10 >= flight.sent.len(),
        "{delivered} of {}",
        flight.sent.len()
    );
    assert_eq!(&flight.sent[..delivered], &messages[..]);
    assert_eq!(world.app.borrow().relay_stats().to_phone.records, 0);

    eprintln!(
        "outputs {} locked {} ppm frames {} sport frames {} vfas {} lq {} rssi {} phone msgs {} sent {}",
        flight.outputs.len(),
        locked.len(),
        stats.frames,
        frames.len(),
        vfas.len(),
        lq.len(),
        rssi.len(),
        messages.len(),
        flight.sent.len()
    );
    // --- Phone → flight: the SettingChange arrived unchanged. ---
    assert_eq!(
        flight.received,
        vec![Message::SettingChange(SettingChange {
            id: 7,
            value: -1234
        })]
    );
}

#[test]
fn ppm_mode_fallback_frsky_d_hub_decodes_to_the_flight_values() {
    use taulink_handset::frsky_d::{self, HubDecoder, hub};

    let mut world = World::new(module_settings(
        InputProtocol::Ppm,
        OutputProtocol::FrskyHub,
    ));
    spawn_taranis(&mut world);
    let jr = spawn_jr_line(&mut world);
    world.run_until(RUN_US);

    let mut decoder = frsky_d::Decoder::new();
    let mut hub_decoder = HubDecoder::default();
    let mut links = Vec::new();
    let mut records = Vec::new();
    for (t, bytes) in jr.borrow().iter() {
        // One frame per 30 ms slot at 9600 Bd: ≤ 19 stuffed bytes = 19.8 ms on the wire.
        assert!(bytes.len() <= frsky_d::MAX_WIRE_LEN);
        decoder.push_all(bytes, |event| match event {
            frsky_d::Event::Frame(frsky_d::Frame::Link(link)) => links.push((*t, link)),
            frsky_d::Event::Frame(frsky_d::Frame::User(data)) => {
                for &b in &data {
                    if let Some(record) = hub_decoder.push(b) {
                        records.push(record);
                    }
                }
            }
            frsky_d::Event::Rejected(r) => panic!("FrSky D frame rejected: {r:?}"),
        });
    }
    let frames = jr.borrow().len();
    // 30 ms slots: 4 s → ≈ 133 frames.
    assert!((120..=134).contains(&frames), "{frames} frames");
    let link = links.last().unwrap().1;
    // A1 = 11.87 V on EdgeTX's 13.2 V scale: 11870 · 255 / 13200 = 229.3 → 229.
    assert_eq!(link.a1, 229);
    assert_eq!(link.a2, 100, "uplink LQ");
    assert_eq!(link.rssi, 100, "downlink LQ");
    let value = |id: u8| records.iter().rev().find(|r| r.id == id).map(|r| r.value);
    // VFAS high precision: 1187 (0.01 V) + 2000.
    assert_eq!(value(hub::id::VFAS), Some(3187));
    assert_eq!(value(hub::id::CURRENT), Some(125));
    assert_eq!(value(hub::id::FUEL), Some(64));
    assert_eq!(
        value(hub::id::TEMP1),
        Some(5),
        "flight mode number (AltitudeHold's id)"
    );
    // Channels arrive on this path too.
    let flight = world.flight.borrow();
    assert_eq!(last_output(&flight)[0], us_to_ticks(WIDTHS_US[0]));
}
