//! The device tool's side of the flight controller, frame by frame: the radio's frames as
//! the module relays them (CRSF records), the answers the flight core queues.

use telemetry::crsf_record::{self, CrsfRecord, MAX_RELAYED_CHUNK_DATA};
use telemetry::handset::crsf::device::DeviceInfo;
use telemetry::handset::crsf::frame::{address, frame_type};
use telemetry::handset::crsf::params::{ParameterChunk, ParameterRead, ParameterWrite};

use super::tree::{self, FOLDERS, PARAMETER_COUNT, SETTINGS_BASE};
use crate::app::FlightApp;
use crate::app::tests::armed_in_the_air;
use crate::settings::{PARAMS, Settings, Value, handles};

/// The Lua tool's own address (ExpressLRS' `elrsV3.lua` sends as 0xEF).
const LUA: u8 = 0xEF;

fn app() -> FlightApp {
    let Some(app) = FlightApp::new(Settings::default(), 0) else {
        panic!("factory settings make a setup");
    };
    app
}

/// An app bound with a link key (writes need the keyed link).
fn keyed_app() -> FlightApp {
    let mut settings = Settings::default();
    settings.set_link_key(Some(telemetry::link::LinkKey::from_bytes([0x5A; 16])));
    let Some(app) = FlightApp::new(settings, 0) else {
        panic!("factory settings make a setup");
    };
    app
}

fn send(app: &mut FlightApp, frame_type: u8, payload: &[u8]) {
    let mut out = [0u8; 64];
    let record = CrsfRecord {
        chunk_limit: 35,
        frame_type,
        payload,
    }
    .encode(&mut out)
    .unwrap()
    .to_vec();
    app.on_crsf_record(&record);
}

/// The one answer queued, as (frame type, CRSF payload).
fn answer(app: &mut FlightApp) -> (u8, Vec<u8>) {
    assert!(app.device_reply_pending());
    let reply = app.take_device_reply().unwrap();
    let record = crsf_record::decode(&reply).unwrap();
    assert_eq!(record.chunk_limit, 0);
    (record.frame_type, record.payload.to_vec())
}

/// Row `number`'s whole description, chunk by chunk as the Lua tool reads it.
fn read_entry(app: &mut FlightApp, number: u8) -> Vec<u8> {
    let mut entry = Vec::new();
    for chunk in 0.. {
        let read = ParameterRead {
            destination: address::FLIGHT_CONTROLLER,
            origin: LUA,
            number,
            chunk,
        };
        send(app, frame_type::PARAMETER_READ, &read.to_payload());
        let (kind, payload) = answer(app);
        assert_eq!(kind, frame_type::PARAMETER_SETTINGS_ENTRY);
        let piece = ParameterChunk::from_payload(&payload).unwrap();
        assert_eq!((piece.destination, piece.number), (LUA, number));
        assert!(piece.data.len() <= 35);
        entry.extend_from_slice(&piece.data);
        if piece.chunks_remaining == 0 {
            break;
        }
    }
    entry
}

/// (parent, type byte, name, the bytes after the name).
fn split(entry: &[u8]) -> (u8, u8, String, Vec<u8>) {
    let end = entry[2..].iter().position(|b| *b == 0).unwrap() + 2;
    (
        entry[0],
        entry[1],
        String::from_utf8(entry[2..end].to_vec()).unwrap(),
        entry[end + 1..].to_vec(),
    )
}

fn write(app: &mut FlightApp, number: u8, value: &[u8]) {
    let write = ParameterWrite {
        destination: address::FLIGHT_CONTROLLER,
        origin: LUA,
        number,
        value: heapless::Vec::from_slice(value).unwrap(),
    };
    send(app, frame_type::PARAMETER_WRITE, &write.to_payload());
}

fn number_of(name: &str) -> u8 {
    SETTINGS_BASE + PARAMS.iter().position(|p| p.name == name).unwrap() as u8
}

#[test]
fn a_ping_is_answered_with_the_device_and_its_row_count() {
    let mut app = app();
    send(
        &mut app,
        frame_type::DEVICE_PING,
        &[address::BROADCAST, LUA],
    );
    let (kind, payload) = answer(&mut app);
    assert_eq!(kind, frame_type::DEVICE_INFO);
    let info = DeviceInfo::from_payload(&payload).unwrap();
    assert_eq!(info.name.as_str(), "TauLink FC");
    assert_eq!(
        (info.destination, info.origin),
        (LUA, address::FLIGHT_CONTROLLER)
    );
    assert_eq!(info.parameter_count, PARAMETER_COUNT);
    assert_eq!(
        usize::from(PARAMETER_COUNT),
        FOLDERS.len() + PARAMS.len() + 5
    );
    // A ping for the module is not ours.
    send(
        &mut app,
        frame_type::DEVICE_PING,
        &[address::TX_MODULE, LUA],
    );
    assert!(!app.device_reply_pending());
}

#[test]
fn every_row_reads_whole_with_a_folder_parent_and_the_setting_name() {
    let mut app = app();
    let mut hidden = 0;
    for number in 1..=PARAMETER_COUNT {
        let entry = read_entry(&mut app, number);
        let (parent, kind, name, _) = split(&entry);
        assert!(
            usize::from(parent) <= FOLDERS.len(),
            "row {number} {name}: parent {parent}"
        );
        if kind & 0x80 != 0 {
            hidden += 1;
        }
        if let Some((_, param)) = tree::setting(number) {
            assert_eq!(name, param.name);
            assert_eq!(parent, tree::folder_of(param.name), "{name}");
            assert_ne!(parent, 0, "{name} sits in a folder");
        }
    }
    // No VTX on this board: its folder and its two settings and the frequency row hide.
    assert_eq!(hidden, 4);
    app.set_vtx_present(true);
    let (_, kind, name, rest) = split(&read_entry(&mut app, number_of("vtx.channel")));
    assert_eq!((kind, name.as_str()), (9, "vtx.channel"));
    assert!(
        rest.starts_with(b"1 5725MHz;2 5745MHz;3 5765MHz;"),
        "{:?}",
        String::from_utf8_lossy(&rest)
    );
}

#[test]
fn three_types_written_disarmed_are_the_values_the_core_holds() {
    let mut app = keyed_app();
    // A small PID gain: FLOAT in thousandths, 3 decimals → 4.500e-3 is 4500.
    let kp = number_of("pid.roll.kp");
    let (_, kind, _, rest) = split(&read_entry(&mut app, kp));
    assert_eq!(kind, 8);
    assert_eq!(
        &rest[..4],
        &3_000i32.to_be_bytes(),
        "3.000e-3 at the factory"
    );
    assert_eq!(rest[16], 3, "3 decimals");
    assert!(rest.ends_with(b"e-3\0"));
    write(&mut app, kp, &4_500i32.to_be_bytes());
    // A whole number in a short range: UINT16.
    let cells = number_of("battery.cells");
    write(&mut app, cells, &4u16.to_be_bytes());
    // A choice: the selection's index.
    let mode = number_of("mode.switch_high");
    write(&mut app, mode, &[0]);
    let live = app.settings();
    assert!((live.get(handles::PID_ROLL_KP) - 0.0045).abs() < 1e-7);
    assert_eq!(live.get(handles::BATTERY_CELLS), 4);
    assert_eq!(live.get(handles::MODE_SWITCH_HIGH), 0);
    // The rows read back the new values; the last one written says it was set.
    let (_, _, _, rest) = split(&read_entry(&mut app, cells));
    assert_eq!(&rest[..2], &4u16.to_be_bytes());
    let (_, _, _, rest) = split(&read_entry(&mut app, mode));
    let options = rest.iter().position(|b| *b == 0).unwrap();
    assert_eq!(rest[options + 1], 0, "the selection's value");
    assert!(
        rest.ends_with(b" (set)\0"),
        "{:?}",
        String::from_utf8_lossy(&rest)
    );
}

#[test]
fn changes_are_refused_armed_unkeyed_out_of_range_and_on_the_bound_link() {
    let mut unkeyed = app();
    let cells = number_of("battery.cells");
    write(&mut unkeyed, cells, &3u16.to_be_bytes());
    assert_eq!(unkeyed.settings().get(handles::BATTERY_CELLS), 0);
    let (_, _, _, rest) = split(&read_entry(&mut unkeyed, cells));
    assert!(rest.ends_with(b"(refused: no phrase)\0"));

    let mut app = keyed_app();
    write(&mut app, cells, &9u16.to_be_bytes());
    assert_eq!(app.settings().get(handles::BATTERY_CELLS), 0, "max 6");
    let bind_id = number_of("link.bind_id");
    let (_, kind, _, _) = split(&read_entry(&mut app, bind_id));
    assert_eq!(kind, 12, "the bound link is shown, not edited");
    write(&mut app, bind_id, &[0, 0, 0, 1]);
    assert_eq!(app.settings().get(handles::LINK_BIND_ID), 0);
    let (_, _, _, last) = split(&read_entry(&mut app, tree::LAST_CHANGE));
    assert_eq!(last, b"link.bind_id refused: read-only\0");
    // Dynamic power changes no link parameter: the one link row the tool writes.
    let dynamic = number_of("link.dynamic_power");
    write(&mut app, dynamic, &0u16.to_be_bytes());
    assert_eq!(app.settings().get(handles::LINK_DYNAMIC_POWER), 0);

    armed_in_the_air(&mut app);
    write(&mut app, cells, &3u16.to_be_bytes());
    assert_eq!(app.settings().get(handles::BATTERY_CELLS), 0);
    let (_, _, _, last) = split(&read_entry(&mut app, tree::LAST_CHANGE));
    assert_eq!(last, b"battery.cells refused: armed\0");
}

#[test]
fn save_asks_for_confirmation_then_hands_the_settings_to_the_firmware() {
    let mut app = keyed_app();
    write(&mut app, number_of("battery.cells"), &3u16.to_be_bytes());
    assert!(
        app.take_device_reply().is_none(),
        "a setting write is not answered"
    );
    write(&mut app, tree::SAVE, &[1]); // start
    let (_, _, rest) = {
        let (_, payload) = answer(&mut app);
        let chunk = ParameterChunk::from_payload(&payload).unwrap();
        let (p, k, _, rest) = split(&chunk.data);
        (p, k, rest)
    };
    assert_eq!(rest[0], 3, "confirmation needed");
    assert!(app.take_save().is_none());
    write(&mut app, tree::SAVE, &[4]); // confirm
    let _ = answer(&mut app);
    let Some((saved, _)) = app.take_save() else {
        panic!("a save is due");
    };
    assert_eq!(saved.get(handles::BATTERY_CELLS), 3);
}

#[test]
fn the_float_scale_keeps_every_digit_of_a_small_gain() {
    let kd = tree::FloatScale::for_range(0.0, 0.1, 0.00004);
    assert_eq!((kd.decimals, kd.exponent), (3, -6));
    assert_eq!(kd.to_wire(0.00004), 40_000);
    assert!((kd.from_wire(45_000) - 0.000045).abs() < 1e-10);
    let rate = tree::FloatScale::for_range(30.0, 2_000.0, 720.0);
    assert_eq!((rate.decimals, rate.exponent), (3, 0));
    let q = tree::FloatScale::for_range(1e-3, 1e9, 480_000.0);
    assert_eq!((q.decimals, q.exponent), (0, 0));
    assert_eq!(tree::folder_of("pid.roll.kp"), 2);
    assert_eq!(tree::folder_of("vtx.band"), tree::VTX_FOLDER);
    let written = tree::written_value(
        PARAMS.iter().find(|p| p.name == "vtx.channel").unwrap(),
        &[4],
    );
    assert_eq!(written, Some(Value::U32(5)));
    assert_eq!(MAX_RELAYED_CHUNK_DATA, 55);
}
